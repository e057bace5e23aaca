"""Part types on a line (``parts.types``, per-robot ``places``), each checked against an independent computation:

* the generator's types against the binomial distribution of the declared shares (a 4-sigma bound and scipy's
  exact binomial test, below), and every other number of the parts the same as a line without types draws;
* per-type counts summed equal the line's totals, and a robot only ever takes the types it has a place for;
* a two-type line where the upstream robot takes only type A, traced by hand: who takes each part, and which place
  (tray slot / outgoing belt point, worked out from the file in the line frame) each part goes to;
* the per-type intervals against scipy's Wilson interval and a batch-means ratio estimator written out here;
* a line whose only type is declared takes the very same parts, at the same times, as the line without types.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy import stats

from pickplace_cli.line.engine import LineEngine
from pickplace_cli.line.parts import Detection, generate
from pickplace_cli.line.spec import parse_line
from pickplace_cli.model.profile import load_profile

PROFILE = load_profile()
TWO = """\
belt: {speed: 0.5, width: 0.3, direction: +y}
robots:
  - name: u
    base: [0.6, 0.0, 0.8]
    window: [0.4, 0.8]
    places:
      A: {tray: {origin: [0.55, 0.35, 0.0], rows: 2, columns: 2, pitch: [0.05, 0.05]}}
  - name: w
    base: [1.4, 0.0, 0.8]
    window: [1.2, 1.6]
    places:
      A: {tray: {origin: [1.35, 0.35, 0.0], rows: 2, columns: 2, pitch: [0.05, 0.05]}}
      B: {belt: {point: [1.4, -0.35, 0.0], velocity: [0.2, 0.0]}}
parts:
  generate: {rate: 4.0, count: 120, seed: 3}
  types: {A: {share: 0.6}, B: {share: 0.4}}
  latency: 0.05
"""


def _engine(text: str) -> LineEngine:
    line = parse_line(text, "l.yaml")
    return LineEngine(line, {r.name: PROFILE for r in line.robots})


# ------------------------------------------------------------------------------------------- the generator


def test_generated_types_follow_the_shares_binomially():
    """N = 20000 parts with shares 0.6 / 0.3 / 0.1: each type's count is Binomial(N, p). For seed 11 every count
    lies within 4 standard deviations of N·p (a correct generator misses that bound with probability ~6e-5 per
    type) and scipy's exact two-sided binomial test gives p > 1e-3; the parts' times, positions and angles are
    exactly those of the same generator without types (the types are drawn last)."""
    text = TWO.replace("count: 120, seed: 3", "count: 20000, seed: 11, angles: true").replace(
        "types: {A: {share: 0.6}, B: {share: 0.4}}", "types: {A: {share: 0.6}, B: {share: 0.3}, C: {share: 0.1}}")
    line = parse_line(text.replace("B: {belt", "C: {belt"), "l.yaml")
    typed = generate(line.parts.generate, line.belt.width, line.parts.types)
    plain = generate(line.parts.generate, line.belt.width)
    n = len(typed)
    assert n == 20000
    for name, p in (("A", 0.6), ("B", 0.3), ("C", 0.1)):
        k = sum(d.type == name for d in typed)
        assert abs(k - n * p) <= 4 * math.sqrt(n * p * (1 - p)), (name, k)
        assert stats.binomtest(k, n, p).pvalue > 1e-3, (name, k)
    assert [(d.t, d.along, d.across, d.angle, d.id) for d in typed] == \
        [(d.t, d.along, d.across, d.angle, d.id) for d in plain]
    assert all(d.type is None for d in plain)
    again = generate(line.parts.generate, line.belt.width, line.parts.types)
    assert [d.type for d in again] == [d.type for d in typed]  # seeded: the same types again


def test_a_zero_share_type_is_never_drawn():
    line = parse_line(TWO.replace("A: {share: 0.6}, B: {share: 0.4}", "A: {share: 0.0}, B: {share: 1.0}"), "l.yaml")
    assert {d.type for d in generate(line.parts.generate, line.belt.width, line.parts.types)} == {"B"}


# ---------------------------------------------------------------------------------------------- the run


@pytest.fixture(scope="module")
def two():
    eng = _engine(TWO)
    for d in generate(eng.line.parts.generate, eng.line.belt.width, eng.line.parts.types):
        eng.offer(d)
    return eng, eng.finish()


def test_per_type_counts_add_up_to_the_totals(two):
    eng, s = two
    assert [t.name for t in s.types] == ["A", "B"]
    assert sum(t.parts for t in s.types) == s.parts == 120
    assert sum(t.picked for t in s.types) == s.picked
    assert sum(t.missed for t in s.types) == s.missed
    # rates: the line's parts/min split by the counts (1e-9: the same products in another order)
    assert sum(t.picks_per_minute for t in s.types) == pytest.approx(s.picks_per_minute, rel=1e-9)
    for t in s.types:
        mine = [r for r in eng.results if r.detection.type == t.name]
        assert t.parts == len(mine) and t.picked == sum(r.picked for r in mine)
    for rs, run in zip(s.robots, eng.runs):  # each robot's picks by type: its own count of the results
        assert rs.type_picks == {k: sum(r.robot == rs.name and r.detection.type == k for r in eng.results)
                                 for k in ("A", "B")}
        assert sum(rs.type_picks.values()) == rs.picks
    assert s.robots[0].as_dict()["picks_by_type"] == {"A": s.robots[0].picks, "B": 0}
    doc = s.as_dict()["types"]
    assert doc["A"]["parts"] + doc["B"]["parts"] == 120 and doc["A"]["share"] == 0.6


def test_a_robot_takes_only_the_types_it_has_a_place_for(two):
    eng, s = two
    by = {}
    for r in eng.results:
        if r.picked:
            by.setdefault(r.robot, set()).add(r.detection.type)
    assert by["u"] == {"A"} and by["w"] == {"A", "B"}
    for r in eng.results:
        if r.detection.type == "B":
            assert r.declines.get("u") == "takes no parts of type B (no place for them)"


def _slot(origin, pitch, columns, k):
    i, j = divmod(k, columns)
    return np.array([origin[0] + i * pitch[0], origin[1] + j * pitch[1], origin[2]])


def test_each_type_goes_to_its_own_place_with_its_own_tray_counter(two):
    """Every part of type A that w takes goes to w's tray slot n mod 4 (n: the A parts w took before it, slots row by
    row from the file's origin and pitch), whatever B parts w placed in between; every B part goes to the outgoing
    belt's point. Line frame, 1e-12 m (one frame transform and back)."""
    eng, _ = two
    w = next(run for run in eng.runs if run.robot.name == "w")
    frame = w.robot.frame
    n_a = 0
    seen_b = False
    for r in eng.results:
        if r.robot != "w":
            continue
        at = frame.to_line(r.cycle.place_point)
        if r.detection.type == "A":
            want = _slot((1.35, 0.35, 0.0), (0.05, 0.05), 2, n_a % 4)
            n_a += 1
            assert r.cycle.target == (n_a - 1) % 4
        else:
            seen_b = True
            # an outgoing belt: the release starts at the point (the place move arrives there)
            want = np.array([1.4, -0.35, 0.0])
        assert np.abs(at - want).max() < 1e-12, (r.detection.id, at, want)
    assert n_a > 4 and seen_b  # the tray went round and B parts came between


def test_hand_traced_small_scenario():
    """Five parts, traced by hand. Robots idle and parts 3 s apart (a cycle is under 1 s): upstream_first asks u
    then w; u takes no B. So part 1 (A) → u, part 2 (B) → w (u left out for its type), part 3 (A) → u. Then two A
    parts seen 0.01 s apart, part 4 0.1 m before u's window, part 5 0.1 m into it: u takes part 4, and is free again
    only when part 5 has passed its last meeting point (worked out below from u's free time), so u declines it as
    busy and w, idle, takes it."""
    eng = _engine(TWO)
    parts = [("1", 0.0, 0.0, "A"), ("2", 3.0, 0.0, "B"), ("3", 6.0, 0.0, "A"), ("4", 9.0, 0.3, "A"),
             ("5", 9.01, 0.5, "A")]
    got = [eng.offer(Detection(i, t, al, 0.0, None, k + 1, kind)) for k, (i, t, al, kind) in enumerate(parts)]
    assert [g.robot for g in got] == ["u", "w", "u", "u", "w"]
    assert got[1].declines["u"] == "takes no parts of type B (no place for them)"
    assert "busy until" in got[4].declines["u"]
    # where part 5 is when u is free again: past u's last meeting point (window end less the tracking)
    u = eng.robots[0]
    assert 0.5 + 0.5 * (got[3].cycle.t_free - 9.01) > u.window[1] - 0.5 * u.dwell
    s = eng.finish()
    assert [(t.name, t.parts, t.picked) for t in s.types] == [("A", 4, 4), ("B", 1, 1)]


def test_a_robot_whose_first_place_never_took_a_part_reports_its_limits():
    """w takes only B parts here (its A place never plans a leg): its peak use of every limit comes from its B
    cycles all the same (one profile: the same limits), none missing. B's place is a fixed point here, so no stop
    leg (planned by the robot's first place) checks a leg either."""
    eng = _engine(TWO.replace("B: {belt: {point: [1.4, -0.35, 0.0], velocity: [0.2, 0.0]}}",
                              "B: {points: [[1.4, -0.35, 0.0]]}"))
    for k, t in enumerate((0.0, 3.0, 6.0)):
        assert eng.offer(Detection(str(k), t, 0.0, 0.0, None, k + 1, "B")).robot == "w"
    s = eng.finish()
    w = s.robots[1]
    assert eng.runs[1].robot.use_keys == []  # its first place (A) never checked a leg
    assert w.picks == 3 and len(w.peak_use) == len(eng.runs[1].instances[1].use_keys) > 0


# ----------------------------------------------------------------------------------------- the intervals


def _batch_means_by_hand(t, missed, B):
    t0, t1 = min(t), max(t)
    w = (t1 - t0) / B
    n_i, m_i = [0] * B, [0] * B
    for ti, mi in zip(t, missed):
        k = min(int((ti - t0) / w), B - 1)
        n_i[k] += 1
        m_i[k] += int(mi)
    R = sum(m_i) / sum(n_i)
    se = math.sqrt(sum((m - R * n) ** 2 for m, n in zip(m_i, n_i)) / (B * (B - 1))) / (sum(n_i) / B)
    return R, stats.t.ppf(0.975, B - 1) * se


def test_per_type_intervals_are_wilson_and_batch_means_of_the_type(two):
    """Wilson equals scipy's (binomtest(...).proportion_ci(method="wilson"), 1e-12); the batch-means half-width is
    the ratio estimator over the type's own windows computed here (1e-12)."""
    eng, s = two
    for ts in s.types:
        rows = [(r.detection.t, not r.picked) for r in eng.results if r.detection.type == ts.name]
        k, n = sum(m for _, m in rows), len(rows)
        ci = stats.binomtest(k, n).proportion_ci(0.95, method="wilson")
        iv = ts.intervals
        assert iv.miss_wilson.low == pytest.approx(ci.low, abs=1e-12)
        assert iv.miss_wilson.high == pytest.approx(ci.high, abs=1e-12)
        B = min(20, n // 10)
        assert iv.batches == B
        R, half = _batch_means_by_hand([x[0] for x in rows], [x[1] for x in rows], B)
        assert iv.miss.estimate == pytest.approx(R, abs=1e-12)
        assert iv.miss.high - iv.miss.estimate == pytest.approx(half, abs=1e-12) or iv.miss.high == 1.0
        assert iv.picks_per_minute.estimate == pytest.approx(ts.picks_per_minute, rel=1e-12)


# ----------------------------------------------------------------------------------------- one kind of part


def test_one_declared_type_takes_the_same_parts_as_no_types():
    """The line of the engine tests' kind without types, and with one type of share 1 that every robot takes:
    the same robot for every part, the same meeting times (exactly: the same computation)."""
    plain = TWO.replace("""    places:
      A: {tray: {origin: [0.55, 0.35, 0.0], rows: 2, columns: 2, pitch: [0.05, 0.05]}}
""", "    place: {tray: {origin: [0.55, 0.35, 0.0], rows: 2, columns: 2, pitch: [0.05, 0.05]}}\n").replace("""    places:
      A: {tray: {origin: [1.35, 0.35, 0.0], rows: 2, columns: 2, pitch: [0.05, 0.05]}}
      B: {belt: {point: [1.4, -0.35, 0.0], velocity: [0.2, 0.0]}}
""", "    place: {tray: {origin: [1.35, 0.35, 0.0], rows: 2, columns: 2, pitch: [0.05, 0.05]}}\n").replace(
        "count: 120", "count: 40")
    untyped = plain.replace("  types: {A: {share: 0.6}, B: {share: 0.4}}\n", "")
    one = plain.replace("types: {A: {share: 0.6}, B: {share: 0.4}}", "types: {only: {share: 1.0}}")
    out = []
    for text in (untyped, one):
        eng = _engine(text)
        res = [eng.offer(d) for d in generate(eng.line.parts.generate, eng.line.belt.width, eng.line.parts.types)]
        out.append([(r.robot, r.cycle.t_meet if r.cycle else None, r.cycle.t_free if r.cycle else None) for r in res])
        s = eng.finish()
        assert (s.types is None) is (text is untyped)
    assert out[0] == out[1]


def test_shares_within_1e9_of_one_are_accepted_and_beyond_refused():
    from pickplace_cli.model.errors import ProfileError

    ok = TWO.replace("B: {share: 0.4}", "B: {share: 0.4000000005}")  # 5e-10 off
    assert parse_line(ok, "l.yaml").parts.types["B"].share == 0.4000000005
    with pytest.raises(ProfileError, match=r"add up to 1.000000002: they must add up to 1 \(within 1e-09\)"):
        parse_line(TWO.replace("B: {share: 0.4}", "B: {share: 0.400000002}"), "l.yaml")


def test_detections_read_their_type():
    from pickplace_cli.line.parts import BadRow, read_detections
    from pickplace_cli.model.errors import TaskError

    rows = list(read_detections(["id,type,t[s],along[m],across[m]\n", "p1,B,0.5,0,0\n", "p2,,0.6,0,0\n",
                                 "p3,b,0.7,0,0\n"], "d.csv", ["A", "B"]))
    assert rows[0] == Detection("p1", 0.5, 0.0, 0.0, None, 1, "B")
    assert isinstance(rows[1], BadRow) and rows[1].error == ("row 2 (d.csv:3): type = '': not a part type of the "
                                                             "line file (parts.types: A, B)")
    assert isinstance(rows[2], BadRow) and "type = 'b'" in rows[2].error  # names are case-sensitive
    with pytest.raises(TaskError, match="missing column 'type'"):
        list(read_detections(["t,along,across\n", "0,0,0\n"], "d.csv", ["A"]))
    with pytest.raises(TaskError, match="column 'type': the line file declares no part types"):
        list(read_detections(["t,along,across,type\n", "0,0,0,A\n"], "d.csv"))


@pytest.mark.parametrize("spec, takes, want_ask, want_out", [
    # upstream_first: every robot, less those without a place for the type
    ({"kind": "upstream_first"}, {1, 2}, [1, 2], {0}),
    # skip (skip = 2): part 1 is robot 0's; it takes no B: with pass_on the robots downstream of it are asked
    ({"kind": "skip", "skip": 2}, {1, 2}, [1, 2], {0}),
    # ... without pass_on the part is robot 0's alone: nobody is asked
    ({"kind": "skip", "skip": 2, "pass_on": False}, {1, 2}, [], {0, 1, 2}),
    # quota: robot 2 is at its share (set below), robot 0 takes no B: robot 1 alone
    ({"kind": "quota"}, {1, 2}, [1], {0, 2}),
])
def test_strategies_leave_out_the_robots_without_the_type(spec, takes, want_ask, want_out):
    from pickplace_cli.line.spec import Quota, Skip, UpstreamFirst
    from pickplace_cli.line.strategies import Sharing

    kind = {"upstream_first": UpstreamFirst, "skip": Skip, "quota": Quota}[spec["kind"]]
    s = Sharing(kind(**spec), 3, [(-0.15, -0.05), (-0.05, 0.05), (0.05, 0.15)])
    if spec["kind"] == "quota":
        s.picks = [0, 0, 1]  # n = 1: robot 2's share 1/3 · 1 is reached
    ask, out = s.order(0.0, 1, takes, "B")
    assert ask == want_ask and set(out) == want_out
    assert out[0] == "takes no parts of type B (no place for them)"
