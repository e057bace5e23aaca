"""The planning methods by name: one list, shared by the library (:mod:`pickplace_cli.paths`, which maps each to
its planner) and the command line (``--method``, whose ``--help`` must not import numpy: this module imports
nothing but :mod:`enum`)."""

from __future__ import annotations

from enum import Enum


class Method(str, Enum):
    """The planning methods (``--method``): ``bspline`` [Li2018], ``ph`` and ``superposition`` [Su2018], ``lame`` and
    ``piecewise-poly`` (Li 2018's baselines), ``bspline-vel`` [Yang2022]."""

    bspline = "bspline"
    ph = "ph"
    superposition = "superposition"
    lame = "lame"
    piecewise_poly = "piecewise-poly"
    bspline_vel = "bspline-vel"
