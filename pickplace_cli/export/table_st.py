"""IEC 61131-3 Structured Text export of the λ → (k1, k2) table, for the online look-up on a PLC.

Li 2018 builds the table offline and reads it online for each move [Li2018, Sec. 3.2]: the controller
computes λ = b/h of the move and interpolates k1, k2. This writes that table and that look-up for a PLC:

* the constants ``<PREFIX>_ROWS`` (DINT), ``<PREFIX>_ETA`` (LREAL, the η the table was built for) and three
  parallel arrays ``<PREFIX>_LAMBDA``, ``<PREFIX>_K1``, ``<PREFIX>_K2`` : ``ARRAY[1..N] OF LREAL`` (λ strictly
  increasing): in the ``strict`` dialect (the default) a ``VAR CONSTANT`` block of the FUNCTION itself, which every
  IEC 61131-3 compiler accepts (matiec, the compiler of Beremiz/OpenPLC, included); in the ``codesys`` dialect a
  ``VAR_GLOBAL CONSTANT`` list before it (a CODESYS/TwinCAT global variable list, an extension of the standard);
* ``FUNCTION <NAME> : BOOL`` with ``VAR_INPUT fLambda : LREAL`` and ``VAR_OUTPUT fK1, fK2 : LREAL``: linear
  interpolation between the two rows around λ (found by bisection, ⌈log2 N⌉ steps), exactly the rule of
  :meth:`pickplace_cli.lookup.bspline_table.Table.lookup`. Outside the table's range the end row is returned (clamped)
  and the function returns FALSE (also for NaN, with the first row); TRUE when λ lies in the range.

Constants are written with the shortest decimal that reads back as the same double, so the PLC's LREAL
table equals the Python table bit for bit. The text is deterministic: the same table gives the same bytes.
Array initialisers are written in ``[ ]`` (IEC 61131-3), as matiec, TwinCAT 3 and CODESYS read them; no identifier is
an IEC keyword or standard function (:mod:`pickplace_cli.model.iec`, case-insensitively).
"""

from __future__ import annotations

import re
from pathlib import Path
from typing import IO

from ..model.errors import ExportError
from ..lookup.bspline_table import Table

#: meta keys of a parsed table that ``format_table`` derives again (not provenance of the build)
DERIVED_META = frozenset({"pickplace look-up table", "units", "a_min, j_min", "fit_k1", "fit_k2", "fit"})
_IDENT = re.compile(r"[A-Za-z_][A-Za-z0-9_]*\Z")
VALUES_PER_LINE = 4
#: the Structured Text dialects of every ST export: strict IEC 61131-3 (constants inside the POU) or CODESYS/TwinCAT
#: (a global constant list beside it)
ST_DIALECTS = ("strict", "codesys")


def check_st_names(names, dialect: str = "strict") -> None:
    """ExportError when ``dialect`` is unknown or a name of the export is not an identifier of its own (the shape, a
    keyword or a standard function of IEC 61131-3, case-insensitively: :func:`~pickplace_cli.model.iec.st_identifier_problem`)."""
    from ..model.iec import st_identifier_problem

    if dialect not in ST_DIALECTS:
        raise ExportError(f"st dialect = {dialect!r}: must be one of {', '.join(ST_DIALECTS)}")
    for what, name in names:
        problem = st_identifier_problem(name)
        if problem:
            raise ExportError(f"{what} = {name!r}: {problem}")


def constants_block(lines: list[str], dialect: str) -> str:
    """The declarations ``lines`` (each ``    NAME : TYPE := VALUE;`` with its newline) as the dialect's constant
    block: ``VAR CONSTANT`` inside the POU (strict) or ``VAR_GLOBAL CONSTANT`` before it (codesys)."""
    head = "VAR CONSTANT\n" if dialect == "strict" else "VAR_GLOBAL CONSTANT\n"
    return head + "".join(lines) + "END_VAR\n"


def st_real(x: float) -> str:
    """An IEC 61131-3 real literal for ``x`` that reads back as the same double (digits '.' digits [E±n]); a negative
    zero is written 0.0 (the same value)."""
    x = float(x) + 0.0  # -0.0 + 0.0 = 0.0
    if x != x or x in (float("inf"), float("-inf")):
        raise ExportError(f"table value {x!r}: Structured Text has no literal for a non-finite number")
    mant, _, exp = repr(x).partition("e")
    if "." not in mant:
        mant += ".0"
    return f"{mant}E{exp}" if exp else mant


def provenance(table: Table, version: str | None = None, extra_meta: dict | None = None) -> list[tuple[str, str]]:
    """(key, value) provenance lines of a table export, sorted by key: the build settings recorded in the
    table (η, weights, optimiser …), its source file name, the Eq. 23 cubic fit and the exporting version."""
    meta = {k: v for k, v in table.meta.items() if k not in DERIVED_META}
    meta.update(extra_meta or {})
    out = {}
    for key, val in meta.items():
        out[str(key)] = ",".join(f"{x:g}" for x in val) if isinstance(val, (list, tuple)) else str(val)
    out["source"] = Path(table.source).name if table.source != "<memory>" else "pickplace build-table"
    lam = table.lam
    out["rows"] = f"{len(lam)} (lambda {lam[0]:g} .. {lam[-1]:g})"
    fit_min = float(meta.get("fit_lambda_min", 5.0))
    g1, g2, res = table.fit(fit_min)
    out["fit_k1"] = " ".join(f"{g:.9g}" for g in g1)
    out["fit_k2"] = " ".join(f"{g:.9g}" for g in g2)
    out["fit"] = (
        f"k_i = g_i0 + g_i1*lambda + g_i2*lambda^2 + g_i3*lambda^3 (Eq. 23), on lambda >= {fit_min:g}, "
        f"max |residual| = {res:.3g} (the ST look-up uses the rows, not the fit)"
    )
    if version is not None:
        out["exported_by"] = f"pickplace {version}"
    return sorted(out.items())


def _comment(text: str) -> str:
    # a comment cannot contain its own terminator; '(*' would nest on some compilers
    return text.replace("*)", "* )").replace("(*", "( *")


def _array(name: str, values, indent: str = "    ") -> str:
    lits = [st_real(v) for v in values]
    lines = [", ".join(lits[i : i + VALUES_PER_LINE]) for i in range(0, len(lits), VALUES_PER_LINE)]
    body = (",\n" + indent * 2).join(lines)
    return f"{indent}{name} : ARRAY[1..{len(lits)}] OF LREAL := [\n{indent * 2}{body}];\n"


def format_table_st(
    table: Table,
    version: str | None = None,
    extra_meta: dict | None = None,
    *,
    prefix: str = "PP_TABLE",
    function: str = "F_PickplaceK",
    dialect: str = "strict",
) -> str:
    """Structured Text of ``table``: header comment (provenance, units), the constants (inside the FUNCTION for
    ``dialect`` strict, a global constant list before it for codesys), the look-up function."""
    for what, ident in (("prefix", prefix), ("function", function)):
        if not _IDENT.match(ident):
            raise ExportError(f"{what} = {ident!r}: must be an IEC 61131-3 identifier (letter or _, then letters, digits, _)")
    n = len(table.rows)
    lam, k1, k2 = table.lam, table.column("k1"), table.column("k2")
    eta = table.eta
    L, K1, K2 = f"{prefix}_LAMBDA", f"{prefix}_K1", f"{prefix}_K2"
    check_st_names([("function", function), ("prefix", f"{prefix}_ROWS"), ("prefix", f"{prefix}_ETA"),
                    ("prefix", L), ("prefix", K1), ("prefix", K2)], dialect)
    out: list[str] = []
    out.append(
        "(* pickplace look-up table: optimal time-ratio factors (k1, k2) of the quintic B-spline method\n"
        "   [Li2018, Eq. (20)-(23)] over lambda = b/h, and the online look-up the paper intends (Sec. 3.2).\n"
        "   Units: lambda = b/h is dimensionless (b = horizontal width of the move [m], h = clearance\n"
        "   height above the higher end point [m]); k1, k2 are dimensionless knot ratios.\n"
        f"   Usage: bInRange := {function}(fLambda := b / h, fK1 => k1, fK2 => k2);\n"
        f"   Dialect: {dialect} ({'IEC 61131-3: the table is a constant block of the FUNCTION' if dialect == 'strict' else 'CODESYS/TwinCAT: the table is a global constant list'}).\n"
    )
    for key, val in provenance(table, version, extra_meta):
        out.append(_comment(f"   {key}: {val}\n"))
    out.append("*)\n\n")
    const = [f"    {prefix}_ROWS : DINT := {n}; (* number of rows *)\n"]
    if eta is not None:
        const.append(f"    {prefix}_ETA : LREAL := {st_real(eta)}; (* lift-off/set-down ratio eta the table was built for *)\n")
    const += ["    (* lambda = b/h [-], strictly increasing *)\n", _array(L, lam),
              "    (* k1 [-] at each lambda *)\n", _array(K1, k1),
              "    (* k2 [-] at each lambda *)\n", _array(K2, k2)]
    if dialect == "codesys":
        out.append(constants_block(const, dialect) + "\n")
    out.append(
        f"FUNCTION {function} : BOOL\n"
        "(* k1, k2 at fLambda by linear interpolation between the two table rows around it.\n"
        f"   Outside [{L}[1], {L}[{n}]] (or NaN) the end row's values are returned and the result is\n"
        "   FALSE; TRUE when fLambda lies in the table's range. *)\n"
        "VAR_INPUT\n"
        "    fLambda : LREAL; (* lambda = b/h [-] *)\n"
        "END_VAR\n"
        "VAR_OUTPUT\n"
        "    fK1 : LREAL; (* k1 [-] *)\n"
        "    fK2 : LREAL; (* k2 [-] *)\n"
        "END_VAR\n"
    )
    # the working variables before the constant block: matiec reads a plain VAR that follows a VAR CONSTANT as
    # constant too ("Assignment to CONSTANT variables is not allowed")
    out.append(
        "VAR\n"
        "    nLo : DINT;\n"
        "    nHi : DINT;\n"
        "    nMid : DINT;\n"
        "    fW : LREAL;\n"
        "END_VAR\n"
    )
    if dialect == "strict":
        out.append(constants_block(const, dialect))
    out.append(
        "IF fLambda <> fLambda THEN (* NaN *)\n"
        f"    fK1 := {K1}[1];\n"
        f"    fK2 := {K2}[1];\n"
        f"    {function} := FALSE;\n"
        f"ELSIF fLambda <= {L}[1] THEN\n"
        f"    fK1 := {K1}[1];\n"
        f"    fK2 := {K2}[1];\n"
        f"    {function} := fLambda >= {L}[1];\n"
        f"ELSIF fLambda >= {L}[{n}] THEN\n"
        f"    fK1 := {K1}[{n}];\n"
        f"    fK2 := {K2}[{n}];\n"
        f"    {function} := fLambda <= {L}[{n}];\n"
        "ELSE\n"
        "    (* bisection: keep L[nLo] <= fLambda < L[nHi] *)\n"
        "    nLo := 1;\n"
        f"    nHi := {n};\n"
        "    WHILE nHi - nLo > 1 DO\n"
        "        nMid := (nLo + nHi) / 2;\n"
        f"        IF fLambda >= {L}[nMid] THEN\n"
        "            nLo := nMid;\n"
        "        ELSE\n"
        "            nHi := nMid;\n"
        "        END_IF;\n"
        "    END_WHILE;\n"
        f"    fW := (fLambda - {L}[nLo]) / ({L}[nHi] - {L}[nLo]);\n"
        f"    fK1 := {K1}[nLo] + fW * ({K1}[nHi] - {K1}[nLo]);\n"
        f"    fK2 := {K2}[nLo] + fW * ({K2}[nHi] - {K2}[nLo]);\n"
        f"    {function} := TRUE;\n"
        "END_IF;\n"
        "END_FUNCTION\n"
    )
    return "".join(out)


def write_table_st(table: Table, stream: IO[str], version: str | None = None, extra_meta: dict | None = None,
                   dialect: str = "strict") -> None:
    """Write :func:`format_table_st` of ``table`` to the text ``stream``."""
    stream.write(format_table_st(table, version, extra_meta, dialect=dialect))
