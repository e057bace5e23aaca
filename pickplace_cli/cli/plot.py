"""`pickplace plot`: figures of a planned move (path, profiles, motor use against limits)."""

from __future__ import annotations

import sys
from typing import Optional

import typer

from .app import Panel, _err, _handle_errors, _task_from_options, _usage, app


@app.command()
@_handle_errors
def plot(
    from_: str = typer.Option(..., "--from", help="Pick point X,Y,Z in m (base frame).", rich_help_panel=Panel.MOVE),
    to: str = typer.Option(..., "--to", help="Place point X,Y,Z in m (base frame).", rich_help_panel=Panel.MOVE),
    output: str = typer.Option(..., "--output", "-o", help="Figure file (.png or .svg), written atomically; '-' = stdout with --format.", rich_help_panel=Panel.OUTPUT),
    methods: str = typer.Option("all", "--methods", "-m", help="'all' or method names separated by commas.", rich_help_panel=Panel.STUDY),
    profile: Optional[str] = typer.Option(None, "--profile", "-p", help="Profile YAML file or shipped name. [default: delta-su2018]", rich_help_panel=Panel.MOVE),
    height: Optional[float] = typer.Option(None, "--height", help="Clearance h in m above the higher end point. [default: profile]", rich_help_panel=Panel.MOVE),
    eta: Optional[float] = typer.Option(None, "--eta", help="Lift-off/set-down ratio η, 0 < η < 1. [default: profile]", rich_help_panel=Panel.MOVE),
    time: str = typer.Option("limits", "--time", "-t", help="Duration of each method's move: 'limits' (every limit of the "
                             "profile holds), 'auto' (the Cartesian capacity alone), 'fit' (joint and motor limits "
                             "alone), 'optimal' (non-uniform time law, same path) or seconds.", rich_help_panel=Panel.METHOD),
    normalised: bool = typer.Option(False, "--normalised", help="Plot with b = 1 and T = 1 against τ (like Li 2018 Fig. 5).", rich_help_panel=Panel.STUDY),
    motors: bool = typer.Option(
        False, "--motors", help="Add each motor's speed, torque and torque rate against time in % of its limit "
        "(line style per joint), and the round trip's RMS motor torque in % of rated: where the motors idle.", rich_help_panel=Panel.STUDY),
    fmt: Optional[str] = typer.Option(None, "--format", "-f", help="png or svg. [default: from the file's suffix]", rich_help_panel=Panel.OUTPUT),
) -> None:
    """Draw the path in the vertical plane (u along the move, z) and |v|, |a|, |j| against time for one or
    several methods, and with --motors how hard each motor works (PNG or SVG; needs the optional extra:
    pip install 'pickplace-cli[plot]')."""
    from ..studies.compare import parse_methods
    from ..model.errors import PickplaceError
    from ..export import atomic_output, check_writable
    from ..export.plot import PlotMove, plot_format, require_matplotlib, write_plot
    from ..planner import PlanOptions
    from ..planner import plan as run_plan
    from ..timing import parse_time

    if motors and normalised:
        _usage("--motors draws the motors at each move's duration: not with --normalised")
    require_matplotlib()
    kind = plot_format(output, fmt)
    check_writable(output)
    from .guards import refuse_overwriting_inputs

    refuse_overwriting_inputs([("-o", output)], [], profile)
    prof, task = _task_from_options(from_, to, profile, height, eta)
    spec = parse_time(time)
    moves = []
    first_error = None
    for m in parse_methods(methods):
        try:
            res = run_plan(task, prof, PlanOptions(method=m, time=spec, fit=spec == "fit"))
        except PickplaceError as exc:
            sys.stderr.write(f"pickplace: method {m.value}: {exc}\n")
            first_error = first_error or exc
            continue
        use = None
        if motors:
            use = _motor_use(res, prof)
        moves.append(PlotMove(f"{m.value} (T = {res.duration.seconds:.4f} s)", res.cartesian, task, use))
    if not moves:
        _err("no method could plan this move")
        raise typer.Exit(first_error.exit_code if first_error else 1)
    title = f"{prof.name}: b = {task.b:.4g} m, h = {task.height:.4g} m, λ = {task.lam:.4g}"
    with atomic_output(output, binary=True) as stream:
        write_plot(moves, stream, kind, normalised, title)


def _motor_use(res, prof) -> tuple:
    """(t [s], motor curves in % of limit, RMS % of rated) of a planned move for ``plot --motors``."""
    import numpy as np

    from ..export.plot import PLOT_SAMPLES
    from ..limits.grid import jump_sides
    from ..limits.motion import limit_use
    from ..planner import motion_model

    path, T = res.cartesian.path, res.duration.seconds
    bp = np.asarray(path.breakpoints, float)
    tau = np.unique(np.clip(np.concatenate([np.linspace(0.0, 1.0, PLOT_SAMPLES), bp,
                                            jump_sides(bp, path.jumps)]), 0.0, 1.0))
    curves, rms = limit_use(motion_model(path, prof), T, tau, dwell=prof.planning.dwell)
    return tau * T, curves, rms
