"""Duration and time law: the rules ``--time`` names and the value a chosen duration is (:mod:`.rules`), ``auto``
from the Cartesian capacity (:mod:`.auto`), the fit's search for the smallest duration every joint and motor limit
allows (:mod:`.search`, on the closed forms of :mod:`.fit`), choosing by rule (:mod:`.choose`), the non-uniform law
(:mod:`.optimal`), the path's shape (:mod:`.shape`), the torque bound (:mod:`.bound`) and the controller's cycle
(:mod:`.cycle`). This module is their public face: every name below is importable from ``pickplace_cli.timing``."""

from __future__ import annotations

from .auto import auto_duration
from .choose import _limits_duration, choose_duration, choose_duration_for, choose_optimal
from .rules import MIN_SECONDS, TIME_RULES, Duration, parse_time
from .search import (
    _smallest_feasible,
    _solve_at,
    _worst_utilisation,
    fit_confirm,
    fit_duration,
    fit_duration_for,
    fit_precise,
    fit_screen,
    screened_root,
)

__all__ = [
    "Duration", "MIN_SECONDS", "TIME_RULES", "auto_duration", "choose_duration", "choose_duration_for",
    "choose_optimal", "fit_confirm", "fit_duration", "fit_duration_for", "fit_precise", "fit_screen", "parse_time",
    "screened_root", "_limits_duration", "_smallest_feasible", "_solve_at", "_worst_utilisation",
]
