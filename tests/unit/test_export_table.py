"""export/table_st.py and export/table_json.py: the λ → (k1, k2) table for PLCs and scripts.

The Structured Text is parsed by ``blark`` (an independent IEC 61131-3 parser) and the look-up FUNCTION
is *executed* by a small interpreter over blark's syntax tree (assignments, IF/ELSIF/ELSE, WHILE,
arithmetic with IEC integer division for DINT, array subscripts), with the array constants read from the
parsed ``VAR_GLOBAL CONSTANT`` block. Its results are compared with ``Table.lookup`` (inside the range)
and with numpy's clamped interpolation (outside).

Tolerance 1e-12 (absolute, k ≤ 1): the ST formula K[lo] + w·(K[hi] − K[lo]) and numpy's interpolation
evaluate the same straight line with a different order of operations, which differs by a few ulp.
"""

from __future__ import annotations

import io
import json
import math

import numpy as np
import pytest

from pickplace_cli.model.errors import ExportError
from pickplace_cli.export.table_json import format_table_json, write_table_json
from pickplace_cli.export.table_st import format_table_st, st_real, write_table_st
from pickplace_cli.lookup.bspline_optimum import TableRow
from pickplace_cli.lookup.bspline_table import Table, load_table

TOL = 1e-12


# ------------------------------------------------------------------------- a tiny ST interpreter (tests)


class ST:
    """Parse ST text with blark, keep its constants (a global constant list, or a FUNCTION's ``VAR CONSTANT``
    block: the strict IEC dialect), run its FUNCTIONs."""

    def __init__(self, text: str) -> None:
        import blark.transform as tf
        from blark.parse import parse_source_code

        result = parse_source_code(text)
        assert result.exception is None, result.exception
        self.tf = tf
        self.code = result.transform()
        self.globals: dict[str, object] = {}
        self.constant_blocks = 0
        self.functions = {}
        for item in self.code.items:
            if isinstance(item, tf.GlobalVariableDeclarations):
                assert item.attrs is not None and "constant" in str(item.attrs).lower()
                self.constant_blocks += 1
                for decl in item.items:
                    (name,) = decl.spec.variables
                    self.globals[str(name)] = self.init_value(decl.init)
            elif isinstance(item, tf.Function):
                self.functions[str(item.name)] = item
                for block in item.declarations:
                    if getattr(block, "attrs", None) is not None and "constant" in str(block.attrs).lower():
                        self.constant_blocks += 1
                        for decl in block.items:
                            (name,) = decl.variables if hasattr(decl, "variables") else decl.spec.variables
                            name = getattr(name, "name", name)
                            self.globals[str(name)] = self.init_value(decl.init)

    def init_value(self, init):
        tf = self.tf
        if isinstance(init, tf.ArrayTypeInitialization):
            (sub,) = init.spec.subranges
            lo, hi = int(str(sub.start.value)), int(str(sub.stop.value))
            values = list(self.flatten(init.value))
            assert len(values) == hi - lo + 1, "initialiser length != array bounds"
            return {lo + i: v for i, v in enumerate(values)}
        return self.eval(init.value, {})

    def flatten(self, node):
        tf = self.tf
        if isinstance(node, tf.ArrayInitialization):
            for el in node.elements:
                assert el.count is None
                yield from self.flatten(el.element)
        else:
            yield self.eval(node, {})

    def call(self, name: str, **inputs):
        """Run FUNCTION ``name``; returns (return value, {output: value})."""
        tf = self.tf
        fn = self.functions[name]
        env: dict[str, object] = {}
        types: dict[str, str] = {}
        outputs = []
        for block in fn.declarations:
            if getattr(block, "attrs", None) is not None and "constant" in str(block.attrs).lower():
                continue  # read once, in __init__
            for decl in block.items:
                typ = str(decl.init.spec.type)
                for var in decl.variables:
                    vname = str(var.variable.name)
                    types[vname] = typ
                    env[vname] = 0 if typ == "DINT" else 0.0
                    if isinstance(block, tf.OutputDeclarations):
                        outputs.append(vname)
        for k, v in inputs.items():
            assert k in env
            env[k] = float(v)
        env[name] = False
        self.types = types
        self.run(fn.body, env)
        return env[name], {k: env[k] for k in outputs}

    def run(self, stmts, env) -> None:
        tf = self.tf
        for st in stmts.statements:
            if isinstance(st, tf.AssignmentStatement):
                (var,) = st.variables
                value = self.eval(st.expression, env)
                if self.types.get(str(var.name)) == "DINT":
                    assert isinstance(value, int)
                env[str(var.name)] = value
            elif isinstance(st, tf.IfStatement):
                branches = [(st.if_expression, st.statements)] + [(e.if_expression, e.statements) for e in st.else_ifs]
                for cond, body in branches:
                    if self.eval(cond, env):
                        self.run(body, env)
                        break
                else:
                    if st.else_clause is not None:
                        self.run(st.else_clause.statements, env)
            elif isinstance(st, tf.WhileStatement):
                guard = 0
                while self.eval(st.expression, env):
                    self.run(st.statements, env)
                    guard += 1
                    assert guard < 64, "WHILE does not terminate"
            else:  # pragma: no cover - the generator uses nothing else
                raise AssertionError(f"statement not supported by the test interpreter: {type(st).__name__}")

    def eval(self, e, env):
        tf = self.tf
        if isinstance(e, tf.Integer):
            return int(str(e.value))
        if isinstance(e, tf.Real):
            return float(str(e.value))
        if isinstance(e, tf.Boolean) if hasattr(tf, "Boolean") else False:
            return str(e.value).upper() == "TRUE"
        if type(e).__name__ in ("TrueLiteral", "FalseLiteral") or str(e) in ("TRUE", "FALSE"):
            return str(e) == "TRUE"
        if isinstance(e, tf.SimpleVariable):
            name = str(e.name)
            return env[name] if name in env else self.globals[name]
        if isinstance(e, tf.MultiElementVariable):
            arr = self.globals[str(e.name.name)]
            (subs,) = e.elements
            (idx,) = subs.subscripts
            return arr[self.eval(idx, env)]
        if isinstance(e, tf.ParenthesizedExpression):
            return self.eval(e.expr, env)
        if isinstance(e, tf.UnaryOperation):
            val = self.eval(e.expr, env)
            return {"NOT": lambda: not val, "-": lambda: -val}[str(e.op).upper()]()
        if isinstance(e, tf.BinaryOperation):
            a, b = self.eval(e.left, env), self.eval(e.right, env)
            op = str(e.op).upper()
            if op == "/" and isinstance(a, int) and isinstance(b, int):
                return int(a / b)  # IEC integer division truncates toward zero
            return {
                "+": lambda: a + b,
                "-": lambda: a - b,
                "*": lambda: a * b,
                "/": lambda: a / b,
                "<": lambda: a < b,
                "<=": lambda: a <= b,
                ">": lambda: a > b,
                ">=": lambda: a >= b,
                "=": lambda: a == b,
                "<>": lambda: a != b,
                "AND": lambda: a and b,
                "OR": lambda: a or b,
            }[op]()
        raise AssertionError(f"expression not supported by the test interpreter: {e!r}")


@pytest.fixture(scope="module")
def shipped():
    return load_table()


@pytest.fixture(scope="module")
def subset(shipped):
    """Every 6th row of the shipped table and its last: real values, a table blark parses in ~1 s.

    blark's Earley parser is slow on long array initialisers (its grammar lets a comma list nest in
    itself): 79-element arrays take ~15 s each, so the full shipped table is parsed by one slow test."""
    rows = shipped.rows[::6]
    rows += shipped.rows[-1:] if rows[-1] is not shipped.rows[-1] else ()
    return Table(rows, meta=dict(shipped.meta), source=shipped.source)


@pytest.fixture(scope="module")
def st_subset(subset):
    return ST(format_table_st(subset, "TEST"))


# ------------------------------------------------------------------------------------------------ ST


def check_constants(table, st):
    assert st.constant_blocks == 1 and set(st.functions) == {"F_PickplaceK"}
    n = len(table.rows)
    assert st.globals["PP_TABLE_ROWS"] == n and st.globals["PP_TABLE_ETA"] == table.eta
    for name, col in (("LAMBDA", "lambda"), ("K1", "k1"), ("K2", "k2")):
        arr = st.globals[f"PP_TABLE_{name}"]
        assert sorted(arr) == list(range(1, n + 1))
        # bit-exact: the literals are the shortest round-trip decimals of the doubles
        assert [arr[i] for i in range(1, n + 1)] == table.column(col).tolist()


def check_lookup_inside(table, st, n_random=300):
    rng = np.random.default_rng(7)
    lam = table.lam
    samples = np.concatenate([lam, rng.uniform(lam[0], lam[-1], n_random), (lam[:-1] + lam[1:]) / 2, [12.2, 28.0]])
    for x in samples:
        ok, out = st.call("F_PickplaceK", fLambda=x)
        k1, k2 = table.lookup(float(x))
        assert ok is True
        assert abs(out["fK1"] - k1) <= TOL and abs(out["fK2"] - k2) <= TOL, x


def check_lookup_outside(table, st):
    lam, k1, k2 = table.lam, table.column("k1"), table.column("k2")
    for x in (0.0, 0.5, lam[0] - 1e-9, lam[-1] + 1e-9, 41.0, 1e6, -3.0):
        ok, out = st.call("F_PickplaceK", fLambda=x)
        assert ok is False, x
        assert out["fK1"] == float(np.interp(x, lam, k1)) and out["fK2"] == float(np.interp(x, lam, k2))
    ok, out = st.call("F_PickplaceK", fLambda=float("nan"))
    assert ok is False and out["fK1"] == k1[0] and out["fK2"] == k2[0]
    for x in (lam[0], lam[-1]):  # the ends themselves are inside
        ok, out = st.call("F_PickplaceK", fLambda=x)
        assert ok is True


def test_st_parses_and_constants_equal_the_table(subset, st_subset):
    check_constants(subset, st_subset)


def test_st_lookup_matches_python_inside_the_range(subset, st_subset):
    check_lookup_inside(subset, st_subset)


def test_st_lookup_clamps_outside_and_flags_it(subset, st_subset):
    check_lookup_outside(subset, st_subset)


@pytest.mark.slow
def test_st_full_shipped_table(shipped):
    """The whole shipped table (79 rows): blark parses it (~50 s: see ``subset``), same checks."""
    st = ST(format_table_st(shipped, "TEST"))
    check_constants(shipped, st)
    check_lookup_inside(shipped, st, n_random=100)
    check_lookup_outside(shipped, st)


def test_st_interpreter_catches_a_wrong_function(subset):
    """The check can fail: interpolating from the wrong end of the interval gives a wrong k1."""
    text = format_table_st(subset, "TEST").replace("fK1 := PP_TABLE_K1[nLo] + fW", "fK1 := PP_TABLE_K1[nHi] + fW")
    ok, out = ST(text).call("F_PickplaceK", fLambda=12.2)
    assert ok and abs(out["fK1"] - subset.lookup(12.2)[0]) > 1e-3


def test_st_non_uniform_small_table():
    rows = tuple(
        TableRow(lam, k1, k2, *(math.nan,) * 6)
        for lam, k1, k2 in ((1.0, 0.5, 0.4), (1.7, 0.45, 0.3), (5.0, 0.4, 0.2), (40.0, 1e-5, 0.123456789012345))
    )
    table = Table(rows, meta={"eta": 0.3, "weights": [0.6, 0.4]}, source="/some/dir/custom.csv")
    text = format_table_st(table)
    st = ST(text)
    assert "1.0E-05" in text and "source: custom.csv" in text and "/some/dir" not in text
    for x in np.linspace(1.0, 40.0, 157):
        ok, out = st.call("F_PickplaceK", fLambda=x)
        k1, k2 = table.lookup(float(x))
        assert ok and abs(out["fK1"] - k1) <= TOL and abs(out["fK2"] - k2) <= TOL


def test_st_header_and_determinism(shipped):
    text = format_table_st(shipped, "TEST", {"lambda_grid": "1..40 step 0.5 (79 rows)"})
    head = text.split("*)", 1)[0]
    for needle in ("eta: 0.5", "weights: 0.5,0.5", "source: bspline-eta0.5.csv", "lambda = b/h is dimensionless",
                   "Li2018", "exported_by: pickplace TEST", "fit_k1: "):
        assert needle in head, needle
    assert text == format_table_st(shipped, "TEST")
    buf = io.StringIO()
    write_table_st(shipped, buf, "TEST", {"lambda_grid": "1..40 step 0.5 (79 rows)"})
    assert buf.getvalue() == text


def test_st_real_literals():
    assert [st_real(x) for x in (1.0, 0.5, 1e-5, 40.0, 1e22, 0.1 + 0.2)] == [
        "1.0", "0.5", "1.0E-05", "40.0", "1.0E+22", "0.30000000000000004"]
    assert [st_real(x) for x in (-0.0, 0.0, -1.5, -1e-300)] == ["0.0", "0.0", "-1.5", "-1.0E-300"]  # no "-0.0"
    with pytest.raises(ExportError):
        st_real(float("inf"))
    with pytest.raises(ExportError, match="prefix"):
        format_table_st(load_table(), prefix="1BAD")


# ---------------------------------------------------------------------------------------------- JSON


def test_json_table(shipped):
    text = format_table_json(shipped, "TEST")
    doc = json.loads(text)
    assert doc["format"] == "pickplace-table/1" and doc["eta"] == 0.5 and doc["weights"] == [0.5, 0.5]
    assert doc["columns"] == ["lambda", "k1", "k2", "a_max", "j_max", "v_max", "F", "a_min", "j_min"]
    for c in doc["columns"]:
        assert doc["rows"][c] == shipped.column(c).tolist()  # exact doubles
    assert doc["units"]["lambda"] == "-" and doc["units"]["a_max"] == "m/s^2"
    g1, g2, res = shipped.fit(5.0)
    assert doc["fit"]["k1"] == g1.tolist() and doc["fit"]["max_residual"] == res
    assert doc["provenance"]["source"] == "bspline-eta0.5.csv (shipped)" and doc["provenance"]["exported_by"] == "pickplace TEST"
    assert text == format_table_json(shipped, "TEST") and text.endswith("}\n")
    buf = io.StringIO()
    write_table_json(shipped, buf, "TEST")
    assert buf.getvalue() == text
    # the rows read back give the same look-up as the table
    back = Table(tuple(TableRow(*vals) for vals in zip(*(doc["rows"][c] for c in doc["columns"]))), meta={"eta": doc["eta"]})
    assert back.lookup(12.2) == shipped.lookup(12.2)
