"""How sure a run's miss rate and picks/min are: confidence intervals over the run, and over a sweep's seeds.

**Batch means** (the interval the line reports). Misses are not independent: a bunch of Poisson arrivals keeps every
robot busy and several parts in a row are missed, then a gap lets every part through. The run's feed (first to last
detection) is cut into B windows of equal length (``BATCHES``, fewer when a window would hold fewer than
``MIN_PER_BATCH`` parts on average; no interval below ``MIN_BATCHES``); window i holds n_i parts, m_i of them
missed and p_i picked. The miss rate is the ratio R = Σm_i / Σn_i, and its standard error the ratio estimator's
over the windows,

    SE(R) = sqrt( Σ (m_i − R·n_i)² / (B·(B − 1)) ) / n̄,    n̄ = Σn_i / B,

so the correlation inside a window is counted (windows several cycles long are nearly independent of each other);
picks/min is the reported rate ± the standard error of the windows' rates 60·p_i/w (w the window's length [s]),
sd/√B. Both intervals are estimate ± t_{(1+level)/2, B−1}·SE (Student's t with B − 1 degrees of freedom).

**Wilson** (shown beside it): the binomial score interval over the N parts, exact in its assumptions only when the
parts are missed independently; on a busy line it is too narrow (tests: a two-state Markov chain of misses with
correlation 0.55 covers its true rate 95 % of the time by batch means, far less by Wilson).

**Per part type** (a line with several types): each type's miss rate and picks/min by the same two methods over
that type's parts alone (its own windows over its own first to last detection).

**Across seeds** (:func:`across_seeds`): k runs' miss rates (or any per-run figure) → mean ± t_{(1+level)/2, k−1}·sd/√k,
each seed's run being independent.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

#: the confidence level of every interval
LEVEL = 0.95
#: the number of time windows of the batch means
BATCHES = 20
#: fewer windows when they would hold fewer parts than this on average
MIN_PER_BATCH = 10
#: no batch-means interval with fewer windows than this (too few parts): only Wilson's
MIN_BATCHES = 5


def t_quantile(level: float, dof: int) -> float:
    """Student's t quantile t_{(1+level)/2, dof}."""
    from scipy.stats import t

    return float(t.ppf(0.5 + level / 2.0, dof))


def wilson(k: int, n: int, level: float = LEVEL) -> tuple[float, float]:
    """The Wilson score interval (low, high) of a binomial share k/n; (0, 1) for n = 0."""
    if n <= 0:
        return 0.0, 1.0
    from scipy.stats import norm

    z = float(norm.ppf(0.5 + level / 2.0))
    p = k / n
    centre = (p + z * z / (2 * n)) / (1 + z * z / n)
    half = z * math.sqrt(p * (1 - p) / n + z * z / (4 * n * n)) / (1 + z * z / n)
    return max(centre - half, 0.0), min(centre + half, 1.0)


@dataclass(frozen=True)
class Interval:
    """An estimate with its interval [low, high] at ``level``, and how it was found."""

    estimate: float
    low: float
    high: float
    method: str
    level: float = LEVEL

    @property
    def half(self) -> float:
        """Half the interval's width."""
        return (self.high - self.low) / 2.0

    def as_dict(self) -> dict:
        return {"estimate": self.estimate, "low": self.low, "high": self.high, "half_width": self.half,
                "level": self.level, "method": self.method}


@dataclass(frozen=True)
class RunIntervals:
    """A run's intervals: the miss rate by batch means (None: too few parts) and by Wilson, picks/min by batch means
    (None alike), the number of windows and their length [s]."""

    miss: Interval | None
    miss_wilson: Interval
    picks_per_minute: Interval | None
    batches: int
    window: float

    def as_dict(self) -> dict:
        return {"miss_rate": None if self.miss is None else self.miss.as_dict(),
                "miss_rate_wilson": self.miss_wilson.as_dict(),
                "picks_per_minute": None if self.picks_per_minute is None else self.picks_per_minute.as_dict(),
                "batches": self.batches, "window_s": self.window}


def batch_count(parts: int, batches: int = BATCHES) -> int:
    """The windows used for ``parts`` parts: ``batches``, fewer so that each holds ``MIN_PER_BATCH`` on average."""
    return int(min(batches, parts // MIN_PER_BATCH))


def run_intervals(t: np.ndarray, missed: np.ndarray, picks_per_minute: float, level: float = LEVEL,
                  batches: int = BATCHES) -> RunIntervals:
    """The intervals of a run (module docstring) from each part's detection time ``t`` [s] and whether it was
    ``missed``; ``picks_per_minute`` is the run's reported rate (the centre of its interval)."""
    t = np.asarray(t, float)
    missed = np.asarray(missed, bool)
    n = len(t)
    k = int(missed.sum())
    lo, hi = wilson(k, n, level)
    rate = k / n if n else 0.0
    w_int = Interval(rate, lo, hi, "wilson", level)
    B = batch_count(n, batches)
    t0, t1 = (float(t.min()), float(t.max())) if n else (0.0, 0.0)
    if B < MIN_BATCHES or t1 <= t0:
        return RunIntervals(None, w_int, None, 0, 0.0)
    width = (t1 - t0) / B
    idx = np.minimum(((t - t0) / width).astype(int), B - 1)
    n_i = np.bincount(idx, minlength=B).astype(float)
    m_i = np.bincount(idx, weights=missed.astype(float), minlength=B)
    p_i = n_i - m_i
    tq = t_quantile(level, B - 1)
    se = math.sqrt(float(np.sum((m_i - rate * n_i) ** 2)) / (B * (B - 1))) / (n / B)
    miss = Interval(rate, max(rate - tq * se, 0.0), min(rate + tq * se, 1.0), "batch means", level)
    rates = 60.0 * p_i / width
    se_p = float(np.std(rates, ddof=1)) / math.sqrt(B)
    picks = Interval(picks_per_minute, max(picks_per_minute - tq * se_p, 0.0), picks_per_minute + tq * se_p,
                     "batch means", level)
    return RunIntervals(miss, w_int, picks, B, width)


def across_seeds(values, level: float = LEVEL) -> Interval | None:
    """mean ± t·sd/√k of k independent runs' figures (module docstring); None for fewer than two."""
    x = np.asarray([v for v in values if v is not None and math.isfinite(v)], float)
    if len(x) < 2:
        return None
    mean = float(x.mean())
    half = t_quantile(level, len(x) - 1) * float(x.std(ddof=1)) / math.sqrt(len(x))
    return Interval(mean, mean - half, mean + half, f"mean of {len(x)} seeds", level)


def result_arrays(results) -> tuple[np.ndarray, np.ndarray]:
    """(detection times [s], missed?) of a run's per-part results (bad rows left out)."""
    rows = [(r.detection.t, not r.picked) for r in results if r.detection is not None]
    return np.array([x[0] for x in rows], float), np.array([x[1] for x in rows], bool)


def type_arrays(results, kind: str) -> tuple[np.ndarray, np.ndarray]:
    """(detection times [s], missed?) of the parts of type ``kind`` (:func:`result_arrays` of that type's parts)."""
    return result_arrays([r for r in results if r.detection is not None and r.detection.type == kind])


def summary_intervals(summary, results, level: float = LEVEL) -> RunIntervals:
    """The intervals of a finished run from its per-part results, picks/min centred on the summary's."""
    return run_intervals(*result_arrays(results), summary.picks_per_minute, level)
