"""Figures of planned moves (``pickplace plot``): the path in the vertical plane of the move and the norms
|v|, |a|, |j| against time, one curve per method — the figure of [Li2018, Fig. 5] for a user's own move.

matplotlib is an optional extra (``pip install 'pickplace-cli[plot]'``); it is imported only here, and
only through :class:`matplotlib.figure.Figure` (no pyplot, no global backend switch). Output is
deterministic: no date or software version in the file's metadata, a fixed SVG hash salt.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import IO, Sequence

import numpy as np

from ..model.errors import ExportError

#: formats ``write_plot`` accepts (matplotlib's names)
FORMATS = ("png", "svg")
#: samples per curve (plus every breakpoint of the path and both sides of it, so jumps show as steps)
PLOT_SAMPLES = 1001


def require_matplotlib() -> None:
    """ExportError (one line, with the install command) when matplotlib is not installed."""
    try:
        import matplotlib  # noqa: F401
    except ImportError:
        raise ExportError(
            "plot: needs matplotlib, which is not installed; install the optional extra: "
            "pip install 'pickplace-cli[plot]'"
        ) from None


@dataclass(frozen=True)
class PlotMove:
    """One curve set: ``label``, the timed move ``trajectory`` (CartesianTrajectory) and its ``task``."""

    label: str
    trajectory: object
    task: object
    #: ``plot --motors``: (t [s] (N,), [(joint, quantity, % of limit (N,))], [(joint, RMS % of rated)]) or None
    motors: tuple | None = None


def plot_format(path: str | None, fmt: str | None) -> str:
    """The figure format: ``fmt`` if given, else the output file's suffix (.png, .svg)."""
    if fmt:
        f = fmt.lower()
    elif path and path != "-" and "." in path.rsplit("/", 1)[-1]:
        f = path.rsplit(".", 1)[-1].lower()
    else:
        raise ExportError(f"output {path or '-'}: cannot tell the figure format; give --format png|svg or a .png/.svg file")
    if f not in FORMATS:
        given = f"format = {f!r}" if fmt else f"output {path}: its suffix {f!r}"
        raise ExportError(f"{given}: a figure is written as {' or '.join(FORMATS)}")
    return f


def _samples(traj) -> np.ndarray:
    bp = np.asarray(traj.path.breakpoints, float)
    tau = np.concatenate([np.linspace(0.0, 1.0, PLOT_SAMPLES), bp, np.clip(bp - 1e-9, 0, 1), np.clip(bp + 1e-9, 0, 1)])
    return np.unique(np.clip(tau, 0.0, 1.0))


def make_figure(moves: Sequence[PlotMove], normalised: bool = False, title: str | None = None):
    """A matplotlib Figure: (path in the u–z plane) and |v|, |a|, |j| against time, one colour per move.

    ``normalised``: plot the motion with b = 1 and T = 1 (τ on the time axis, peaks divided by b) as in
    [Li2018, Fig. 5]; otherwise in SI units at each move's duration (t in s, m/s, m/s², m/s³).
    """
    require_matplotlib()
    from matplotlib.figure import Figure

    if not moves:
        raise ExportError("plot: no move to draw")
    motors = any(mv.motors is not None for mv in moves)
    fig = Figure(figsize=(11.0, 13.5 if motors else 7.5), layout="constrained")
    if motors:
        panel = fig.subplot_mosaic([["path", "v"], ["a", "j"], ["motor speed", "motor torque"],
                                    ["motor torque rate", "rms"]])
    else:
        panel = fig.subplot_mosaic([["path", "v"], ["a", "j"]])
    ax_path, ax_v, ax_a, ax_j = panel["path"], panel["v"], panel["a"], panel["j"]
    for k, mv in enumerate(moves):
        traj, task = mv.trajectory, mv.task
        path = traj.path
        tau = _samples(traj)
        color = f"C{k % 10}"
        p = path(tau, 0)
        u = (p - task.p_from) @ task.e_u
        ax_path.plot(u, p[:, 2], color=color, label=mv.label)
        T = traj.duration
        b = task.b if (normalised and task.b > 0) else 1.0
        x = tau if normalised else tau * T
        for order, ax in ((1, ax_v), (2, ax_a), (3, ax_j)):
            d = np.linalg.norm(path(tau, order), axis=1)
            y = d / b if normalised else d / T**order
            ax.plot(x, y, color=color, label=mv.label)
    t0 = moves[0].task
    ax_path.plot([0.0, t0.b], [t0.p_from[2], t0.p_to[2]], "k.", ms=8)
    ax_path.axhline(t0.z_top, color="0.6", lw=0.8, ls="--", label=f"clearance h = {t0.height:g} m")
    ax_path.set_xlabel("u along the move [m]")
    ax_path.set_ylabel("z [m]")
    ax_path.set_title("path in the vertical plane of the move")
    ax_path.legend(fontsize="small")
    tl = "τ = t/T [1]" if normalised else "t [s]"
    units = ("[1]", "[1]", "[1]") if normalised else ("[m/s]", "[m/s²]", "[m/s³]")
    names = ("|v|", "|a|", "|j|")
    for ax, name, unit in zip((ax_v, ax_a, ax_j), names, units):
        ax.set_xlabel(tl)
        ax.set_ylabel(f"{name} {unit}" + (" (b = 1, T = 1)" if normalised else ""))
        ax.grid(True, lw=0.4, color="0.85")
        ax.set_title(f"{name}{' normalised' if normalised else ''}")
    ax_path.grid(True, lw=0.4, color="0.85")
    if motors:
        _motor_panels(moves, panel)
    if title:
        fig.suptitle(title)
    return fig


_JOINT_STYLES = ("-", "--", ":", "-.")


def _motor_panels(moves: Sequence[PlotMove], ax) -> None:
    """Each motor's speed, torque and torque rate against time as % of its limit (colour: move, line style:
    joint), and the RMS motor torque over the round trip as % of rated (bars): where the motors idle."""
    rms_bars: list[tuple[int, str, float]] = []
    for k, mv in enumerate(moves):
        if mv.motors is None:
            continue
        t, curves, rms = mv.motors
        joints = list(dict.fromkeys(j for j, _, _ in curves))
        for joint, quantity, pct in curves:
            style = _JOINT_STYLES[joints.index(joint) % len(_JOINT_STYLES)]
            ax[quantity].plot(t, pct, color=f"C{k % 10}", ls=style, lw=1.1, label=f"{mv.label.split(' (')[0]} {joint}")
        rms_bars += [(k, joint, pct) for joint, pct in rms]
    for quantity in ("motor speed", "motor torque", "motor torque rate"):
        a = ax[quantity]
        a.axhline(100.0, color="k", lw=0.9)
        a.set_xlabel("t [s]")
        a.set_ylabel("% of limit")
        a.set_title(f"{quantity} (|value| / limit)")
        a.grid(True, lw=0.4, color="0.85")
        if a.lines[:-1]:
            a.legend(fontsize="x-small", ncol=2)
    a = ax["rms"]
    if rms_bars:
        joints = list(dict.fromkeys(j for _, j, _ in rms_bars))
        n = max(k for k, _, _ in rms_bars) + 1
        width = 0.8 / n
        labelled: set[int] = set()
        for k, joint, pct in rms_bars:
            label = None if k in labelled else moves[k].label.split(" (")[0]
            labelled.add(k)
            a.bar(joints.index(joint) + (k - (n - 1) / 2) * width, pct, width, color=f"C{k % 10}", label=label)
        a.legend(fontsize="x-small")
        a.set_xticks(range(len(joints)), joints)
    a.axhline(100.0, color="k", lw=0.9)
    a.set_ylabel("% of rated torque")
    a.set_title("RMS motor torque over the round trip (with dwells)")
    a.grid(True, axis="y", lw=0.4, color="0.85")


def write_plot(moves: Sequence[PlotMove], stream: IO[bytes], fmt: str = "png", normalised: bool = False,
               title: str | None = None) -> None:
    """Draw ``moves`` and write the figure to the binary ``stream`` as ``fmt`` (png or svg), deterministically."""
    import matplotlib

    if fmt not in FORMATS:
        raise ExportError(f"format = {fmt!r}: a figure is written as {' or '.join(FORMATS)}")
    fig = make_figure(moves, normalised, title)
    metadata = {"Date": None, "Creator": None} if fmt == "svg" else {"Software": None}
    with matplotlib.rc_context({"svg.hashsalt": "pickplace", "svg.fonttype": "path"}):
        fig.savefig(stream, format=fmt, metadata=metadata, dpi=110)
