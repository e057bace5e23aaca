"""The fast CSV number printer (export/fastfloat.py) prints exactly what ``%.12g`` / ``%d`` print."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra import numpy as hnp

from pickplace_cli.export import fastfloat
from pickplace_cli.export.csv import format_rows


def _reference(data: np.ndarray, int_columns: int, sep: str = ",", newline: str = "\n") -> str:
    m = data.shape[1]
    row = sep.join(["%d"] * int_columns + ["%.12g"] * (m - int_columns)) + newline
    return "".join(row % tuple(r) for r in (np.asarray(data, dtype=float) + 0.0).tolist())


def test_fast_printer_is_active_and_passes_its_probe():
    assert fastfloat.format_block(np.zeros((1, 1))) == "0\n"  # orjson is a dependency: the fast path is on
    assert fastfloat._state["ok"] is True
    probe = fastfloat._probe_array()
    assert fastfloat.format_block(probe, 1) == _reference(probe, 1)


@pytest.mark.parametrize("value, text", [
    (0.0, "0"), (-0.0, "0"), (1.0, "1"), (-2.5, "-2.5"), (1e-4, "0.0001"), (9.99999999999e-5, "9.99999999999e-05"),
    (9.9999999999995e-5, "0.0001"), (999999999999.4, "999999999999"), (999999999999.6, "1e+12"),
    (123456789012.0, "123456789012"), (0.1 + 0.2, "0.3"), (1 / 3, "0.333333333333"), (1e-7, "1e-07"),
    (float("nan"), "nan"), (float("inf"), "inf"), (float("-inf"), "-inf"), (5e-324, "4.94065645841e-324"),
])
def test_edge_values(value, text):
    assert fastfloat.format_block(np.array([[value]])) == text + "\n"
    assert text == "%.12g" % (value + 0.0)


def test_integer_columns():
    data = np.array([[1.0, 0.5], [12.0, -1e-9], [1e13, 3.0], [-4.0, 1e20]])
    assert fastfloat.format_block(data, 1) == _reference(data, 1) == "1,0.5\n12,-1e-09\n10000000000000,3\n-4,1e+20\n"


_floats = st.one_of(
    st.floats(allow_nan=True, allow_infinity=True),
    st.floats(min_value=-1e13, max_value=1e13),
    st.floats(min_value=-1e-3, max_value=1e-3),
    st.integers(-10**6, 10**6).map(float),
    st.tuples(st.integers(-10**12, 10**12), st.integers(0, 16)).map(lambda t: t[0] / 10.0 ** t[1]),  # ties, short decimals
)


@settings(max_examples=300, deadline=None, derandomize=True)
@given(hnp.arrays(np.float64, hnp.array_shapes(min_dims=2, max_dims=2, min_side=1, max_side=12), elements=_floats))
def test_random_arrays_print_as_percent(data):
    assert fastfloat.format_block(data) == _reference(data, 0)


def test_random_magnitudes_many():
    rng = np.random.default_rng(7)
    for _ in range(50):
        data = rng.standard_normal((40, 9)) * 10.0 ** rng.integers(-9, 15, (40, 9))
        data[rng.random(data.shape) < 0.2] = 0.0
        assert fastfloat.format_block(data) == _reference(data, 0)


@pytest.mark.parametrize("sep, newline", [(",", "\n"), (";", "\r\n"), ("\t", "\n")])
def test_format_rows_same_text_with_and_without_the_fast_printer(monkeypatch, sep, newline):
    rng = np.random.default_rng(3)
    data = np.hstack([np.arange(1, 31, dtype=float)[:, None], rng.standard_normal((30, 6)) * 10.0 ** rng.integers(-6, 4, (30, 6))])
    fast = format_rows(data, sep, newline, 1)
    monkeypatch.setitem(fastfloat._state, "ok", False)
    assert fastfloat.format_block(data, 1) is None
    slow = format_rows(data, sep, newline, 1)
    assert fast == slow == _reference(data, 1, sep, newline)


def test_not_a_table_is_left_to_percent():
    assert fastfloat.format_block(np.zeros((0, 3))) == ""
    assert fastfloat.format_block(np.zeros(3)) is None
    assert fastfloat.format_block(np.zeros((2, 2)), int_columns=3) is None
    assert format_rows(np.zeros((0, 3))) == ""
