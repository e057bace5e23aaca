"""SCARA robot (serial RRP): closed-form kinematics, analytic joint derivatives and rigid-body dynamics.

References
----------
[Spong2006] M. W. Spong, S. Hutchinson, M. Vidyasagar, "Robot Modeling and Control", Wiley 2006:
            Ch. 3 (inverse kinematics of the planar elbow arm), Ch. 4 (velocity Jacobian), Ch. 7 (dynamics of
            the two-link planar elbow manipulator).

Conventions (SI units: m, rad, s, kg, N, N·m)
---------------------------------------------
* Base frame on the axis of joint 1, z up. Joints: q1 [rad] shoulder, q2 [rad] elbow (relative to
  link 1), both about vertical axes, counter-clockwise positive seen from above; q3 [m] prismatic,
  positive up. The tool rotation q4 is held fixed by this planner and is not modelled.
* Tool position:  x = l1 cos q1 + l2 cos(q1 + q2),  y = l1 sin q1 + l2 sin(q1 + q2),  z = z0 + q3.
* ``elbow = "left"``  ⇔ q2 > 0 (elbow bends counter-clockwise seen from above);
  ``elbow = "right"`` ⇔ q2 < 0.
* Dynamics: links 1 and 2 move in the horizontal plane (no gravity on q1, q2). The mass moved by the
  z axis, m3 + payload, is a point mass at the end of link 2 for the planar dynamics and is lifted by
  joint 3 against gravity.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from enum import Enum
from typing import ClassVar

import numpy as np

from ..model.errors import UnreachableError
from .delta import _check_non_negative, _check_positive, _samples


class Elbow(str, Enum):
    """Elbow branch of the planar IK: LEFT ⇔ q2 > 0 (counter-clockwise seen from above), RIGHT ⇔ q2 < 0."""

    LEFT = "left"
    RIGHT = "right"


@dataclass(frozen=True)
class ScaraRobot:
    """SCARA robot: planar 2R arm (``l1``, ``l2`` [m]) carrying a vertical prismatic axis (``z0`` [m] its zero).

    Dynamics [Spong2006, Ch. 7]: link masses ``m1``, ``m2`` [kg] with centres of mass ``lc1``, ``lc2``
    [m] from their proximal joint and inertias ``I1``, ``I2`` [kg·m²] about their own centre of mass
    (vertical axis); ``m3`` [kg] quill + tool moved by the z axis; ``payload`` [kg]; ``g`` [m/s²].
    ``elbow`` is "left" or "right" (see :class:`Elbow`). Masses default to 0 for kinematics-only use.

    Raises ValueError (naming field, value and rule) for a non-positive/non-finite link length, a
    negative/non-finite mass, inertia, centre-of-mass distance or g, or an unknown elbow.
    """

    l1: float
    l2: float
    elbow: Elbow | str = Elbow.RIGHT
    z0: float = 0.0
    m1: float = 0.0
    m2: float = 0.0
    lc1: float = 0.0
    lc2: float = 0.0
    I1: float = 0.0
    I2: float = 0.0
    m3: float = 0.0
    payload: float = 0.0
    g: float = 9.80665

    joint_names: ClassVar[tuple[str, ...]] = ("q1", "q2", "q3")
    joint_units: ClassVar[tuple[str, ...]] = ("rad", "rad", "m")

    def __post_init__(self) -> None:
        _check_positive(self, ("l1", "l2"))
        _check_non_negative(self, ("m1", "m2", "lc1", "lc2", "I1", "I2", "m3", "payload", "g"))
        if not math.isfinite(self.z0):
            raise ValueError(f"ScaraRobot.z0 = {self.z0!r} is not physical: must be finite")
        try:
            elbow = Elbow(self.elbow)
        except ValueError:
            raise ValueError(f"ScaraRobot.elbow = {self.elbow!r} is invalid: must be 'left' or 'right'") from None
        object.__setattr__(self, "elbow", elbow)

    @property
    def carried_mass(self) -> float:
        """m3 + payload [kg]: the mass moved by the z axis, a point mass at the end of link 2."""
        return self.m3 + self.payload

    # ------------------------------------------------------------------ kinematics
    def reachable(self, p: np.ndarray) -> np.ndarray:
        """Boolean mask (N,): True where |l1 − l2| ≤ √(x² + y²) ≤ l1 + l2 (z is unbounded here)."""
        p = _samples(p, "p")
        c2 = self._cos_q2(p)
        return (np.abs(c2) <= 1.0 + 1e-12) & np.all(np.isfinite(p), axis=1)

    def _cos_q2(self, p: np.ndarray) -> np.ndarray:
        rho2 = p[:, 0] ** 2 + p[:, 1] ** 2
        return (rho2 - self.l1**2 - self.l2**2) / (2.0 * self.l1 * self.l2)

    def inverse_kinematics(self, p: np.ndarray) -> np.ndarray:
        """Joints q (N, 3) [rad, rad, m] for tool positions p (N, 3) [m], closed form [Spong2006, Ch. 3]:

            cos q2 = (x² + y² − l1² − l2²) / (2 l1 l2),  q2 = atan2(±√(1 − cos² q2), cos q2)  (+ for "left")
            q1 = atan2(y, x) − atan2(l2 sin q2, l1 + l2 cos q2),   q3 = z − z0

        q1 is wrapped to (−π, π]. Raises UnreachableError naming the first sample outside the annulus
        |l1 − l2| ≤ ρ ≤ l1 + l2 (a relative slack of 1e-12 on cos q2 absorbs round-off at the boundary).
        """
        p = _samples(p, "p")
        c2 = self._cos_q2(p)
        bad = ~(np.abs(c2) <= 1.0 + 1e-12) | ~np.isfinite(p[:, 2])
        if bad.any():
            n = int(np.argmax(bad))
            x, y, z = p[n]
            raise UnreachableError(
                f"SCARA: sample {n} at p = ({x:.6g}, {y:.6g}, {z:.6g}) m is unreachable "
                f"(radius {math.hypot(x, y):.6g} m outside [{abs(self.l1 - self.l2):.6g}, {self.l1 + self.l2:.6g}] m)",
                index=int(n),
            )
        c2 = np.clip(c2, -1.0, 1.0)
        s2 = np.sqrt((1.0 - c2) * (1.0 + c2))
        if self.elbow is Elbow.RIGHT:
            s2 = -s2
        q2 = np.arctan2(s2, c2)
        q1 = np.arctan2(p[:, 1], p[:, 0]) - np.arctan2(self.l2 * s2, self.l1 + self.l2 * c2)
        q1 = np.where(q1 <= -np.pi, q1 + 2.0 * np.pi, np.where(q1 > np.pi, q1 - 2.0 * np.pi, q1))
        return np.stack((q1, q2, p[:, 2] - self.z0), axis=1)

    def forward_kinematics(self, q: np.ndarray) -> np.ndarray:
        """Tool positions p (N, 3) [m] for q (N, 3): (l1 c1 + l2 c12, l1 s1 + l2 s12, z0 + q3)."""
        q = _samples(q, "q")
        q12 = q[:, 0] + q[:, 1]
        x = self.l1 * np.cos(q[:, 0]) + self.l2 * np.cos(q12)
        y = self.l1 * np.sin(q[:, 0]) + self.l2 * np.sin(q12)
        return np.stack((x, y, self.z0 + q[:, 2]), axis=1)

    def jacobian(self, q: np.ndarray, p: np.ndarray | None = None) -> np.ndarray:
        """J (N, 3, 3), ṗ = J q̇ [Spong2006, Ch. 4] (``p`` is unused; the Delta's Jacobian needs it):

            [[−l1 s1 − l2 s12, −l2 s12, 0],
             [ l1 c1 + l2 c12,  l2 c12, 0],
             [ 0,               0,      1]]      det J = l1 l2 sin q2
        """
        q = _samples(q, "q")
        c1, s1, c12, s12 = self._trig(q)
        J = np.zeros((q.shape[0], 3, 3))
        J[:, 0, 0] = -self.l1 * s1 - self.l2 * s12
        J[:, 0, 1] = -self.l2 * s12
        J[:, 1, 0] = self.l1 * c1 + self.l2 * c12
        J[:, 1, 1] = self.l2 * c12
        J[:, 2, 2] = 1.0
        return J

    def jacobian_dot(self, q: np.ndarray, qd: np.ndarray) -> np.ndarray:
        """J̇ (N, 3, 3) in closed form, with θ = q1 + q2:

            [[−l1 c1 q̇1 − l2 c12 θ̇, −l2 c12 θ̇, 0],
             [−l1 s1 q̇1 − l2 s12 θ̇, −l2 s12 θ̇, 0],
             [0, 0, 0]]
        """
        q = _samples(q, "q")
        qd = _samples(qd, "qd")
        c1, s1, c12, s12 = self._trig(q)
        w1 = qd[:, 0]
        w12 = qd[:, 0] + qd[:, 1]
        Jd = np.zeros((q.shape[0], 3, 3))
        Jd[:, 0, 1] = -self.l2 * c12 * w12
        Jd[:, 1, 1] = -self.l2 * s12 * w12
        Jd[:, 0, 0] = -self.l1 * c1 * w1 + Jd[:, 0, 1]
        Jd[:, 1, 0] = -self.l1 * s1 * w1 + Jd[:, 1, 1]
        return Jd

    def jacobian_ddot(self, q: np.ndarray, qd: np.ndarray, qdd: np.ndarray) -> np.ndarray:
        """J̈ (N, 3, 3) in closed form, with θ = q1 + q2:

            J̈[:, 1] = (l2 s12 θ̇² − l2 c12 θ̈,  −l2 c12 θ̇² − l2 s12 θ̈, 0)
            J̈[:, 0] = J̈[:, 1] + (l1 s1 q̇1² − l1 c1 q̈1,  −l1 c1 q̇1² − l1 s1 q̈1, 0)
        """
        q = _samples(q, "q")
        qd = _samples(qd, "qd")
        qdd = _samples(qdd, "qdd")
        c1, s1, c12, s12 = self._trig(q)
        w1, a1 = qd[:, 0], qdd[:, 0]
        w12, a12 = qd[:, 0] + qd[:, 1], qdd[:, 0] + qdd[:, 1]
        Jdd = np.zeros((q.shape[0], 3, 3))
        Jdd[:, 0, 1] = self.l2 * (s12 * w12**2 - c12 * a12)
        Jdd[:, 1, 1] = -self.l2 * (c12 * w12**2 + s12 * a12)
        Jdd[:, 0, 0] = self.l1 * (s1 * w1**2 - c1 * a1) + Jdd[:, 0, 1]
        Jdd[:, 1, 0] = -self.l1 * (c1 * w1**2 + s1 * a1) + Jdd[:, 1, 1]
        return Jdd

    @staticmethod
    def _trig(q: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        q12 = q[:, 0] + q[:, 1]
        return np.cos(q[:, 0]), np.sin(q[:, 0]), np.cos(q12), np.sin(q12)

    def joint_motion(
        self, p: np.ndarray, v: np.ndarray, a: np.ndarray, j: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """q, q̇, q̈, q⃛ (each (N, 3); rad-based for q1, q2 and m-based for q3) from p, v, a, j, analytically.

        Differentiating p = FK(q):  v = J q̇,  a = J q̈ + J̇ q̇,  j = J q⃛ + 2 J̇ q̈ + J̈ q̇, so

            q̇ = J⁻¹ v,   q̈ = J⁻¹ (a − J̇ q̇),   q⃛ = J⁻¹ (j − 2 J̇ q̈ − J̈ q̇)

        with J̇ (:meth:`jacobian_dot`) and J̈ (:meth:`jacobian_ddot`) in closed form and the planar 2×2
        block of J inverted explicitly (det = l1 l2 sin q2, zero at a singularity). Here the products
        J̇ q̇ and 2 J̇ q̈ + J̈ q̇ are written out (θ = q1 + q2, e1 = (c1, s1), e12 = (c12, s12), ⊥ = +90°):

            J̇ q̇        = −l1 q̇1² e1 − l2 θ̇² e12
            2J̇ q̈ + J̈ q̇ = −3 l1 q̇1 q̈1 e1 − l1 q̇1³ e1⊥ − 3 l2 θ̇ θ̈ e12 − l2 θ̇³ e12⊥
        """
        p = _samples(p, "p")
        v = _samples(v, "v")
        a = _samples(a, "a")
        j = _samples(j, "j")
        q = self.inverse_kinematics(p)
        c1, s1, c12, s12 = self._trig(q)
        l1, l2 = self.l1, self.l2
        # planar J and its inverse
        J00 = -l1 * s1 - l2 * s12
        J01 = -l2 * s12
        J10 = l1 * c1 + l2 * c12
        J11 = l2 * c12
        det = l1 * l2 * np.sin(q[:, 1])

        def solve(bx: np.ndarray, by: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
            return (J11 * bx - J01 * by) / det, (-J10 * bx + J00 * by) / det

        qd1, qd2 = solve(v[:, 0], v[:, 1])
        w12 = qd1 + qd2
        bx = a[:, 0] + l1 * qd1**2 * c1 + l2 * w12**2 * c12
        by = a[:, 1] + l1 * qd1**2 * s1 + l2 * w12**2 * s12
        qdd1, qdd2 = solve(bx, by)
        a12 = qdd1 + qdd2
        # 2 J̇ q̈ + J̈ q̇ = r1 e1 + t1 e1⊥ + r2 e12 + t2 e12⊥, with e⊥ = (−sin, cos)
        r1 = -3.0 * l1 * qd1 * qdd1
        t1 = -l1 * qd1 * qd1 * qd1
        r2 = -3.0 * l2 * w12 * a12
        t2 = -l2 * w12 * w12 * w12
        kx = r1 * c1 - t1 * s1 + r2 * c12 - t2 * s12
        ky = r1 * s1 + t1 * c1 + r2 * s12 + t2 * c12
        qddd1, qddd2 = solve(j[:, 0] - kx, j[:, 1] - ky)
        qd = np.stack((qd1, qd2, v[:, 2]), axis=1)
        qdd = np.stack((qdd1, qdd2, a[:, 2]), axis=1)
        qddd = np.stack((qddd1, qddd2, j[:, 2]), axis=1)
        return q, qd, qdd, qddd

    def singularity_measure(self, q: np.ndarray, p: np.ndarray | None = None) -> np.ndarray:
        """|sin q2| (N,), dimensionless in [0, 1]: det J / (l1 l2); 0 with the arm fully stretched or folded.

        ``p`` is accepted for symmetry with the Delta and is unused.
        """
        q = _samples(q, "q")
        return np.abs(np.sin(q[:, 1]))

    # ------------------------------------------------------------------ dynamics
    def mass_matrix(self, q: np.ndarray) -> np.ndarray:
        """M(q) (N, 3, 3) in kg·m² and kg `[Spong2006, Ch. 7]`, carried mass m_t = m3 + payload as a point at l2:

            M11 = m1 lc1² + I1 + m2 (l1² + lc2² + 2 l1 lc2 c2) + I2 + m_t (l1² + l2² + 2 l1 l2 c2)
            M12 = m2 (lc2² + l1 lc2 c2) + I2 + m_t (l2² + l1 l2 c2)
            M22 = m2 lc2² + I2 + m_t l2²,      M33 = m_t
        """
        q = _samples(q, "q")
        M11, M12, M22, _ = self._mass_terms(q)
        M = np.zeros((q.shape[0], 3, 3))
        M[:, 0, 0] = M11
        M[:, 0, 1] = M[:, 1, 0] = M12
        M[:, 1, 1] = M22
        M[:, 2, 2] = self.carried_mass
        return M

    def _mass_terms(self, q: np.ndarray) -> tuple[np.ndarray, np.ndarray, float, np.ndarray]:
        mt = self.carried_mass
        l1, l2, lc2 = self.l1, self.l2, self.lc2
        c2 = np.cos(q[:, 1])
        M22 = self.m2 * lc2**2 + self.I2 + mt * l2**2
        M12 = M22 + (self.m2 * lc2 + mt * l2) * l1 * c2
        M11 = self.m1 * self.lc1**2 + self.I1 + (self.m2 + mt) * l1**2 + 2.0 * (M12 - M22) + M22
        h = -(self.m2 * lc2 + mt * l2) * l1 * np.sin(q[:, 1])
        return M11, M12, M22, h

    def inverse_dynamics(
        self, q: np.ndarray, qd: np.ndarray, qdd: np.ndarray, p: np.ndarray, a: np.ndarray
    ) -> np.ndarray:
        """Joint torques/force (N, 3) [N·m, N·m, N], gravity included [Spong2006, Ch. 7]:

            τ1 = M11 q̈1 + M12 q̈2 + h (2 q̇1 q̇2 + q̇2²)
            τ2 = M12 q̈1 + M22 q̈2 − h q̇1²                  h = −(m2 lc2 + m_t l2) l1 sin q2
            f3 = m_t (q̈3 + g)                              m_t = m3 + payload

        The arm moves in the horizontal plane, so gravity acts only on the z axis. ``p`` and ``a`` are
        accepted for the Robot protocol and unused. Power balance: Σ τ_i q̇_i = d/dt(KE + PE).
        """
        q = _samples(q, "q")
        qd = _samples(qd, "qd")
        qdd = _samples(qdd, "qdd")
        M11, M12, M22, h = self._mass_terms(q)
        w1, w2 = qd[:, 0], qd[:, 1]
        tau1 = M11 * qdd[:, 0] + M12 * qdd[:, 1] + h * (2.0 * w1 * w2 + w2 * w2)
        tau2 = M12 * qdd[:, 0] + M22 * qdd[:, 1] - h * w1 * w1
        f3 = self.carried_mass * (qdd[:, 2] + self.g)
        return np.stack((tau1, tau2, f3), axis=1)

    def torque_rate(
        self, q: np.ndarray, qd: np.ndarray, qdd: np.ndarray, qddd: np.ndarray,
        p: np.ndarray | None = None, v: np.ndarray | None = None, a: np.ndarray | None = None,
        j: np.ndarray | None = None,
    ) -> tuple[np.ndarray, np.ndarray]:
        """Time derivatives (dA, dG), each (N, 3) [N·m/s, N·m/s, N/s], of the inertial part A (everything but
        gravity) and the static part G = (0, 0, m_t g) of :meth:`inverse_dynamics`, analytically.

        With k = (m2 lc2 + m_t l2) l1: Ṁ11 = 2 h q̇2, Ṁ12 = h q̇2, Ṁ22 = 0, ḣ = −k cos q2 q̇2; G is constant.
        """
        q = _samples(q, "q")
        qd = _samples(qd, "qd")
        qdd = _samples(qdd, "qdd")
        qddd = _samples(qddd, "qddd")
        M11, M12, M22, h = self._mass_terms(q)
        k = (self.m2 * self.lc2 + self.carried_mass * self.l2) * self.l1
        w1, w2 = qd[:, 0], qd[:, 1]
        a1, a2 = qdd[:, 0], qdd[:, 1]
        hd = -k * np.cos(q[:, 1]) * w2
        dM11, dM12 = 2.0 * h * w2, h * w2
        d1 = (
            dM11 * a1 + M11 * qddd[:, 0] + dM12 * a2 + M12 * qddd[:, 1]
            + hd * (2.0 * w1 * w2 + w2 * w2) + h * (2.0 * (a1 * w2 + w1 * a2) + 2.0 * w2 * a2)
        )
        d2 = dM12 * a1 + M12 * qddd[:, 0] + M22 * qddd[:, 1] - hd * w1 * w1 - 2.0 * h * w1 * a1
        d3 = self.carried_mass * qddd[:, 2]
        return np.stack((d1, d2, d3), axis=1), np.zeros_like(qd)

    def kinetic_energy(self, q: np.ndarray, qd: np.ndarray, v: np.ndarray | None = None) -> np.ndarray:
        """KE (N,) [J] = ½ q̇ᵀ M(q) q̇ (z term ½ m_t q̇3² included). ``v`` is unused (symmetry with the Delta)."""
        q = _samples(q, "q")
        qd = _samples(qd, "qd")
        M11, M12, M22, _ = self._mass_terms(q)
        w1, w2, w3 = qd[:, 0], qd[:, 1], qd[:, 2]
        return 0.5 * (M11 * w1 * w1 + 2.0 * M12 * w1 * w2 + M22 * w2 * w2 + self.carried_mass * w3 * w3)

    def potential_energy(self, q: np.ndarray, p: np.ndarray | None = None) -> np.ndarray:
        """PE (N,) [J] = m_t g (z0 + q3), zero at z = 0; the links move horizontally and add a constant (0)."""
        q = _samples(q, "q")
        return self.carried_mass * self.g * (self.z0 + q[:, 2])
