"""Clavel Delta robot (3 translational DOF): closed-form kinematics, analytic joint derivatives and a
lumped-mass inverse dynamics model.

References
----------
[Clavel1988]  R. Clavel, "DELTA, a fast robot with parallel geometry", Proc. 18th Int. Symp. on
              Industrial Robots, 1988.
[Codourey1998] A. Codourey, "Dynamic modeling of parallel robots for computed-torque control
              implementation", Int. J. Robotics Research 17(12), 1998.
[Su2018]      the prototype whose dimensions the tests use (R = 0.150, r = 0.051, L = 0.325, l = 0.800 m),
              as quoted in the project's task description.

Conventions (SI units: m, rad, s, kg, N, N·m; the tests rely on every line of this list)
-------------------------------------------------------------------------------------
* Base frame at the centre of the fixed platform, z up; the workspace lies at z < 0.
* Arm i = 1, 2, 3 sits at φ_i = 0°, 120°, 240° from +x (arm 1 on +x). Its motor axis is tangential
  (perpendicular to the radial direction) at distance ``R`` from the centre.
* q_i = 0: upper arm horizontal, pointing radially outwards; q_i > 0 rotates it DOWNWARDS.
* Elbow of arm i:            E_i(q_i) = Rz(φ_i) · (R + L cos q_i, 0, −L sin q_i)
* Platform joint of arm i:   C_i(p)   = p + Rz(φ_i) · (r, 0, 0)
* Loop closure:              f_i = ‖d_i‖² − l² = 0,  d_i = C_i − E_i  (the forearm vector, elbow → platform)
* Inverse kinematics returns the knee-OUT branch (elbow outside, the usual working branch); on it
  d_i · E_i′ > 0 for every arm. Forward kinematics returns the platform *below* the elbows (lower z).

In arm i's own frame (rotate by −φ_i), with (x′, y′, z) = Rz(−φ_i) p and a = x′ − (R − r):
    d_i = (a − L cos q, y′, z + L sin q),   E′ = (−L sin q, 0, −L cos q),
    E″ = (−L cos q, 0, L sin q),            E‴ = −E′.

Implementation note: internally every arm-wise quantity is a (3, N) array (axis 0 arm, axis 1 sample) so
numpy's inner loops run over the long sample axis; public inputs and outputs keep axis 0 = samples.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import ClassVar

import numpy as np

from ..model.errors import UnreachableError

#: arm angles φ_i [rad]: arm 1 on +x, then 120° and 240°
PHI = np.deg2rad([0.0, 120.0, 240.0])
_COS_PHI = np.cos(PHI)[:, None]  # (3, 1): broadcasts against (3, N) arm-major arrays
_SIN_PHI = np.sin(PHI)[:, None]
#: rows 0–2 give the radial, rows 3–5 the tangential in-plane component of a vector, per arm
_ROT = np.concatenate((np.stack((np.cos(PHI), np.sin(PHI)), axis=1), np.stack((-np.sin(PHI), np.cos(PHI)), axis=1)))
_NEXT = [1, 2, 0]  # arm i+1 (cyclic)
_NEXT2 = [2, 0, 1]  # arm i+2 (cyclic)


def _samples(x: np.ndarray, name: str, width: int = 3) -> np.ndarray:
    """``x`` as a float (N, width) array, or ValueError saying which argument has which wrong shape."""
    arr = np.asarray(x, dtype=float)
    if arr.ndim != 2 or arr.shape[1] != width:
        raise ValueError(f"{name} must have shape (N, {width}), got {arr.shape}")
    return arr


def _check_positive(obj: object, names: tuple[str, ...]) -> None:
    for name in names:
        value = getattr(obj, name)
        if not (math.isfinite(value) and value > 0.0):
            raise ValueError(f"{type(obj).__name__}.{name} = {value!r} is not physical: must be finite and > 0")


def _check_non_negative(obj: object, names: tuple[str, ...]) -> None:
    for name in names:
        value = getattr(obj, name)
        if not (math.isfinite(value) and value >= 0.0):
            raise ValueError(f"{type(obj).__name__}.{name} = {value!r} is not physical: must be finite and >= 0")


def _local(x: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Radial, tangential (each (3, N)) and vertical ((N,)) components of vectors x (N, 3) in each arm's frame."""
    rt = _ROT @ x[:, :2].T
    return rt[:3], rt[3:], x[:, 2]


def _gram_extremes(d: np.ndarray, det_a: np.ndarray, l2: float | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Smallest and largest eigenvalue (N,) of the Gram matrix G = AAᵀ whose rows are the forearm vectors
    d[:, i] (``d`` (3 components, 3 arms, N); ``det_a`` = det A (N,)), in closed form (trigonometric solution
    of the characteristic cubic of a symmetric 3×3 matrix, B = G − mI with m = tr G / 3; Smith 1961).

    ``l2``: when every forearm has length l (q and p from the inverse kinematics), the diagonal of G is
    l² and B has a zero diagonal, so the cubic needs only the dot products g_ij = d_i·d_j of different
    arms. Without it (any q, p a caller passes) the diagonal is computed. The largest eigenvalue comes from
    the cubic, the smallest from λ_min λ_mid = det G / λ_max and λ_min + λ_mid = tr G − λ_max in the
    cancellation-free form."""
    g = (d[:, _GRAM_I] * d[:, _GRAM_J]).sum(axis=0)  # (3, N): g01, g02, g12
    if l2 is not None:
        m = l2
        pp = np.sqrt(np.maximum((g * g).sum(axis=0) / 3.0, 1e-300))  # √(tr B² / 6)
        half_det = g.prod(axis=0) / (pp * pp * pp)  # det(B/pp) / 2 = g01 g02 g12 / pp³
    else:
        diag = (d * d).sum(axis=0)  # (3, N): g00, g11, g22
        m = diag.sum(axis=0) / 3.0
        a0, a1, a2 = diag - m
        g01, g02, g12 = g
        pp = np.sqrt(np.maximum((a0 * a0 + a1 * a1 + a2 * a2 + 2.0 * (g * g).sum(axis=0)) / 6.0, 1e-300))
        det_b = a0 * (a1 * a2 - g12 * g12) - g01 * (g01 * a2 - g12 * g02) + g02 * (g01 * g12 - a1 * g02)
        half_det = det_b / (2.0 * pp * pp * pp)
    phi = np.arccos(np.minimum(np.maximum(half_det, -1.0), 1.0)) / 3.0
    hi = m + 2.0 * pp * np.cos(phi)
    prod = det_a * det_a / hi  # det G = (det A)²
    rest = 3.0 * m - hi
    lo = 2.0 * prod / (rest + np.sqrt(np.maximum(rest * rest - 4.0 * prod, 0.0)))
    return lo, hi


_GRAM_I = np.array([0, 0, 1])  # the off-diagonal entries (0,1), (0,2), (1,2) of G
_GRAM_J = np.array([1, 2, 2])
#: gather indices of the reciprocal basis c[k, i] = d[k+1, i+1] d[k+2, i+2] − d[k+2, i+1] d[k+1, i+2]
#: (component k, arm i, indices mod 3): the four factors in one fancy index, (4, 3, 3)
_K = np.arange(3)[:, None]
_I = np.arange(3)[None, :]
_CROSS_ROWS = np.stack(np.broadcast_arrays((_K + 1) % 3, (_K + 2) % 3, (_K + 2) % 3, (_K + 1) % 3))
_CROSS_COLS = np.stack(np.broadcast_arrays((_I + 1) % 3, (_I + 2) % 3, (_I + 1) % 3, (_I + 2) % 3))
del _K, _I


class _Arms:
    """Arm-wise quantities of one (q, p) configuration, each (3, N): cos q, sin q and the forearm vector d in
    the arm frame (radial dr, tangential dt, vertical dz), D = d·E′ and D2 = d·E″ (see module docstring).
    ``rates``: (v_r, v_t, v_z, ḋ_r, ḋ_z) once :meth:`DeltaRobot._joint_rates` ran (the torque rates reuse them)."""

    __slots__ = ("c", "s", "dr", "dt", "dz", "D", "D2", "_base", "_recip", "rates")

    def __init__(self, L: float, c: np.ndarray, s: np.ndarray, dr: np.ndarray, dt: np.ndarray, dz: np.ndarray,
                 D: np.ndarray | None = None, D2: np.ndarray | None = None):
        self.c, self.s, self.dr, self.dt, self.dz = c, s, dr, dt, dz
        self.D = -L * (s * dr + c * dz) if D is None else D
        self.D2 = L * (s * dz - c * dr) if D2 is None else D2
        self._base = None
        self._recip = None
        self.rates = None

    def base_frame(self) -> np.ndarray:
        """d in the base frame, (3 components x, y, z; 3 arms; N) (computed once per configuration)."""
        if self._base is None:
            d = np.empty((3, *self.dr.shape))
            d[0] = self.dr * _COS_PHI - self.dt * _SIN_PHI
            d[1] = self.dr * _SIN_PHI + self.dt * _COS_PHI
            d[2] = self.dz
            self._base = d
        return self._base


@dataclass(frozen=True)
class DeltaRobot:
    """Clavel Delta robot [Clavel1988] with a rigid-body dynamic model (default) or the lumped-mass model of
    [Codourey1998] (``dynamics="lumped"``).

    Geometry [m]: ``R`` fixed-platform radius (centre → motor axis), ``r`` moving-platform radius
    (platform centre → forearm joint line), ``L`` upper-arm length (motor axis → elbow), ``l`` forearm
    (parallelogram) length.

    Dynamics: ``upper_arm_inertia`` [kg·m²] the upper arm's own inertia about its motor axis;
    ``upper_arm_mass`` [kg] with its centre of mass ``upper_arm_com`` [m] from the motor axis (used for
    gravity only, its inertia is in ``upper_arm_inertia``); ``elbow_mass`` [kg] lumped at the elbow;
    ``forearm_mass`` [kg] of ONE forearm pair (rods and end fittings); ``forearm_end_elbow`` and
    ``forearm_end_plate`` [kg] the part of it in the end fittings (ball cups, springs) at the elbow and at the
    plate; ``forearm_rod_inertia`` [kg·m²] one pair's rods about their own centre of mass, perpendicular to the
    rods (None: a uniform rod, m_rod l²/12 with m_rod = forearm_mass − the end fittings); ``plate_mass`` [kg]
    travelling plate; ``payload`` [kg]; ``g`` [m/s²]. Masses default to 0 for kinematics-only use.

    ``dynamics``: "rigid" (every parallelogram rod a slender rigid body that translates and turns, its end
    fittings point masses at the elbow and the plate: exact for the Delta's rigid bodies) or "lumped" (each pair's
    whole mass split ⅔ to the elbow, ⅓ to the plate [Codourey1998], the model of the papers; the end-fitting
    fields and the rod inertia are then unused).

    Raises ValueError (naming field, value and rule) for a non-positive/non-finite length, a negative/non-finite
    mass, inertia, centre-of-mass distance or g, end fittings heavier than the pair, or an unknown ``dynamics``.
    """

    R: float
    r: float
    L: float
    l: float  # noqa: E741 — the forearm length is "l" in every Delta paper
    upper_arm_inertia: float = 0.0
    upper_arm_mass: float = 0.0
    upper_arm_com: float = 0.0
    elbow_mass: float = 0.0
    forearm_mass: float = 0.0
    plate_mass: float = 0.0
    payload: float = 0.0
    g: float = 9.80665
    forearm_end_elbow: float = 0.0
    forearm_end_plate: float = 0.0
    forearm_rod_inertia: float | None = None
    dynamics: str = "rigid"

    joint_names: ClassVar[tuple[str, ...]] = ("q1", "q2", "q3")
    joint_units: ClassVar[tuple[str, ...]] = ("rad", "rad", "rad")

    def __post_init__(self) -> None:
        _check_positive(self, ("R", "r", "L", "l"))
        _check_non_negative(
            self,
            (
                "upper_arm_inertia",
                "upper_arm_mass",
                "upper_arm_com",
                "elbow_mass",
                "forearm_mass",
                "plate_mass",
                "payload",
                "g",
                "forearm_end_elbow",
                "forearm_end_plate",
            ),
        )
        if self.forearm_rod_inertia is not None:
            _check_non_negative(self, ("forearm_rod_inertia",))
        if self.dynamics not in ("rigid", "lumped"):
            raise ValueError(f"DeltaRobot.dynamics = {self.dynamics!r} is not a model: must be 'rigid' or 'lumped'")
        ends = self.forearm_end_elbow + self.forearm_end_plate
        if ends > self.forearm_mass * (1.0 + 1e-12):
            raise ValueError(
                f"DeltaRobot.forearm_end_elbow + forearm_end_plate = {ends:g} kg is more than the forearm pair's mass "
                f"{self.forearm_mass:g} kg: the end fittings are part of the pair"
            )

    # ------------------------------------------------------------------ mass parameters
    @property
    def rod_mass(self) -> float:
        """m_rod [kg]: one pair's rods without their end fittings."""
        return max(self.forearm_mass - self.forearm_end_elbow - self.forearm_end_plate, 0.0)

    @property
    def rod_inertia(self) -> float:
        """I_rod [kg·m²]: one pair's rods about their centre of mass, perpendicular to the rods (uniform: m_rod l²/12)."""
        return self.rod_mass * self.l**2 / 12.0 if self.forearm_rod_inertia is None else self.forearm_rod_inertia

    @property
    def _rod_ends(self) -> tuple[float, float]:
        """(α, β) [kg] of a pair's rods: their kinetic energy is ½α‖v_E‖² + ½α‖v_C‖² + β v_E·v_C with v_E, v_C
        the elbow and plate velocities (α = m_rod/4 + I_rod/l², β = m_rod/4 − I_rod/l²: the centre of mass
        moves with (v_E + v_C)/2, the rod turns at ‖v_C − v_E‖/l). Lumped: (⅔ m, ⅓ m) at the ends, no coupling."""
        if self.dynamics == "lumped":
            return 0.0, 0.0
        m4, ir = 0.25 * self.rod_mass, self.rod_inertia / self.l**2
        return m4 + ir, m4 - ir

    @property
    def arm_inertia(self) -> float:
        """I_b [kg·m²], arm-side inertia per arm: I_arm + (m_elbow + m_end,elbow + α) L² (rigid), or
        I_arm + (m_elbow + ⅔ m_forearm) L² (lumped [Codourey1998])."""
        if self.dynamics == "lumped":
            return self.upper_arm_inertia + (self.elbow_mass + 2.0 / 3.0 * self.forearm_mass) * self.L**2
        return self.upper_arm_inertia + (self.elbow_mass + self.forearm_end_elbow + self._rod_ends[0]) * self.L**2

    @property
    def arm_gravity_moment(self) -> float:
        """First mass moment of one arm about its motor axis [kg·m]: m_ua·L_c + (m_elbow + m_end,elbow + ½ m_rod)·L
        (rigid: half of each rod's weight on each end), m_ua·L_c + (m_elbow + ⅔ m_forearm)·L (lumped)."""
        if self.dynamics == "lumped":
            return self.upper_arm_mass * self.upper_arm_com + (self.elbow_mass + 2.0 / 3.0 * self.forearm_mass) * self.L
        elbow = self.elbow_mass + self.forearm_end_elbow + 0.5 * self.rod_mass
        return self.upper_arm_mass * self.upper_arm_com + elbow * self.L

    @property
    def platform_mass(self) -> float:
        """m_p [kg], the mass the plate's acceleration drives: m_plate + m_payload + 3 (m_end,plate + α) (rigid),
        m_plate + m_payload + 3·⅓ m_forearm (lumped [Codourey1998])."""
        if self.dynamics == "lumped":
            return self.plate_mass + self.payload + self.forearm_mass
        return self.plate_mass + self.payload + 3.0 * (self.forearm_end_plate + self._rod_ends[0])

    @property
    def platform_weight_mass(self) -> float:
        """The mass whose weight the plate carries [kg]: m_plate + m_payload + 3 (m_end,plate + ½ m_rod) (rigid);
        the lumped model's m_p."""
        if self.dynamics == "lumped":
            return self.platform_mass
        return self.plate_mass + self.payload + 3.0 * (self.forearm_end_plate + 0.5 * self.rod_mass)

    # ------------------------------------------------------------------ kinematics
    def _ik(self, p: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """(a, y′, K, discriminant, z, ρ²) of :meth:`inverse_kinematics`, arm-wise (3, N) except z (N,)."""
        xr, yt, z = _local(p)
        e = self.R - self.r
        a = xr - e
        c0 = ((p * p).sum(axis=1) + e * e + self.L**2 - self.l**2) / (2.0 * self.L)
        K = c0 - (e / self.L) * xr  # = (a² + y′² + z² + L² − l²) / (2L)
        rho2 = a * a + z * z
        return a, yt, K, rho2 - K * K, z, rho2

    def reachable(self, p: np.ndarray) -> np.ndarray:
        """Boolean mask (N,): True where every arm of the knee-out branch can reach p (N, 3) [m]."""
        p = _samples(p, "p")
        disc = self._ik(p)[3]
        return np.all(disc >= 0.0, axis=0) & np.all(np.isfinite(p), axis=1)

    def _solve(self, p: np.ndarray) -> tuple[np.ndarray, _Arms]:
        """q (3, N) and the arm quantities at p (N, 3); UnreachableError for the first bad sample."""
        a, yt, K, disc, z, rho2 = self._ik(p)
        bad = ~(disc >= 0.0)  # also catches NaN
        if bad.any():
            n = int(np.argmax(bad.any(axis=0)))
            arm = int(np.argmax(bad[:, n]))
            x, y, zz = p[n]
            raise UnreachableError(
                f"Delta: sample {n} at p = ({x:.6g}, {y:.6g}, {zz:.6g}) m is unreachable "
                f"(arm {arm + 1} cannot close its loop: L = {self.L} m, l = {self.l} m)",
                index=int(n),
            )
        root = np.sqrt(disc)
        L = self.L
        # q = θ − ψ with cos θ = K/ρ, sin θ = −√disc/ρ, cos ψ = a/ρ, sin ψ = z/ρ
        S = -root * a - K * z  # ρ² sin q
        C = K * a - root * z  # ρ² cos q
        q = np.arctan2(S, C)
        c = C / rho2
        s = S / rho2
        # on this branch D = d·E′ = −L (s a + c z) = L √disc and D₂ = d·E″ = L (s z − c a + L) = L (L − K)
        # (expand S, C: s a + c z = −√disc, s z − c a = −K): exact, and free of the cancellation near D = 0
        arms = _Arms(L, c, s, a - L * c, yt, z + L * s, D=L * root, D2=L * (L - K))
        return q, arms

    def inverse_kinematics(self, p: np.ndarray) -> np.ndarray:
        """Joint angles q (N, 3) [rad] for platform positions p (N, 3) [m], knee-out branch, closed form.

        Per arm, ‖d_i‖² = l² in the arm frame reads (a − L cos q)² + y′² + (z + L sin q)² = l², i.e.

            a cos q − z sin q = K,      K = (a² + y′² + z² + L² − l²) / (2L).

        With ρ = √(a² + z²), ψ = atan2(z, a) the left side is ρ cos(q + ψ); the knee-out root is
        q + ψ = θ = atan2(−√(ρ² − K²), K). Expanding cos(θ − ψ), sin(θ − ψ) gives q in (−π, π] directly:

            q = atan2(−√(ρ² − K²)·a − K z,  K a − √(ρ² − K²)·z)

        The minus sign on the root picks sin(q + ψ) < 0, the knee-out branch (d_i · E_i′ = −Lρ sin(q + ψ) > 0).
        Raises UnreachableError naming the first sample whose discriminant ρ² − K² is negative. The
        working mode (platform below the elbows, z < 0) is assumed, as everywhere in this module.
        """
        p = _samples(p, "p")
        return self._solve(p)[0].T.copy()

    def forward_kinematics(self, q: np.ndarray) -> np.ndarray:
        """Platform positions p (N, 3) [m] for joint angles q (N, 3) [rad], closed form.

        p is the intersection of the three spheres ‖p − S_i‖ = l centred at
        S_i = E_i − Rz(φ_i)(r, 0, 0) = Rz(φ_i)(R − r + L cos q_i, 0, −L sin q_i) (trilateration): with
        e_x ∥ S_2 − S_1, e_y in the plane of the centres, e_z = e_x × e_y, d = ‖S_2 − S_1‖,
        i = e_x·(S_3 − S_1), j = e_y·(S_3 − S_1):

            x = d / 2,  y = (i² + j² − 2 i x) / (2 j),  z = ±√(l² − x² − y²),  p = S_1 + x e_x + y e_y + z e_z

        and the sign that puts the platform below (lower z) is taken. Raises UnreachableError naming the
        first sample where the spheres do not meet (l² − x² − y² < 0) or the centres are collinear.
        """
        q = _samples(q, "q")
        qt = q.T
        u = (self.R - self.r) + self.L * np.cos(qt)
        Sx = u * _COS_PHI
        Sy = u * _SIN_PHI
        Sz = -self.L * np.sin(qt)
        ux, uy, uz = Sx[1] - Sx[0], Sy[1] - Sy[0], Sz[1] - Sz[0]
        wx, wy, wz = Sx[2] - Sx[0], Sy[2] - Sy[0], Sz[2] - Sz[0]
        d = np.sqrt(ux * ux + uy * uy + uz * uz)
        with np.errstate(divide="ignore", invalid="ignore"):
            ux, uy, uz = ux / d, uy / d, uz / d  # e_x
            i = ux * wx + uy * wy + uz * wz
            wx, wy, wz = wx - i * ux, wy - i * uy, wz - i * uz
            j = np.sqrt(wx * wx + wy * wy + wz * wz)
            wx, wy, wz = wx / j, wy / j, wz / j  # e_y
            x = 0.5 * d
            y = (i * i + j * j - 2.0 * i * x) / (2.0 * j)
        h2 = self.l**2 - x * x - y * y
        bad = ~((h2 >= 0.0) & (j > 1e-12 * self.l) & (d > 1e-12 * self.l))
        if bad.any():
            n = int(np.argmax(bad))
            q1, q2, q3 = q[n]
            raise UnreachableError(
                f"Delta: sample {n} at q = ({q1:.6g}, {q2:.6g}, {q3:.6g}) rad cannot be assembled "
                f"(the forearm spheres of radius l = {self.l} m do not meet)",
                index=int(n),
            )
        # e_z = e_x × e_y; choose the root with the lower z: sign(h) = −sign(e_z,z)
        zx = uy * wz - uz * wy
        zy = uz * wx - ux * wz
        zz = ux * wy - uy * wx
        h = np.sqrt(h2)
        h = np.where(zz > 0.0, -h, h)
        return np.stack(
            (
                Sx[0] + x * ux + y * wx + h * zx,
                Sy[0] + x * uy + y * wy + h * zy,
                Sz[0] + x * uz + y * wz + h * zz,
            ),
            axis=1,
        )

    def _arms(self, q: np.ndarray, p: np.ndarray) -> _Arms:
        """Arm quantities for a given (q, p) pair (q (N, 3), p (N, 3)); no consistency check."""
        qt = q.T
        c = np.cos(qt)
        s = np.sin(qt)
        xr, yt, z = _local(p)
        return _Arms(self.L, c, s, xr - (self.R - self.r) - self.L * c, yt, z + self.L * s)

    def constraint_matrices(self, q: np.ndarray, p: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """A (N, 3, 3) and the diagonal of B (N, 3) of the velocity relation A ṗ = B q̇.

        Differentiating f_i = ‖C_i − E_i(q_i)‖² − l² = 0 gives d_i · ṗ = (d_i · E_i′) q̇_i, so row i of A is
        d_iᵀ (base frame) [m] and B_ii = d_i · E_i′ [m²/rad]. A is singular at a parallel (type-2)
        singularity, B at a serial (type-1) one. ``q`` and ``p`` must belong together (p = FK(q)).
        """
        q = _samples(q, "q")
        p = _samples(p, "p")
        arms = self._arms(q, p)
        dx, dy, dz = arms.base_frame()
        return np.stack((dx.T, dy.T, dz.T), axis=-1), arms.D.T.copy()

    def inverse_jacobian(self, q: np.ndarray, p: np.ndarray) -> np.ndarray:
        """J⁻¹ = B⁻¹A (N, 3, 3) [rad/m]: maps platform velocity to joint velocity, q̇ = J⁻¹ ṗ."""
        A, B = self.constraint_matrices(q, p)
        return A / B[:, :, None]

    def jacobian(self, q: np.ndarray, p: np.ndarray) -> np.ndarray:
        """J = A⁻¹B (N, 3, 3) [m/rad]: maps joint velocity to platform velocity, ṗ = J q̇.

        A⁻¹ by the adjugate: its column i is (d_{i+1} × d_{i+2}) / det A (arm indices cyclic).
        """
        q = _samples(q, "q")
        p = _samples(p, "p")
        arms = self._arms(q, p)
        (cx, cy, cz), det = self._reciprocal(arms)
        # column i of A⁻¹ is c_i/det; J = A⁻¹ B scales column i by B_ii
        k = arms.D / det
        return np.stack(((cx * k).T, (cy * k).T, (cz * k).T), axis=1)

    @staticmethod
    def _reciprocal(arms: _Arms) -> tuple[np.ndarray, np.ndarray]:
        """The reciprocal basis c_i = d_{i+1} × d_{i+2} as (3 components, 3 arms, N) and det A = d_1 · (d_2 × d_3)
        (N,) (computed once per configuration: the dynamics and the singularity measure both use them)."""
        if arms._recip is None:
            d = arms.base_frame()
            f = d[_CROSS_ROWS, _CROSS_COLS]  # (4, 3, 3, N): the four factors of every cross-product entry
            c = f[0] * f[1] - f[2] * f[3]  # (y1 z2 − z1 y2, z1 x2 − x1 z2, x1 y2 − y1 x2)
            arms._recip = (c, (d[:, 0] * c[:, 0]).sum(axis=0))
        return arms._recip

    def joint_motion(
        self, p: np.ndarray, v: np.ndarray, a: np.ndarray, j: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """q [rad], q̇ [rad/s], q̈ [rad/s²], q⃛ [rad/s³] (each (N, 3)) from p, v, a, j (each (N, 3), SI), analytically.

        Per arm, with d = C − E(q), D = d·E′ (the diagonal of B) and D₂ = d·E″, the time derivatives of
        f = d·d − l² = 0 are each linear in the highest joint derivative:

            ḟ/2 = d·ḋ = 0,              ḋ = v − E′q̇                  ⇒ q̇ = d·v / D
            f̈/2 = ḋ·ḋ + d·d̈ = 0,       d̈ = a − E″q̇² − E′q̈           ⇒ q̈ = (ḋ·ḋ + d·a − D₂ q̇²) / D
            f⃛/2 = 3ḋ·d̈ + d·d⃛ = 0,     d⃛ = j − E‴q̇³ − 3E″q̇q̈ − E′q⃛
                                                          ⇒ q⃛ = (3ḋ·d̈ + d·j + D q̇³ − 3 D₂ q̇ q̈) / D

        using E‴ = −E′ (so d·E‴ = −D). No finite differences. D → 0 at a serial singularity.
        """
        q, arms, (qd, qdd, qddd), _ = self._motion(p, v, a, j)
        return q.T.copy(), qd.T.copy(), qdd.T.copy(), qddd.T.copy()

    def _motion(self, p, v, a, j) -> tuple:
        """Validated inputs → q (3, N), the arm geometry, (q̇, q̈, q⃛) (each (3, N)) and (v, a, j) as arrays."""
        p = _samples(p, "p")
        v = _samples(v, "v")
        a = _samples(a, "a")
        j = _samples(j, "j")
        q, arms = self._solve(p)
        return q, arms, self._joint_rates(arms, v, a, j), (v, a, j)

    def _joint_rates(self, arms: _Arms, v: np.ndarray, a: np.ndarray, j: np.ndarray):
        """q̇, q̈, q⃛ (each (3, N)) of :meth:`joint_motion` from the arm geometry of the configuration."""
        L = self.L
        c, s, dr, dt, dz, D, D2 = arms.c, arms.s, arms.dr, arms.dt, arms.dz, arms.D, arms.D2
        vr, vt, vz = _local(v)
        ar, at, az = _local(a)
        jr, jt, jz = _local(j)
        qd = (dr * vr + dt * vt + dz * vz) / D
        # ḋ = v − E′q̇, E′ = (−L s, 0, −L c)
        Lq = L * qd
        d1r = vr + s * Lq
        d1z = vz + c * Lq
        qdd = (d1r * d1r + vt * vt + d1z * d1z + dr * ar + dt * at + dz * az - D2 * qd * qd) / D
        # d̈ = a − E″q̇² − E′q̈, E″ = (−L c, 0, L s)
        Lq2 = Lq * qd
        Lqq = L * qdd
        d2r = ar + c * Lq2 + s * Lqq
        d2z = az - s * Lq2 + c * Lqq
        qddd = (
            3.0 * (d1r * d2r + vt * at + d1z * d2z)
            + dr * jr
            + dt * jt
            + dz * jz
            + qd * (D * qd * qd - 3.0 * D2 * qdd)
        ) / D
        arms.rates = (vr, vt, vz, d1r, d1z)
        return qd, qdd, qddd

    def motion_and_dynamics(
        self, p: np.ndarray, v: np.ndarray, a: np.ndarray, j: np.ndarray, rates: bool = True
    ) -> tuple:
        """(q, q̇, q̈, q⃛, A, G, dA, dG, μ) in one pass over the arm geometry: :meth:`joint_motion`,
        :meth:`split_dynamics` (dA, dG None unless ``rates``) and :meth:`singularity_measure` at the platform
        motion p, v, a, j (each (N, 3), SI), sharing one inverse kinematics. Each (N, 3) except μ (N,).
        (The separate methods recompute cos q, sin q and the forearm vectors from q; this pass takes them
        from the inverse kinematics, so values agree to round-off, not bitwise.)"""
        q, arms, (qd, qdd, qddd), (v, a, j) = self._motion(p, v, a, j)
        A, G, dA, dG = self._dynamics(arms, qd, qdd, qddd, v, a, j, rates)
        # (N, 3) views of the arm-major (3, N) arrays, not copies: the caller combines and indexes them anyway
        out = [x.T for x in (q, qd, qdd, qddd, A, G)]
        out += [None if x is None else x.T for x in (dA, dG)]
        return (*out, self._singularity(arms))

    def singularity_measure(self, q: np.ndarray, p: np.ndarray) -> np.ndarray:
        """Dimensionless distance from singularity (N,), in [0, 1]; 0 at a singularity.

            μ = min( min_i |d̂_i · Ê_i′| ,  1/cond₂(Â) )

        * |d̂_i · Ê_i′| = |B_ii| / (l L) is the cosine of the angle between forearm i and the tangent of
          its elbow circle; it vanishes at a serial (type-1, inverse-kinematic) singularity, where the
          forearm lies in the plane of the upper arm and the motor axis (arm stretched or folded).
        * Â = A / l has the unit forearm directions as rows; 1/cond₂(Â) = σ_min/σ_max vanishes at a
          parallel (type-2, direct-kinematic) singularity, where the three forearms become coplanar.
          σ² are the extreme eigenvalues of the 3×3 Gram matrix ÂÂᵀ, in closed form (:func:`_gram_extremes`,
          ~5× faster than a batched eigvalsh); the measure is accurate to ~1e-8 relative (worst where two
          eigenvalues coincide), far below any useful margin.
        """
        q = _samples(q, "q")
        p = _samples(p, "p")
        return self._singularity(self._arms(q, p), from_ik=False)

    def _singularity(self, arms: _Arms, from_ik: bool = True) -> np.ndarray:
        """The measure of :meth:`singularity_measure`; ``from_ik``: the arms come from the inverse kinematics
        (every forearm of length l, which the Gram extremes then use); else the caller's q, p."""
        serial = np.abs(arms.D).min(axis=0) / (self.l * self.L)
        lo, hi = _gram_extremes(arms.base_frame(), self._reciprocal(arms)[1], self.l * self.l if from_ik else None)
        parallel = np.sqrt(np.maximum(lo, 0.0) / hi)
        return np.minimum(serial, parallel)

    # ------------------------------------------------------------------ dynamics
    def inverse_dynamics(
        self, q: np.ndarray, qd: np.ndarray, qdd: np.ndarray, p: np.ndarray, a: np.ndarray
    ) -> np.ndarray:
        """Motor torques (N, 3) [N·m] at the joints, gravity included: the rigid-body model (default) or the
        lumped-mass model [Codourey1998] (``dynamics="lumped"``).

        By virtual power, every body's inertial and weight load acts on the motors through the point it moves
        with: the upper arm about its axis, the elbow point E_i (velocity E_i′ q̇_i) and the plate (velocity ṗ):

            τ_i = I_arm q̈_i − g m_ua L_c cos q_i + E_i′·f_E,i + B_ii λ_i,     Aᵀλ = F_C

        * A parallelogram rod pair (mass m_rod, inertia I_rod about its centre, length l) moves its centre with
          (v_E + v_C)/2 and turns at ω with ‖ω‖ l = ‖v_C − v_E‖ (ω ⟂ rod; a slender rod has no inertia about its
          own axis). Its inertial power m a_c·v_c + I_rod ω̇·ω = (m/4)(a_E + a_C)·(v_E + v_C) + (I_rod/l²) d̈·ḋ
          puts α a_E + β a_C on the elbow and β a_E + α a_C on the plate, α = m/4 + I/l², β = m/4 − I/l²
          (uniform rod: m/3 and m/6), and half its weight on each end. The end fittings are point masses at
          the elbow and the plate. a_E = E′q̈ + E″q̇² (E′·E″ = 0, ‖E′‖ = L), so
            E′·f_E = (m_elbow + m_end,E + α) L² q̈ + β E′·p̈ − g (m_elbow + m_end,E + ½m_rod) L cos q,
            F_C = m_p p̈ + β Σ_k a_E,k + m_w g e_z
          with m_p = :attr:`platform_mass` and m_w = :attr:`platform_weight_mass`.
        * Lumped: each pair's mass ⅔ at the elbow, ⅓ on the plate (β = 0, m_w = m_p, I_b = :attr:`arm_inertia`).
        * F_C is the force the arms exert on the plate; by virtual work (J⁻¹)ᵀ τ = F with J⁻¹ = B⁻¹A:
          τ_i = B_ii λ_i where Aᵀλ = F, solved with the reciprocal basis λ_i = F·(d_{i+1} × d_{i+2}) / det A.
        * The weight terms are NEGATIVE for a horizontal arm: the motor pulls the arm up, against q > 0
          (downwards); the sign is the one consistent with τ·q̇ = dE/dt.

        ``q`` and ``p`` must belong together (p = FK(q)); ``qd`` enters the rigid model's rod coupling
        (the elbows' centripetal acceleration). Power balance: Σ τ_i q̇_i = d/dt(KE + PE)
        (:meth:`kinetic_energy`, :meth:`potential_energy`).
        """
        q = _samples(q, "q")
        qd = _samples(qd, "qd")
        qdd = _samples(qdd, "qdd")
        p = _samples(p, "p")
        a = _samples(a, "a")
        A, G, _, _ = self._dynamics(self._arms(q, p), qd.T, qdd.T, None, None, a, None, rates=False)
        return (A + G).T.copy()

    def torque_rate(
        self, q: np.ndarray, qd: np.ndarray, qdd: np.ndarray, qddd: np.ndarray,
        p: np.ndarray, v: np.ndarray, a: np.ndarray, j: np.ndarray,
    ) -> tuple[np.ndarray, np.ndarray]:
        """Time derivatives (dA, dG), each (N, 3) [N·m/s], of the two parts of :meth:`inverse_dynamics`:
        the inertial part A = I_b q̈ + D λ(m_p p̈) and the static part G = τ_g(q) + D λ(m_p g e_z).

        Differentiating τ_i = I_b q̈_i − g M cos q_i + D_i λ_i analytically (no finite differences):

            Ḋ_i = ḋ_i·E_i′ + d_i·E_i″ q̇_i = −L (sin q_i ḋ_r + cos q_i ḋ_z) + D₂ q̇_i,   ḋ = v − E′q̇
            Aᵀλ = F  ⇒  Aᵀλ̇ = Ḟ − Σ_k ḋ_k λ_k  ⇒  λ̇_i = (Ḟ − Σ_k ḋ_k λ_k)·(d_{i+1} × d_{i+2}) / det A

        with Ḟ = m_p p⃛ for the inertial part and 0 for gravity; d/dt(−g M cos q) = g M sin q q̇.
        Inputs as for :meth:`joint_motion` / :meth:`inverse_dynamics` (q, p must belong together).
        """
        return self.split_dynamics(q, qd, qdd, qddd, p, v, a, j)[2:]  # type: ignore[return-value]

    def split_dynamics(
        self, q: np.ndarray, qd: np.ndarray, qdd: np.ndarray, qddd: np.ndarray,
        p: np.ndarray, v: np.ndarray, a: np.ndarray, j: np.ndarray, rates: bool = True,
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray | None, np.ndarray | None]:
        """(A, G, dA, dG), each (N, 3): :meth:`inverse_dynamics` = A + G split into its inertial part A and
        static (gravity) part G, and their time derivatives (:meth:`torque_rate`; None unless ``rates``),
        sharing one evaluation of the arm geometry."""
        q = _samples(q, "q")
        qd = _samples(qd, "qd")
        qdd = _samples(qdd, "qdd")
        p = _samples(p, "p")
        a = _samples(a, "a")
        if rates:
            qddd = _samples(qddd, "qddd")
            v = _samples(v, "v")
            j = _samples(j, "j")
        A, G, dA, dG = self._dynamics(self._arms(q, p), qd.T, qdd.T, None if qddd is None else qddd.T, v, a, j, rates)
        return A.T.copy(), G.T.copy(), None if dA is None else dA.T.copy(), None if dG is None else dG.T.copy()

    def _dynamics(self, arms: _Arms, qd, qdd, qddd, v, a, j, rates: bool):
        """(A, G, dA, dG) of :meth:`split_dynamics`, arm-major (3, N), from the arm geometry; q̇, q̈, q⃛ (3, N).

        The inertial load on the plate and its static load go through the same reciprocal basis as one
        stacked (2 loads, 3 components, N) array (numpy's cost is per call at these sizes). The rigid model's
        rod coupling β (see :meth:`inverse_dynamics`) adds β E′·p̈ to each arm and β Σ_k a_E,k to the plate;
        its rates, β d/dt(E′·p̈) = β (q̇ E″·p̈ + E′·p⃛) and β Σ_k ȧ_E,k with ȧ_E = E′q⃛ + 3E″q̇q̈ − E′q̇³."""
        C, det = self._reciprocal(arms)  # (3 components, 3 arms, N), (N,)
        L, mp, g, M = self.L, self.platform_mass, self.g, self.arm_gravity_moment
        beta = self._rod_ends[1]
        c, s = arms.c, arms.s
        F = np.zeros((2, 3, len(det)))  # forces on the plate [N]: inertial, static
        F[0] = mp * a.T
        F[1, 2] = self.platform_weight_mass * g
        if beta:
            ar, _, az = _local(a)
            # elbow accelerations a_E (arm frame: radial, vertical), summed over the arms in the base frame
            er, ez = -L * (s * qdd + c * qd * qd), L * (s * qd * qd - c * qdd)
            F[0, 0] += beta * (er * _COS_PHI).sum(axis=0)
            F[0, 1] += beta * (er * _SIN_PHI).sum(axis=0)
            F[0, 2] += beta * ez.sum(axis=0)
        lam = (F[:, :, None] * C).sum(axis=1) / det  # (2, 3 arms, N): λ_i = F·c_i / det A
        Dlam = arms.D * lam
        A = self.arm_inertia * qdd + Dlam[0]
        if beta:
            A = A - (beta * L) * (s * ar + c * az)  # β E′·p̈
        G = Dlam[1] - (g * M) * c
        if not rates:
            return A, G, None, None
        w = qd
        if arms.rates is not None:  # from _joint_rates at the same configuration and velocity
            vr, vt, vz, d1r, d1z = arms.rates
        else:
            vr, vt, vz = _local(v)
            d1r = vr + s * L * w
            d1z = vz + c * L * w
        d1 = np.empty((3, *d1r.shape))  # ḋ = v − E′q̇ in the base frame (3 components, 3 arms, N)
        d1[2] = d1z
        Ddot = -L * (s * d1r + c * d1[2]) + arms.D2 * w
        d1[0] = d1r * _COS_PHI - vt * _SIN_PHI
        d1[1] = d1r * _SIN_PHI + vt * _COS_PHI
        # Aᵀλ̇ = Ḟ − Σ_k ḋ_k λ_k with Ḟ = m_p p⃛ (+ β Σ_k ȧ_E,k) (inertial) and 0 (static)
        R = -(d1[None] * lam[:, None]).sum(axis=2)  # (2, 3 components, N)
        R[0] += mp * j.T
        if beta:
            w2 = w * w
            jr, _, jz = _local(j)
            sr = -L * (s * qddd + 3.0 * c * w * qdd - s * w2 * w)  # ȧ_E, radial and vertical (arm frame)
            sz = L * (3.0 * s * w * qdd - c * qddd + c * w2 * w)
            R[0, 0] += beta * (sr * _COS_PHI).sum(axis=0)
            R[0, 1] += beta * (sr * _SIN_PHI).sum(axis=0)
            R[0, 2] += beta * sz.sum(axis=0)
        lam_dot = (R[:, :, None] * C).sum(axis=1) / det
        rate = Ddot * lam + arms.D * lam_dot
        dA = self.arm_inertia * qddd + rate[0]
        if beta:
            dA = dA + (beta * L) * (w * (s * az - c * ar) - (s * jr + c * jz))  # β (q̇ E″·p̈ + E′·p⃛)
        dG = rate[1] + (g * M) * s * w
        return A, G, dA, dG

    def kinetic_energy(self, q: np.ndarray, qd: np.ndarray, v: np.ndarray) -> np.ndarray:
        """KE (N,) [J]: Σ_i ½ I_b q̇_i² + ½ m_p ‖v‖² + β Σ_i (E_i′ q̇_i)·v (the rods' coupling; 0 when lumped)."""
        q = _samples(q, "q")
        qd = _samples(qd, "qd")
        v = _samples(v, "v")
        ke = 0.5 * self.arm_inertia * np.sum(qd * qd, axis=1) + 0.5 * self.platform_mass * np.sum(v * v, axis=1)
        beta = self._rod_ends[1]
        if beta:
            vr, _, vz = _local(v)
            qt = q.T
            ke = ke - beta * self.L * (qd.T * (np.sin(qt) * vr + np.cos(qt) * vz)).sum(axis=0)
        return ke

    def potential_energy(self, q: np.ndarray, p: np.ndarray) -> np.ndarray:
        """PE (N,) [J], zero at q = 0 and z = 0: −g M Σ_i sin q_i + m_w g z (M = :attr:`arm_gravity_moment`,
        m_w = :attr:`platform_weight_mass`)."""
        q = _samples(q, "q")
        p = _samples(p, "p")
        return -self.g * self.arm_gravity_moment * np.sum(np.sin(q), axis=1) + self.platform_weight_mass * self.g * p[:, 2]
