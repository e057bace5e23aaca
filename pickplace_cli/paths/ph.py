"""Quintic Pythagorean-hodograph corners with the 3-4-5 law on arc length [Su2018, Sec. II].

The path A B C D E F G of [Su2018, Fig. 3] in the vertical plane of the move (local u along the move, v
up, origin at the pick point A): a vertical segment A→B of length j = h − m, a quintic PH corner B→C
that turns from vertical to horizontal within a box of width r and height m (Eq. 5–18), a horizontal
segment C→E of length w − 2r through the top point D, the mirrored corner E→F and the vertical segment
F→G. The 3-4-5 law runs on the total arc length l_all (Eq. 19–21); the curve parameter γ of a corner is
found from the arc length by inverting the quintic Eq. (17) (Newton with a bisection safeguard).

Interface
---------
* :func:`plan_ph` (``--method ph``) → CartesianPath. Parameters: ``m`` [m], vertical extent of the corners,
  0 < m ≤ h; ``r`` [m], horizontal extent, 0 < r ≤ w/2. Defaults m = h, r = w/2: the optimised trajectory
  of Sec. II.D (|AB| = |GF| = 0, |CE| = 0, two PH corners meeting at D). The path length l_all
  decreases in both m and r (``tests/papers/test_su2018.py``), so the defaults give the shortest path
  and, by Eq. (22), the shortest cycle time.
* ``path.peaks`` are the true maxima of ‖v‖, ‖a‖, ‖j‖ along the 3-D path (normal part κṡ² included),
  so ``--time auto`` holds the true acceleration norm to [a].
* The paper's own cycle time, Eq. (22), bounds only the tangential acceleration s̈ ≤ [a]:
  :func:`cycle_time_eq22` (the paper's closed form in h, w, m, r) and :func:`paper_duration`
  (``sqrt(10 l_all/(√3 [a]))`` for a task and capacity). ``path.parameters["a_max_tangential"]`` is
  the tangential peak 10/√3·l_all at T = 1 s, so T_paper = sqrt(a_max_tangential/[a]).

Notes on the paper
------------------
* Eq. (3) gives x′ = u² − v², y′ = 2uv; the control points of Eq. (7)–(12) (which are right: P0P1 is
  vertical, P4P5 horizontal) belong to x′ = 2uv, y′ = u² − v². We use the control points.
* Eq. (18) gives l_BC = u0²/5 + u0u2/15 + u2²/5 + v2²/5; Sec. II.B writes u0²/5 + u0u2/15 + 2u2²/5. They
  agree because u2 = v2 (Eq. 13, third line).
* With unequal pick and place heights (not in the paper) each corner spans its own end's rise by
  default (m_i = h_i, no vertical segment); a given m applies to both corners and must be ≤ the clearance h.
* The jerk is bounded but not continuous: the 3-4-5 law starts and stops with s‴ = 60 l_all, and at each
  join of two pieces dκ/ds changes (at D it changes sign by symmetry, Eq. 9 gives dκ/dγ ≠ 0 at γ = 1),
  so the normal jerk jumps by 2|dκ/ds|ṡ³ there. ``parameters["jerk_jumps_at"]`` lists those τ.
"""

from __future__ import annotations

import math

import numpy as np

from ..model.errors import TaskError
from ..curves.laws import POLY345
from ..model.task import Task
from ..model.trajectory import CartesianPath
from ._motion import ArcLengthPath, ParametricPiece, Placed, Segment, local_endpoints, sampled_peaks, to_cartesian

_P = np.polynomial.Polynomial


def ph_coefficients(m: float, r: float) -> tuple[float, float, float]:
    """(u0, u2, v2) of the corner that ends at (r, m) with zero end curvature [Su2018, Eq. (14)]."""
    if not (m > 0 and r > 0 and math.isfinite(m) and math.isfinite(r)):
        raise TaskError(f"m, r = {m!r}, {r!r}: the PH corner needs a vertical and a horizontal extent > 0 (m)")
    alpha = math.sqrt(m * m + r * r + 70.0 * m * r)
    u0 = math.sqrt(5.0 * (35.0 * m + r - alpha) / 34.0)
    u2 = math.sqrt(5.0 * (m + 35.0 * r - alpha) / 68.0)
    return u0, u2, u2  # v2 = u2 (Eq. 13, third line)


def ph_control_points(u0: float, u2: float, v2: float) -> np.ndarray:
    """The six Bézier control points P0 … P5 (6, 2) = (X, Y) of [Su2018, Eq. (12)] (u1 = v1 = v0 = 0)."""
    y1 = u0 * u0 / 5.0
    p3 = (u0 * v2 / 15.0, y1 + u0 * u2 / 15.0)
    p5 = (p3[0] + 2.0 * u2 * v2 / 5.0, p3[1] + (u2 * u2 - v2 * v2) / 5.0)
    return np.array([(0.0, 0.0), (0.0, y1), (0.0, y1), p3, p3, p5])


def ph_sigma(gamma: np.ndarray, u0: float, u2: float, v2: float) -> np.ndarray:
    """σ(γ) = ‖P′(γ)‖ = u² + v², as the quartic of [Su2018, Eq. (16)]."""
    g = np.asarray(gamma, float)
    c4 = u0 * u0 + 2 * u0 * u2 + u2 * u2 + v2 * v2
    return (((c4 * g - (4 * u0 * u0 + 4 * u0 * u2)) * g + (6 * u0 * u0 + 2 * u0 * u2)) * g - 4 * u0 * u0) * g + u0 * u0


def ph_arc_length(gamma: np.ndarray, u0: float, u2: float, v2: float) -> np.ndarray:
    """l(γ) = ∫₀^γ σ, the quintic of [Su2018, Eq. (17)]."""
    g = np.asarray(gamma, float)
    c4 = u0 * u0 + 2 * u0 * u2 + u2 * u2 + v2 * v2
    return ((((c4 / 5 * g - (4 * u0 * u0 + 4 * u0 * u2) / 4) * g + (6 * u0 * u0 + 2 * u0 * u2) / 3) * g - 2 * u0 * u0) * g + u0 * u0) * g


def ph_length(u0: float, u2: float, v2: float) -> float:
    """l_BC = u0²/5 + u0u2/15 + u2²/5 + v2²/5 [Su2018, Eq. (18)]."""
    return u0 * u0 / 5 + u0 * u2 / 15 + u2 * u2 / 5 + v2 * v2 / 5


def ph_curvature(gamma: np.ndarray, u0: float, u2: float, v2: float) -> np.ndarray:
    """Unsigned curvature κ(γ) = 4u0v2(γ − γ²)/σ² [Su2018, Eq. (9)] (1/m)."""
    g = np.asarray(gamma, float)
    return 4 * u0 * v2 * (g - g * g) / ph_sigma(g, u0, u2, v2) ** 2


class PHCorner(ParametricPiece):
    """The corner B→C in its own frame XOY of [Su2018, Fig. 4]: from (0, 0) heading +Y to (r, m) heading +X."""

    def __init__(self, m: float, r: float) -> None:
        self.m, self.r = float(m), float(r)
        self.u0, self.u2, self.v2 = ph_coefficients(self.m, self.r)
        cp = ph_control_points(self.u0, self.u2, self.v2)
        # Bernstein → power basis: B_i^5(γ) = C(5,i) γ^i (1-γ)^(5-i)
        basis = [math.comb(5, i) * _P([0, 1]) ** i * _P([1, -1]) ** (5 - i) for i in range(6)]
        xy = [sum((cp[i, d] * basis[i] for i in range(6)), _P([0.0])) for d in (0, 1)]
        # Horner tables, highest power first: _horner[k] has shape (6, 2) for the k-th derivative
        self._horner = []
        for k in range(4):
            c = np.zeros((6, 2))
            for d in (0, 1):
                ck = xy[d].deriv(k).coef[::-1] if k else xy[d].coef[::-1]
                c[6 - len(ck):, d] = ck
            self._horner.append(c)
        self.g0, self.g1 = 0.0, 1.0
        self.length = ph_length(self.u0, self.u2, self.v2)
        self._build_table(65)

    def curve(self, g: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        g = np.asarray(g, float)[:, None]
        out = []
        for c in self._horner:
            acc = np.zeros((g.shape[0], 2))
            for row in c:
                acc = acc * g + row
            out.append(acc)
        return tuple(out)  # type: ignore[return-value]

    def hodograph(self, g: np.ndarray) -> np.ndarray:
        """(x′, y′) = (2uv, u² − v²) with u = u0(1−γ)² + u2γ², v = v2γ² (Eq. 5 with u1 = v0 = v1 = 0)."""
        g = np.asarray(g, float)
        u = self.u0 * (1 - g) ** 2 + self.u2 * g * g
        v = self.v2 * g * g
        return np.column_stack([2 * u * v, u * u - v * v])

    def arclength(self, g: np.ndarray) -> np.ndarray:
        return ph_arc_length(g, self.u0, self.u2, self.v2)

    def speed(self, g: np.ndarray) -> np.ndarray:
        return ph_sigma(g, self.u0, self.u2, self.v2)


def path_length(h: float, w: float, m: float, r: float) -> float:
    """l_all = 2j + 2l_BC + w − 2r with j = h − m [Su2018, Eq. (20)] (m)."""
    return 2 * (h - m) + 2 * ph_length(*ph_coefficients(m, r)) + w - 2 * r


def cycle_time_eq22(h, w, a_max, m=None, r=None):
    """The paper's cycle time T = sqrt(10(2h + w + 4/34·ψ)/(√3 a_max)) [Su2018, Eq. (22)] (s).

    ψ = ζ − α + sqrt(0.5(β − αζ)), α = sqrt(m² + r² + 70mr), β = m² + r² + 36mr, ζ = m + r; defaults m = h,
    r = w/2. It bounds only the tangential acceleration of the 3-4-5 law (peak 10/√3·l_all/T²).
    Vectorised: h, w (m), a_max (m/s²), m, r may be arrays (float for scalars). β − αζ ≥ 0 in exact
    arithmetic; a round-off negative (at m = 0 or r = 0) is clipped to 0.
    """
    h, w = np.asarray(h, float), np.asarray(w, float)
    m = h if m is None else np.asarray(m, float)
    r = w / 2 if r is None else np.asarray(r, float)
    alpha = np.sqrt(m * m + r * r + 70 * m * r)
    beta = m * m + r * r + 36 * m * r
    zeta = m + r
    psi = zeta - alpha + np.sqrt(np.maximum(0.5 * (beta - alpha * zeta), 0.0))
    t = np.sqrt(10 * (2 * h + w + 4 / 34 * psi) / (math.sqrt(3) * np.asarray(a_max, float)))
    return float(t) if t.ndim == 0 else t


def _corner_params(task: Task, m: float | None, r: float | None) -> tuple[float, float, float, float, float, float]:
    b, h1, h2 = local_endpoints(task)
    if b <= 0:
        raise TaskError("from/to are vertically aligned (b = 0): a PH corner needs a horizontal move (method ph)")
    if r is None:
        r = b / 2
    if not (math.isfinite(r) and 0 < r <= b / 2 * (1 + 1e-12)):
        raise TaskError(f"r = {r!r}: the PH corner's horizontal extent must satisfy 0 < r ≤ w/2 = {b / 2:g} m")
    r = min(float(r), b / 2)
    if m is None:
        m1, m2 = h1, h2
    else:
        hmin = min(h1, h2)
        if not (math.isfinite(m) and 0 < m <= hmin * (1 + 1e-12)):
            raise TaskError(f"m = {m!r}: the PH corner's vertical extent must satisfy 0 < m ≤ h = {hmin:g} m")
        m1 = m2 = min(float(m), hmin)
    return b, h1, h2, m1, m2, r


def ph_path(task: Task, m: float | None = None, r: float | None = None) -> tuple[ArcLengthPath, dict]:
    """The local ArcLengthPath A…G and the points A…G (local (u, v), m) of [Su2018, Fig. 3]."""
    b, h1, h2, m1, m2, r = _corner_params(task, m, r)
    A, G = np.array([0.0, 0.0]), np.array([b, h1 - h2])
    B, C = np.array([0.0, h1 - m1]), np.array([r, h1])
    E, F = np.array([b - r, h1]), np.array([b, h1 - m2])
    D = np.array([b / 2, h1])
    c1 = PHCorner(m1, r)
    c2 = c1 if m2 == m1 else PHCorner(m2, r)
    pieces = [
        Placed(Segment(A, B)),
        Placed(c1, c=B),
        Placed(Segment(C, E)),
        Placed(c2, M=np.diag([-1.0, 1.0]), c=np.array([b, h1 - m2]), reverse=True),
        Placed(Segment(F, G)),
    ]
    return ArcLengthPath(pieces, POLY345), {"A": A, "B": B, "C": C, "D": D, "E": E, "F": F, "G": G, "corners": (c1, c2)}


def plan_ph(task: Task, m: float | None = None, r: float | None = None) -> CartesianPath:
    """CartesianPath of the PH method (``--method ph``); m, r in m (defaults m = h, r = w/2, Sec. II.D)."""
    arc, pts = ph_path(task, m, r)
    c1, c2 = pts["corners"]
    joints = arc.joints_tau()
    peaks = sampled_peaks(arc.derivatives, joints)
    L = arc.length
    params = {
        "m": c1.m,
        "r": c1.r,
        "u0": c1.u0,
        "u2": c1.u2,
        "v2": c1.v2,
        "l_bc_m": c1.length,
        "length_m": L,
        "law": POLY345.name,
        "a_max_tangential": POLY345.peak(2) * L,  # m at T = 1 s: Eq. (22) T = sqrt(this/[a])
        "continuity": 2,  # acceleration continuous (zero at the ends); the jerk jumps (see jerk_jumps_at)
        "jerk_jumps_at": [float(t) for t in joints],
    }
    if c2 is not c1:
        params.update({"m_place": c2.m, "l_bc_place_m": c2.length})
    return to_cartesian(task, arc, "ph", params, peaks, joints)


def paper_duration(task: Task, capacity, m: float | None = None, r: float | None = None) -> float:
    """T of [Su2018, Eq. (22)] for this task: sqrt(10 l_all/(√3 [a])) (s), tangential acceleration only.

    Equals :func:`cycle_time_eq22` for equal pick and place heights. ``capacity`` is a
    :class:`~pickplace_cli.model.profile.Capacity` (only [a] enters, as in the paper).
    """
    arc, _ = ph_path(task, m, r)
    return math.sqrt(POLY345.peak(2) * arc.length / capacity.acceleration)
