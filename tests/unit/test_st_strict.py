"""Every Structured Text export in both dialects (strict IEC 61131-3, the default; codesys): parsed by two independent
grammars (blark's lark grammar of TwinCAT ST, and the tree-sitter IEC 61131-3 ST grammar from PyPI), every identifier
checked against IEC 61131-3's keywords, data types, standard functions and function blocks (the list is written out
below from the standard's tables, not taken from the code), and the exported look-ups evaluated by transcribing the
ST's arithmetic here (the constants read from the exported text) against ``Table.lookup`` / ``Table2D.lookup`` on
more than 5,000 points each.
"""

from __future__ import annotations

import re

import numpy as np
import pytest

from pickplace_cli.export.table2d_st import format_table_2d_st
from pickplace_cli.export.table_st import format_table_st
from pickplace_cli.lookup.bspline_table import load_table
from pickplace_cli.lookup.table2d import TableJumpError, load_table_2d
from pickplace_cli.model.errors import TableError

# IEC 61131-3 (3rd ed.), written out from its tables: keywords (Annex C), elementary and generic data types (tables
# 10, 11), standard functions (tables 22-36: conversion, numerical, arithmetic, bit-shift, bitwise, selection,
# comparison, character string, time and date, endianness, validity) and standard function blocks (tables 43-46).
IEC_KEYWORDS = set("""
ABSTRACT ACTION AND ANY ARRAY AT BY CASE CLASS CONFIGURATION CONSTANT CONTINUE DO ELSE ELSIF EN END_ACTION END_CASE
END_CLASS END_CONFIGURATION END_FOR END_FUNCTION END_FUNCTION_BLOCK END_IF END_INTERFACE END_METHOD END_NAMESPACE
END_PROGRAM END_REPEAT END_RESOURCE END_STEP END_STRUCT END_TRANSITION END_TYPE END_VAR END_WHILE ENO EXIT EXTENDS
F_EDGE FALSE FINAL FOR FROM FUNCTION FUNCTION_BLOCK IF IMPLEMENTS INITIAL_STEP INTERFACE INTERNAL INTERVAL METHOD MOD
NAMESPACE NON_RETAIN NOT NULL OF ON OR OVERRIDE PRIORITY PRIVATE PROGRAM PROTECTED PUBLIC R_EDGE READ_ONLY READ_WRITE
REF REF_TO REPEAT RESOURCE RETAIN RETURN SINGLE STEP STRUCT SUPER TASK THEN THIS TO TRANSITION TRUE TYPE UNTIL USING
VAR VAR_ACCESS VAR_CONFIG VAR_EXTERNAL VAR_GLOBAL VAR_IN_OUT VAR_INPUT VAR_OUTPUT VAR_TEMP WHILE WITH XOR
""".split())
IEC_TYPES = set("""
BOOL BYTE WORD DWORD LWORD SINT INT DINT LINT USINT UINT UDINT ULINT REAL LREAL TIME LTIME DATE LDATE TIME_OF_DAY
TOD LTIME_OF_DAY LTOD DATE_AND_TIME DT LDATE_AND_TIME LDT STRING WSTRING CHAR WCHAR
ANY_DERIVED ANY_ELEMENTARY ANY_MAGNITUDE ANY_NUM ANY_REAL ANY_INT ANY_UNSIGNED ANY_SIGNED ANY_DURATION ANY_BIT
ANY_CHARS ANY_STRING ANY_CHAR ANY_DATE
""".split())
IEC_FUNCTIONS = set("""
TRUNC ABS SQRT LN LOG EXP SIN COS TAN ASIN ACOS ATAN ATAN2 ADD SUB MUL DIV MOD EXPT MOVE SHL SHR ROL ROR AND OR XOR
NOT SEL MAX MIN LIMIT MUX GT GE EQ LE LT NE LEN LEFT RIGHT MID CONCAT INSERT DELETE REPLACE FIND
ADD_TIME SUB_TIME MUL_TIME DIV_TIME ADD_LTIME SUB_LTIME MUL_LTIME DIV_LTIME ADD_TOD_TIME ADD_DT_TIME SUB_TOD_TIME
SUB_DT_TIME SUB_DATE_DATE SUB_TOD_TOD SUB_DT_DT CONCAT_DATE_TOD CONCAT_DATE CONCAT_TOD CONCAT_DT SPLIT_DATE SPLIT_TOD
SPLIT_DT DAY_OF_WEEK TO_BIG_ENDIAN TO_LITTLE_ENDIAN FROM_BIG_ENDIAN FROM_LITTLE_ENDIAN IS_VALID IS_VALID_BCD
SR RS R_TRIG F_TRIG CTU CTD CTUD CTU_INT CTU_DINT CTU_LINT CTU_UDINT CTU_ULINT CTD_INT CTD_DINT CTD_LINT CTD_UDINT
CTD_ULINT CTUD_INT CTUD_DINT CTUD_LINT CTUD_UDINT CTUD_ULINT TP TON TOF LTP LTON LTOF
""".split())
_ELEMENTARY = sorted((IEC_TYPES - {t for t in IEC_TYPES if t.startswith("ANY")}) | {"BCD"})


def reserved(name: str) -> bool:
    up = name.upper()
    if up in IEC_KEYWORDS | IEC_TYPES | IEC_FUNCTIONS:
        return True
    for a in _ELEMENTARY:  # typed conversions: INT_TO_REAL, TO_LREAL, TRUNC_DINT, REAL_TRUNC_INT, BCD_TO_INT …
        if up in (f"TO_{a}", f"TRUNC_{a}") or any(up in (f"{a}_TO_{b}", f"{a}_TRUNC_{b}") for b in _ELEMENTARY):
            return True
    return False


def test_reserved_list_catches_the_old_name():
    """The 2-D export once named a variable nE: the standard comparison function NE, case-insensitively."""
    assert reserved("nE") and reserved("int_to_real") and reserved("Mid") and not reserved("nEi")


# ------------------------------------------------------------------------------------------- the exports


def _small_1d():
    t = load_table()
    from pickplace_cli.lookup.bspline_table import Table

    rows = t.rows[::6] + (t.rows[-1:] if (len(t.rows) - 1) % 6 else ())
    return Table(rows, meta=dict(t.meta), source=t.source)


@pytest.fixture(scope="module")
def exports():
    """name → ST text of every ST export, in both dialects (the tables small enough for blark's Earley parser)."""
    from .controller_samples import table_st_texts

    out = {}
    for dialect in ("strict", "codesys"):
        out[f"table1d-{dialect}"] = format_table_st(_small_1d(), "TEST", dialect=dialect)
        out[f"table2d-{dialect}"] = format_table_2d_st(_small_2d(), "TEST", dialect=dialect)
        for kind, text in table_st_texts(dialect).items():
            out[f"{kind}-{dialect}"] = text
    return out


def _small_2d():
    """A 3 η × 4 λ table with a basin jump (test_table_2d's synthetic table)."""
    from .test_table_2d import _synthetic

    return _synthetic(k2_of=lambda e, lam: 0.7 if (e >= 0.6 and lam >= 8) else 0.2 + 0.01 * lam)


def _tree_sitter(text: str):
    import tree_sitter as ts
    import tree_sitter_iec61131_3_st as grammar

    return ts.Parser(ts.Language(grammar.language())).parse(text.encode())


def _errors(node) -> list:
    out = []
    if node.type == "ERROR" or node.is_missing:
        out.append(node)
    for c in node.children:
        out += _errors(c)
    return out


def _identifiers(node) -> set[str]:
    out = {node.text.decode()} if node.type == "identifier" else set()
    for c in node.children:
        out |= _identifiers(c)
    return out


def test_tree_sitter_grammar_rejects_broken_st():
    """The second grammar can fail: a FUNCTION without END_IF, and a statement without its ';'."""
    good = "FUNCTION F_A : BOOL\nVAR_INPUT x : LREAL; END_VAR\nIF x > 1.0 THEN F_A := TRUE; END_IF;\nEND_FUNCTION\n"
    assert not _errors(_tree_sitter(good).root_node)
    assert _errors(_tree_sitter(good.replace("END_IF;", "")).root_node)
    assert _errors(_tree_sitter(good.replace("F_A := TRUE;", "F_A := TRUE")).root_node)


@pytest.mark.parametrize("dialect", ["strict", "codesys"])
def test_every_export_parses_with_tree_sitter_and_names_no_reserved_word(exports, dialect):
    for name, text in exports.items():
        if not name.endswith(dialect):
            continue
        tree = _tree_sitter(text)
        assert not _errors(tree.root_node), (name, [e.start_point for e in _errors(tree.root_node)][:3])
        idents = _identifiers(tree.root_node)
        assert idents, name
        bad = sorted(i for i in idents if reserved(i))
        assert not bad, (name, bad)
        if dialect == "strict":  # constants inside the POU: no global list, a standard POU around everything
            assert "VAR_GLOBAL" not in text, name
        else:
            assert "VAR_GLOBAL CONSTANT" in text, name


@pytest.mark.slow
@pytest.mark.parametrize("dialect", ["strict", "codesys"])
def test_every_export_parses_with_blark(exports, dialect):
    """~15 s a dialect: blark's Earley parser takes ~0.5 s per array initialiser."""
    from blark.parse import parse_source_code

    for name, text in exports.items():
        if name.endswith(dialect):
            result = parse_source_code(text)
            assert result.exception is None, (name, result.exception)


# -------------------------------------------------------------- the look-ups, transcribed from the ST text

_ARRAY = re.compile(r"(\w+) : ARRAY\[1\.\.(\d+)(?:, 1\.\.(\d+))?\] OF (LREAL|BOOL) := \[(.*?)\];", re.S)


def st_arrays(text: str) -> dict[str, list]:
    """The constant arrays of an export, read from its text (1-based lists; 2-D arrays as lists of rows)."""
    out = {}
    for name, n1, n2, typ, body in _ARRAY.findall(text):
        body = re.sub(r"\(\*.*?\*\)", "", body, flags=re.S)
        vals = [v.strip() for v in body.split(",")]
        vals = [v == "TRUE" for v in vals] if typ == "BOOL" else [float(v) for v in vals]
        if n2:
            rows, cols = int(n1), int(n2)
            assert len(vals) == rows * cols
            out[name] = [None] + [[None] + vals[i * cols:(i + 1) * cols] for i in range(rows)]
        else:
            assert len(vals) == int(n1)
            out[name] = [None] + vals
    return out


def lookup_1d_as_st(x: float, L: list, K1: list, K2: list) -> tuple[bool, float, float]:
    """F_PickplaceK, statement by statement (IEC DINT division truncates toward zero)."""
    n = len(L) - 1
    if x != x:
        return False, K1[1], K2[1]
    if x <= L[1]:
        return x >= L[1], K1[1], K2[1]
    if x >= L[n]:
        return x <= L[n], K1[n], K2[n]
    lo, hi = 1, n
    while hi - lo > 1:
        mid = int((lo + hi) / 2)
        if x >= L[mid]:
            lo = mid
        else:
            hi = mid
    w = (x - L[lo]) / (L[hi] - L[lo])
    return True, K1[lo] + w * (K1[hi] - K1[lo]), K2[lo] + w * (K2[hi] - K2[lo])


@pytest.mark.parametrize("dialect", ["strict", "codesys"])
def test_1d_lookup_transcribed_matches_table_lookup_on_5000_points(dialect):
    """Tolerance 1e-12 (k ≤ 1): ST computes k[lo] + w·(k[hi] − k[lo]) and Table.lookup numpy's slope·(x − x_lo) +
    k[lo]: the same straight line in another order of operations, a few ulp apart."""
    table = load_table()
    text = format_table_st(table, "TEST", dialect=dialect)
    # the statements transcribed below are the export's own
    for stmt in ("fW := (fLambda - PP_TABLE_LAMBDA[nLo]) / (PP_TABLE_LAMBDA[nHi] - PP_TABLE_LAMBDA[nLo]);",
                 "fK1 := PP_TABLE_K1[nLo] + fW * (PP_TABLE_K1[nHi] - PP_TABLE_K1[nLo]);",
                 "nMid := (nLo + nHi) / 2;", "IF fLambda >= PP_TABLE_LAMBDA[nMid] THEN"):
        assert stmt in text, stmt
    arr = st_arrays(text)
    L, K1, K2 = arr["PP_TABLE_LAMBDA"], arr["PP_TABLE_K1"], arr["PP_TABLE_K2"]
    assert L[1:] == table.lam.tolist()  # the literals read back as the same doubles
    rng = np.random.default_rng(34)
    xs = np.concatenate([rng.uniform(table.lam[0], table.lam[-1], 5000), table.lam, (table.lam[1:] + table.lam[:-1]) / 2])
    assert len(xs) >= 5000
    worst = 0.0
    for x in xs:
        ok, k1, k2 = lookup_1d_as_st(float(x), L, K1, K2)
        r1, r2 = table.lookup(float(x))
        assert ok
        worst = max(worst, abs(k1 - r1), abs(k2 - r2))
    assert worst <= 1e-12, worst
    assert lookup_1d_as_st(table.lam[0] - 1.0, L, K1, K2) == (False, K1[1], K2[1])


def lookup_2d_as_st(lam: float, eta: float, a: dict, P: str) -> tuple[bool, float, float]:
    """F_PickplaceK2D, statement by statement."""
    L, E, K1, K2, J = (a[f"{P}_{s}"] for s in ("LAMBDA", "ETA", "K1", "K2", "JUMP"))
    nl, ne = len(L) - 1, len(E) - 1
    inside = L[1] <= lam <= L[nl] and E[1] <= eta <= E[ne]

    def bisect(x, axis, n):
        if n == 1:
            return 1, 1, 0.0
        if x <= axis[1]:
            return 1, 2, 0.0
        if x >= axis[n]:
            return n - 1, n, 1.0
        lo, hi = 1, n
        while hi - lo > 1:
            mid = int((lo + hi) / 2)
            if x >= axis[mid]:
                lo = mid
            else:
                hi = mid
        return lo, hi, (x - axis[lo]) / (axis[hi] - axis[lo])

    l0, l1, wl = bisect(lam, L, nl)
    e0, e1, we = bisect(eta, E, ne)
    if inside and not J[e0][l0]:
        k = [(G[e0][l0] + wl * (G[e0][l1] - G[e0][l0])) * (1.0 - we) + (G[e1][l0] + wl * (G[e1][l1] - G[e1][l0])) * we
             for G in (K1, K2)]
        return True, k[0], k[1]
    ei = e1 if we >= 0.5 else e0
    li = l1 if wl >= 0.5 else l0
    return False, K1[ei][li], K2[ei][li]


@pytest.mark.parametrize("dialect", ["strict", "codesys"])
def test_2d_lookup_transcribed_matches_table2d_lookup_on_5000_points(dialect):
    """Tolerance 1e-12 (k ≤ 1): the ST's bilinear formula and Table2D's nested lerps are the same plane in another
    order of operations."""
    table = load_table_2d()
    text = format_table_2d_st(table, "TEST", dialect=dialect)
    for stmt in ("nEi := nE0;", "fK1 := (PP_TABLE2D_K1[nE0, nL0] + fWl * (PP_TABLE2D_K1[nE0, nL1] - PP_TABLE2D_K1[nE0, nL0])) * (1.0 - fWe)"):
        assert stmt in text, stmt
    arr = st_arrays(text)
    rng = np.random.default_rng(35)
    lams = rng.uniform(table.lams[0], table.lams[-1], 6000)
    etas = rng.uniform(table.etas[0], table.etas[-1], 6000)
    checked = jumps = 0
    worst = 0.0
    for lam, eta in zip(lams, etas):
        ok, k1, k2 = lookup_2d_as_st(float(lam), float(eta), arr, "PP_TABLE2D")
        try:
            r1, r2 = table.lookup(float(lam), float(eta))
        except TableJumpError:
            assert not ok  # the ST flags the same cells
            jumps += 1
            continue
        assert ok
        worst = max(worst, abs(k1 - r1), abs(k2 - r2))
        checked += 1
    assert checked >= 5000 and worst <= 1e-12, (checked, jumps, worst)
    with pytest.raises(TableError):
        table.lookup(float(table.lams[-1]) + 1.0, float(table.etas[0]))
    assert not lookup_2d_as_st(float(table.lams[-1]) + 1.0, float(table.etas[0]), arr, "PP_TABLE2D")[0]
