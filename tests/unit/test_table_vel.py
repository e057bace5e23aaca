"""table_vel.py: the bspline-vel table over the dimensionless groups (build, symmetry fill, I/O, lookup)
and the shipped table (provenance, a rebuilt sample, accuracy against the exact solve)."""

from __future__ import annotations

import time

import numpy as np
import pytest

from pickplace_cli.errors import TableError
from pickplace_cli.methods import bspline_vel as bv
from pickplace_cli.table_vel import (
    GROUP_AXES,
    VelGrid,
    build_vel_table,
    default_vel_table_path,
    format_vel_table,
    load_vel_table,
    parse_vel_table,
    reverse_params,
)
from pickplace_cli.task import Task

SMALL = VelGrid(h_min=0.1, h_max=0.3, h_count=2, v_max=0.2, v_count=2)


@pytest.fixture(scope="module")
def small():
    return build_vel_table(SMALL, workers=1)


def _node_task(grid, idx, b=0.3, T=0.25):
    axes = grid.axes()
    g = {k: float(axes[i][j]) for i, (k, j) in enumerate(zip(GROUP_AXES, idx))}
    g["eta"] = grid.eta
    return bv.task_from_groups(g, b=b, duration=T), T


def test_symmetry_fill_equals_direct_solves(small):
    """Nodes filled by symmetry (mirror, reversal) hold the optimum a direct exact solve finds there
    (parameters 1e-6, F 1e-8: the optimiser's tolerance); only one node per orbit was solved."""
    assert small.meta["solved_nodes"] == 12 and small.meta["nodes"] == 32  # 2 × 6 orbits of 16 velocity nodes
    for idx in [(0, 0, 1, 1, 0), (1, 1, 0, 0, 1), (1, 1, 1, 1, 1), (0, 1, 1, 0, 0)]:
        task, T = _node_task(SMALL, idx)
        res = bv.solve(bv.make_problem(task, T))
        np.testing.assert_allclose(small.params[idx], res.params, atol=1e-6)
        assert small.F[idx] == pytest.approx(res.F, abs=1e-8)


def test_reverse_params_is_an_involution():
    p = (0.02, 0.2, 0.7, 0.95, 0.1, 0.4, 0.8)
    assert reverse_params(reverse_params(p)) == pytest.approx(p, abs=1e-15)
    assert reverse_params(p) == pytest.approx((0.05, 0.3, 0.8, 0.98, 0.8, 0.4, 0.1), abs=1e-15)


def test_format_parse_round_trip_and_lookup_at_nodes(small):
    text = format_vel_table(small, "test")
    assert text.count("\n") < 20 + small.meta["solved_nodes"] + 5  # one row per orbit
    back = parse_vel_table(text, "mem")
    np.testing.assert_allclose(back.params, small.params, rtol=1e-8, atol=1e-9)  # 9 significant digits
    np.testing.assert_allclose(back.F, small.F, rtol=1e-8)
    task, T = _node_task(SMALL, (1, 0, 1, 1, 0), b=0.42, T=0.3)
    np.testing.assert_allclose(back.lookup(task, T), small.params[(1, 0, 1, 1, 0)], atol=1e-8)
    # between nodes: the multilinear blend of the cell's corners (midpoint of the h/b axis in log scale)
    mid = dict(zip(GROUP_AXES, [float(np.sqrt(0.1 * 0.3)), -0.2, 0.2, 0.2, -0.2]), eta=0.5)
    want = (small.params[0, 0, 1, 1, 0] + small.params[1, 0, 1, 1, 0]) / 2
    np.testing.assert_allclose(back.lookup(bv.task_from_groups(mid), 1.0), want, atol=1e-8)


def test_build_is_the_same_on_a_process_pool():
    grid = VelGrid(h_min=0.2, h_max=0.4, h_count=2, v_max=0.1, v_count=2)
    seen = []
    one = build_vel_table(grid, workers=1)
    two = build_vel_table(grid, workers=2, progress=lambda d, t: seen.append((d, t)), chunk=2)
    np.testing.assert_array_equal(one.params, two.params)
    assert seen and seen[-1][0] == seen[-1][1] == one.meta["solved_nodes"]


@pytest.mark.parametrize(
    "edit,match",
    [
        (lambda s: s.replace("# method: bspline-vel\n", ""), "not a bspline-vel table"),
        (lambda s: s.replace("# v_count: 2\n", ""), "v_count"),
        (lambda s: s.replace("h_over_b,v0_along", "hb,v0_along"), "header must be"),
        (lambda s: s.rsplit("\n", 2)[0] + "\n", "no row"),
        (lambda s: s.replace("0.1,-0.2,-0.2,-0.2,-0.2,", "0.1,-0.2,-0.2,-0.2,x,"), "not a number"),
        (lambda s: s.replace("0.1,-0.2,-0.2,-0.2,-0.2,", "0.1,-0.2,-0.2,-0.2,-0.15,"), "not a value of the grid"),
    ],
)
def test_corrupt_tables_are_one_line_errors(small, edit, match):
    with pytest.raises(TableError, match=match):
        parse_vel_table(edit(format_vel_table(small, "test")), "bad.csv")


def test_lookup_refuses_what_the_table_does_not_cover(small):
    ok, T = _node_task(SMALL, (0, 1, 0, 1, 1))
    with pytest.raises(TableError, match="eta = 0.4"):
        small.lookup(Task(ok.p_from, ok.p_to, ok.height, 0.4, ok.v_from, ok.v_to), T)
    with pytest.raises(TableError, match="heights differ"):
        small.lookup(Task(ok.p_from, ok.p_to + [0, 0, 0.01], ok.height, 0.5, ok.v_from, ok.v_to), T)
    with pytest.raises(TableError, match="vertical"):
        small.lookup(Task(ok.p_from, ok.p_to, ok.height, 0.5, ok.v_from + [0, 0, 0.1], ok.v_to), T)
    with pytest.raises(TableError, match="outside the table's range"):
        small.lookup(Task(ok.p_from, ok.p_to, ok.height, 0.5, ok.v_from * 2, ok.v_to), T)
    with pytest.raises(TableError, match="no such file"):
        load_vel_table("/nonexistent/vel.csv")


# ------------------------------------------------------------------------------------ the shipped table


@pytest.fixture(scope="module")
def shipped():
    return load_vel_table()


def test_shipped_table_provenance(shipped):
    text = default_vel_table_path().read_text(encoding="utf-8")
    for key in ("# method: bspline-vel", "# eta: 0.5", "# margin: 0.01", "# tool_version:", "# solver:", "# units:"):
        assert key in text
    assert shipped.grid == VelGrid()


def test_shipped_table_sample_rebuilds(shipped):
    """Three shipped nodes re-solved now give the shipped optimum (parameters 1e-5, F 1e-7: 9 digits
    written, optimiser tolerance)."""
    for idx in [(0, 4, 0, 2, 3), (3, 1, 2, 3, 1), (6, 2, 4, 0, 2)]:
        task, T = _node_task(shipped.grid, idx)
        res = bv.solve(bv.make_problem(task, T), bv.VelSettings(margin=shipped.grid.margin))
        np.testing.assert_allclose(shipped.params[idx], res.params, atol=1e-5)
        assert shipped.F[idx] == pytest.approx(res.F, abs=1e-7)


HELD_OUT = 12


def _held_out(n, seed=77):
    rng = np.random.default_rng(seed)
    for _ in range(n):
        hb = float(np.exp(rng.uniform(np.log(0.025), np.log(1.0))))
        v = rng.uniform(-0.5, 0.5, 4)
        g = dict(h_over_b=hb, eta=0.5, v0_along=v[0], v0_across=v[1], v1_along=v[2], v1_across=v[3])
        T = float(rng.uniform(0.15, 0.4))
        yield bv.task_from_groups(g, b=float(rng.uniform(0.1, 0.5)), duration=T), T


@pytest.mark.slow
def test_seeded_solve_is_exact_and_the_table_alone_is_approximate(shipped):
    """Held-out moves (random groups, not nodes). The seeded solver (table answer polished by the exact
    stages, one run each) is a local search; on this set it reaches the multi-start's optimum or a better
    one on every move (F ≥ multi-start F − 1e-8, common normalisers; README reports a move elsewhere where
    it does not, hence "exact" takes the better of both). The table's answer alone is instant but
    approximate: its F loss against the exact optimum is below 1 % only on part of the set (the optimum
    is a minimax point that moves fast with the groups; README): the test pins today's accuracy, median
    loss under 5 %."""
    losses = []
    for task, T in _held_out(HELD_OUT):
        prob = bv.make_problem(task, T)
        glob = bv.solve(prob)
        seeded = bv.optimum(task, T, "seeded")[1]
        A, J = min(glob.a_min, seeded.a_min), min(glob.j_min, seeded.j_min)
        assert A / seeded.a_max + J / seeded.j_max >= A / glob.a_max + J / glob.j_max - 1e-8
        _, a, j = bv.exact_peaks(prob, shipped.lookup(task, T))
        losses.append(1 - (A / a + J / j) / (A / seeded.a_max + J / seeded.j_max))
    assert np.median(losses) < 0.05 and min(losses) >= -1e-9


def test_table_answer_is_fast(shipped):
    """Table answer (groups, cell, interpolation) in well under 1 ms (median of 200; generous for CI)."""
    task, T = next(_held_out(1))
    shipped.lookup(task, T)
    times = []
    for _ in range(200):
        t0 = time.perf_counter()
        shipped.lookup(task, T)
        times.append(time.perf_counter() - t0)
    assert np.median(times) < 1e-3
