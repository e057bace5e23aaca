"""Look-up table of the conveyor-tracking B-spline's optimal shape [Yang2022, Eq. (37)], over the
dimensionless groups the optimum depends on (``curves.vel_problem.groups``).

Yang et al. train two neural networks because their interior-point solve takes minutes; here the exact
solve takes tens of milliseconds, and this table gives answers in well under a millisecond. The optimum
(τ6, τ7, τ9, τ10, λ1, λ2, λ3) of a move depends only on h/b, η and the end velocities times the duration
over the width, v0·T/b and v1·T/b, resolved along the move, across it and vertically (lengths scale out,
the base frame's orientation and origin do not matter, and v and T enter only as v·T). The table covers
the paper's setting — equal pick and place heights, horizontal conveyors (no vertical velocity) — for one
η, on a grid of

    h/b (geometric), v0_along, v0_across, v1_along, v1_across (uniform in [−V, V])

(the file holds one node per symmetry orbit, see below). The answer (:meth:`VelTable.lookup`) is the
better, by F estimated in one batch of the solver's evaluator, of two interpolants of the 32 corners of the
query's cell (h/b in log scale): plain multilinear, and multilinear with λ1, λ2, λ3 blended as the
via-point displacements they make (:meth:`VelTable.via_interpolate`).

**Accuracy, and why it is limited.** The optimum is a minimax point: several acceleration (or jerk)
peaks are equal there, so a shape that is optimal for a nearby problem loses F to *first* order in the
distance (one peak rises), and F has more than one local maximum, so the optimum also jumps. Measured:
moving one velocity group by 0.02 and keeping the old optimum loses 0.6 % of F (median), 5 % (worst);
averaging the exact optima at the 32 corners of a cell of half-width d around a point (2d in log h/b)
loses, at the point, 7.1 % median / 18 % worst (10 points) for d = 0.125 (this grid), 2.1 % / 11 % for
d = 0.0625 and 0.84 % / 5.7 % for d = 0.03125: first order in d, so no grid that builds in minutes holds
F within 1 % everywhere by interpolation. On the 200 held-out moves of ``bench/bench_conveyor.py`` (F
against the best exact solve; count within 1 %, median / 95th percentile / worst loss): multilinear 31/200,
2.78 / 10.5 / 26.8 %; via-point λ 37/200, 2.32 / 7.3 / 13.3 %; the better of the two (the answer) 40/200,
2.14 / 6.7 / 10.4 %, in 0.35 ms (median, load ~3 on 2 cores). Tried and worse: a tensor-product cubic spline
of the optima (5/200, worst 72 %: the optima have kinks and steep ramps between nodes), corner optima (best
of 32: 19/200), corner sensitivities (first-order Taylor blend, slopes by warm solves: 0/20 within 1 %,
median 9.4 %, against 2/20, 3.1 % multilinear; scratch script), a local SLSQP polish of the F stage (one
iteration 2.9 ms; converged, 20 ms, still 5/60 beyond 1 %); the rest by bench/bench_conveyor_table.py. The
exact answer stays fast: the table also stores each node's minimisers of a_max and j_max, and
``VelTable.seeds`` gives the interpolated and the 32 corner values of all three as starts for
``lookup.vel_solver.solve_seeded``.

Symmetries cut the build by four: mirroring the move in its vertical plane (across components negated)
leaves the optimum unchanged; running the move backwards (v0 ↔ v1 with along and across kept, since both
the velocity and the frame flip) maps τ6 ↔ 1 − τ10, τ7 ↔ 1 − τ9, λ1 ↔ λ3. Only one node of each orbit is
solved; tests check both symmetries on the exact solver.
"""

from __future__ import annotations

import io
import math
from collections.abc import Callable, Sequence
from dataclasses import asdict, dataclass, field
from pathlib import Path

import numpy as np

from ..model.errors import TableError

DEFAULT_VEL_TABLE = "bspline-vel-eta0.5.csv"
GROUP_AXES = ("h_over_b", "v0_along", "v0_across", "v1_along", "v1_across")
PARAM_COLUMNS = ("tau6", "tau7", "tau9", "tau10", "lambda1", "lambda2", "lambda3")
#: the minimisers of a_max and j_max (stage 1 of Eq. 37): starts for the exact solve's first stage
STAGE_COLUMNS = tuple(f"{c}_a" for c in PARAM_COLUMNS) + tuple(f"{c}_j" for c in PARAM_COLUMNS)
COLUMNS = GROUP_AXES + PARAM_COLUMNS + ("F", "a_min", "j_min") + STAGE_COLUMNS
#: the columns of tables written before the stage-1 minimisers were stored (still read)
COLUMNS_V1 = GROUP_AXES + PARAM_COLUMNS + ("F", "a_min", "j_min")
_CORNERS = np.array(np.meshgrid(*[[0, 1]] * 5, indexing="ij")).reshape(5, -1).T  # (32, 5) cell corners


@dataclass(frozen=True)
class VelGrid:
    """Grid of the table: ``h_count`` values of h/b from ``h_min`` to ``h_max`` (geometric) and
    ``v_count`` values of each velocity group from −``v_max`` to ``v_max`` (uniform, v·T/b)."""

    eta: float = 0.5
    h_min: float = 0.025
    h_max: float = 1.0
    h_count: int = 7
    v_max: float = 0.5
    v_count: int = 5
    margin: float = 0.01

    def __post_init__(self) -> None:
        if not (0 < self.eta < 1):
            raise TableError(f"eta = {self.eta!r}: the lift-off/set-down ratio must lie strictly between 0 and 1")
        if not (0 < self.h_min < self.h_max and self.h_count >= 2):
            raise TableError(f"h_over_b = {self.h_min!r}..{self.h_max!r} ({self.h_count}): need 0 < min < max, ≥ 2 values")
        if not (self.v_max > 0 and self.v_count >= 2):
            raise TableError(f"v_max = {self.v_max!r} ({self.v_count}): need v_max > 0 and ≥ 2 values")

    def axes(self) -> list[np.ndarray]:
        h = np.geomspace(self.h_min, self.h_max, self.h_count)
        v = np.linspace(-self.v_max, self.v_max, self.v_count)
        return [h, v, v, v, v]


# ------------------------------------------------------------------------------------------- symmetries


def mirror_index(idx: tuple[int, ...], n_v: int) -> tuple[int, ...]:
    """Node index of the mirrored move (across components negated): same optimum."""
    h, a0, c0, a1, c1 = idx
    return (h, a0, n_v - 1 - c0, a1, n_v - 1 - c1)


def swap_index(idx: tuple[int, ...]) -> tuple[int, ...]:
    """Node index of the reversed move (v0 ↔ v1): optimum mapped by :func:`reverse_params`."""
    h, a0, c0, a1, c1 = idx
    return (h, a1, c1, a0, c0)


def reverse_params(p: Sequence[float]) -> tuple[float, ...]:
    """Shape parameters of the time-reversed move: knots τ → 1 − τ (in reverse order), λ1 ↔ λ3."""
    t6, t7, t9, t10, l1, l2, l3 = p
    return (1 - t10, 1 - t9, 1 - t7, 1 - t6, l3, l2, l1)


def _orbit(idx: tuple[int, ...], n_v: int) -> list[tuple[tuple[int, ...], bool]]:
    """(node, reversed?) of every image of ``idx`` under the two symmetries."""
    m = mirror_index(idx, n_v)
    return [(idx, False), (m, False), (swap_index(idx), True), (swap_index(m), True)]


# ------------------------------------------------------------------------------------------------ build


@dataclass(frozen=True)
class VelTable:
    """The grid and, per node, the optimum: ``params`` (shape + (7,)), ``F``, ``a_min``, ``j_min``
    (a_min, j_min are the normalisers of F for the move scaled to b = 1 m, T = 1 s), and the stage-1
    minimisers ``params_a``, ``params_j`` (shape + (7,); None in tables written without them)."""

    grid: VelGrid
    params: np.ndarray
    F: np.ndarray
    a_min: np.ndarray
    j_min: np.ndarray
    meta: dict = field(default_factory=dict)
    source: str = "<memory>"
    params_a: np.ndarray | None = None
    params_j: np.ndarray | None = None

    def __post_init__(self) -> None:
        axes = self.grid.axes()
        object.__setattr__(self, "_axes", axes)
        object.__setattr__(self, "_scaled", [np.log(axes[0])] + axes[1:])  # h/b interpolated in log scale
        shape = tuple(len(a) for a in axes)
        if self.params.shape != shape + (7,):
            raise TableError(f"{self.source}: parameters have shape {self.params.shape}, the grid needs {shape + (7,)}")
        for name in ("params_a", "params_j"):
            arr = getattr(self, name)
            if arr is not None and arr.shape != shape + (7,):
                raise TableError(f"{self.source}: {name} has shape {arr.shape}, the grid needs {shape + (7,)}")
        if not np.all(np.isfinite(self.params)):
            raise TableError(f"{self.source}: a parameter is not a finite number")

    # -------------------------------------------------------------------------------------- lookup
    def query_groups(self, task, duration: float) -> np.ndarray:
        """The five table groups of ``task`` at ``duration`` (TableError when the table does not apply)."""
        from ..curves.vel_problem import groups

        g = groups(task, duration)
        if abs(g["eta"] - self.grid.eta) > 1e-9:
            raise TableError(
                f"eta = {g['eta']:g}: the table {self.source} was built for eta = {self.grid.eta:g}; "
                f"build one with `pickplace build-table --method bspline-vel --eta {g['eta']:g}` or use the exact solver"
            )
        if abs(g["dz_over_b"]) > 1e-9:
            raise TableError(
                f"from/to heights differ (Δz/b = {g['dz_over_b']:.3g}): the table covers equal-height moves "
                "[Yang2022, Sec. 2.2]; use the exact solver"
            )
        for end in ("v0", "v1"):
            if abs(g[f"{end}_vertical"]) > 1e-12:
                raise TableError(
                    f"{end} vertical = {g[f'{end}_vertical']:.3g} (v·T/b): the table covers horizontal conveyors; "
                    "use the exact solver"
                )
        x = np.array([g[a] for a in GROUP_AXES])
        for name, value, axis in zip(GROUP_AXES, x, self._axes):  # type: ignore[attr-defined]
            if not (axis[0] * (1 - 1e-12) - 1e-12 <= value <= axis[-1] * (1 + 1e-12) + 1e-12):
                raise TableError(
                    f"{name} = {value:.4g} is outside the table's range [{axis[0]:g}, {axis[-1]:g}] ({self.source}); "
                    "use the exact solver or build a wider table (pickplace build-table --method bspline-vel)"
                )
        return x

    def _cell(self, x: np.ndarray) -> tuple[list[np.ndarray], np.ndarray]:
        """Corner indices (32, 5) and multilinear weights (32,) of the cell holding ``x``."""
        idx, frac = [], []
        for k, a in enumerate(self._scaled):  # type: ignore[attr-defined]
            v = math.log(x[k]) if k == 0 else float(x[k])
            i = min(max(int(np.searchsorted(a, v, side="right")) - 1, 0), len(a) - 2)
            idx.append(i)
            frac.append(min(max((v - a[i]) / (a[i + 1] - a[i]), 0.0), 1.0))
        f = np.array(frac)
        w = np.prod(np.where(_CORNERS == 1, f, 1.0 - f), axis=1)
        return [_CORNERS[:, k] + idx[k] for k in range(5)], w

    def interpolate(self, x: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, float, float]:
        """(interpolated params (7,), corner params (32, 7), weights (32,), a_min, j_min) at groups ``x``."""
        at, w = self._cell(x)
        corner = self.params[tuple(at)]
        return w @ corner, corner, w, float(w @ self.a_min[tuple(at)]), float(w @ self.j_min[tuple(at)])

    def seeds(self, task, duration: float) -> dict[str, np.ndarray]:
        """Starts for the exact solve of ``task`` in ``duration`` seconds, one (k, 7) array per stage of
        Eq. (37) ("a", "j": the minimisers of a_max, j_max; "F": the optimum), interpolated one first, then
        the cell's 32 corner values (each a node's exact optimum). Tables without stage-1 columns give the
        F values for all three."""
        x = self.query_groups(task, duration)
        at, w = self._cell(x)
        out = {}
        for kind, arr in (("a", self.params_a), ("j", self.params_j), ("F", self.params)):
            corner = (self.params if arr is None else arr)[tuple(at)]
            p = w @ corner
            p[:4] = _order_knots(p[:4], self.grid.margin)
            out[kind] = np.vstack([p[None, :], corner])
        return out

    def via_interpolate(self, x: np.ndarray, at: list[np.ndarray] | None = None, w: np.ndarray | None = None) -> np.ndarray:
        """Parameters (7,) at groups ``x`` with λ1, λ2, λ3 interpolated as the via-point displacements they
        make, not as numbers: λ_i moves via point i by λ_i·o_i, o_i = v0·T/b, (v0 − v1)·T/b/2, −v1·T/b
        [Yang2022, Eq. (25)–(27)] (horizontal, (along, across)). The corners' displacements λ_i·o_i (each
        with its own o_i) are blended multilinearly and projected on the query's o_i: λ_i = d_i·o_i/|o_i|²
        (clipped to [0, 1]; the multilinear λ_i where o_i = 0, where λ_i does not change the path). A λ of
        a corner whose offset is short moves the path little however large it is, so it no longer pulls the
        blend (multilinear λ: 31/200 held-out moves within 1 % of the exact F, worst loss 26.8 %; this:
        37/200, worst 13.3 %). Knots are multilinear as in :meth:`interpolate`."""
        if at is None or w is None:
            at, w = self._cell(x)
        corner = self.params[tuple(at)]
        p = w @ corner
        axes = self._axes  # type: ignore[attr-defined]
        cv = [axes[k][at[k]] for k in range(1, 5)]  # corner groups (32,) each: v0 along/across, v1 along/across
        v0, v1 = np.stack(cv[:2], axis=1), np.stack(cv[2:], axis=1)
        off = np.stack([v0, (v0 - v1) / 2, -v1], axis=1)  # (32, 3, 2)
        d = np.einsum("c,ci,cid->id", w, corner[:, 4:], off)  # blended displacement of each via point (3, 2)
        q0, q1 = np.asarray(x[1:3], float), np.asarray(x[3:5], float)
        o = np.stack([q0, (q0 - q1) / 2, -q1])
        oo = np.einsum("id,id->i", o, o)
        ok = oo > 1e-12
        lam = np.where(ok, np.einsum("id,id->i", d, o) / np.where(ok, oo, 1.0), p[4:])
        p[4:] = np.clip(lam, 0.0, 1.0)
        p[:4] = _order_knots(p[:4], self.grid.margin)
        return p

    def candidates(self, task, duration: float) -> tuple[np.ndarray, np.ndarray]:
        """(candidates (2, 7), sampled F (2,)) of ``task`` in ``duration`` seconds: the via-point
        interpolation (:meth:`via_interpolate`) and the multilinear one, with F = a_min/a_max + j_min/j_max
        estimated in one batch of the solver's evaluator (‖a‖, ‖j‖ at 8 points per knot span; a_min, j_min
        interpolated from the cell's corners)."""
        from ..curves.vel_problem import _Evaluator, _grid, make_problem

        x = self.query_groups(task, duration)
        at, w = self._cell(x)
        lin = w @ self.params[tuple(at)]
        lin[:4] = _order_knots(lin[:4], self.grid.margin)
        cand = np.vstack([self.via_interpolate(x, at, w), lin])
        ga, gj = _Evaluator(make_problem(task, duration)).sampled(cand, *_grid(8))
        a_min, j_min = float(w @ self.a_min[tuple(at)]), float(w @ self.j_min[tuple(at)])
        return cand, a_min / np.sqrt(ga.max(axis=1)) + j_min / np.sqrt(gj.max(axis=1))

    def lookup(self, task, duration: float) -> tuple[float, ...]:
        """Shape parameters (τ6, τ7, τ9, τ10, λ1, λ2, λ3) for ``task`` run in ``duration`` seconds: of the
        two interpolants of the query's cell (:meth:`candidates`: λ as via-point displacements, and plain
        multilinear; h/b in log scale) the one with the larger estimated F. Held-out accuracy and cost:
        module docstring."""
        cand, f = self.candidates(task, duration)
        return tuple(float(c) for c in cand[int(np.argmax(f))])


def _order_knots(t: np.ndarray, margin: float) -> np.ndarray:
    """Keep interpolated knots in the order of Eq. (36) (a convex combination of ordered knot vectors is
    ordered; this only guards round-off)."""
    t = t.copy()
    t[0] = max(t[0], margin * 0.5)
    t[1] = min(max(t[1], t[0] + 1e-9), 0.5 - 1e-9)
    t[2] = max(t[2], 0.5 + 1e-9)
    t[3] = min(max(t[3], t[2] + 1e-9), 1 - margin * 0.5)
    return t


def solve_node(args: tuple) -> tuple[tuple[int, ...], tuple[float, ...], float, float, float]:
    """Exact optimum at one grid node (runs in a worker process): (node, params, F, a_min, j_min), the
    normalisers for b = 1 m, T = 1 s."""
    from ..curves.vel_problem import VelSettings, make_problem, task_from_groups
    from .vel_solver import solve

    idx, groups, eta, settings = args
    g = dict(zip(GROUP_AXES, groups), eta=eta)
    task = task_from_groups(g, b=1.0, duration=1.0)
    prob = make_problem(task, 1.0)
    res = solve(prob, settings or VelSettings())
    return idx, res.params, res.F, res.a_min * prob.scale, res.j_min * prob.scale, res.params_a, res.params_j


def _solve_chunk(items: list[tuple]) -> list[tuple]:
    return [solve_node(a) for a in items]


def build_vel_table(
    grid: VelGrid = VelGrid(),
    settings=None,
    workers: int = 1,
    progress: Callable[[int, int], None] | None = None,
    chunk: int = 8,
) -> VelTable:
    """Solve the optimum at one node of every symmetry orbit of ``grid`` (exact solver, ``settings`` a
    ``VelSettings`` whose margin is replaced by the grid's) and fill the others by symmetry.

    ``workers`` > 1 uses a process pool (concurrent.futures); ``progress(done, total)`` is called as
    chunks of ``chunk`` nodes finish. The result does not depend on ``workers``.
    """
    from dataclasses import replace

    from ..curves.vel_problem import VelSettings

    settings = replace(settings or VelSettings(), margin=grid.margin)
    axes = grid.axes()
    shape = tuple(len(a) for a in axes)
    n_v = grid.v_count
    reps: dict[tuple[int, ...], tuple[int, ...]] = {}
    for idx in np.ndindex(*shape):
        rep = min(i for i, _ in _orbit(idx, n_v))
        reps[idx] = rep
    todo = sorted(set(reps.values()))
    items = [(idx, tuple(float(axes[k][i]) for k, i in enumerate(idx)), grid.eta, settings) for idx in todo]
    chunks = [items[i : i + chunk] for i in range(0, len(items), chunk)]
    results: dict[tuple[int, ...], tuple] = {}
    total = len(items)
    done = 0
    if workers > 1:
        from concurrent.futures import as_completed

        from .executors import local_pool

        with local_pool(workers) as pool:  # Ctrl-C: the parent's
            futures = [pool.submit(_solve_chunk, c) for c in chunks]
            try:
                for fut in as_completed(futures):
                    for r in fut.result():
                        results[r[0]] = r[1:]
                    done += len(fut.result())
                    if progress:
                        progress(done, total)
            except BaseException:
                for f in futures:
                    f.cancel()
                raise
    else:
        for c in chunks:
            for r in _solve_chunk(c):
                results[r[0]] = r[1:]
            done += len(c)
            if progress:
                progress(done, total)
    params, F, a_min, j_min, params_a, params_j = _fill_by_symmetry(grid, results)
    meta = {"method": "bspline-vel", "solved_nodes": len(todo), "nodes": int(np.prod(shape)),
            "solver": {k: v for k, v in asdict(settings).items()}}
    return VelTable(grid, params, F, a_min, j_min, meta, params_a=params_a, params_j=params_j)


def _fill_by_symmetry(grid: VelGrid, known: dict) -> tuple[np.ndarray, ...]:
    """Full arrays (params, F, a_min, j_min, params_a, params_j) from the values at one node of every orbit
    (``known``: node → (params, F, a_min, j_min[, params_a, params_j])); TableError when an orbit has no
    known node. params_a, params_j are None when the rows have none."""
    shape = tuple(len(a) for a in grid.axes())
    params = np.empty(shape + (7,))
    F, a_min, j_min = np.empty(shape), np.empty(shape), np.empty(shape)
    staged = all(len(v) == 6 for v in known.values())
    stage = [np.empty(shape + (7,)), np.empty(shape + (7,))] if staged else None
    for idx in np.ndindex(*shape):
        for node, rev in _orbit(idx, grid.v_count):
            if node in known:
                p, f, am, jm = known[node][:4]
                # node → idx by the same map (each map is its own inverse); the stage-1 minimisers too
                params[idx] = reverse_params(p) if rev else p
                F[idx], a_min[idx], j_min[idx] = f, am, jm
                if stage is not None:
                    for arr, q in zip(stage, known[node][4:]):
                        arr[idx] = reverse_params(q) if rev else q
                break
        else:
            raise TableError(f"node {idx} of the grid has no row (nor a symmetric one)")
    return (params, F, a_min, j_min) + (tuple(stage) if stage is not None else (None, None))


# -------------------------------------------------------------------------------------------------- I/O


def default_vel_table_path() -> Path:
    from ..model.resources import data_dir

    return data_dir("tables") / DEFAULT_VEL_TABLE


def format_vel_table(table: VelTable, version: str, extra_meta: dict | None = None) -> str:
    """CSV text: ``#`` provenance lines, a header, one row per node (fixed format, deterministic)."""
    g = table.grid
    meta = dict(table.meta)
    meta.update(extra_meta or {})
    out = io.StringIO()
    out.write("# pickplace look-up table: optimal shape of the conveyor-tracking quintic B-spline [Yang2022, Eq. (37)]\n")
    out.write(f"# tool_version: {version}\n")
    out.write("# method: bspline-vel\n")
    for key in ("eta", "h_min", "h_max", "h_count", "v_max", "v_count", "margin"):
        out.write(f"# {key}: {getattr(g, key):g}\n")
    for key in sorted(meta):
        if key == "method":
            continue
        val = meta[key]
        if isinstance(val, dict):
            val = ", ".join(f"{k}={v}" for k, v in val.items())
        out.write(f"# {key}: {val}\n")
    out.write("# grid: h_over_b geometric from h_min to h_max (h_count values); each v group uniform in [-v_max, v_max]\n")
    out.write("# units: h_over_b = h/b; v0_along … v1_across = v·T/b (v [m/s] resolved along the move e_u, across it\n")
    out.write("#   e_z × e_u; T [s]; b [m]); tau*, lambda* dimensionless; F dimensionless (≤ 2); a_min, j_min the\n")
    out.write("#   minima of a_max, j_max for the move scaled to b = 1 m, T = 1 s (m/s^2, m/s^3)\n")
    out.write("# equal pick/place heights, horizontal conveyor velocities. One row per symmetry orbit (the node with\n")
    out.write("#   the smallest grid index); the reader fills the mirrored (across negated) and reversed (v0 <-> v1:\n")
    out.write("#   tau6 <-> 1-tau10, tau7 <-> 1-tau9, lambda1 <-> lambda3) nodes\n")
    staged = table.params_a is not None and table.params_j is not None
    if staged:
        out.write("# *_a, *_j: the minimisers of a_max and of j_max (stage 1 of Eq. 37), starts for the exact solve\n")
    out.write(",".join(COLUMNS if staged else COLUMNS_V1) + "\n")
    axes = g.axes()
    for idx in np.ndindex(*table.F.shape):
        if min(i for i, _ in _orbit(idx, g.v_count)) != idx:
            continue
        vals = [axes[k][i] for k, i in enumerate(idx)] + list(table.params[idx]) + [
            table.F[idx], table.a_min[idx], table.j_min[idx]]
        if staged:
            vals += list(table.params_a[idx]) + list(table.params_j[idx])  # type: ignore[index]
        out.write(",".join(f"{v:.9g}" for v in vals) + "\n")
    return out.getvalue()


def parse_vel_table(text: str, source: str = "<table>") -> VelTable:
    """Read a table written by :func:`format_vel_table`; TableError (with file:line) on anything wrong."""
    from .bspline_table import read_numeric_table

    def check(header: list[str], lineno: int) -> None:
        if tuple(header) not in (COLUMNS, COLUMNS_V1):
            raise TableError(f"{source}:{lineno}: header must be {','.join(COLUMNS)}")

    meta, _, numeric = read_numeric_table(text, source, check)
    rows = [vals for _, vals in numeric]
    if meta.get("method") != "bspline-vel":
        raise TableError(f"{source}: not a bspline-vel table (no '# method: bspline-vel' line)")
    try:
        grid = VelGrid(
            eta=float(meta["eta"]), h_min=float(meta["h_min"]), h_max=float(meta["h_max"]),
            h_count=int(meta["h_count"]), v_max=float(meta["v_max"]), v_count=int(meta["v_count"]),
            margin=float(meta["margin"]),
        )
    except KeyError as exc:
        raise TableError(f"{source}: header line '# {exc.args[0]}: VALUE' is missing") from None
    except ValueError as exc:
        raise TableError(f"{source}: a grid value in the header is not a number ({exc})") from None
    axes = grid.axes()
    known: dict = {}
    for vals in rows:
        idx = []
        for k, axis in enumerate(axes):
            i = int(np.argmin(np.abs(axis - vals[k])))
            if not math.isclose(axis[i], vals[k], rel_tol=1e-7, abs_tol=1e-9):
                raise TableError(f"{source}: {GROUP_AXES[k]} = {vals[k]:g} is not a value of the grid in the header")
            idx.append(i)
        known[tuple(idx)] = (tuple(vals[5:12]), vals[12], vals[13], vals[14]) + (
            (tuple(vals[15:22]), tuple(vals[22:29])) if len(vals) == len(COLUMNS) else ())
    params, F, a_min, j_min, params_a, params_j = _fill_by_symmetry(grid, known)
    return VelTable(grid, params, F, a_min, j_min, dict(meta), source, params_a, params_j)


def load_vel_table(path: str | Path | None = None) -> VelTable:
    """Read a bspline-vel table file (default: the shipped one); TableError when missing or corrupt."""
    from .bspline_table import read_table_file

    p = Path(path) if path is not None else default_vel_table_path()
    return read_table_file(p, parse_vel_table, str(p), "pickplace build-table --method bspline-vel")  # type: ignore[return-value]
