"""What to do when a plan is not written: the fix that works, named for the limit that failed."""

from __future__ import annotations

import math
from dataclasses import replace


def holding_time(plan, profile, options) -> float | None:
    """The duration [s] of ``--time limits`` for the move of ``plan`` (the same task and options), rounded up to
    0.1 ms so that the number shown holds too (every limit of a fixed path holds at every longer duration); None
    when it cannot be planned (e.g. a conveyor move, whose path depends on the duration)."""
    from ..model.errors import PickplaceError
    from ..planner import plan as run_plan

    try:
        found = run_plan(plan.task, profile, replace(options, time="limits", shape=False, fit=False))
    except PickplaceError:
        return None
    if not found.report.ok:
        return None
    return math.ceil(found.duration.seconds * 1e4 - 1e-6) / 1e4


def not_written(plans: list, profile, options, code: int, table: dict | None = None) -> str:
    """The one line after a plan whose verdict stops the trajectory: what was not written and the fix that works
    (``code`` 3: a timed limit; 4: a position past a joint's range, the singularity margin or the workcell box).
    ``table``: what the summary says of a drive's table, when one was judged (``cli.controller.table_info``: its
    ``moving_ends`` and ``table_end``)."""
    from ..timing import parse_time

    options = replace(options, time=parse_time(options.time))
    bad = [r for p in plans for r in p.report.violations]
    moving = (table or {}).get("moving_ends") if (table or {}).get("table_end") == "hold" else None
    if code == 4 or any(r.kind == "reach" for r in bad):
        return ("trajectory not written: a position is past a joint's range, the singularity margin or the workcell box "
                "(exit 4), which no duration fixes: lower --height, move the pick or place point, or --fit-workspace "
                "(lowers the height until the path fits)")
    if not bad and any(p.report.unresolved for p in plans):  # plan --strict: a peak the samples do not resolve
        return ("trajectory not written (--strict: a peak is not resolved by the written samples): a higher --rate "
                "resolves it; --write-anyway writes it as it is")
    if not bad and moving:  # a table that ends (starts) moving: the drive's step to (from) rest, whatever the duration
        from .controller import moving_cause

        return f"table not written: {moving_cause(moving)}; --write-anyway writes it as it is"
    if not bad:  # the trajectory holds: the drive's table broke a limit (its verdict above), which no trajectory duration
        # computed here is known to fix (a table's steps need not fall steadily as the move slows)
        return ("table not written: the table breaks a limit as the drive interpolates it (its verdict above), while "
                "the trajectory holds; a longer --time, a lower --limit-use, another table format or a shorter "
                "--cycle may hold; --write-anyway writes it as it is")
    headroom = any(r.target < 1.0 and r.utilisation <= 1.0 for r in bad)
    extra = "; or a larger --limit-use (the ratings allow it)" if headroom else ""
    if options.time in ("fit", "optimal", "limits"):
        return f"trajectory not written (a limit is exceeded){extra}; --write-anyway writes it as it is"
    failing = next((p for p in plans if not p.report.ok), plans[0])
    t = holding_time(failing, profile, options) if failing.method != "bspline-vel" else None
    given = "the duration given" if not isinstance(options.time, str) else f"--time {options.time}"
    if t is None:
        return (f"trajectory not written: {given} breaks a limit; --time limits holds every limit{extra}; "
                "--write-anyway writes it as it is")
    return (f"trajectory not written: {given} breaks a limit; --time {t:.4f} or --time limits holds every "
            f"limit{extra}; --write-anyway writes it as it is")
