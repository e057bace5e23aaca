"""The verdict engine's replay of plan()'s first samples (pickplace_cli.pipelines.verdict_fit) against the functions it
replays, bitwise: the path evaluator of plan_bspline, the check grid of check_grid_order, the model on that grid, the
RMS integrals of MotionModel.rms_integrals. Bitwise (np.array_equal), because the engine's JSON lines must be
plan()'s byte for byte: fit_s is a function of every one of these numbers."""

from __future__ import annotations

import functools

import numpy as np
import pytest

from pickplace_cli.limits.grid import check_grid_order, span_nodes
from pickplace_cli.model.profile import load_profile, parse_profile
from pickplace_cli.model.task import Task
from pickplace_cli.model.trajectory import CartesianTrajectory
from pickplace_cli.paths import plan_path
from pickplace_cli.paths.bspline import batch_paths
from pickplace_cli.pipelines.verdict_fit import FirstSamples, Pieces, model_at, rms_integrals, take_moves
from pickplace_cli.planner import motion_model
from pickplace_cli.timing import choose_duration

DELTA = load_profile("delta-su2018")


@functools.cache
def scara():
    """scara-600's robot, limits and planning defaults (its controller block left out: the engine never reads it)."""
    from pathlib import Path

    import pickplace_cli

    text = (Path(pickplace_cli.__file__).resolve().parent.parent / "profiles" / "scara-600.yaml").read_text()
    return parse_profile(text.split("\ncontroller:")[0] + "\n", "scara-600.yaml")


def delta_moves(n: int, seed: int) -> list[Task]:
    rng = np.random.default_rng(seed)
    out = []
    for _ in range(n):
        r, a = rng.uniform(0.02, 0.2), rng.uniform(0, 2 * np.pi)
        z0, z1 = rng.uniform(-0.85, -0.75, 2)
        if rng.random() < 0.4:
            z1 = z0  # one height: the closed-form symmetric path
        out.append(Task([-r * np.cos(a), -r * np.sin(a), z0], [r * np.cos(a), r * np.sin(a), z1],
                        float(rng.uniform(0.01, 0.06)), 0.5))
    return out


def planned(tasks, profile, params=None):
    """Each move's path as plan() plans it, and the engine's Pieces of the same moves (batch_paths, as the engine)."""
    paths = [plan_path(t, "bspline", **(params or {})) for t in tasks]
    k1 = np.array([p.parameters["k1"] for p in paths])
    k2 = np.array([p.parameters["k2"] for p in paths])
    via = np.stack([t.via_points() - t.p_from for t in tasks])
    breaks, coef, _ = batch_paths(k1, k2, via)
    return paths, Pieces(breaks, coef, via, np.stack([t.p_from for t in tasks]))


@pytest.mark.parametrize("params", [None, {"k1": 0.05, "k2": 0.5}, {"k1": 0.4, "k2": 0.13}])
def test_pieces_evaluate_every_path_bitwise_as_the_planned_path(params):
    # table k's (closed forms), k1 = 0.05 (outside the closed forms: the de Boor route) and a given pair
    tasks = delta_moves(40, seed=1)
    paths, pieces = planned(tasks, DELTA, params)
    rng = np.random.default_rng(2)
    taus = [np.sort(np.concatenate([[0.0, 1.0], rng.uniform(0, 1, 50), p.breakpoints])) for p in paths]
    move = np.repeat(np.arange(len(tasks)), [len(t) for t in taus])
    got = pieces.all_orders(np.concatenate(taus), move)
    at = 0
    for p, tau in zip(paths, taus):
        ref = p.all_orders(tau)
        for order in range(4):
            assert np.array_equal(got[order][at : at + len(tau)], ref[order])
        at += len(tau)


@pytest.mark.parametrize("rate", [1000.0, 250.0, 4000.0])
def test_first_samples_are_plan_s_check_grid_and_rms_start(rate):
    # short moves (output samples sparser than the check's uniform grid: it is added) and long ones (left out)
    tasks = delta_moves(30, seed=3)
    paths, pieces = planned(tasks, DELTA)
    taus = []
    for p, scale in zip(paths, np.linspace(0.3, 3.0, len(paths))):
        T = choose_duration(p, DELTA.capacity, "auto").seconds * scale
        taus.append(CartesianTrajectory(p, T).sample_times(rate) / T)
    first = FirstSamples(taus, pieces.breaks)
    starts = np.concatenate([[0], np.cumsum(first.lengths)])
    for k, (p, tau) in enumerate(zip(paths, taus)):
        grid, order = check_grid_order(tau, p.breakpoints, p.jumps)
        mine = first.grid[starts[k] : starts[k + 1]]
        assert np.array_equal(mine, grid[order])
        # every Gauss–Kronrod node's grid point, as the model's first round finds it (nearest, within 1e-9)
        nodes = span_nodes(p.breakpoints, p.jumps)[1]
        spans = np.flatnonzero(first.span_owner == k)
        assert np.array_equal(np.concatenate([first.a[spans], [1.0]]), span_nodes(p.breakpoints, p.jumps)[0])
        at = first.node_at.reshape(-1, 15)[spans].ravel()
        i = np.minimum(np.maximum(np.searchsorted(mine, nodes), 1), len(mine) - 1)
        i = np.where(np.abs(mine[i - 1] - nodes) < np.abs(mine[i] - nodes), i - 1, i)
        assert np.array_equal(at, i)
        assert first.nodes_ok[k] == (np.abs(mine[i] - nodes).max() <= 1e-9)


@pytest.mark.parametrize("which", ["delta", "scara"])
def test_model_and_rms_integrals_on_the_first_samples_are_plan_s(which):
    prof = DELTA if which == "delta" else scara()
    if which == "delta":
        tasks = delta_moves(25, seed=5)
    else:
        rng = np.random.default_rng(5)
        tasks = []
        for _ in range(25):
            r0, r1 = rng.uniform(0.25, 0.55, 2)
            a0, a1 = rng.uniform(-1.0, 1.0, 2)
            tasks.append(Task([r0 * np.cos(a0), r0 * np.sin(a0), -0.15], [r1 * np.cos(a1), r1 * np.sin(a1), -0.12],
                              0.025, 0.5))
    paths, pieces = planned(tasks, prof)
    Ts = [choose_duration(p, prof.capacity, "auto").seconds for p in paths]
    taus = [CartesianTrajectory(p, T).sample_times(prof.planning.rate) / T for p, T in zip(paths, Ts)]
    first = FirstSamples(taus, pieces.breaks)
    model = motion_model(paths[0], prof)
    idx = np.arange(len(paths))
    parts, keep = model_at(model, pieces, first.grid, np.repeat(idx, first.lengths), first.lengths)
    assert keep.all()
    starts = np.concatenate([[0], np.cumsum(first.lengths)])
    integrals, ends = rms_integrals(first, idx, parts, starts, model, pieces, idx, lambda j: motion_model(paths[j], prof))
    more_rounds = 0
    for k, (p, tau) in enumerate(zip(paths, taus)):
        own = motion_model(p, prof)
        grid, order = check_grid_order(tau, p.breakpoints, p.jumps)
        ref = own.parts(grid, order=order).sorted()  # plan()'s first samples, sorted as its fit screens them
        for name in ("tau", "p", "q", "qd1", "qdd1", "qddd1", "A", "G", "Am", "Gm", "dAm", "dGm", "singularity"):
            assert np.array_equal(getattr(parts, name)[starts[k] : starts[k + 1]], getattr(ref, name)), name
        calls = []
        torques = own._torques
        own._torques = lambda *a, **kw: calls.append(1) or torques(*a, **kw)  # the quadrature's further rounds
        i_ref, g_ref = own.rms_integrals(ref)
        more_rounds += bool(calls)
        assert np.array_equal(integrals[k], i_ref) and np.array_equal(ends[k], g_ref)
    assert more_rounds >= 2  # (moves whose quadrature needs more than the first round are among them)
    # a subset of the moves (as the engine keeps those clear of every limit)
    sub, sub_starts = take_moves(parts, starts, np.array([1, 4, 7]))
    assert np.array_equal(sub.Am, np.concatenate([parts.Am[starts[k] : starts[k + 1]] for k in (1, 4, 7)]))
    assert np.array_equal(sub_starts, np.concatenate([[0], np.cumsum(first.lengths[[1, 4, 7]])]))


def test_model_at_leaves_out_moves_with_an_unreachable_point():
    tasks = delta_moves(3, seed=6)
    tasks[1] = Task([0.0, 0.0, -0.8], [0.1, 0.0, -0.3], 0.025, 0.5)  # z = −0.3 m: above the arms' reach
    paths, pieces = planned(tasks, DELTA)
    taus = [np.linspace(0, 1, 50)] * 3
    model = motion_model(paths[0], DELTA)
    parts, keep = model_at(model, pieces, np.concatenate(taus), np.repeat(np.arange(3), 50), np.full(3, 50))
    assert keep.tolist() == [True, False, True] and len(parts.tau) == 100
