"""Look-up table λ → (k1*, k2*) of the B-spline method [Li2018, Sec. 3.2, Eq. (20)–(23)].

Build (offline): for every λ on a grid, maximise F = w_a F_a + w_j F_j (Eq. 22) over (k1, k2) ∈ (0, 1)²,
F_a = min a_max / a_max (Eq. 20), F_j = min j_max / j_max (Eq. 21), peaks on the normalised path (b = 1,
T = 1). Use (online): ``Table.lookup(λ)`` interpolates linearly between rows.

The optimisation is global, not a single gradient run (F has a kink where two jerk peaks are equal,
two local maxima at small λ, and min a_max is only approached as k2 → 0):

1. Coarse stage, shared by every λ: s_u and s_v do not depend on λ — only the scale 1/λ of the v axis
   does — so the acceleration and jerk of both axes are sampled once per (k1, k2) on a grid (step
   ``grid_step``, plus the row k2 = ``k2_floor``), and each λ's a_max, j_max, F on the whole grid are
   array reductions.
2. Refinement: from the best grid points (several distinct local optima for F) a bounded Nelder–Mead
   on the exact objective (peaks from the piecewise-polynomial roots, not samples) polishes each;
   the best refined value wins. min a_max is taken as the infimum over k2 ≥ ``k2_floor`` (it is reached
   only in the limit k2 → 0 [Li2018, Sec. 3.1]; at 1e-4 it is within ~1e-5 relative of the limit).
"""

from __future__ import annotations

import csv
import io
import math
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Callable, Sequence

import numpy as np

from .errors import TableError

COLUMNS = ("lambda", "k1", "k2", "a_max", "j_max", "v_max", "F", "a_min", "j_min")
DEFAULT_TABLE = "bspline-eta0.5.csv"
FIT_LAMBDA_MIN = 5.0

#: Li 2018 Table 2: g_{i,j} of k_i* = Σ_j g_{i,j} λ^j (Eq. 23)
LI2018_TABLE2 = (
    (0.579, -1.99e-2, 5.09e-4, -4.91e-6),
    (0.218, -1.09e-2, 4.15e-4, -5.41e-6),
)


@dataclass(frozen=True)
class TableSettings:
    """Optimiser settings of ``build_table`` (recorded in the table's provenance header)."""

    eta: float = 0.5
    weights: tuple[float, float] = (0.5, 0.5)
    grid_step: float = 0.01
    k2_floor: float = 1e-4
    samples_per_piece: int = 16
    refine_xatol: float = 1e-5
    refine_candidates: int = 4
    basin_margin: float = 0.03

    def __post_init__(self) -> None:
        if not (0 < self.eta < 1):
            raise TableError(f"eta = {self.eta!r}: the lift-off/set-down ratio must lie strictly between 0 and 1")
        wa, wj = self.weights
        if not (wa > 0 and wj > 0 and math.isclose(wa + wj, 1.0, abs_tol=1e-9)):
            raise TableError(f"weights = {wa!r},{wj!r}: need w_a > 0, w_j > 0 and w_a + w_j = 1 (Li 2018 Eq. 22)")
        if not (0 < self.grid_step <= 0.1):
            raise TableError(f"grid_step = {self.grid_step!r}: must lie in (0, 0.1]")


# ------------------------------------------------------------------------------------- normalised peaks


def _unit_spline(k1: float, k2: float, eta: float):
    """2-D spline (s_u, s_v) of [Li2018, Eq. (16)] (v not yet scaled by 1/λ)."""
    from .bspline import li_knots, make_spline, solve_control_points

    knots = li_knots(k1, k2)
    via = np.array([[0.0, 0.0], [0.0, eta], [0.5, 1.0], [1.0, eta], [1.0, 0.0]])
    return make_spline(knots, solve_control_points(knots, knots[[0, 7, 8, 9, 16]], via))


def normalised_peaks(
    k1: float, k2: float, lam: float, eta: float = 0.5, orders: tuple[int, ...] = (1, 2, 3)
) -> tuple[float, ...]:
    """Exact peaks of the normalised path (b = 1, T = 1) [Li2018, Eq. (17)–(19)]: (v_max, a_max, j_max)
    for the default ``orders``; λ scales the v column of the piece polynomials (Eq. 17)."""
    from .bspline import _left_derivatives, piece_coefficients
    from .peaks import ppoly_norm_peak

    s = _unit_spline(k1, k2, eta)
    breaks = np.unique(s.t)
    derivs = [d * np.array([1.0, 1.0 / lam]) for d in _left_derivatives(s, breaks)]
    return tuple(ppoly_norm_peak(*piece_coefficients(s, r, derivs))[0] for r in orders)


def _sample_taus(knots: np.ndarray, per_piece: int) -> np.ndarray:
    br = np.unique(knots)
    u = np.linspace(0.0, 1.0, per_piece + 1)[:-1]
    return np.append((br[:-1, None] + np.diff(br)[:, None] * u[None, :]).ravel(), 1.0)


@dataclass
class _Coarse:
    k1: np.ndarray  # (G,)
    k2: np.ndarray  # (G,)
    acc: np.ndarray  # (G, M, 2) sampled s_u'', s_v''
    jerk: np.ndarray  # (G, M, 2)

    def peaks(self, lam: float) -> tuple[np.ndarray, np.ndarray]:
        scale = np.array([1.0, 1.0 / lam])
        a = np.sqrt(np.max(np.sum((self.acc * scale) ** 2, axis=2), axis=1))
        j = np.sqrt(np.max(np.sum((self.jerk * scale) ** 2, axis=2), axis=1))
        return a, j


def _coarse_grid(settings: TableSettings) -> tuple[np.ndarray, np.ndarray]:
    step = settings.grid_step
    ks = np.round(np.arange(step, 1.0 - step / 2, step), 10)
    k1, k2 = np.meshgrid(ks, np.concatenate(([settings.k2_floor], ks)), indexing="ij")
    return k1.ravel(), k2.ravel()


def _sample_chunk(args: tuple[np.ndarray, np.ndarray, float, int]) -> tuple[np.ndarray, np.ndarray]:
    k1s, k2s, eta, per_piece = args
    m = 6 * per_piece + 1
    acc = np.empty((len(k1s), m, 2))
    jerk = np.empty((len(k1s), m, 2))
    for i, (k1, k2) in enumerate(zip(k1s, k2s)):
        s = _unit_spline(float(k1), float(k2), eta)
        taus = _sample_taus(s.t, per_piece)
        acc[i] = s(taus, nu=2)
        jerk[i] = s(taus, nu=3)
    return acc, jerk


# ------------------------------------------------------------------------------------------- optimiser


@dataclass(frozen=True)
class TableRow:
    lam: float
    k1: float
    k2: float
    a_max: float
    j_max: float
    v_max: float
    F: float
    a_min: float
    j_min: float


def _minimise(fun: Callable[[float, float], float], starts: Sequence[tuple[float, float]], lo2: float, xatol: float):
    from scipy.optimize import minimize

    best = None
    for k1, k2 in starts:
        res = minimize(
            lambda x: fun(float(x[0]), float(x[1])),
            x0=np.array([k1, k2]),
            method="Nelder-Mead",
            bounds=[(1e-3, 1 - 1e-3), (lo2, 1 - 1e-3)],
            options={"xatol": xatol, "fatol": 1e-10, "maxiter": 2000,
                     "initial_simplex": np.array([[k1, k2], [k1 + 0.01, k2], [k1, k2 + 0.01]])},
        )
        if best is None or res.fun < best.fun:
            best = res
    assert best is not None
    return float(best.x[0]), float(best.x[1]), float(best.fun)


def _minimise_on_floor(fun: Callable[[float, float], float], k1_starts: Sequence[float], k2: float, xatol: float) -> float:
    """min over k1 of fun(k1, k2) with k2 fixed, by bounded Brent in a ±0.02 bracket around each start."""
    from scipy.optimize import minimize_scalar

    best = math.inf
    for k1 in k1_starts:
        res = minimize_scalar(
            lambda x: fun(float(x), k2), bounds=(max(1e-3, k1 - 0.02), min(1 - 1e-3, k1 + 0.02)),
            method="bounded", options={"xatol": xatol * 0.1},
        )
        best = min(best, float(res.fun))
    return best


def _local_optima(values: np.ndarray, shape: tuple[int, int], count: int) -> list[int]:
    """Flat indices of up to ``count`` best local minima of ``values`` on the 2-D grid (8-neighbourhood)."""
    v = values.reshape(shape)
    pad = np.pad(v, 1, constant_values=np.inf)
    is_min = np.ones(shape, dtype=bool)
    for di in (-1, 0, 1):
        for dj in (-1, 0, 1):
            if di or dj:
                is_min &= v <= pad[1 + di : 1 + di + shape[0], 1 + dj : 1 + dj + shape[1]]
    idx = np.flatnonzero(is_min.ravel())
    idx = idx[np.argsort(values[idx])][:count]
    if idx.size == 0:
        idx = np.array([int(np.argmin(values))])
    return [int(i) for i in idx]


def optimise_lambda(lam: float, coarse: _Coarse, settings: TableSettings) -> TableRow:
    """Global optimum of F (Eq. 22) at one λ, from the coarse grid and a bounded local refinement."""
    eta = settings.eta
    wa, wj = settings.weights
    lo2 = settings.k2_floor
    shape = (len(np.unique(coarse.k1)), len(coarse.k1) // len(np.unique(coarse.k1)))
    a_grid, j_grid = coarse.peaks(lam)
    cache: dict[tuple[float, float], tuple[float, float]] = {}

    def peaks(k1: float, k2: float) -> tuple[float, float]:
        """Exact (a_max, j_max) at (k1, k2), memoised (F's refinement revisits points)."""
        key = (k1, k2)
        if key not in cache:
            cache[key] = normalised_peaks(k1, k2, lam, eta, (2, 3))  # type: ignore[assignment]
        return cache[key]

    def a_only(k1: float, k2: float) -> float:
        return normalised_peaks(k1, k2, lam, eta, (2,))[0]

    def j_only(k1: float, k2: float) -> float:
        return normalised_peaks(k1, k2, lam, eta, (3,))[0]

    def starts(values: np.ndarray) -> list[tuple[float, float]]:
        """Grid local minima whose sampled value is within ``basin_margin`` of the best one.

        Samples under-estimate a peak by well under 1 % at ``samples_per_piece`` = 16, so a basin whose
        sampled value is more than a few per cent worse cannot hold the global optimum."""
        idx = _local_optima(values, shape, settings.refine_candidates)
        best = values[idx[0]]
        keep = [i for i in idx if values[i] <= best + settings.basin_margin * abs(best)]
        return [(float(coarse.k1[i]), float(coarse.k2[i])) for i in keep]

    xatol = settings.refine_xatol
    # Sampled grid values under-estimate peaks, so only the refined exact values are used below.
    a_starts = starts(a_grid)
    if all(k2 == lo2 for _, k2 in a_starts):
        # the infimum of a_max lies at k2 → 0 [Li2018, Sec. 3.1]: a 1-D bounded search along k2 = k2_floor
        a_min = _minimise_on_floor(a_only, [k1 for k1, _ in a_starts], lo2, xatol)
    else:
        _, _, a_min = _minimise(a_only, a_starts, lo2, xatol)
    _, _, j_min = _minimise(j_only, starts(j_grid), lo2, xatol)

    def neg_f(k1: float, k2: float) -> float:
        a, j = peaks(k1, k2)
        return -(wa * a_min / a + wj * j_min / j)

    f_grid = -(wa * a_min / a_grid + wj * j_min / j_grid)
    # F may have two local maxima (small λ): refine every grid local maximum near the best
    k1, k2, nf = _minimise(neg_f, starts(f_grid), lo2, xatol)
    v, a, j = normalised_peaks(k1, k2, lam, eta)
    return TableRow(lam, k1, k2, a, j, v, -nf, a_min, j_min)



# ------------------------------------------------------------------------------------------------ table


@dataclass(frozen=True)
class Table:
    """A λ → (k1*, k2*) table with its provenance (``meta``) and fitted cubic (Eq. 23)."""

    rows: tuple[TableRow, ...]
    meta: dict = field(default_factory=dict)
    source: str = "<memory>"

    def __post_init__(self) -> None:
        lam = self.lam
        if len(lam) < 2:
            raise TableError(f"{self.source}: a table needs at least two rows, got {len(lam)}")
        if np.any(np.diff(lam) <= 0):
            raise TableError(f"{self.source}: lambda must increase strictly from row to row")

    @property
    def lam(self) -> np.ndarray:
        return np.array([r.lam for r in self.rows])

    def column(self, name: str) -> np.ndarray:
        attr = "lam" if name == "lambda" else name
        return np.array([getattr(r, attr) for r in self.rows])

    @property
    def eta(self) -> float | None:
        e = self.meta.get("eta")
        return None if e is None else float(e)

    def lookup(self, lam: float, eta: float | None = None) -> tuple[float, float]:
        """(k1, k2) at ``lam`` by linear interpolation between rows; TableError outside the range."""
        lo, hi = float(self.lam[0]), float(self.lam[-1])
        if not np.isfinite(lam):
            raise TableError(f"lambda = {lam!r}: not a finite width/height ratio")
        if not (lo - 1e-9 <= lam <= hi + 1e-9):
            raise TableError(
                f"lambda = b/h = {lam:.4g} is outside the table's range [{lo:g}, {hi:g}] ({self.source}); "
                "change --height, build a wider table (pickplace build-table), or give --k1 and --k2"
            )
        if eta is not None and self.eta is not None and abs(eta - self.eta) > 1e-9:
            raise TableError(
                f"eta = {eta:g}: the table {self.source} was built for eta = {self.eta:g}; "
                f"build one with `pickplace build-table --eta {eta:g}` or give --k1 and --k2"
            )
        return float(np.interp(lam, self.lam, self.column("k1"))), float(np.interp(lam, self.lam, self.column("k2")))

    def fit(self, lam_min: float | None = None, degree: int = 3) -> tuple[np.ndarray, np.ndarray, float]:
        """Least-squares cubic of Eq. (23) over the rows with λ ≥ ``lam_min`` (default: the ``fit_lambda_min``
        of the header, else 5): g1, g2 as (g_i0 … g_i3) and the max |residual| over those rows.

        Below λ ≈ 5 the optimum moves fast (k2 rises to 0.4 at λ = 1) and no cubic follows it; the table
        rows, not the fit, are what ``plan`` uses."""
        if lam_min is None:
            lam_min = float(self.meta.get("fit_lambda_min", FIT_LAMBDA_MIN))
        sel = self.lam >= lam_min - 1e-12
        if sel.sum() < degree + 1:
            sel = np.ones_like(sel)
        lam = self.lam[sel]
        k1, k2 = self.column("k1")[sel], self.column("k2")[sel]
        g1 = np.polynomial.polynomial.polyfit(lam, k1, degree)
        g2 = np.polynomial.polynomial.polyfit(lam, k2, degree)
        res = max(
            np.max(np.abs(np.polynomial.polynomial.polyval(lam, g1) - k1)),
            np.max(np.abs(np.polynomial.polynomial.polyval(lam, g2) - k2)),
        )
        return g1, g2, float(res)


def lambda_grid(lam_min: float, lam_max: float, step: float) -> np.ndarray:
    for name, v in (("lambda-min", lam_min), ("lambda-max", lam_max), ("lambda-step", step)):
        if not (np.isfinite(v) and v > 0):
            raise TableError(f"{name} = {v!r}: must be a finite number > 0")
    if lam_max <= lam_min:
        raise TableError(f"lambda-max = {lam_max:g}: must be greater than lambda-min = {lam_min:g}")
    n = int(math.floor((lam_max - lam_min) / step + 1e-9))
    grid = lam_min + step * np.arange(n + 1)
    if lam_max - grid[-1] > 1e-9 * step:
        grid = np.append(grid, lam_max)
    return np.round(grid, 12)


def build_table(
    lams: Sequence[float],
    settings: TableSettings = TableSettings(),
    progress: Callable[[int, int], None] | None = None,
    workers: int = 1,
) -> Table:
    """Optimal (k1*, k2*) for every λ in ``lams`` (see the module docstring for the method).

    ``progress(done, total)`` is called as work finishes (total = coarse chunks + λ values).
    ``workers`` > 1 uses a process pool (results are identical to the sequential build).
    """
    from concurrent.futures import ProcessPoolExecutor

    lams = [float(x) for x in lams]
    k1, k2 = _coarse_grid(settings)
    n_chunks = max(8, 4 * workers)
    chunks = [(a, b, settings.eta, settings.samples_per_piece) for a, b in zip(np.array_split(k1, n_chunks), np.array_split(k2, n_chunks))]
    total = len(chunks) + len(lams)
    done = 0

    def tick() -> None:
        nonlocal done
        done += 1
        if progress:
            progress(done, total)

    pool = ProcessPoolExecutor(max_workers=workers) if workers > 1 else None
    try:
        mapper = pool.map if pool else map
        parts = []
        for part in mapper(_sample_chunk, chunks):
            parts.append(part)
            tick()
        coarse = _Coarse(k1, k2, np.concatenate([p[0] for p in parts]), np.concatenate([p[1] for p in parts]))
        rows = []
        if pool:
            futs = [pool.submit(optimise_lambda, lam, coarse, settings) for lam in lams]
            for fut in futs:
                rows.append(fut.result())
                tick()
        else:
            for lam in lams:
                rows.append(optimise_lambda(lam, coarse, settings))
                tick()
    finally:
        if pool:
            pool.shutdown(cancel_futures=True)
    meta = {"method": "bspline", **{k: v for k, v in asdict(settings).items()}}
    meta["weights"] = list(settings.weights)
    return Table(tuple(rows), meta=meta)


# ------------------------------------------------------------------------------------------------- I/O


def default_table_path() -> Path:
    from .resources import data_dir

    return data_dir("tables") / DEFAULT_TABLE


def format_table(table: Table, version: str, extra_meta: dict | None = None) -> str:
    """CSV text: ``#`` provenance lines, a header, one row per λ (fixed format, deterministic)."""
    meta = dict(table.meta)
    meta.update(extra_meta or {})
    fit_min = float(meta.setdefault("fit_lambda_min", FIT_LAMBDA_MIN))
    g1, g2, res = table.fit(fit_min)
    out = io.StringIO()
    out.write("# pickplace look-up table: optimal time-ratio factors of the quintic B-spline method [Li2018, Eq. (20)-(23)]\n")
    out.write(f"# tool_version: {version}\n")
    for key in sorted(meta):
        val = meta[key]
        val = ",".join(f"{x:g}" for x in val) if isinstance(val, (list, tuple)) else val
        out.write(f"# {key}: {val}\n")
    out.write("# units: lambda = b/h (dimensionless); k1, k2 dimensionless; v_max, a_max, j_max, a_min, j_min are the\n")
    out.write("#   normalised peaks |v|, |a|, |j| of the path with b = 1 m, T = 1 s (m/s, m/s^2, m/s^3); F dimensionless\n")
    out.write("# a_min, j_min: min over (k1, k2) of a_max, j_max at that lambda (the normalisers of Eq. 20-21)\n")
    out.write(f"# fit_k1: {' '.join(f'{g:.9g}' for g in g1)}\n")
    out.write(f"# fit_k2: {' '.join(f'{g:.9g}' for g in g2)}\n")
    out.write(f"# fit: k_i = g_i0 + g_i1*lambda + g_i2*lambda^2 + g_i3*lambda^3 (Eq. 23), fitted on lambda >= {fit_min:g}, max |residual| = {res:.3g}\n")
    out.write(",".join(COLUMNS) + "\n")
    for r in table.rows:
        out.write(",".join(f"{x:.10g}" for x in (r.lam, r.k1, r.k2, r.a_max, r.j_max, r.v_max, r.F, r.a_min, r.j_min)) + "\n")
    return out.getvalue()


def parse_table(text: str, source: str = "<table>") -> Table:
    """Read a table written by :func:`format_table`; TableError (with file:line) on anything wrong."""
    meta: dict = {}
    header: list[str] | None = None
    rows: list[TableRow] = []
    for lineno, line in enumerate(text.splitlines(), 1):
        s = line.strip()
        if not s:
            continue
        if s.startswith("#"):
            body = s[1:].strip()
            if ":" in body and header is None:
                key, _, val = body.partition(":")
                meta.setdefault(key.strip(), val.strip())
            continue
        cells = next(csv.reader([s]))
        if header is None:
            header = [c.strip() for c in cells]
            missing = [c for c in ("lambda", "k1", "k2") if c not in header]
            if missing:
                raise TableError(f"{source}:{lineno}: header lacks column(s) {', '.join(missing)} (need {', '.join(COLUMNS)})")
            continue
        if len(cells) != len(header):
            raise TableError(f"{source}:{lineno}: {len(cells)} values, header has {len(header)} columns")
        try:
            vals = {h: float(c) for h, c in zip(header, cells)}
        except ValueError:
            raise TableError(f"{source}:{lineno}: not a number in row {s!r}") from None
        bad = [h for h, v in vals.items() if not math.isfinite(v)]
        if bad:
            raise TableError(f"{source}:{lineno}: {bad[0]} = {vals[bad[0]]}: values must be finite")
        for name in ("k1", "k2"):
            if not 0 < vals[name] < 1:
                raise TableError(f"{source}:{lineno}: {name} = {vals[name]:g}: must lie strictly between 0 and 1")
        nan = float("nan")
        rows.append(TableRow(*(vals.get(c, nan) for c in COLUMNS)))
    if header is None or not rows:
        raise TableError(f"{source}: no table rows (expected a header '{','.join(COLUMNS)}' and data)")
    if "eta" not in meta:
        raise TableError(f"{source}: no '# eta: VALUE' header line: the table must say which η it was built for")
    try:
        meta["eta"] = float(meta["eta"])
    except ValueError:
        raise TableError(f"{source}: eta = {meta['eta']!r} in the header is not a number") from None
    return Table(tuple(rows), meta=meta, source=source)


_CACHE: dict[tuple[str, float, int], Table] = {}


def load_table(path: str | Path | None = None) -> Table:
    """Read a table file (default: the shipped table); TableError when missing or corrupt."""
    p = Path(path) if path is not None else default_table_path()
    try:
        st = p.stat()
        key = (str(p.resolve()), st.st_mtime, st.st_size)
        if key in _CACHE:
            return _CACHE[key]
        text = p.read_text(encoding="utf-8")
    except FileNotFoundError:
        raise TableError(f"table {p}: no such file (build one with `pickplace build-table -o {p}`)") from None
    except (OSError, UnicodeDecodeError) as exc:
        raise TableError(f"table {p}: cannot read: {exc}") from None
    table = parse_table(text, str(p))
    _CACHE[key] = table
    return table
