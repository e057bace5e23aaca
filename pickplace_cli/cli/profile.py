"""`pickplace profile validate|show`: validate or inspect a robot/workcell profile."""

from __future__ import annotations

from typing import Optional

import typer

from .app import _finite, _handle_errors, app


profile_app = typer.Typer(help="Validate or inspect a robot/workcell profile.", no_args_is_help=True)


app.add_typer(profile_app, name="profile")


@profile_app.command("validate")
@_handle_errors
def profile_validate(
    profile: str = typer.Argument(..., help="Profile YAML file or shipped name."),
) -> None:
    """Validate a profile: exit 0 and one line when it is valid, exit 1 with the first problem otherwise."""
    from ..model.profile import load_profile, resolve_profile_path
    from ..robots import build_robot

    prof = load_profile(profile)
    build_robot(prof.robot)
    typer.echo(f"ok: {resolve_profile_path(profile)}: {prof.name} ({prof.robot.kind})")


@profile_app.command("show")
@_handle_errors
def profile_show(
    profile: str = typer.Argument("delta-su2018", help="Profile YAML file or shipped name."),
    z: Optional[float] = typer.Option(None, "--z", help="Working height in m for the workspace extent. [default: middle of the workcell box, or the robot's home height]"),
) -> None:
    """Show a profile with its derived values: lumped masses, workspace extent at the working height, limits."""
    from rich.console import Console
    from rich.markup import escape

    from ..model.profile import load_profile
    from ..robots import build_robot

    _finite("z", z, "in m (no NaN or inf)")
    prof = load_profile(profile)
    robot = build_robot(prof.robot)
    specs = prof.robot.joint_specs()
    out = Console(highlight=False, soft_wrap=True)
    out.print(f"[bold]{escape(prof.name)}[/] ({prof.robot.kind}): {escape(prof.description)}")
    kind = prof.robot.kind
    if kind == "delta":
        out.print(
            f"lumped model (Codourey 1998): arm inertia I_b = {robot.arm_inertia:.5g} kg·m² per arm "
            f"(upper arm + elbow + 2/3 forearm at L); travelling mass m_p = {robot.platform_mass:.4g} kg "
            f"(plate + payload + 3 × 1/3 forearm pair); arm gravity moment {robot.arm_gravity_moment:.4g} kg·m"
        )
    elif kind == "scara":
        out.print(f"carried by link 2 (z axis + payload, lumped at its end): {robot.carried_mass:.4g} kg")
    else:
        out.print("moved masses (payload included): " + ", ".join(f"{n} {m:g} kg" for n, m in zip("xyz", robot.masses)))
    rot = getattr(prof.robot, "rotary", None)
    if rot is not None:  # the fourth axis: what it turns and how the tool angle follows from the joints
        angle = f"q1 + q2 {'+' if rot.sign > 0 else '-'} q4" if kind == "scara" else f"{'' if rot.sign > 0 else '-'}q4"
        out.print(escape(
            f"rotary fourth axis: tool angle = {angle} (rad, about the base z axis); turns J_t = {rot.inertia:.4g} "
            f"kg·m² (shaft {rot.shaft_inertia:g}, tool {rot.tool_inertia:g}, payload {rot.payload_inertia:g})"
        ))
    cap = prof.capacity
    out.print(escape(
        f"capacity: [v] = {cap.velocity:g} m/s, [a] = {cap.acceleration:g} m/s², "
        f"[j] = {cap.jerk if cap.jerk is not None else 'not limited'}{' m/s³' if cap.jerk else ''}"
    ))
    pl = prof.planning
    out.print(f"planning: height {pl.height:g} m, η = {pl.eta:g}, rate {pl.rate:g} Hz, dwell {pl.dwell:g} s")
    if z is None:
        box = prof.workcell.box
        z = (box.min[2] + box.max[2]) / 2 if box else (-0.8 if kind == "delta" else (robot.z0 - 0.1 if kind == "scara" else 0.0))
    if kind == "gantry":
        out.print("workspace: the travel box " + ", ".join(f"{n} [{a.travel[0]:g}, {a.travel[1]:g}] m" for n, a in zip("xyz", prof.robot.axes)))
    else:
        from ..studies.workspace import radial_extent

        out.print(escape(f"workspace at z = {z:g} m: {radial_extent(prof, z).describe()}"))
    def g(x, unit: str = "") -> str:
        return "–" if x is None else f"{x:g}{unit}"

    for name, unit, s in zip(robot.joint_names, robot.joint_units, specs):
        lim, d = s.limits, s.drive
        pos = "–" if lim.position is None else f"[{lim.position[0]:.4g}, {lim.position[1]:.4g}] {unit}"
        out.print(escape(
            f"{name}: position {pos}; velocity {g(lim.velocity, f' {unit}/s')}; "
            f"acceleration {g(lim.acceleration, f' {unit}/s²')}; jerk {g(lim.jerk, f' {unit}/s³')}"
        ))
        if d is not None:
            out.print(escape(
                f"    drive: gear {d.gear_ratio:g}, efficiency {d.efficiency:g}, rotor {d.rotor_inertia:g} kg·m²; "
                f"rated {g(d.rated_torque, ' N·m')}, peak {g(d.peak_torque, ' N·m')}, speed {g(d.max_speed, ' rad/s')}, "
                f"torque rate {g(d.torque_rate, ' N·m/s')}"
            ))
