"""Value objects of the pipeline: CartesianPath → CartesianTrajectory → JointTrajectory.

One evaluation convention everywhere: ``f(x, order=0)`` returns an ``(N, 3)`` array; axis 0 is samples.
``order`` is the time derivative: 0 position [m], 1 velocity, 2 acceleration, 3 jerk.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, Callable, Mapping

import numpy as np

#: Signature of a path/trajectory evaluator: (x (N,), order) -> (N, 3).
Evaluator = Callable[[np.ndarray, int], np.ndarray]


#: most output samples of one move (1 s at the profile's highest rate, 1 MHz; ~1.5 GB of model arrays)
MAX_SAMPLES = 1_000_000


@dataclass(frozen=True)
class CartesianPath:
    """Geometry + motion law on normalised time ``tau`` ∈ [0, 1] (duration T = 1).

    ``path(tau, order)`` gives the ``order``-th derivative with respect to ``tau`` in m/1^order, i.e. the
    motion of the move when it takes exactly one second. Scaling to a duration T is exact:
    d^k p/dt^k = path(t/T, k) / T^k.

    ``max_order`` is the highest derivative that exists and is continuous (3 = jerk for every method here).
    ``peaks`` are the exact maxima of ‖d^k p/dτ^k‖ for k = 1, 2, 3 on τ ∈ [0, 1] (m/1^k), computed by the
    method itself from its own closed form (not from samples); ``breakpoints`` are the τ where the pieces
    of the curve join (knots), useful to samplers. ``jumps`` are the τ where a derivative up to jerk may
    step (a motion law's jerk, a corner's curvature rate): the limit check samples both one-sided limits
    there and never interpolates across them. None (the default) takes every breakpoint as a possible
    jump, the safe choice; a path that is C⁴ across its knots (an interpolating quintic spline) passes ().
    """

    evaluate: Evaluator
    method: str
    parameters: Mapping[str, Any]
    peaks: tuple[float, float, float]
    breakpoints: np.ndarray = field(default_factory=lambda: np.array([0.0, 1.0]))
    max_order: int = 3
    jumps: np.ndarray | tuple | None = None
    #: optional (tau (N,)) → [p, p′, p″, p‴] in one pass (new arrays); :meth:`all_orders` falls back to
    #: ``evaluate`` per order without it
    evaluate_all: Callable[[np.ndarray], list] | None = None
    #: optional angle law of the tool about the vertical (a rotary fourth axis): ``angle(tau, order)`` → (N,) in
    #: rad/1^order and ``angle.all_orders(tau)`` → (4, N), on the same τ and scaled with T like the path
    #: (:mod:`pickplace_cli.curves.rotation`); None: the tool does not turn
    angle: Any = None

    def angle_orders(self, tau: np.ndarray) -> np.ndarray | None:
        """θ, θ′, θ″, θ‴ at τ as a (4, N) array [rad/1^k], or None when the path carries no angle law."""
        return None if self.angle is None else self.angle.all_orders(np.atleast_1d(np.asarray(tau, dtype=float)))

    @property
    def jump_points(self) -> np.ndarray:
        """Interior τ where a derivative up to jerk may step (``jumps``, or every breakpoint when None)."""
        j = np.asarray(self.breakpoints if self.jumps is None else self.jumps, float)
        return j[(j > 0.0) & (j < 1.0)]

    def __call__(self, tau: np.ndarray, order: int = 0) -> np.ndarray:
        if not 0 <= order <= self.max_order:
            raise ValueError(f"order must be in 0..{self.max_order}, got {order}")
        return self.evaluate(np.atleast_1d(np.asarray(tau, dtype=float)), order)

    def all_orders(self, tau: np.ndarray) -> list[np.ndarray]:
        """[p, p′, p″, p‴] at τ (each (N, 3)), as four calls of the path would give them."""
        tau = np.atleast_1d(np.asarray(tau, dtype=float))
        if self.evaluate_all is not None:
            return self.evaluate_all(tau)
        return [self.evaluate(tau, k) for k in range(4)]


@dataclass(frozen=True)
class CartesianTrajectory:
    """A CartesianPath run in ``duration`` seconds.

    Attributes
    ----------
    path : CartesianPath
        The path, a function of τ ∈ `[0, 1]`, in m.
    duration : float
        T [s].

    Notes
    -----
    ``traj(t, order)`` evaluates the motion at times ``t`` [s], shape (N, 3): position [m] (order 0), velocity
    [m/s], acceleration [m/s²], jerk [m/s³].
    """

    path: CartesianPath
    duration: float

    def __post_init__(self) -> None:
        if not (np.isfinite(self.duration) and self.duration > 0):
            raise ValueError(f"duration must be a finite positive number of seconds, got {self.duration!r}")

    def __call__(self, t: np.ndarray, order: int = 0) -> np.ndarray:
        t = np.atleast_1d(np.asarray(t, dtype=float))
        return self.path(t / self.duration, order) / self.duration**order

    def peaks(self) -> tuple[float, float, float]:
        """Exact peaks of |v| [m/s], |a| [m/s²], |j| [m/s³] (scaled from the path's normalised peaks)."""
        T = self.duration
        v, a, j = self.path.peaks
        return v / T, a / T**2, j / T**3

    def sample_times(self, rate: float) -> np.ndarray:
        """Times from 0 to T inclusive at ``rate`` Hz; the last interval may be shorter so T is always a sample."""
        if not (np.isfinite(rate) and rate > 0):
            raise ValueError(f"rate must be a finite positive number of Hz, got {rate!r}")
        n = self.duration * rate + 1e-9
        if not n <= MAX_SAMPLES:
            from .errors import TaskError

            raise TaskError(
                f"rate = {rate:g} Hz: the move of T = {self.duration:.6g} s would have {n + 1:.4g} samples; "
                f"at most {MAX_SAMPLES:,} per move (lower --rate, or check the duration)"
            )
        n = int(np.floor(n))
        t = np.arange(n + 1) / rate
        if self.duration - t[-1] > 1e-9 * min(1.0 / rate, self.duration):
            t = np.append(t, self.duration)
        else:
            t[-1] = self.duration
        if len(t) < 2:  # rate below 1/T: still the two ends
            t = np.array([0.0, self.duration])
        return t


@dataclass(frozen=True)
class JointTrajectory:
    """Sampled joint motion: every array is (N, n_joints) with axis 0 = samples at times ``t`` (N,).

    Attributes
    ----------
    t : numpy.ndarray
        Sample times [s], (N,).
    q, qd, qdd, qddd : numpy.ndarray
        Joint position [rad or m], velocity [/s], acceleration [/s²] and jerk [/s³].
    names, units : tuple of str
        Each joint's name and unit (``rad`` or ``m``).
    torque : numpy.ndarray or None
        Joint-side torque [N·m] or force [N], gravity included.
    motor_speed, motor_torque : numpy.ndarray or None
        Each motor's speed [rad/s] and torque [N·m].
    angle_weights : tuple of float or None
        A rotary fourth axis: the tool angle is θ = q · angle_weights [rad].

    Units are per joint (``units``: "m" for prismatic, "rad" for revolute); derivatives are per second.
    ``torque`` is joint-side force/torque [N or N·m] (inverse dynamics, gravity included);
    ``motor_speed`` [rad/s] = N·q̇ and ``motor_torque`` [N·m] = torque/(N·η) + J_rotor·N·q̈ (joints without a
    drive: gear 1, efficiency 1, no rotor). ``None`` when not computed.
    """

    t: np.ndarray
    q: np.ndarray
    qd: np.ndarray
    qdd: np.ndarray
    qddd: np.ndarray
    names: tuple[str, ...]
    units: tuple[str, ...]
    torque: np.ndarray | None = None
    motor_speed: np.ndarray | None = None
    motor_torque: np.ndarray | None = None
    #: a robot with a rotary fourth axis: the tool angle about the base z axis is θ = q·angle_weights [rad] (and
    #: θ̇ = q̇·w, θ̈ = q̈·w: it is linear in the joints); None: the tool does not turn
    angle_weights: tuple[float, ...] | None = None

    def __post_init__(self) -> None:
        n = len(self.t)
        if np.ndim(self.t) != 1:
            raise ValueError(f"t must be 1-D, got shape {np.shape(self.t)}")
        shape = (n, len(self.names))
        for name in ("q", "qd", "qdd", "qddd", "torque", "motor_speed", "motor_torque"):
            arr = getattr(self, name)
            if arr is not None and np.shape(arr) != shape:
                raise ValueError(f"{name} must have shape {shape} (samples × joints), got {np.shape(arr)}")
        if len(self.units) != len(self.names):
            raise ValueError(f"units ({len(self.units)}) and names ({len(self.names)}) differ in length")
