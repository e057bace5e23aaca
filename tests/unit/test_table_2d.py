"""lookup/table2d.py: the (λ, η) → (k1, k2) table (issue 16): grids, jumps, lookup, file format, the shipped table,
its interpolation error at seeded held-out points, the build (tiny grids only), the ST export (blark)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from pickplace_cli.lookup import bspline_build as B
from pickplace_cli.lookup import bspline_optimum as O
from pickplace_cli.lookup import table2d as T2
from pickplace_cli.model.errors import TableError
from pickplace_cli.export.table2d_st import format_table_2d_st


def _row(lam, k1, k2):  # peaks and F are not used by the look-up: placeholders (a table file holds finite values)
    return O.TableRow(lam, k1, k2, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0)


def _synthetic(k1_of=lambda e, lam: 0.3 + 0.1 * e + 0.001 * lam, k2_of=lambda e, lam: 0.1 + 0.05 * e):
    etas, lams = (0.2, 0.4, 0.6), (1.0, 2.0, 4.0, 8.0)
    rows = tuple(_row(lam, k1_of(e, lam), k2_of(e, lam)) for e in etas for lam in lams)
    return T2.Table2D(etas, lams, rows, {"method": "bspline"})


def test_grids():
    assert T2.eta_grid(0.1, 0.9, 0.05).tolist() == pytest.approx(np.arange(0.1, 0.9001, 0.05).tolist(), abs=1e-12)
    assert T2.eta_grid(0.4, 0.4, 0.05).tolist() == [0.4]
    assert T2.parse_eta_list("0.1, 0.3,0.5").tolist() == [0.1, 0.3, 0.5]
    g = T2.log_lambda_grid(0.5, 200, 40)
    assert len(g) == 40 and g[0] == 0.5 and g[-1] == 200 and np.allclose(np.diff(np.log(g)), math.log(400) / 39, rtol=1e-8)
    assert T2.log_lambda_grid(28, 28, 1).tolist() == [28.0]
    assert B.lambda_grid(28, 28, 0.5).tolist() == [28.0]  # the one-row grid is a grid (issue 16)
    for bad, match in (((0.9, 0.1, 0.05), "eta-max = 0.1: must not be less than eta-min = 0.9"),
                       ((0.0, 0.5, 0.05), r"eta-min = 0.0: must lie in \[0.01, 0.99\]"),
                       ((0.1, 0.5, 0.0), "eta-step = 0.0: must be a finite number > 0")):
        with pytest.raises(TableError, match=match):
            T2.eta_grid(*bad)
    with pytest.raises(TableError, match="eta-list = '0.3,0.2': the values must increase strictly"):
        T2.parse_eta_list("0.3,0.2")
    with pytest.raises(TableError, match="eta-list: 1.5: every η must lie in"):
        T2.parse_eta_list("0.2,1.5")
    with pytest.raises(TableError, match="lambda-points = 1: need 1 for lambda-min = lambda-max"):
        T2.log_lambda_grid(1, 2, 1)


def test_bilinear_lookup_is_exact_on_a_bilinear_table():
    """k linear in η and λ separately (a bilinear function): the lookup reproduces it (tolerance 1e-12,
    round-off of the two linear steps)."""
    t = _synthetic()
    for lam, eta in ((1.0, 0.2), (3.3, 0.25), (8.0, 0.6), (5.5, 0.51)):
        k1, k2 = t.lookup(lam, eta)
        assert k1 == pytest.approx(0.3 + 0.1 * eta + 0.001 * lam, abs=1e-12)
        assert k2 == pytest.approx(0.1 + 0.05 * eta, abs=1e-12)
    with pytest.raises(TableError, match=r"outside the 2-D table's grid \[1, 8\] x \[0.2, 0.6\]"):
        t.lookup(0.5, 0.3)
    assert t.jumps == []


def test_a_jump_is_found_and_never_interpolated_across():
    """k2 steps by 0.5 between λ = 2 and 4 at η = 0.4 and 0.6: the two cells on each side of those edges
    refuse to interpolate (TableJumpError), the cells away from them still interpolate."""
    t = _synthetic(k2_of=lambda e, lam: 0.7 if (e >= 0.4 and lam >= 4) else 0.2)
    # listed by their lower end, η first then λ
    assert [(ax, a, b) for ax, a, b in t.jumps] == [("eta", (4.0, 0.2), (4.0, 0.4)), ("eta", (8.0, 0.2), (8.0, 0.4)),
                                                    ("lambda", (2.0, 0.4), (4.0, 0.4)), ("lambda", (2.0, 0.6), (4.0, 0.6))]
    with pytest.raises(T2.TableJumpError, match="jumps between basins"):
        t.lookup(3.0, 0.5)
    with pytest.raises(T2.TableJumpError):
        t.lookup(6.0, 0.3)
    assert t.lookup(1.5, 0.5) == pytest.approx((0.3 + 0.05 + 0.0015, 0.2), abs=1e-12)
    text = T2.format_table_2d(t, "TEST")
    assert "# basin_jumps: (4, 0.2)-(4, 0.4); (8, 0.2)-(8, 0.4); (2, 0.4)-(4, 0.4); (2, 0.6)-(4, 0.6)" in text


def test_csv_round_trip_and_bad_files():
    t = _synthetic()
    back = T2.parse_table_2d(T2.format_table_2d(t, "TEST"), "t.csv")
    assert back.etas == t.etas and back.lams == t.lams
    assert np.array_equal(back.grid("k1"), np.round(t.grid("k1"), 10))
    text = T2.format_table_2d(t, "TEST")
    lines = text.splitlines()
    with pytest.raises(TableError, match=r"t.csv: \(eta, lambda\) = \(0.6, 8\) is missing"):
        T2.parse_table_2d("\n".join(lines[:-1]), "t.csv")
    with pytest.raises(TableError, match=r"t.csv:\d+: \(eta, lambda\) = \(0.6, 8\) appears twice"):
        T2.parse_table_2d("\n".join(lines + lines[-1:]), "t.csv")
    bad = text.replace(lines[-1], lines[-1].replace(lines[-1].split(",")[3], "1.5", 1))
    with pytest.raises(TableError, match=r"t.csv:\d+: k2 = 1.5: must lie strictly between 0 and 1"):
        T2.parse_table_2d(bad, "t.csv")


@pytest.fixture(scope="module")
def shipped():
    return T2.load_table_2d()


def test_shipped_table_covers_the_issue_range(shipped):
    assert shipped.etas[0] == pytest.approx(0.1) and shipped.etas[-1] == pytest.approx(0.9)
    assert shipped.lams[0] == 0.5 and shipped.lams[-1] >= 200
    assert shipped.source == "bspline-2d.csv (shipped)"
    # the η = 0.5 row of the 2-D table is the optimiser's answer at those λ (same settings as the 1-D table)
    i = shipped.etas.index(0.5)
    lam = shipped.lams[20]
    s = O.TableSettings(eta=0.5)
    want = O.optimise_lambda(lam, O._coarse_for(s), s)
    # the file keeps λ to 10 significant digits, so the optimiser here starts from a λ ~1e-9 away and its
    # Nelder-Mead stops elsewhere within its xatol (refine_xatol = 1e-5): k within 2e-5, F within 1e-8 relative
    assert shipped.grid("k1")[i, 20] == pytest.approx(want.k1, abs=2e-5)
    assert shipped.grid("k2")[i, 20] == pytest.approx(want.k2, abs=2e-5)
    assert shipped.grid("F")[i, 20] == pytest.approx(want.F, rel=1e-8)


def test_interpolated_F_within_half_a_percent_at_seeded_points(shipped):
    """F at the table's (k1, k2) vs the optimiser's F at 6 seeded held-out (λ, η) (bench/bench_table2d.py does
    240 and reports the distribution): within 0.5 %, the issue's bound. F of both with the optimiser's
    normalisers a_min, j_min and exact peaks. Points in a jump cell are planned on demand: skipped here."""
    rng = np.random.default_rng(7)
    checked = 0
    for lam, eta in zip(np.exp(rng.uniform(math.log(2.0), math.log(200.0), 8)), rng.uniform(0.25, 0.9, 8)):
        try:
            k1, k2 = shipped.lookup(float(lam), float(eta))
        except T2.TableJumpError:
            continue
        s = O.TableSettings(eta=float(eta), grid_step=O.ON_DEMAND_GRID)
        ref = O.optimise_lambda(float(lam), O._coarse_for(s), s)
        _, a, j = O.fast_peaks(k1, k2, float(lam), float(eta))[0]
        f = 0.5 * ref.a_min / a + 0.5 * ref.j_min / j
        assert f >= ref.F * (1 - 0.005), (lam, eta)
        checked += 1
    assert checked >= 6


def _f_at(k1, k2, lam, eta):
    """(F at (k1, k2), the optimiser's F*) at (λ, η): both with the optimiser's normalisers and exact peaks."""
    s = O.TableSettings(eta=eta)
    ref = O.optimise_lambda(lam, O._coarse_for(s), s)
    _, a, j = O.fast_peaks(k1, k2, lam, eta)[0]
    return 0.5 * ref.a_min / a + 0.5 * ref.j_min / j, ref.F


@pytest.mark.parametrize("lam, eta", [(0.65975842, 0.128225863), (1.613827064, 0.562098434), (1.30405091, 0.650445439)])
def test_tall_moves_are_polished_to_within_half_a_percent(shipped, lam, eta):
    """The three held-out points of bench_table2d (seed 20240616) where bilinear interpolation alone loses > 0.5 %
    of F (1.32 %, 0.78 %, 0.52 %; all λ < 2): the polish of ``lookup_polished`` brings each within 0.05 %."""
    k1, k2 = shipped.lookup(lam, eta)
    f_raw, f_ref = _f_at(k1, k2, lam, eta)
    assert f_raw < f_ref * (1 - 0.005)  # the interpolation alone misses (this test would pass without a polish else)
    p1, p2, polished = shipped.lookup_polished(lam, eta)
    assert polished
    f, _ = _f_at(p1, p2, lam, eta)
    assert f >= f_ref * (1 - 5e-4)


def test_no_polish_for_flat_moves(shipped):
    assert shipped.lookup_polished(12.2, 0.4) == (*shipped.lookup(12.2, 0.4), False)


def test_a_jump_cell_takes_the_best_basin(shipped):
    """(λ 1.2615, η 0.1260) lies in a jump cell; the on-demand solve alone (start grid 0.025) lands in the basin
    k2 → 1 and loses 1.65 % of F (bench_table2d seed 7); the best of it and the corners' basins is within 0.05 %."""
    lam, eta = 1.26149927, 0.126046661
    with pytest.raises(T2.TableJumpError):
        shipped.lookup(lam, eta)
    k1, k2, _ = O.solve_on_demand(lam, eta)
    k1, k2 = shipped.best_in_cell(lam, eta, others=[(k1, k2)])
    f, f_ref = _f_at(k1, k2, lam, eta)
    assert f >= f_ref * (1 - 5e-4)


def test_tiny_2d_build_parallel_equals_sequential_and_resumes(tmp_path):
    lams, etas = [2.0, 3.0], [0.3, 0.5]
    seq, rep = T2.run_build_2d(lams, etas)
    assert rep.rows == 4 and rep.computed == 4
    row = seq.rows[2]  # η = 0.5, λ = 2: the same as the 1-D build's row
    assert row == B.build_table([2.0, 3.0]).rows[0]
    ckpt = tmp_path / "t.csv.partial.jsonl"
    par, _ = T2.run_build_2d(lams, etas, workers=2, checkpoint=ckpt)
    assert par.rows == seq.rows
    again, rep2 = T2.run_build_2d(lams, etas, checkpoint=ckpt, resume=True)
    assert rep2.resumed == 4 and rep2.computed == 0 and again.rows == seq.rows
    with pytest.raises(TableError, match="written for other settings"):
        T2.run_build_2d(lams, etas, O.TableSettings(grid_step=0.02), checkpoint=ckpt, resume=True)


# ------------------------------------------------------------------------------------ Structured Text


def test_st_2d_parses_with_blark_and_interpolates_like_lookup():
    """The 2-D ST look-up of a 3 η × 4 λ table with a jump: blark parses it; the FUNCTION, run by the test
    interpreter of test_export_table (extended to 2-D subscripts and BOOL), gives Table2D.lookup's values
    (tolerance 1e-12: another order of the same bilinear operations) and FALSE in a jump cell / outside."""
    pytest.importorskip("blark")
    from tests.unit.test_export_table import ST

    class ST2(ST):
        def init_value(self, init):
            tf = self.tf
            if isinstance(init, tf.ArrayTypeInitialization):
                subs = init.spec.subranges
                bounds = [(int(str(s.start.value)), int(str(s.stop.value))) for s in subs]
                values = list(self.flatten(init.value))
                shape = [hi - lo + 1 for lo, hi in bounds]
                assert len(values) == int(np.prod(shape))
                if len(bounds) == 1:
                    return {bounds[0][0] + i: v for i, v in enumerate(values)}
                return {(bounds[0][0] + i // shape[1], bounds[1][0] + i % shape[1]): v for i, v in enumerate(values)}
            return self.eval(init.value, {})

        def eval(self, e, env):
            tf = self.tf
            if isinstance(e, tf.MultiElementVariable):
                arr = self.globals[str(e.name.name)]
                (subs,) = e.elements
                idx = tuple(self.eval(i, env) for i in subs.subscripts)
                return arr[idx[0] if len(idx) == 1 else idx]
            if str(e) in ("TRUE", "FALSE"):
                return str(e) == "TRUE"
            return super().eval(e, env)

    t = _synthetic(k2_of=lambda e, lam: 0.7 if (e >= 0.6 and lam >= 8) else 0.2 + 0.01 * lam)
    st = ST2(format_table_2d_st(t, "TEST"))
    assert st.globals["PP_TABLE2D_NETA"] == 3 and st.globals["PP_TABLE2D_NLAMBDA"] == 4
    for lam, eta in ((1.0, 0.2), (3.3, 0.25), (5.0, 0.3), (1.5, 0.5), (8.0, 0.2)):
        ok, out = st.call("F_PickplaceK2D", fLambda=lam, fEta=eta)
        assert ok is True, (lam, eta)
        k1, k2 = t.lookup(lam, eta)
        assert abs(out["fK1"] - k1) < 1e-12 and abs(out["fK2"] - k2) < 1e-12
    ok, out = st.call("F_PickplaceK2D", fLambda=6.0, fEta=0.5)  # the cell with the jump: nearest node
    assert ok is False and (out["fK1"], out["fK2"]) == (t.grid("k1")[2, 3], t.grid("k2")[2, 3])
    ok, out = st.call("F_PickplaceK2D", fLambda=20.0, fEta=0.3)  # outside: clamped to the nearest node
    assert ok is False and out["fK1"] == t.grid("k1")[0, 3]


def test_shipped_jumps_are_never_interpolated_across(shipped):
    """Every basin jump of the shipped table (listed in its header): a point just off the middle of the jump edge,
    on either side of it, lies in a cell that is not interpolated (TableJumpError; plan solves it on demand)."""
    jumps = shipped.jumps
    assert jumps, "the shipped grid crosses basins at small λ and η (README)"
    lams, etas = shipped.lams, shipped.etas
    for axis, (lam_a, eta_a), (lam_b, eta_b) in jumps:
        lam_m, eta_m = 0.5 * (lam_a + lam_b), 0.5 * (eta_a + eta_b)
        il, ie = lams.index(lam_a), etas.index(eta_a)
        if axis == "lambda":  # the edge runs along λ at η = eta_a: the cells below and above it in η
            sides = [(lam_m, e) for e in (0.5 * (etas[ie - 1] + eta_a) if ie else None,
                                          0.5 * (eta_a + etas[ie + 1]) if ie + 1 < len(etas) else None) if e is not None]
        else:  # along η at λ = lam_a: the cells left and right of it in λ
            sides = [(x, eta_m) for x in (0.5 * (lams[il - 1] + lam_a) if il else None,
                                          0.5 * (lam_a + lams[il + 1]) if il + 1 < len(lams) else None) if x is not None]
        assert sides
        for lam, eta in sides:
            with pytest.raises(T2.TableJumpError):
                shipped.lookup(lam, eta)


def test_plan_in_a_jump_cell_is_solved_on_demand_and_says_so():
    from pickplace_cli.model.profile import load_profile
    from pickplace_cli.model.task import Task
    from pickplace_cli.planner import PlanOptions, plan

    # λ = 0.305 / 0.2 = 1.525, η = 0.12: the cell (λ 1.466 … 1.709, η 0.1 … 0.15) holds a jump of k2 (0 → 0.92)
    p = plan(Task([-0.1525, 0, -0.8], [0.1525, 0, -0.8], 0.2, 0.12), load_profile("delta-su2018"), PlanOptions())
    assert p.parameters["k_source"].startswith("(λ, η) in a cell of 2-D table bspline-2d.csv (shipped) across a basin jump")
    assert "solved on demand and from each corner's basin" in p.parameters["k_source"]
