"""Parameter studies from the papers, as functions (the README, the tests and the benchmarks call them).

:func:`fig11_study` — [Su2018, Fig. 11]: the cycle time of the PH method minus that of the superposition
method over 0 ≤ h ≤ 0.3 m, 0 ≤ w ≤ 1 m. The paper reports that the difference is negative (PH faster)
on 99.70 % of its grid. Two versions:

* **paper**: the paper's formulas, Eq. (22) for PH (m = h, r = w/2; only the tangential acceleration
  s̈ ≤ a_max) against Eq. (26)–(27) for superposition (each axis's acceleration ≤ a_max);
* **true**: both methods timed so that the *norm* of the tool acceleration along the actual path
  stays ≤ a_max (what ``--time auto`` does): T = sqrt(â/a_max), â the true peak at T = 1.

Both are independent of a_max (every time scales as 1/sqrt(a_max)). The true version also scales:
a path of width w and height h is the path of width 1 and height ρ = h/w scaled by w, so
T_true(h, w) = sqrt(w·â(ρ)/a_max) and the sign of the difference depends on ρ only. The study finds
the ratios ρ* where the sign changes (a log scan of ρ refined by brentq) and classifies every grid point
by its ρ, exactly, without planning 300,000 paths.

Edges of the grid: at h = 0 both methods are the same horizontal 3-4-5 move (a tie; the paper's formulas
agree there too); at w = 0 the paper's Eq. (22) is finite, but the actual PH path degenerates (r = 0:
the tool would reverse at the top at full speed, unbounded acceleration), so in the true version PH is
not faster there.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

#: relative margin under which two cycle times count as a tie (not "faster")
TIE = 1e-12


@dataclass(frozen=True)
class Fig11Result:
    """Outcome of :func:`fig11_study`. Fractions are of all grid points, in % (0–100)."""

    h: np.ndarray  # (nh,) m
    w: np.ndarray  # (nw,) m
    paper_faster: np.ndarray  # (nh, nw) bool: Eq. (22) < Eq. (26)/(27)
    true_faster: np.ndarray  # (nh, nw) bool: true-norm T_ph < T_sup
    crossings: tuple[float, ...]  # ρ = h/w where the true sign changes
    faster_below: bool  # PH (true) is faster for ρ below the first crossing

    @property
    def paper_percent(self) -> float:
        return 100.0 * float(self.paper_faster.mean())

    @property
    def true_percent(self) -> float:
        return 100.0 * float(self.true_faster.mean())


def normalised_accel_peaks(rho: float) -> tuple[float, float]:
    """True peaks of ‖a‖ (m at T = 1 s) of PH (m = h, r = w/2) and superposition for w = 1 m, h = ρ m."""
    from ..paths.ph import plan_ph
    from ..paths.superposition import plan_superposition
    from ..model.task import Task

    task = Task(np.zeros(3), np.array([1.0, 0.0, 0.0]), float(rho))
    return plan_ph(task).peaks[1], plan_superposition(task).peaks[1]


def true_times(h: float, w: float, a_max: float) -> tuple[float, float]:
    """(T_ph, T_sup) in s holding the true acceleration norm to a_max (m/s²), for h, w > 0 (m)."""
    aph, asup = normalised_accel_peaks(h / w)
    return float(np.sqrt(w * aph / a_max)), float(np.sqrt(w * asup / a_max))


def paper_times(h, w, a_max):
    """(T_ph, T_sup) in s by the paper's formulas, Eq. (22) (m = h, r = w/2) and Eq. (26)–(27); vectorised."""
    from ..paths.ph import cycle_time_eq22
    from ..paths.superposition import cycle_time

    return cycle_time_eq22(h, w, a_max), cycle_time(h, w, a_max)


def _log_difference(rho: float) -> float:
    aph, asup = normalised_accel_peaks(rho)
    return float(np.log(aph / asup))  # < 0 ⟺ PH faster (T ∝ sqrt(â))


def true_crossings(rho_min: float, rho_max: float, scan: int = 40) -> tuple[tuple[float, ...], bool]:
    """Ratios ρ ∈ [rho_min, rho_max] where T_ph − T_sup (true norms) changes sign, and whether PH is
    faster below the first one. A log scan of ``scan`` points, each sign change refined by brentq to
    1e-10 relative (a pair of crossings closer than one scan step would be missed)."""
    from scipy.optimize import brentq

    r = np.geomspace(rho_min, rho_max, scan)
    d = np.array([_log_difference(x) for x in r])
    out = []
    for i in np.flatnonzero(np.sign(d[:-1]) != np.sign(d[1:])):
        out.append(float(brentq(_log_difference, r[i], r[i + 1], xtol=1e-14, rtol=1e-10)))
    return tuple(out), bool(d[0] < 0)


def fig11_study(h_max: float = 0.3, w_max: float = 1.0, step: float = 0.001, scan: int = 40) -> Fig11Result:
    """[Su2018, Fig. 11] on the grid h = 0, step … h_max, w = 0, step … w_max (m), both versions."""
    h = np.linspace(0.0, h_max, int(round(h_max / step)) + 1)
    w = np.linspace(0.0, w_max, int(round(w_max / step)) + 1)
    H, W = np.meshgrid(h, w, indexing="ij")
    tph, tsup = paper_times(H, W, 1.0)
    paper = tph < tsup * (1.0 - TIE)
    inner = (H > 0) & (W > 0)
    rho = np.where(inner, H / np.where(W > 0, W, 1.0), np.nan)
    crossings, below = true_crossings(float(np.nanmin(rho)), float(np.nanmax(rho)), scan)
    # the sign alternates at each crossing: count the crossings below each ρ
    n_below = np.searchsorted(np.array(crossings), np.where(inner, rho, 0.0)) if crossings else np.zeros(H.shape, int)
    faster = np.where(n_below % 2 == 0, below, not below)
    true = inner & faster
    return Fig11Result(h, w, paper, true, crossings, below)
