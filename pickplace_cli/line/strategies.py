"""How a line shares its parts out: which robots are asked for a part, in which order.

Every strategy answers, for the n-th part (n = 1, 2, …), the robots to ask in turn (upstream first unless said
otherwise) and the robots it leaves out with the reason. The first robot asked that can take the part in time
(:meth:`~pickplace_cli.line.robot.LineRobot.plan`) takes it; a part no robot takes is missed. Robots are indexed
from upstream (0) to downstream.

* ``upstream_first`` — every robot is asked, upstream first ("all targets considered").
* ``quota`` — robot i is asked while its picks are below share_i · n (+ its feedback credit): each robot takes its
  share of the flow, the rest passes on. With ``feedback``, a part that leaves the line unpicked after a robot
  passed it on because of its share gives that robot (the most upstream such) one more pick.
* ``bands`` — robot i is asked for the parts whose ``across`` lies in its band [low, high) (the last band closed);
  with an ``overlap`` tolerance the robots whose band is within that distance are asked after it, upstream first.
* ``skip`` — the n-th part is robot k's with k = (n − 1) mod (skip + 1): each robot takes one part and lets
  ``skip`` pass; with ``pass_on`` a part its robot cannot take is offered to the robots downstream of it.

**Part types.** On a line with several part types a robot takes only the types it has a place for: every strategy
makes its choice as above, and the robots that do not take the part's type are then left out of it (the reason
says so). Under ``skip`` a part whose robot does not take its type goes on to the robots downstream of it with
``pass_on`` and is missed without; under ``quota`` the shares stay shares of all parts.
"""

from __future__ import annotations

from enum import Enum
from typing import Callable


class StrategyName(str, Enum):
    upstream_first = "upstream_first"
    quota = "quota"
    bands = "bands"
    skip = "skip"


class Sharing:
    """The state of a strategy over a run: ``order(across, n)`` → (robots to ask, {robot: reason left out}),
    ``picked(i)`` when robot i takes a part, ``missed(left_out)`` when no robot does."""

    def __init__(self, spec, n_robots: int, bands: list[tuple[float, float]]) -> None:
        self.spec, self.n = spec, n_robots
        self.bands = bands
        self.picks = [0] * n_robots
        self.credit = [0] * n_robots
        shares = getattr(spec, "shares", None)
        self.shares = [float(s) for s in shares] if shares is not None else [1.0 / n_robots] * n_robots
        skip = getattr(spec, "skip", None)
        self.skip = int(n_robots - 1 if skip is None else skip)

    def order(self, across: float, n: int, takes: set | None = None,
              kind: str | None = None) -> tuple[list[int], dict[int, str]]:
        """(robots to ask in turn, {robot: reason left out}) for the n-th part at ``across`` [m]; ``takes``: the
        robots that take its type ``kind`` (None: every robot)."""
        ask, out = _ORDER[StrategyName(self.spec.kind)](self, across, n)
        if takes is None:
            return ask, out
        for i in ask:
            if i not in takes:
                out[i] = f"takes no parts of type {kind} (no place for them)"
        return [i for i in ask if i in takes], out

    def picked(self, i: int) -> None:
        self.picks[i] += 1

    def missed(self, left_out: dict[int, str]) -> None:
        if getattr(self.spec, "feedback", False):
            quota = sorted(i for i, why in left_out.items() if why.startswith("share"))
            if quota:
                self.credit[quota[0]] += 1


def _upstream_first(s: Sharing, across: float, n: int):
    return list(range(s.n)), {}


def _quota(s: Sharing, across: float, n: int):
    ask, out = [], {}
    for i in range(s.n):
        allowance = s.shares[i] * n + s.credit[i]
        if s.picks[i] < allowance - 1e-9:
            ask.append(i)
        else:
            out[i] = (f"share reached ({s.picks[i]} picks of {s.shares[i]:g} × {n} parts"
                      + (f" + {s.credit[i]} feedback" if s.credit[i] else "") + ")")
    return ask, out


def _bands(s: Sharing, across: float, n: int):
    tol = float(getattr(s.spec, "overlap", 0.0))
    own, near, out = [], [], {}
    top = max(hi for _, hi in s.bands)
    for i, (lo, hi) in enumerate(s.bands):
        inside = lo <= across < hi or across == hi == top  # [low, high); the highest band is closed
        if inside:
            own.append(i)
        elif lo - tol <= across <= hi + tol:
            near.append(i)
        else:
            out[i] = f"outside its band [{lo:g}, {hi:g}] m (across {across:.4f} m)"
    return own + near, out


def _skip(s: Sharing, across: float, n: int):
    k = (n - 1) % (s.skip + 1)
    if k >= s.n:
        return [], {i: f"skip: part {n} is for no robot ((n − 1) mod {s.skip + 1} = {k})" for i in range(s.n)}
    ask = [k] + (list(range(k + 1, s.n)) if getattr(s.spec, "pass_on", True) else [])
    out = {i: f"skip: part {n} is robot {k + 1}'s" for i in range(s.n) if i not in ask}
    return ask, out


_ORDER: dict[StrategyName, Callable] = {
    StrategyName.upstream_first: _upstream_first,
    StrategyName.quota: _quota,
    StrategyName.bands: _bands,
    StrategyName.skip: _skip,
}
