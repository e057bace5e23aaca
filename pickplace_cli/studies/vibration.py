"""Residual vibration: one flexible mode per Cartesian axis, excited by the tool's acceleration.

Model (per base-frame axis i = x, y, z; SI units): the tool carries a flexible mode of natural frequency
f_n [Hz] (ω = 2π f_n [rad/s]) and damping ratio ζ (0 ≤ ζ < 1), whose relative displacement x_i [m] obeys

    ẍ_i + 2ζ_i ω_i ẋ_i + ω_i² x_i = −a_i(t),      x_i(0) = ẋ_i(0) = 0,

with a(t) the commanded tool acceleration [m/s²] during the move 0 ≤ t ≤ T and a = 0 afterwards (the tool
dwells). This is the base-excited single-degree-of-freedom oscillator the residual-vibration literature
uses; the profile's ``vibration`` section gives f_n and ζ per axis (stated estimates, not measurements).

The state at the end of the move is the Duhamel integral of the *continuous* acceleration (no samples):
with s = −ζω + iω_d, ω_d = ω√(1 − ζ²) and the complex integral I = ∫₀ᵀ e^{s(T−t)} a(t) dt,

    x(T) = −Im(I)/ω_d,        ẋ(T) = −Im(s·I)/ω_d

(the impulse response is h(t) = e^{−ζωt} sin(ω_d t)/ω_d = Im(e^{st})/ω_d, and h′(t) = Im(s e^{st})/ω_d).
I is computed by composite Gauss–Legendre quadrature on the path's pieces (split at its breakpoints, where
a derivative of a may jump), each piece subdivided so that no sub-interval spans more than a quarter of a
damped period; 8 nodes per sub-interval integrate a polynomial of degree 15 exactly.

After T the mode rings freely: x(t) = Re(C e^{s(t−T)}), whose envelope at T is the **residual amplitude**

    A = √( x(T)² + ((ẋ(T) + ζω x(T)) / ω_d)² )   [m],

decaying as A·e^{−ζω(t−T)}. Every time derivative of a free damped mode multiplies the complex amplitude by
s, and |s| = ω, so the residual *acceleration* (what an accelerometer on the plate reads once the move is
over, as in [Li2018, Table 3]) has envelope ω²·A [m/s²] exactly.

Departure from [Li2018, Sec. 4]: the paper measures the residual vibration along the local u and v axes on
a real robot; this model uses the base-frame x, y, z axes (for a move along x, u = x and v = z) and a
single mode per axis with no coupling between axes and no dependence on the pose.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..model.errors import ProfileError

#: Gauss–Legendre nodes per sub-interval (exact for polynomials of degree 2·8 − 1 = 15)
GAUSS_NODES = 8
#: a sub-interval spans at most this fraction of a damped period 2π/ω_d
MAX_PERIOD_FRACTION = 0.25
#: every piece between breakpoints is split into at least this many sub-intervals (non-polynomial laws)
MIN_SUBINTERVALS = 4


@dataclass(frozen=True)
class ResidualVibration:
    """Residual vibration after one move, per base-frame axis x, y, z (arrays of shape (3,)).

    ``frequency`` [Hz] and ``damping`` [1] are the modes; ``displacement`` x(T) [m] and ``velocity`` ẋ(T)
    [m/s] the modal state when the move ends; ``amplitude`` [m] the envelope of the free decay at T;
    ``acceleration_amplitude`` [m/s²] = ω²·amplitude, the envelope of the residual acceleration.
    """

    frequency: np.ndarray
    damping: np.ndarray
    displacement: np.ndarray
    velocity: np.ndarray
    amplitude: np.ndarray
    acceleration_amplitude: np.ndarray

    def __post_init__(self) -> None:
        for name in ("frequency", "damping", "displacement", "velocity", "amplitude", "acceleration_amplitude"):
            arr = np.asarray(getattr(self, name), float)
            if arr.shape != (3,):
                raise ValueError(f"{name} must have shape (3,) (axes x, y, z), got {arr.shape}")
            object.__setattr__(self, name, arr)

    @property
    def max_amplitude(self) -> float:
        """Largest residual displacement amplitude over the three axes [m]."""
        return float(np.max(self.amplitude))

    @property
    def max_acceleration_amplitude(self) -> float:
        """Largest residual acceleration amplitude over the three axes [m/s²]."""
        return float(np.max(self.acceleration_amplitude))

    def settling_time(self, tolerance: float) -> float:
        """Time after the move [s] until every axis' envelope A·e^{−ζωt} is below ``tolerance`` [m]
        (0 when it already is; inf for an undamped mode that starts above it)."""
        if not (np.isfinite(tolerance) and tolerance > 0):
            raise ValueError(f"tolerance must be a finite positive number of metres, got {tolerance!r}")
        rate = self.damping * 2.0 * np.pi * self.frequency
        out = 0.0
        for amp, r in zip(self.amplitude, rate):
            if amp <= tolerance:
                continue
            out = max(out, float(np.log(amp / tolerance) / r) if r > 0 else float("inf"))
        return out

    def as_dict(self) -> dict:
        return {
            "frequency_hz": self.frequency.tolist(),
            "damping": self.damping.tolist(),
            "displacement_at_end_m": self.displacement.tolist(),
            "velocity_at_end_m_s": self.velocity.tolist(),
            "amplitude_m": self.amplitude.tolist(),
            "acceleration_amplitude_m_s2": self.acceleration_amplitude.tolist(),
            "max_amplitude_m": self.max_amplitude,
            "max_acceleration_amplitude_m_s2": self.max_acceleration_amplitude,
        }


def _modes(frequency, damping) -> tuple[np.ndarray, np.ndarray]:
    f = np.broadcast_to(np.asarray(frequency, float), (3,)).copy()
    z = np.broadcast_to(np.asarray(damping, float), (3,)).copy()
    if not np.all(np.isfinite(f) & (f > 0)):
        raise ProfileError(f"vibration.frequency = {f.tolist()}: natural frequencies must be finite and > 0 Hz")
    if not np.all(np.isfinite(z) & (z >= 0) & (z < 1)):
        raise ProfileError(f"vibration.damping = {z.tolist()}: damping ratios must satisfy 0 <= ζ < 1 (underdamped)")
    return f, z


def residual_amplitude(x: np.ndarray, xd: np.ndarray, frequency, damping) -> np.ndarray:
    """Envelope at the end of the move [m] of the free decay from state (x [m], ẋ [m/s]) (see module doc)."""
    f, z = _modes(frequency, damping)
    w = 2.0 * np.pi * f
    wd = w * np.sqrt(1.0 - z * z)
    x = np.asarray(x, float)
    xd = np.asarray(xd, float)
    return np.hypot(x, (xd + z * w * x) / wd)


def _quadrature(edges: np.ndarray, max_step: float) -> tuple[np.ndarray, np.ndarray]:
    """Composite Gauss–Legendre nodes and weights on [edges[0], edges[-1]] (every sub-interval ≤ max_step)."""
    g, gw = np.polynomial.legendre.leggauss(GAUSS_NODES)
    lengths = np.diff(edges)
    keep = lengths > 0
    lo, lengths = edges[:-1][keep], lengths[keep]
    counts = np.maximum(MIN_SUBINTERVALS, np.ceil(lengths / max_step)).astype(int)
    starts = np.concatenate([lo0 + np.arange(n) * (L / n) for lo0, L, n in zip(lo, lengths, counts)])
    widths = np.repeat(lengths / counts, counts)
    nodes = (starts[:, None] + widths[:, None] * (g[None, :] + 1.0) / 2.0).ravel()
    weights = (widths[:, None] * gw[None, :] / 2.0).ravel()
    return nodes, weights


def mode_state(traj, frequency, damping) -> tuple[np.ndarray, np.ndarray]:
    """Modal state (x(T) [m], ẋ(T) [m/s]), each (3,), at the end of the move ``traj`` (a
    :class:`~pickplace_cli.model.trajectory.CartesianTrajectory`), from rest, by the Duhamel integral of its
    continuous acceleration (module docstring)."""
    f, z = _modes(frequency, damping)
    T = float(traj.duration)
    w = 2.0 * np.pi * f
    wd = w * np.sqrt(1.0 - z * z)
    s = -z * w + 1j * wd  # (3,)
    edges = np.unique(np.concatenate([[0.0, 1.0], np.clip(np.asarray(traj.path.breakpoints, float), 0.0, 1.0)])) * T
    max_step = MAX_PERIOD_FRACTION * 2.0 * np.pi / float(np.max(wd))
    t, wt = _quadrature(edges, max_step)
    a = traj(t, 2)  # (N, 3) m/s²
    kernel = np.exp(np.outer(T - t, s))  # (N, 3)
    integral = np.sum((wt[:, None] * kernel) * a, axis=0)  # I per axis
    x = -integral.imag / wd
    xd = -(s * integral).imag / wd
    return x, xd


def residual_vibration(traj, vibration) -> ResidualVibration:
    """Residual vibration of ``traj`` for the modes of ``vibration`` (the profile's
    :class:`~pickplace_cli.model.profile.Vibration` section, or any object with ``frequency`` [Hz] and
    ``damping`` [1], each a number or three numbers for x, y, z)."""
    f, z = _modes(vibration.frequency, vibration.damping)
    x, xd = mode_state(traj, f, z)
    amp = residual_amplitude(x, xd, f, z)
    w = 2.0 * np.pi * f
    return ResidualVibration(f, z, x, xd, amp, w * w * amp)
