"""Options in the wrong unit: a value that is a valid number in SI units but was meant in another (ms, mm, kHz).

Rules (each one line on stderr; a refusal exits 1 before any work):

* ``--from``/``--to`` [m]: refused when the point lies outside the profile's workcell box (a gantry: its travel; no
  box: farther than 10 m) and the same numbers in millimetres lie inside: ``-152.5,0,-800`` (a point that is out
  of reach either way; the message names the unit and the point in metres).
* ``--height`` [m]: refused when it is more than the workcell box is tall (a gantry: its z travel; no box: 2 m) and
  the same number in millimetres is not: ``--height 25`` (the path would leave the box anyway).
* ``--time`` [s]: a warning from 10 s on (``--time 180``: milliseconds meant? a 180 s move at 1 kHz is 180,001
  samples): a slow move can be meant (commissioning at low speed) and is planned as asked.
* ``--rate`` [Hz]: a warning when a move gets fewer than :data:`FEW_SAMPLES` samples (``--rate 10`` for a 0.18 s
  move: 3): the file is a correct sampling, but a drive that interpolates it follows another motion; a preview at a
  low rate can be meant. Without ``--rate`` (the profile's rate) the warning names the short move, not a rate.
"""

from __future__ import annotations

import sys

#: a move sampled with fewer samples than this gets a warning
FEW_SAMPLES = 10
#: a given duration from this on [s] gets a warning
LONG_MOVE_S = 10.0
def check_option_units(a, prof) -> None:
    """TaskError (exit 1) for ``--from``/``--to``/``--height`` in millimetres (module docstring); a warning for a
    ``--time`` of 10 s or more."""
    from ..model.errors import TaskError
    from ..model.plausible import millimetre_height, millimetre_point
    from .app import _parse_pose

    for name, text in (("from", a.from_), ("to", a.to)):
        if text is None:
            continue
        p, _ = _parse_pose(name, text)  # X,Y,Z or X,Y,Z,THETA (the tool angle: not a length)
        found = millimetre_point(p, prof)
        if found is not None:
            mm, where = found
            raise TaskError(f"{name} = {text}: {where} of profile {prof.name}: millimetres meant? in metres: "
                            f"--{name} {','.join(f'{c:g}' for c in mm)} (coordinates are in m)")
    if a.height is not None:
        tall = millimetre_height(a.height, prof)
        if tall is not None:
            raise TaskError(f"height = {a.height:g} m: more than the workcell of profile {prof.name} is tall "
                            f"({tall:g} m): millimetres meant? --height {a.height / 1000:g} (the height is in m)")
    try:
        seconds = float(a.time)
    except (TypeError, ValueError):
        return
    if seconds >= LONG_MOVE_S:
        sys.stderr.write(f"pickplace: warning: --time {seconds:g}: a {seconds:g} s move; milliseconds meant? "
                         f"--time {seconds / 1000:g} (the duration is in s)\n")


def refuse_unreadable(legs, options, rate, cycle: float | None = None, named: str = "--cycle") -> None:
    """TaskError (exit 1) when a move within its limits would be written as samples (a CSV or MCAP trajectory, not a
    drive's table: ``options.read_written``) in fewer than the samples ``check`` reads a move from: plan would say
    every limit holds of a file check refuses. The message names the rate (or the cycle) and the least that works.
    (The library's :func:`~pickplace_cli.planner.plan` returns such a plan: it writes no file.)"""
    import math

    from ..model.errors import TaskError
    from ..timing.written import MIN_SAMPLES

    if not options.read_written:
        return
    for leg in legs:
        n, T = len(leg.t), float(leg.report.duration)
        if n >= MIN_SAMPLES or not leg.report.ok:  # (a move past a limit: its verdict is the answer, nothing is written)
            continue
        why = (f"fewer than the {MIN_SAMPLES} check reads a move from (a quintic spline): the file could not be "
               "checked")
        if cycle is not None:
            raise TaskError(f"{named} {cycle:g} s: {n} samples (one per cycle) for a {T:.4g} s move, {why}; a cycle of "
                            f"{T / (MIN_SAMPLES - 1):.3g} s or less, or a drive's table (-f pvt, cam)")
        need = f"{math.ceil((MIN_SAMPLES - 1) / T * 1.001):g}"
        given = f"--rate {rate:g} Hz" if rate is not None else "the profile's planning.rate"
        raise TaskError(f"{given}: {n} samples for a {T:.4g} s move, {why}; --rate {need} Hz or more, or a drive's "
                        "table (-f pvt, cam)")


def warn_few_samples(legs, rate, cycle: float | None = None, named: str = "--cycle") -> None:
    """A warning when a planned move has fewer than :data:`FEW_SAMPLES` samples (module docstring); on a controller
    ``cycle`` [s] the samples are one per cycle, and the warning names the cycle (``named``: where it was given)."""
    for leg in legs:
        n = len(leg.t)
        if n < FEW_SAMPLES:
            if cycle is not None:
                sys.stderr.write(f"pickplace: warning: {named} {cycle:g} s: {n} samples (one per cycle) for a "
                                 f"{leg.report.duration:.4g} s move (a drive interpolating them follows another "
                                 f"motion); milliseconds meant? {cycle / 1000:g} s (the cycle is in s)\n")
                return
            if rate is None:  # the profile's rate: the move is what is short, not a rate the user gave
                sys.stderr.write(f"pickplace: warning: a {leg.report.duration:.4g} s move: {n} samples at the "
                                 "profile's planning.rate (a drive interpolating them follows another motion); the "
                                 "duration is in s\n")
                return
            sys.stderr.write(f"pickplace: warning: --rate {rate:g} Hz: {n} samples for a {leg.report.duration:.4g} s "
                             f"move (a drive interpolating them follows another motion); kHz meant? --rate "
                             f"{rate * 1000:g} (the rate is in Hz)\n")
            return
