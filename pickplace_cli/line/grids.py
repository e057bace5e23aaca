"""The check grids of a line robot's legs that are not B-spline moves (a tracking leg's), and how the limit
columns' peaks on the grids become the use of every limit (:class:`UsePlan`)."""

from __future__ import annotations

import numpy as np

#: uniform samples of a tracking leg's grid (plus its Gauss–Legendre nodes)
TRACK_UNIFORM = 9


class TrackBasis:
    """The grid of a tracking leg (constant velocity, τ ∈ [0, 1]): uniform samples and Gauss–Legendre nodes."""

    def __init__(self) -> None:
        from .moves import gauss_legendre

        x, w = gauss_legendre()
        nodes = 0.5 + 0.5 * x
        self.tau = np.unique(np.concatenate([np.linspace(0.0, 1.0, TRACK_UNIFORM), nodes]))
        self.gl_index = np.searchsorted(self.tau, nodes)
        self.gl_weight = 0.5 * w


_TRACK = None


def track_basis() -> TrackBasis:
    global _TRACK
    if _TRACK is None:
        _TRACK = TrackBasis()
    return _TRACK


class UsePlan:
    """How the columns' peaks (:meth:`~pickplace_cli.limits.motion.MotionModel.columns`) become the use of every limit
    as the limit report gives it (``keys``: (joint, quantity) per row): peak/limit; the singularity measure
    limit/minimum; a [min, max] range by the side nearer its bound, |x − mid| / half-range. Built once per robot."""

    def __init__(self, meta: list) -> None:
        self.meta = meta
        keys, cols, limits, lower = [], [], [], []
        ranges: dict = {}
        for c, (joint, quantity, _unit, limit, _kind, sign) in enumerate(meta):
            base, _, side = quantity.rpartition(" ")
            if side in ("max", "min") and base.startswith(("position", "workcell")):
                ranges.setdefault((joint, base), {})[side] = (c, float(limit))
            else:
                keys.append((joint, quantity))
                cols.append(c)
                limits.append(float(limit))
                lower.append(sign < 0)
        self.cols, self.limits, self.lower = np.array(cols, int), np.array(limits), np.array(lower, bool)
        rmax, rmin, mid, half = [], [], [], []
        for key, sides in ranges.items():
            (cmax, hi), (cmin, lo) = sides["max"], sides["min"]
            keys.append(key)
            rmax.append(cmax)
            rmin.append(cmin)
            mid.append((lo + hi) / 2)
            half.append((hi - lo) / 2)
        self.rmax, self.rmin, self.mid, self.half = np.array(rmax, int), np.array(rmin, int), np.array(mid), np.array(half)
        self.keys = keys

    def __call__(self, peak: np.ndarray) -> np.ndarray:
        """(L, C) column peaks (column sign convention) → (L, R) use per row."""
        v = peak[:, self.cols]
        with np.errstate(divide="ignore", invalid="ignore"):
            single = np.where(self.lower, np.where(-v > 0, self.limits / -v, np.inf), v / self.limits)
        vmax, vmin = peak[:, self.rmax], -peak[:, self.rmin]
        ranged = np.maximum((vmax - self.mid) / self.half, (self.mid - vmin) / self.half)
        return np.concatenate([single, ranged], axis=1)


def _leg_of(index, grids) -> int:
    if index is None:
        return 0
    start = 0
    for k, g in enumerate(grids):
        start += len(g[0])
        if index < start:
            return k
    return len(grids) - 1
