"""`pickplace profile validate|show`: validate or inspect a robot/workcell profile."""

from __future__ import annotations

from typing import Optional

import typer

from .app import Panel, _finite, _handle_errors, app


profile_app = typer.Typer(help="Validate, inspect, list or copy robot/workcell profiles.", no_args_is_help=True)


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
    z: Optional[float] = typer.Option(None, "--z", help="Working height in m for the workspace extent. [default: middle of the workcell box, or the robot's home height]", rich_help_panel=Panel.STUDY),
) -> None:
    """Show a profile with its derived values: lumped masses, workspace extent at the working height, limits."""
    from .render import console
    from rich.markup import escape

    from ..model.profile import load_profile, resolve_profile_path
    from ..robots import build_robot

    _finite("z", z, "in m (no NaN or inf)")
    prof = load_profile(profile)
    robot = build_robot(prof.robot)
    specs = prof.robot.joint_specs()
    out = console(highlight=False, soft_wrap=True)
    out.print(f"[bold]{escape(prof.name)}[/] ({prof.robot.kind}), from {escape(str(resolve_profile_path(profile)))}")
    for line in model_lines(prof.robot):  # the numbers the model uses, as read (the description is free text)
        out.print(escape(line))
    if prof.description:
        out.print(escape(f"description (free text, not read by the model): {prof.description}"))
    kind = prof.robot.kind
    if kind == "delta":
        if prof.robot.dynamics == "lumped":
            out.print(
                f"lumped model (Codourey 1998): arm inertia I_b = {robot.arm_inertia:.5g} kg·m² per arm "
                f"(upper arm + elbow + 2/3 forearm at L); travelling mass m_p = {robot.platform_mass:.4g} kg "
                f"(plate + payload + 3 × 1/3 forearm pair); arm gravity moment {robot.arm_gravity_moment:.4g} kg·m"
            )
        else:
            m = prof.robot.masses
            out.print(
                f"rigid-body model: each pair's rods {robot.rod_mass:.4g} kg, inertia {robot.rod_inertia:.4g} kg·m² "
                f"about their centre ({'uniform rods' if m.forearm_rod_inertia is None else 'as given'}), end "
                f"fittings {m.forearm_end_elbow:g} kg at the elbow and {m.forearm_end_plate:g} kg at the plate; "
                f"arm inertia at the motor axis I_b = {robot.arm_inertia:.5g} kg·m² per arm; mass the plate's "
                f"acceleration drives {robot.platform_mass:.4g} kg; weight on the plate "
                f"{robot.platform_weight_mass:.4g} kg; arm gravity moment {robot.arm_gravity_moment:.4g} kg·m"
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
    for line in workcell_lines(prof) + controller_lines(prof):
        out.print(escape(line))
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


def _xyz(v) -> str:
    return "(" + ", ".join(f"{c:g}" for c in v) + ")"


def workcell_lines(prof) -> list[str]:
    """The workcell section as ``profile show`` prints it: the box, the conveyor velocities and the belt window."""
    w = prof.workcell
    box = w.box
    lines = [f"workcell: box {_xyz(box.min)} … {_xyz(box.max)} m (the tool stays inside)" if box is not None
             else "workcell: no box (the robot's reach and joint ranges bound the tool)"]
    for what, v in (("pick", w.conveyor_pick_velocity), ("place", w.conveyor_place_velocity)):
        if v is not None:
            lines.append(f"    {what} conveyor velocity {_xyz(v)} m/s")
    if w.belt_window is not None:
        lines.append(f"    belt window {_xyz(w.belt_window.min)} … {_xyz(w.belt_window.max)} m")
    return lines


def controller_lines(prof) -> list[str]:
    """The controller section as ``profile show`` prints it: the cycle and each joint's drive view."""
    c = prof.controller
    if c is None:
        return ["controller: none (no cycle: samples at planning.rate; drive columns in the model's units)"]
    cycle = "no cycle (samples at planning.rate)" if c.cycle is None else f"cycle {c.cycle:g} s"
    from ..model.controller import joint_kinds

    lines = [f"controller: {cycle}"]
    for j, kind in zip(c.joints or (), joint_kinds(prof.robot)):
        extra = f", {j.counts_per_rev} counts per motor revolution" if j.counts_per_rev is not None else ""
        unit = "rad" if kind == "revolute" else "m"
        lines.append(f"    drive joint {j.name}: unit {j.unit}{extra}, sign {j.sign:+d}, offset {j.offset:g} {unit}")
    return lines


def model_lines(robot) -> list[str]:
    """The geometry and masses of a profile's robot model, as read from the file (SI units)."""
    if robot.kind == "delta":
        g, m = robot.geometry, robot.masses
        return [f"geometry: R = {g.R:g} m, r = {g.r:g} m, L = {g.L:g} m, l = {g.l:g} m",
                f"masses: upper arm {m.upper_arm:g} kg (inertia {m.upper_arm_inertia:g} kg·m² about the motor axis, "
                f"centre of mass {m.upper_arm_com:g} m from it), elbow {m.elbow:g} kg, forearm pair {m.forearm_pair:g} kg, "
                f"plate {m.plate:g} kg, payload {robot.payload:g} kg"]
    if robot.kind == "scara":
        links = [f"link {k} length {ln.length:g} m, mass {ln.mass:g} kg, centre of mass {ln.com:g} m, inertia "
                 f"{ln.inertia:g} kg·m²" for k, ln in ((1, robot.link1), (2, robot.link2))]
        return [f"geometry: {links[0]}; {links[1]}; elbow {robot.elbow}; z0 = {robot.z0:g} m",
                f"masses: z axis {robot.z_mass:g} kg, payload {robot.payload:g} kg"]
    return ["geometry: " + "; ".join(f"{a.name} travel [{a.travel[0]:g}, {a.travel[1]:g}] m" for a in robot.axes),
            "masses: " + ", ".join(f"{a.name} axis {a.mass:g} kg" for a in robot.axes) + f", payload {robot.payload:g} kg"]


@profile_app.command("list")
@_handle_errors
def profile_list() -> None:
    """List the shipped profiles: name, robot kind and file (copy one with `pickplace profile init NAME FILE`)."""
    from ..model.profile import load_profile, shipped_profiles

    for name, path in shipped_profiles().items():
        prof = load_profile(str(path))
        typer.echo(f"{name}\t{prof.robot.kind}\t{path}")


@profile_app.command("path")
@_handle_errors
def profile_path(
    profile: str = typer.Argument(..., help="Shipped profile name (or a file)."),
) -> None:
    """Print the file a profile name stands for, e.g. to copy it: cp "$(pickplace profile path gantry)" mine.yaml."""
    from ..model.profile import resolve_profile_path

    typer.echo(str(resolve_profile_path(profile).resolve()))


@profile_app.command("init")
@_handle_errors
def profile_init(
    profile: str = typer.Argument(..., help="Shipped profile name to start from (see `pickplace profile list`)."),
    output: str = typer.Argument(..., metavar="FILE", help="The new profile file (not overwritten if it exists)."),
) -> None:
    """Copy a shipped profile to FILE to edit it (an existing FILE is left as it is: exit 1). The copy's first line
    points an editor's YAML language server at the shipped JSON Schema, so the editor validates and completes it."""
    import os

    from ..export import atomic_output, check_writable
    from ..model.errors import ExportError
    from ..model.profile import resolve_profile_path, shipped_profiles

    if profile not in shipped_profiles():
        resolve_profile_path(profile)  # the usual error for an unknown name
    if os.path.lexists(output):
        raise ExportError(f"output {output}: exists; give a new file name (profile init never overwrites)")
    check_writable(output)
    text = resolve_profile_path(profile).read_text(encoding="utf-8")
    from ..model.profile import SCHEMA_FILE
    from ..model.resources import data_dir

    # the editor's schema line names the shipped schema beside the shipped profile; the copy names it where it is
    header = f"# yaml-language-server: $schema={SCHEMA_FILE}\n"
    if text.startswith(header):
        text = f"# yaml-language-server: $schema={(data_dir('profiles') / SCHEMA_FILE).resolve()}\n" + text[len(header):]
    with atomic_output(output) as stream:
        stream.write(text)
    typer.echo(f"{output}: a copy of the shipped profile {profile}; edit it and check it with "
               f"`pickplace profile validate {output}`", err=True)
