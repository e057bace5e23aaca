"""``--optimize shape --time optimal``: the chosen shape's time law with and without the SQP's smoothing term, the
shorter as written kept.

The smoothing term (``law_sqp.SQP_SMOOTH``) keeps a time-optimal law from following its binding rows with wiggles a
few knots wide, which a reader of the written samples sees as torque-rate peaks (``law_sqp``'s notes); it costs
0.1-0.7 % of the duration. Once the shape is chosen (seconds of search), two more law solves cost little, so the
plan is made twice: with the term (the shipped law) and without it, the latter read back as ``check --strict``
reads it (every peak resolved by the samples, the law slowed until it is: a law without the term must not leave
the file's peaks undecided). The shorter plan that holds every limit as written is kept; the law's note says which.
On the Adept cycle with 120 law coefficients the law without the term is kept: 1.0096 × the free-path minimum with
the capacity held (1.0103 × with the term), 1.0087 × with the motors alone (1.0095 ×),
``python bench/bench_shape_law_coefficients.py --coefficients 120``.
"""

from __future__ import annotations

from dataclasses import replace
from typing import Callable


def shortest_as_written(planned: Callable, options):
    """``planned(options)`` → Plan, run with the shipped smoothing (``options``) and without the term (weight 0,
    read as ``check --strict`` reads it); the shorter of those whose report holds every limit (the shipped one when
    neither does or they tie). The other's duration is named in the kept law's note."""
    from ..model.errors import PickplaceError

    shipped = planned(options)
    try:
        bare = planned(replace(options, law_smoothing=0.0, strict=True))
    except PickplaceError:  # (strict: the written tool columns refused at a low rate) the shipped plan stands
        return shipped
    if bare.report.exit_code() != 0 or not (bare.duration.seconds < shipped.duration.seconds or not shipped.report.ok):
        return replace(shipped, duration=replace(shipped.duration, law=_said(
            shipped.duration.law, f"without the smoothing term {bare.duration.seconds:.6g} s as written: not shorter"
            if bare.report.exit_code() == 0 else "without the smoothing term its written samples do not hold")))
    said = f"without the smoothing term: shorter as written than with it ({shipped.duration.seconds:.6g} s)"
    report = replace(bare.report, strict=options.strict)
    return replace(bare, duration=replace(bare.duration, law=_said(bare.duration.law, said)), report=report)


def _said(law: str | None, note: str) -> str:
    return note if not law else f"{law}; {note}"
