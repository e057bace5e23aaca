"""Look-up table (λ, η) → (k1*, k2*) of the B-spline method [Li2018, Sec. 3.2, Eq. (20)–(23)].

Once normalised (b = 1, T = 1), Li 2018's optimum depends on λ = b/h and the lift-off ratio η only (and the
weights of Eq. 22, fixed per table), so one table over a λ × η grid covers every move. Each row is
:func:`pickplace_cli.lookup.bspline_optimum.optimise_lambda` at that (λ, η): the 1-D build, run once per η.

Reading (:meth:`Table2D.lookup`): bilinear interpolation in (λ, η) inside the grid cell around the point.
The optimum is not continuous everywhere: where another basin of F takes over, (k1*, k2*) jumps between two
neighbouring grid points, and interpolating across that edge gives a (k1, k2) far from both optima (a
table that lies). :func:`find_jumps` marks every edge of the grid whose change of k1 or k2 exceeds
``JUMP_K``; a cell with a marked edge is not interpolated (``lookup`` raises ``TableJumpError``, and the
planner solves that (λ, η) on demand). The marked edges are listed in the file's header.
"""

from __future__ import annotations

import bisect
import functools
import hashlib
import io
import json
import math
from dataclasses import asdict, dataclass, field, replace
from pathlib import Path
from typing import TYPE_CHECKING, Callable, Sequence

import numpy as np

from ..model.errors import TableError
from .bspline_build import BuildReport, step_grid
from .checkpoint import CheckpointWriter, refuse_row_of_other_run
from .executors import local_pool
from .bspline_optimum import ALGORITHM_VERSION, TableRow, TableSettings, _optimise_chunk
from .bspline_table import COLUMNS, read_numeric_table, read_table_file, write_meta

if TYPE_CHECKING:  # pragma: no cover
    from concurrent.futures import Executor

COLUMNS_2D = ("eta",) + COLUMNS
DEFAULT_TABLE_2D = "bspline-2d.csv"
#: an edge of the grid across which k1* or k2* changes by more than this is a jump between basins of F
#: (on the shipped grid the smooth edges change k by < 0.06, the jumps by > 0.3: see the README)
JUMP_K = 0.15
#: below this λ (tall moves) ``lookup_polished`` polishes the interpolated (k1, k2) (F is steep there: the
#: held-out points that lost > 0.5 % of F by interpolation alone all have λ < 1.7)
POLISH_LAMBDA = 2.0
#: the η a 2-D table may cover (the on-demand solve takes any 0 < η < 1)
ETA_RANGE = (0.01, 0.99)


class TableJumpError(TableError):
    """The (λ, η) lies in a grid cell across which the optimum jumps between basins: not interpolated."""


# ----------------------------------------------------------------------------------------------- grids


def eta_grid(eta_min: float, eta_max: float, step: float) -> np.ndarray:
    """η from ``eta_min`` to ``eta_max`` (included) by ``step``; one value when they are equal."""
    lo, hi = ETA_RANGE
    for name, v in (("eta-min", eta_min), ("eta-max", eta_max)):
        if not (np.isfinite(v) and lo <= v <= hi):
            raise TableError(f"{name} = {v!r}: must lie in [{lo:g}, {hi:g}]")
    return step_grid("eta", eta_min, eta_max, step)


def parse_eta_list(text: str) -> np.ndarray:
    """``--eta-list 0.1,0.3,0.5``: strictly increasing values in ``ETA_RANGE``."""
    lo, hi = ETA_RANGE
    try:
        vals = [float(x) for x in text.split(",") if x.strip()]
    except ValueError:
        raise TableError(f"eta-list = {text!r}: give numbers separated by commas, e.g. 0.1,0.3,0.5") from None
    if not vals:
        raise TableError(f"eta-list = {text!r}: no values")
    for v in vals:
        if not (np.isfinite(v) and lo <= v <= hi):
            raise TableError(f"eta-list: {v!r}: every η must lie in [{lo:g}, {hi:g}]")
    if any(b <= a for a, b in zip(vals, vals[1:])):
        raise TableError(f"eta-list = {text!r}: the values must increase strictly")
    return np.round(np.array(vals), 12)


def log_lambda_grid(lam_min: float, lam_max: float, points: int) -> np.ndarray:
    """``points`` values of λ spaced evenly in log λ from ``lam_min`` to ``lam_max`` (both included)."""
    for name, v in (("lambda-min", lam_min), ("lambda-max", lam_max)):
        if not (np.isfinite(v) and v > 0):
            raise TableError(f"{name} = {v!r}: must be a finite number > 0")
    if points < 1 or (points == 1) != (lam_max == lam_min):
        raise TableError(f"lambda-points = {points}: need 1 for lambda-min = lambda-max, else at least 2")
    if lam_max < lam_min:
        raise TableError(f"lambda-max = {lam_max:g}: must not be less than lambda-min = {lam_min:g}")
    if points == 1:
        return np.array([float(lam_min)])
    grid = np.exp(np.linspace(math.log(lam_min), math.log(lam_max), points))
    grid[0], grid[-1] = lam_min, lam_max
    return np.round(grid, 10)


# ----------------------------------------------------------------------------------------------- table


@dataclass(frozen=True)
class Table2D:
    """Rows of a λ × η grid, η-major (all λ of the first η, then the next …), with provenance ``meta``."""

    etas: tuple[float, ...]
    lams: tuple[float, ...]
    rows: tuple[TableRow, ...]
    meta: dict = field(default_factory=dict)
    source: str = "<memory>"

    def __post_init__(self) -> None:
        ne, nl = len(self.etas), len(self.lams)
        if ne == 0 or nl == 0 or len(self.rows) != ne * nl:
            raise TableError(f"{self.source}: {len(self.rows)} rows, a full {ne} η × {nl} λ grid needs {ne * nl}")
        for name, axis in (("eta", self.etas), ("lambda", self.lams)):
            if any(b <= a for a, b in zip(axis, axis[1:])):
                raise TableError(f"{self.source}: the {name} values of the grid must increase strictly")
        grid = {name: np.array([getattr(r, name) for r in self.rows]).reshape(ne, nl)
                for name in ("k1", "k2", "F", "a_min", "j_min")}
        for arr in grid.values():
            arr.flags.writeable = False
        object.__setattr__(self, "_grid", grid)
        object.__setattr__(self, "_jump_cells", _jump_cells(find_jumps(grid["k1"], grid["k2"]), ne, nl))

    def grid(self, name: str) -> np.ndarray:
        """(len(etas), len(lams)) array of column ``name`` (k1, k2, F, a_min or j_min)."""
        return self._grid[name]  # type: ignore[attr-defined]

    @property
    def jumps(self) -> list[tuple[str, tuple[float, float], tuple[float, float]]]:
        """The grid edges across which the optimum jumps: ("lambda"|"eta", (λ, η) of one end, of the other)."""
        out = []
        for axis, ie, il in find_jumps(self.grid("k1"), self.grid("k2")):
            ie2, il2 = (ie, il + 1) if axis == "lambda" else (ie + 1, il)
            out.append((axis, (self.lams[il], self.etas[ie]), (self.lams[il2], self.etas[ie2])))
        return out

    def covers(self, lam: float, eta: float) -> bool:
        return _within(lam, self.lams) and _within(eta, self.etas)

    def lookup(self, lam: float, eta: float) -> tuple[float, float]:
        """(k1, k2) at (λ, η) by bilinear interpolation in the grid cell around it.

        TableError outside the grid; TableJumpError in a cell with an edge across which the optimum
        jumps between basins (no interpolation there: see the module docstring)."""
        if not (np.isfinite(lam) and np.isfinite(eta)):
            raise TableError(f"lambda, eta = {lam!r}, {eta!r}: not finite")
        if not self.covers(lam, eta):
            raise TableError(
                f"(lambda, eta) = ({lam:.4g}, {eta:.4g}) is outside the 2-D table's grid "
                f"[{self.lams[0]:g}, {self.lams[-1]:g}] x [{self.etas[0]:g}, {self.etas[-1]:g}] ({self.source})"
            )
        il, wl = _cell(lam, self.lams)
        ie, we = _cell(eta, self.etas)
        if (ie, il) in self._jump_cells:  # type: ignore[attr-defined]
            raise TableJumpError(
                f"(lambda, eta) = ({lam:.4g}, {eta:.4g}): the optimum jumps between basins inside this cell of the "
                f"2-D table ({self.source}); not interpolated"
            )
        k1, k2 = self._bilinear(("k1", "k2"), il, wl, ie, we)
        return k1, k2

    def _bilinear(self, names: tuple[str, ...], il: int, wl: float, ie: int, we: float) -> list[float]:
        out = []
        il1, ie1 = min(il + 1, len(self.lams) - 1), min(ie + 1, len(self.etas) - 1)
        for name in names:
            g = self.grid(name)
            out.append(float(_lerp(_lerp(g[ie, il], g[ie, il1], wl), _lerp(g[ie1, il], g[ie1, il1], wl), we)))
        return out

    def lookup_polished(self, lam: float, eta: float) -> tuple[float, float, bool]:
        """(k1, k2, polished): :meth:`lookup`, then, for a tall move (λ < ``POLISH_LAMBDA``), a short bounded
        Nelder–Mead on F of Eq. (22) from the interpolated point (:meth:`polish`). There F is steep across a
        ridge and a k1 off by 1e-3 can cost 1 % of F (bench/bench_table2d.py); the polish only ever raises F,
        ~10–30 ms."""
        k1, k2 = self.lookup(lam, eta)
        if lam >= POLISH_LAMBDA:
            return k1, k2, False
        p1, p2, _ = self.polish(lam, eta, k1, k2)
        return p1, p2, (p1, p2) != (k1, k2)

    def best_in_cell(self, lam: float, eta: float, others: Sequence[tuple[float, float]] = ()) -> tuple[float, float]:
        """(k1, k2) at a (λ, η) in a cell beside a basin jump: the best of :meth:`polish` from each corner's
        optimum (each a global optimum of a nearby problem, so every basin near the cell is a start) and from
        ``others`` (e.g. the on-demand solve's answer)."""
        il, _ = _cell(lam, self.lams)
        ie, _ = _cell(eta, self.etas)
        starts = list(others)
        for de in (0, 1):
            for dl in (0, 1):
                e, l_ = min(ie + de, len(self.etas) - 1), min(il + dl, len(self.lams) - 1)
                k = (float(self.grid("k1")[e, l_]), float(self.grid("k2")[e, l_]))
                if all(max(abs(k[0] - s[0]), abs(k[1] - s[1])) > 1e-3 for s in starts):
                    starts.append(k)
        best = max((self.polish(lam, eta, *s) for s in starts), key=lambda r: r[2])
        return best[0], best[1]

    def polish(self, lam: float, eta: float, k1: float, k2: float) -> tuple[float, float, float]:
        """(k1, k2, F): a bounded Nelder–Mead on F of Eq. (22) at (λ, η) from (k1, k2), with the cell's
        interpolated normalisers a_min, j_min (smooth in λ and η, unlike the optimum) and the table's weights;
        never worse than the start."""
        from scipy.optimize import minimize

        from .bspline_optimum import fast_peaks

        il, wl = _cell(lam, self.lams)
        ie, we = _cell(eta, self.etas)
        a_min, j_min = self._bilinear(("a_min", "j_min"), il, wl, ie, we)
        wa, wj = _weights(self.meta)
        floor = float(self.meta.get("k2_floor", 1e-4))

        def neg_f(x: np.ndarray) -> float:
            _, a, j = fast_peaks(np.array([x[0]]), np.array([x[1]]), lam, eta)[0]
            return -(wa * a_min / a + wj * j_min / j)

        x0 = np.array([min(max(k1, 1e-3), 1 - 1e-3), min(max(k2, floor), 1 - 1e-3)])  # the build's bounds
        f0 = neg_f(x0)
        step = 2e-3
        res = minimize(neg_f, x0, method="Nelder-Mead", bounds=[(1e-3, 1 - 1e-3), (floor, 1 - 1e-3)],
                       options={"xatol": 1e-5, "fatol": 1e-9, "maxiter": 300,
                                "initial_simplex": np.array([x0, x0 + [step, 0.0], x0 + [0.0, step]])})
        if res.fun < f0:
            return float(res.x[0]), float(res.x[1]), -float(res.fun)
        return k1, k2, -f0


def _weights(meta: dict) -> tuple[float, float]:
    """The table's (w_a, w_j) of Eq. (22) from its header (default 0.5, 0.5)."""
    w = meta.get("weights", (0.5, 0.5))
    if isinstance(w, str):
        w = tuple(float(x) for x in w.split(","))
    return float(w[0]), float(w[1])


def _within(x: float, axis: Sequence[float]) -> bool:
    return axis[0] - 1e-9 <= x <= axis[-1] + 1e-9


def _lerp(a: float, b: float, w: float) -> float:
    return a if w == 0.0 else a + w * (b - a)


def _cell(x: float, axis: Sequence[float]) -> tuple[int, float]:
    """Index i of the cell [axis[i], axis[i+1]] holding x (clamped into the axis) and the weight of axis[i+1]."""
    n = len(axis)
    if n == 1 or x <= axis[0]:
        return 0, 0.0
    if x >= axis[-1]:
        return n - 2, 1.0
    i = bisect.bisect_right(axis, x) - 1
    return i, (x - axis[i]) / (axis[i + 1] - axis[i])


def find_jumps(k1: np.ndarray, k2: np.ndarray, threshold: float = JUMP_K) -> list[tuple[str, int, int]]:
    """Edges of the grid (k arrays (η, λ)) across which k1 or k2 changes by more than ``threshold``:
    ("lambda", iη, iλ) is the edge from λ[iλ] to λ[iλ+1] at η[iη]; ("eta", iη, iλ) from η[iη] to η[iη+1]."""
    out = []
    dl = np.maximum(np.abs(np.diff(k1, axis=1)), np.abs(np.diff(k2, axis=1)))
    de = np.maximum(np.abs(np.diff(k1, axis=0)), np.abs(np.diff(k2, axis=0)))
    out += [("lambda", int(i), int(j)) for i, j in zip(*np.nonzero(dl > threshold))]
    out += [("eta", int(i), int(j)) for i, j in zip(*np.nonzero(de > threshold))]
    return sorted(out, key=lambda e: (e[1], e[2], e[0]))


def _jump_cells(edges: list[tuple[str, int, int]], ne: int, nl: int) -> frozenset[tuple[int, int]]:
    """Cells (iη, iλ) (lower-left corner indices) that have a jump edge (a one-value axis has one cell 0)."""
    cells = set()
    for axis, ie, il in edges:
        if axis == "lambda":
            cells.update((i, il) for i in (ie - 1, ie) if 0 <= i < max(ne - 1, 1))
        else:
            cells.update((ie, j) for j in (il - 1, il) if 0 <= j < max(nl - 1, 1))
    return frozenset(cells)


# ----------------------------------------------------------------------------------------------- build


def settings_key_2d(settings: TableSettings, etas: Sequence[float]) -> str:
    """A short hash of everything that determines a row besides (λ, η)."""
    blob = json.dumps({"algorithm": ALGORITHM_VERSION, "grid": "2d", **asdict(replace(settings, eta=0.5))}, sort_keys=True)
    return hashlib.sha256(blob.encode()).hexdigest()[:16]


def read_checkpoint_2d(path: Path, settings: TableSettings) -> dict[tuple[float, float], TableRow]:
    """Rows of a 2-D checkpoint for the same settings, keyed by (η, λ); a line cut short by a kill is ignored."""
    key = settings_key_2d(settings, ())
    try:
        lines = path.read_text(encoding="utf-8").splitlines()
    except FileNotFoundError:
        return {}
    except (OSError, UnicodeDecodeError) as exc:
        raise TableError(f"checkpoint {path}: cannot read: {exc}") from None
    if not lines:
        return {}
    try:
        head = json.loads(lines[0])
    except json.JSONDecodeError:
        head = {}
    if not isinstance(head, dict) or head.get("checkpoint") != "pickplace build-table 2d":
        raise TableError(f"checkpoint {path}: line 1 is not a pickplace 2-D build-table checkpoint header; delete the file")
    if head.get("settings_key") != key:
        raise TableError(f"checkpoint {path}: settings_key = {head.get('settings_key')}: written for other settings "
                         f"({head.get('settings')}), this build has {key}; run without --resume to start over")
    rows: dict[tuple[float, float], TableRow] = {}
    for lineno, line in enumerate(lines[1:], 2):
        try:
            rec = json.loads(line)
            rows[(float(rec["eta"]), float(rec["lambda"]))] = TableRow(*(float(rec[c]) for c in COLUMNS))
        except (json.JSONDecodeError, KeyError, TypeError, ValueError):
            if lineno == len(lines):
                break
            raise TableError(f"checkpoint {path}:{lineno}: not a table row; delete the file") from None
        refuse_row_of_other_run(rec, key, path, lineno)
    return rows


def _open_checkpoint(path: Path, settings: TableSettings, append: bool) -> CheckpointWriter:
    head = {"checkpoint": "pickplace build-table 2d", "settings_key": settings_key_2d(settings, ()),
            "settings": asdict(replace(settings, eta=0.5)), "algorithm": ALGORITHM_VERSION}
    return CheckpointWriter(path, head, settings_key_2d(settings, ()), append)


def _optimise_chunk_2d(eta: float, lams: Sequence[float], settings: TableSettings) -> tuple[float, list[TableRow]]:
    """One task of a parallel 2-D build: the rows of ``lams`` at ``eta`` (module level: executors pickle it)."""
    return eta, _optimise_chunk(lams, replace(settings, eta=eta))


def run_build_2d(
    lams: Sequence[float],
    etas: Sequence[float],
    settings: TableSettings = TableSettings(),
    *,
    progress: Callable[[int, int], None] | None = None,
    workers: int = 1,
    executor: Executor | None = None,
    checkpoint: str | Path | None = None,
    resume: bool = False,
) -> tuple[Table2D, BuildReport]:
    """Optimal (k1*, k2*) at every (λ, η) of the grid: :func:`pickplace_cli.lookup.bspline_build.run_build` over η too.

    Tasks are (η, chunk of λ), η by η, so a worker mostly reuses its coarse grid of the previous task
    (the coarse stage depends on η). ``checkpoint``/``resume`` as in ``run_build`` (rows keyed by (η, λ))."""
    lams = [float(x) for x in lams]
    etas = [float(x) for x in etas]
    if not lams or not etas:
        raise TableError("grid: no (lambda, eta) values to build")
    ckpt = Path(checkpoint) if checkpoint is not None else None
    done: dict[tuple[float, float], TableRow] = {}
    if ckpt is not None and resume:
        saved = read_checkpoint_2d(ckpt, settings)
        done = {(e, lam): saved[(e, lam)] for e in etas for lam in lams if (e, lam) in saved}
    resumed, total = len(done), len(lams) * len(etas)
    parallel = executor is not None or workers > 1
    per_eta = max(1, math.ceil(8 * max(workers, 1) / len(etas))) if parallel else 1
    tasks = []
    for e in etas:
        todo = [lam for lam in lams if (e, lam) not in done]
        n = max(1, min(per_eta, len(todo)))
        tasks += [(e, tuple(todo[i::n])) for i in range(n) if todo[i::n]]
    if progress:
        progress(resumed, total)
    fh = _open_checkpoint(ckpt, settings, append=resume) if ckpt is not None else None

    def finish(eta: float, rows: list[TableRow]) -> None:
        for r in rows:
            done[(eta, r.lam)] = r
        if fh is not None:
            fh.add([{"eta": eta, **dict(zip(COLUMNS, (r.lam, r.k1, r.k2, r.a_max, r.j_max, r.v_max, r.F, r.a_min, r.j_min)))}
                    for r in rows])
        if progress:
            progress(len(done), total)

    pool, futures = None, []
    try:
        if tasks and parallel:
            from concurrent.futures import as_completed

            if executor is None:
                executor = pool = local_pool(workers)
            futures = [executor.submit(_optimise_chunk_2d, e, chunk, settings) for e, chunk in tasks]
            for fut in as_completed(futures):
                finish(*fut.result())
        else:
            for e, chunk in tasks:
                finish(*_optimise_chunk_2d(e, chunk, settings))
    finally:
        for fut in futures:
            fut.cancel()
        if pool is not None:
            pool.shutdown(wait=True, cancel_futures=True)
        if fh is not None:
            fh.close()
    meta = {"method": "bspline", **{k: v for k, v in asdict(settings).items() if k != "eta"}}
    meta["weights"] = list(settings.weights)
    table = Table2D(tuple(etas), tuple(lams), tuple(done[(e, lam)] for e in etas for lam in lams), meta=meta)
    computed = total - resumed
    return table, BuildReport(total, computed, resumed, len(tasks) if computed else 0, ckpt)


# ------------------------------------------------------------------------------------------------- I/O


def format_table_2d(table: Table2D, version: str, extra_meta: dict | None = None) -> str:
    """CSV text: ``#`` provenance lines (with the basin jumps), a header, one row per (η, λ), η-major."""
    meta = dict(table.meta)
    meta.update(extra_meta or {})
    meta["grid"] = f"{len(table.etas)} eta x {len(table.lams)} lambda"
    jumps = table.jumps
    meta["jump_threshold"] = JUMP_K
    meta["basin_jumps"] = "; ".join(
        f"({a[0]:.4g}, {a[1]:g})-({b[0]:.4g}, {b[1]:g})" for _, a, b in jumps) if jumps else "none"
    out = io.StringIO()
    out.write("# pickplace 2-D look-up table: optimal time-ratio factors of the quintic B-spline method over "
              "(lambda, eta) [Li2018, Eq. (20)-(22)]\n")
    out.write(f"# tool_version: {version}\n")
    write_meta(out, meta)
    out.write("# units: eta, lambda = b/h, k1, k2 dimensionless; v_max, a_max, j_max, a_min, j_min are the normalised\n")
    out.write("#   peaks |v|, |a|, |j| of the path with b = 1 m, T = 1 s (m/s, m/s^2, m/s^3); F dimensionless\n")
    out.write("#   basin_jumps are the grid edges (lambda, eta)-(lambda, eta) across which k1 or k2 changes by more than\n")
    out.write("#   jump_threshold; the cells beside them are not interpolated (plan solves those moves on demand)\n")
    out.write(",".join(COLUMNS_2D) + "\n")
    for e, r in zip((e for e in table.etas for _ in table.lams), table.rows):
        out.write(",".join(f"{x:.10g}" for x in (e, r.lam, r.k1, r.k2, r.a_max, r.j_max, r.v_max, r.F, r.a_min, r.j_min)) + "\n")
    return out.getvalue()


def parse_table_2d(text: str, source: str = "<table>") -> Table2D:
    """Read a table written by :func:`format_table_2d`; TableError (with file:line) on anything wrong."""

    def check(header: list[str], lineno: int) -> None:
        missing = [c for c in ("eta", "lambda", "k1", "k2") if c not in header]
        if missing:
            raise TableError(f"{source}:{lineno}: header lacks column(s) {', '.join(missing)} (need {', '.join(COLUMNS_2D)})")

    meta, header, numeric = read_numeric_table(text, source, check)
    if header is None or not numeric:
        raise TableError(f"{source}: no table rows (expected a header '{','.join(COLUMNS_2D)}' and data)")
    nan = float("nan")
    by_key: dict[tuple[float, float], TableRow] = {}
    for lineno, values in numeric:
        vals = dict(zip(header, values))
        for name in ("k1", "k2"):
            if not 0 < vals[name] < 1:
                raise TableError(f"{source}:{lineno}: {name} = {vals[name]:g}: must lie strictly between 0 and 1")
        key = (vals["eta"], vals["lambda"])
        if key in by_key:
            raise TableError(f"{source}:{lineno}: (eta, lambda) = ({key[0]:g}, {key[1]:g}) appears twice")
        by_key[key] = TableRow(*(vals.get(c, nan) for c in COLUMNS))
    etas = sorted({e for e, _ in by_key})
    lams = sorted({lam for _, lam in by_key})
    missing = [(e, lam) for e in etas for lam in lams if (e, lam) not in by_key]
    if missing:
        e, lam = missing[0]
        raise TableError(f"{source}: (eta, lambda) = ({e:g}, {lam:g}) is missing: the rows must fill the "
                         f"{len(etas)} eta x {len(lams)} lambda grid ({len(missing)} missing)")
    return Table2D(tuple(etas), tuple(lams), tuple(by_key[(e, lam)] for e in etas for lam in lams), meta, source)


@functools.lru_cache(maxsize=1)
def default_table_2d_path() -> Path:
    from ..model.resources import data_dir

    return data_dir("tables") / DEFAULT_TABLE_2D


def load_table_2d(path: str | Path | None = None) -> Table2D:
    """Read a 2-D table file (default: the shipped one); TableError when missing or corrupt."""
    p = Path(path) if path is not None else default_table_2d_path()
    source = f"{DEFAULT_TABLE_2D} (shipped)" if path is None else str(p)
    return read_table_file(p, parse_table_2d, source, "pickplace build-table --eta-min 0.1 --eta-max 0.9 --eta-step 0.05")  # type: ignore[return-value]
