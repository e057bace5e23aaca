"""Strategies against hand-worked cases: the sharing rules alone (line/strategies.py), then whole small lines whose
parts are far enough apart (or close enough) that who takes which part follows from the rule by hand."""

from __future__ import annotations

import numpy as np
import pytest

from pickplace_cli.line.engine import LineEngine
from pickplace_cli.line.parts import Detection
from pickplace_cli.line.spec import Bands, Quota, Skip, UpstreamFirst, parse_line
from pickplace_cli.line.strategies import Sharing
from pickplace_cli.model.profile import load_profile

PROFILE = load_profile()


def _walk(sharing: Sharing, across: list[float], can) -> list:
    """Who takes each part: the first robot asked that ``can(i, n)``; None when missed."""
    out = []
    for n, x in enumerate(across, 1):
        ask, left = sharing.order(x, n)
        who = next((i for i in ask if can(i, n)), None)
        if who is None:
            sharing.missed(left)
        else:
            sharing.picked(who)
        out.append(who)
    return out


def test_quota_shares_hand_worked():
    """shares 0.25/0.75, both robots always able: part n goes to robot i while picks_i < share_i · n
    (n = 1: r1 0 < 0.25; 2: r1 1 < 0.5 no, r2; 3: r1 1 < 0.75 no, r2; 4: r1 1 < 1 no, r2; 5: r1 1 < 1.25)."""
    s = Sharing(Quota(kind="quota", shares=[0.25, 0.75]), 2, [(-1, 0), (0, 1)])
    assert _walk(s, [0.0] * 8, lambda i, n: True) == [0, 1, 1, 1, 0, 1, 1, 1]


def test_quota_feedback_hand_worked():
    """shares 0.5/0.5, robot 2 can take nothing: part 1 → r1; part 2: r1 over its share (1 < 1 no), r2 cannot:
    missed; with feedback r1 (passed on for its share) gets one more pick, so part 3 (1 < 1.5 + 1) → r1 and
    part 4 (2 < 2 + 1) → r1. Without feedback part 4 is missed (2 < 2 no)."""
    def can(i, n):
        return i == 0

    plain = Sharing(Quota(kind="quota", shares=[0.5, 0.5]), 2, [(-1, 0), (0, 1)])
    assert _walk(plain, [0.0] * 4, can) == [0, None, 0, None]
    fed = Sharing(Quota(kind="quota", shares=[0.5, 0.5], feedback=True), 2, [(-1, 0), (0, 1)])
    assert _walk(fed, [0.0] * 4, can) == [0, None, 0, 0]
    assert fed.credit == [1, 0]  # one part (2) was missed after r1 passed it on for its share


def test_skip_hand_worked():
    s = Sharing(Skip(kind="skip"), 3, [(-1, 0)] * 3)  # default skip = robots − 1: round robin
    assert _walk(s, [0.0] * 6, lambda i, n: True) == [0, 1, 2, 0, 1, 2]
    s = Sharing(Skip(kind="skip", skip=3), 3, [(-1, 0)] * 3)  # every 4th part is for no robot
    assert _walk(s, [0.0] * 8, lambda i, n: True) == [0, 1, 2, None, 0, 1, 2, None]
    # robot 1 cannot take part 1: passed on to the robots downstream of it (robot 2 takes it); without pass_on: missed
    s = Sharing(Skip(kind="skip", skip=1), 2, [(-1, 0)] * 2)
    assert _walk(s, [0.0] * 2, lambda i, n: not (i == 0 and n == 1)) == [1, 1]
    s = Sharing(Skip(kind="skip", skip=1, pass_on=False), 2, [(-1, 0)] * 2)
    assert _walk(s, [0.0] * 2, lambda i, n: not (i == 0 and n == 1)) == [None, 1]


def test_bands_hand_worked():
    bands = [(-0.15, 0.0), (0.0, 0.15)]
    s = Sharing(Bands(kind="bands"), 2, bands)
    assert _walk(s, [-0.1, 0.1, 0.0, 0.15, 0.2], lambda i, n: True) == [0, 1, 1, 1, None]
    # overlap 0.01: a part 0.005 m into r2's band is r2's, then r1's when r2 cannot take it
    s = Sharing(Bands(kind="bands", overlap=0.01), 2, bands)
    assert s.order(0.005, 1)[0] == [1, 0]
    assert _walk(s, [0.005, 0.02], lambda i, n: i == 0) == [0, None]


# ------------------------------------------------------------------------------------------- whole lines

LINE = """\
belt: {speed: 0.5, width: 0.3}
robots:
  - name: r1
    base: [0.6, 0.0, 0.8]
    window: [0.4, 0.8]
    place: {points: [[0.6, 0.35, 0.0]]}
  - name: r2
    base: [1.4, 0.0, 0.8]
    window: [1.2, 1.6]
    place: {points: [[1.4, 0.35, 0.0]]}
parts: {latency: 0.05}
"""


def _run(strategy: str, parts: list[tuple[float, float]]) -> list:
    line = parse_line(LINE + f"strategy: {strategy}\n", "l.yaml")
    eng = LineEngine(line, {r.name: PROFILE for r in line.robots})
    return [eng.offer(Detection(str(k), t, 0.0, x, None, k)).robot for k, (t, x) in enumerate(parts, 1)]


APART = [(3.0 * k, x) for k, x in enumerate([-0.1, 0.1, -0.05, 0.05, 0.0])]  # 3 s apart: every robot is free


@pytest.mark.parametrize("strategy, expected", [
    ("{kind: upstream_first}", ["r1"] * 5),
    ("{kind: quota}", ["r1", "r2", "r1", "r2", "r1"]),
    ("{kind: quota, shares: [0.25, 0.75]}", ["r1", "r2", "r2", "r2", "r1"]),
    ("{kind: skip}", ["r1", "r2", "r1", "r2", "r1"]),
    ("{kind: bands}", ["r1", "r2", "r1", "r2", "r2"]),
])
def test_strategies_on_a_line_with_free_robots(strategy, expected):
    """Parts 3 s apart (a cycle here takes < 1 s): who takes which follows from the rule alone."""
    assert _run(strategy, APART) == expected


def test_a_busy_upstream_robot_passes_the_next_part_on_and_a_claim_limit_does_too():
    """Two parts 0.05 s apart at the same place: r1 takes the first; its cycle (two 0.1 s dwells and two moves)
    ends after the second part has left a 0.12 m window: with window [0.4, 0.52] r2 takes the second. With the long
    window r1 takes both (it meets the second about 0.2 m in); with claim 0.05 m it may not: r2 takes it."""
    two = [(0.0, 0.0), (0.05, 0.0)]
    assert _run("{kind: upstream_first}", two) == ["r1", "r1"]
    assert _run("{kind: upstream_first, claim: 0.05}", two) == ["r1", "r2"]
    short = LINE.replace("window: [0.4, 0.8]", "window: [0.4, 0.52]")
    line = parse_line(short + "strategy: {kind: upstream_first}\n", "l.yaml")
    eng = LineEngine(line, {r.name: PROFILE for r in line.robots})
    got = [eng.offer(Detection(str(k), t, 0.0, x, None, k)) for k, (t, x) in enumerate(two, 1)]
    assert [g.robot for g in got] == ["r1", "r2"]
    assert "r1: busy until t = " in got[1].declines["r1"]
