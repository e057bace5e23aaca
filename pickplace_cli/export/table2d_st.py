"""IEC 61131-3 Structured Text export of the 2-D (λ, η) → (k1, k2) table (``build-table --eta-min … -f st``).

* the constants (a ``VAR CONSTANT`` block of the FUNCTION in the ``strict`` IEC 61131-3 dialect, the default; a
  ``VAR_GLOBAL CONSTANT`` list before it in the ``codesys`` dialect): ``<PREFIX>_NETA``, ``<PREFIX>_NLAMBDA`` (DINT); the axes ``<PREFIX>_ETA``
  (``ARRAY[1..NE] OF LREAL``) and ``<PREFIX>_LAMBDA`` (``ARRAY[1..NL]``), both strictly increasing; the optima
  ``<PREFIX>_K1``, ``<PREFIX>_K2`` : ``ARRAY[1..NE, 1..NL] OF LREAL`` (η index first; initialiser row by row);
  ``<PREFIX>_JUMP`` : ``ARRAY[1..NE, 1..NL] OF BOOL``, TRUE for the grid cell whose lower corner is (i, j)
  when the optimum jumps between basins inside it (:func:`pickplace_cli.lookup.table2d.find_jumps`).
* ``FUNCTION <NAME> : BOOL`` (VAR_INPUT fLambda, fEta; VAR_OUTPUT fK1, fK2): bilinear interpolation in the
  cell around (λ, η) (bisection on each axis), the rule of :meth:`pickplace_cli.lookup.table2d.Table2D.lookup`;
  TRUE then. Outside the grid, or in a jump cell, it returns FALSE with the values of the nearest grid node
  (clamped), which the caller may use knowing they are not the optimum there (pickplace plan solves such a
  move on demand instead).

Constants are the shortest decimals that read back as the same doubles; the text is deterministic.
"""

from __future__ import annotations

from ..model.errors import ExportError
from ..lookup.table2d import Table2D, _jump_cells, find_jumps
from .table_st import _IDENT, VALUES_PER_LINE, _comment, check_st_names, constants_block, st_real

DERIVED_META = frozenset({"pickplace 2-D look-up table", "units", "basin_jumps"})


def _init(values: list[str], indent: str = "        ") -> str:
    lines = [", ".join(values[i : i + VALUES_PER_LINE]) for i in range(0, len(values), VALUES_PER_LINE)]
    return "[\n" + indent + (",\n" + indent).join(lines) + "]"


def _bisect(var: str, axis: str, n: int, lo: str, hi: str, mid: str, w: str) -> str:
    """ST that sets lo, hi = lo + 1 (lo = hi = 1 for a one-value axis) and the weight w of hi for var."""
    if n == 1:
        return f"{lo} := 1;\n{hi} := 1;\n{w} := 0.0;\n"
    return (
        f"IF {var} <= {axis}[1] THEN\n"
        f"    {lo} := 1;\n    {hi} := 2;\n    {w} := 0.0;\n"
        f"ELSIF {var} >= {axis}[{n}] THEN\n"
        f"    {lo} := {n - 1};\n    {hi} := {n};\n    {w} := 1.0;\n"
        "ELSE\n"
        f"    {lo} := 1;\n"
        f"    {hi} := {n};\n"
        f"    WHILE {hi} - {lo} > 1 DO\n"
        f"        {mid} := ({lo} + {hi}) / 2;\n"
        f"        IF {var} >= {axis}[{mid}] THEN\n"
        f"            {lo} := {mid};\n"
        "        ELSE\n"
        f"            {hi} := {mid};\n"
        "        END_IF;\n"
        "    END_WHILE;\n"
        f"    {w} := ({var} - {axis}[{lo}]) / ({axis}[{hi}] - {axis}[{lo}]);\n"
        "END_IF;\n"
    )


def format_table_2d_st(
    table: Table2D, version: str | None = None, extra_meta: dict | None = None, *,
    prefix: str = "PP_TABLE2D", function: str = "F_PickplaceK2D", dialect: str = "strict",
) -> str:
    """Structured Text of a 2-D table: header comment (provenance, jumps), constants (inside the FUNCTION for
    ``dialect`` strict, a global list before it for codesys), look-up function."""
    for what, ident in (("prefix", prefix), ("function", function)):
        if not _IDENT.match(ident):
            raise ExportError(f"{what} = {ident!r}: must be an IEC 61131-3 identifier (letter or _, then letters, digits, _)")
    ne, nl = len(table.etas), len(table.lams)
    E, L, K1, K2, J = (f"{prefix}_{s}" for s in ("ETA", "LAMBDA", "K1", "K2", "JUMP"))
    check_st_names([("function", function)] + [("prefix", x) for x in (E, L, K1, K2, J, f"{prefix}_NETA")], dialect)
    cells = _jump_cells(find_jumps(table.grid("k1"), table.grid("k2")), ne, nl)
    meta = {k: v for k, v in table.meta.items() if k not in DERIVED_META}
    meta.update(extra_meta or {})
    jumps = table.jumps
    meta["basin_jumps"] = "; ".join(f"({a[0]:.4g}, {a[1]:g})-({b[0]:.4g}, {b[1]:g})" for _, a, b in jumps) or "none"
    if version is not None:
        meta["exported_by"] = f"pickplace {version}"
    out = [
        "(* pickplace 2-D look-up table: optimal time-ratio factors (k1, k2) of the quintic B-spline method\n"
        "   [Li2018, Eq. (20)-(22)] over lambda = b/h and eta (lift-off/set-down ratio), both dimensionless.\n"
        f"   Usage: bInterpolated := {function}(fLambda := b / h, fEta := eta, fK1 => k1, fK2 => k2);\n"
        "   FALSE: outside the grid or in a cell across a basin jump; k1, k2 are then the nearest node's.\n"
        f"   Dialect: {dialect} ({'IEC 61131-3: the table is a constant block of the FUNCTION' if dialect == 'strict' else 'CODESYS/TwinCAT: the table is a global constant list'}).\n"
    ]
    for key in sorted(meta):
        val = meta[key]
        val = ",".join(f"{x:g}" for x in val) if isinstance(val, (list, tuple)) else val
        out.append(_comment(f"   {key}: {val}\n"))
    out.append("*)\n\n")
    const = [f"    {prefix}_NETA : DINT := {ne};\n    {prefix}_NLAMBDA : DINT := {nl};\n",
             f"    {E} : ARRAY[1..{ne}] OF LREAL := {_init([st_real(x) for x in table.etas])};\n",
             f"    {L} : ARRAY[1..{nl}] OF LREAL := {_init([st_real(x) for x in table.lams])};\n"]
    for name, col in ((K1, "k1"), (K2, "k2")):
        vals = [st_real(x) for x in table.grid(col).ravel()]
        const.append(f"    (* {col} [-], row i = eta index, column j = lambda index *)\n")
        const.append(f"    {name} : ARRAY[1..{ne}, 1..{nl}] OF LREAL := {_init(vals)};\n")
    flags = ["TRUE" if (i, j) in cells else "FALSE" for i in range(ne) for j in range(nl)]
    const.append("    (* TRUE: the cell with lower corner (i, j) holds a basin jump (not interpolated) *)\n")
    const.append(f"    {J} : ARRAY[1..{ne}, 1..{nl}] OF BOOL := {_init(flags)};\n")
    if dialect == "codesys":
        out.append(constants_block(const, dialect) + "\n")
    out.append(
        f"FUNCTION {function} : BOOL\n"
        "VAR_INPUT\n    fLambda : LREAL; (* lambda = b/h [-] *)\n    fEta : LREAL; (* eta [-] *)\nEND_VAR\n"
        "VAR_OUTPUT\n    fK1 : LREAL; (* k1 [-] *)\n    fK2 : LREAL; (* k2 [-] *)\nEND_VAR\n"
        # the working variables before the constant block (matiec reads a VAR after a VAR CONSTANT as constant)
        "VAR\n    nE0 : DINT;\n    nE1 : DINT;\n    nL0 : DINT;\n    nL1 : DINT;\n    nMid : DINT;\n"
        "    nEi : DINT;\n    nLi : DINT;\n    fWe : LREAL;\n    fWl : LREAL;\n    bIn : BOOL;\nEND_VAR\n"
        + (constants_block(const, dialect) if dialect == "strict" else "") +
        f"bIn := fLambda >= {L}[1] AND fLambda <= {L}[{nl}] AND fEta >= {E}[1] AND fEta <= {E}[{ne}];\n"
    )
    out.append(_bisect("fLambda", L, nl, "nL0", "nL1", "nMid", "fWl"))
    out.append(_bisect("fEta", E, ne, "nE0", "nE1", "nMid", "fWe"))
    out.append(
        f"IF bIn AND NOT {J}[nE0, nL0] THEN\n"
        f"    fK1 := ({K1}[nE0, nL0] + fWl * ({K1}[nE0, nL1] - {K1}[nE0, nL0])) * (1.0 - fWe)\n"
        f"        + ({K1}[nE1, nL0] + fWl * ({K1}[nE1, nL1] - {K1}[nE1, nL0])) * fWe;\n"
        f"    fK2 := ({K2}[nE0, nL0] + fWl * ({K2}[nE0, nL1] - {K2}[nE0, nL0])) * (1.0 - fWe)\n"
        f"        + ({K2}[nE1, nL0] + fWl * ({K2}[nE1, nL1] - {K2}[nE1, nL0])) * fWe;\n"
        f"    {function} := TRUE;\n"
        "ELSE (* outside, NaN or a jump cell: the nearest node *)\n"
        "    nEi := nE0;\n    IF fWe >= 0.5 THEN nEi := nE1; END_IF;\n"
        "    nLi := nL0;\n    IF fWl >= 0.5 THEN nLi := nL1; END_IF;\n"
        f"    fK1 := {K1}[nEi, nLi];\n    fK2 := {K2}[nEi, nLi];\n"
        f"    {function} := FALSE;\n"
        "END_IF;\nEND_FUNCTION\n"
    )
    return "".join(out)
