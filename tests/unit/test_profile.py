"""profile.py: shipped profiles validate; every kind of bad profile is one line naming file:line, field, value."""

from __future__ import annotations

import pytest

from pickplace_cli.model.errors import ProfileError
from pickplace_cli.model.profile import load_profile, parse_profile, shipped_profiles

GANTRY = """\
name: g
robot:
  kind: gantry
  axes:
    - {name: x, travel: [-1, 1], mass: 1}
    - {name: y, travel: [-1, 1], mass: 1}
    - {name: z, travel: [-1, 0.2], mass: 1}
capacity: {velocity: 10, acceleration: 160}
planning: {height: 0.025, eta: 0.5, rate: 1000}
"""


@pytest.mark.parametrize("name", sorted(shipped_profiles()))
def test_shipped_profiles_validate(name):
    prof = load_profile(name)
    assert prof.name
    assert prof.planning.height > 0


def test_gantry_profile_meets_the_issue():
    """Issue: travel at least x, y ∈ [−1, 1] m, z ∈ [−1, 0.2] m; a 1 m move in 1 s is fine."""
    prof = load_profile("gantry")
    tr = [a.travel for a in prof.robot.axes]
    assert tr[0][0] <= -1 and tr[0][1] >= 1 and tr[1][0] <= -1 and tr[1][1] >= 1
    assert tr[2][0] <= -1 and tr[2][1] >= 0.2


@pytest.mark.parametrize(
    "edit,match",
    [
        (("mass: 1}", "mass: 1, colour: red}", 1), r"<p>:5: unknown key 'robot.axes.0.colour'"),
        (("velocity: 10", "velocity: -10", 1), r"<p>:8: capacity.velocity = -10: Input should be greater than 0"),
        (("velocity: 10", "velocity: .nan", 1), r"<p>:8: capacity.velocity = nan"),
        (("eta: 0.5", "eta: 1.5", 1), r"<p>:9: planning.eta = 1.5: Input should be less than 1"),
        (("travel: [-1, 1], mass: 1}", "travel: [1, -1], mass: 1}", 1), r"<p>:5: robot.axes.0"),
        (("kind: gantry", "kind: hexapod", 1), r"<p>:3: robot.*hexapod"),
        (("name: g\n", "", 1), r"name: required field is missing"),
        (("planning:", "capacity: {velocity: 1, acceleration: 1}\nplanning:", 1), r"duplicate key 'capacity' \(first at line 8\)"),
        (("name: g", "name: [unclosed", 1), r"not valid YAML"),
    ],
)
def test_bad_profiles_one_line(edit, match):
    old, new, n = edit
    text = GANTRY.replace(old, new, n)
    with pytest.raises(ProfileError, match=match) as ei:
        parse_profile(text, "<p>")
    assert "\n" not in str(ei.value)


def test_not_a_mapping():
    with pytest.raises(ProfileError, match="must be a YAML mapping"):
        parse_profile("- 1\n- 2\n", "<p>")


def test_missing_profile_names_the_shipped_ones(tmp_path):
    with pytest.raises(ProfileError, match="shipped: .*gantry"):
        load_profile(str(tmp_path / "nope.yaml"))


def test_profile_is_frozen():
    prof = parse_profile(GANTRY)
    with pytest.raises(Exception):
        prof.name = "other"  # type: ignore[misc]


# ---------------------------------------------------------------- messages that name field, value and rule


def _edit(name: str, old: str, new: str) -> str:
    from pickplace_cli.model.profile import resolve_profile_path

    text = resolve_profile_path(name).read_text()
    assert old in text, old
    return text.replace(old, new, 1)


@pytest.mark.parametrize(
    "name,old,new,expect",
    [
        # a one-element range in a per-joint list: was "robot.joints: Input should be a valid dictionary" (the
        # single-spec branch of the union) or "required field is missing"
        ("scara-600", "position: [-2.3038346, 2.3038346]", "position: [-0.6981317]",
         "<p>:19: robot.joints.0.limits.position = [-0.6981317]: needs 2 values, got 1; expected: joint range [min, max] in rad"),
        ("delta-su2018", "position: [-0.6981317, 1.5707963]", "position: [-0.6981317]",
         "robot.joints.limits.position = [-0.6981317]: needs 2 values, got 1; expected: joint range [min, max] in rad"),
        ("scara-600", "position: [-2.3038346, 2.3038346]", "position: [-1, 0, 1]",
         "robot.joints.0.limits.position = [-1, 0, 1]: needs 2 values, got 3"),
        ("scara-600", "position: [-2.3038346, 2.3038346]", "position: [a, 1]",
         "robot.joints.0.limits.position.0 = 'a': must be a number"),
        ("scara-600", "frequency: [12.0, 12.0, 30.0]", "frequency: [12.0, 12.0]",
         "vibration.frequency = [12.0, 12.0]: needs 3 values, got 2; expected: natural frequency f_n of the mode along x, y, z in Hz"),
        ("scara-600", "frequency: [12.0, 12.0, 30.0]", "frequency: 12",
         "vibration.frequency = 12: must be a list"),
        ("scara-600", "length: 0.325", "length: [0.325]",
         "<p>:11: robot.link1.length = [0.325]: must be a number, not a list; expected: link length in m"),
        ("delta-su2018", "L: 0.325", "L: [0.325]", "robot.geometry.L = [0.325]: must be a number, not a list; expected: upper arm length"),
        ("scara-600", "velocity: 4.0", "velocity: {a: 1}", "capacity.velocity = {a: 1}: must be a number, not a mapping"),
        ("scara-600", "  payload: 1.0 ", "  payload: true ", "<p>:16: robot.payload = true: must be a number, not a flag"),
        ("scara-600", "elbow: right", "elbow: yes", "robot.elbow = true: must be text (quote it), not a flag"),
        ("scara-600", "  payload: 1.0 ", "  payload: '0.5' ",
         "<p>:16: robot.payload = '0.5': must be a number, not text (write the number without quotes)"),
        ("delta-4axis", "rate: 1000.0", 'rate: "1000"', "planning.rate = '1000': must be a number, not text"),
        ("delta-4axis", "{name: A1, unit: counts, counts_per_rev: 1048576}",
         "{name: A1, unit: counts, counts_per_rev: '1048576'}",
         "controller.joints.0.counts_per_rev = '1048576': must be a number, not text"),
        ("delta-4axis", "{name: A1, unit: counts, counts_per_rev: 1048576}",
         "{name: A1, unit: counts, counts_per_rev: " + "1" * 400 + "}",
         "controller.joints.0.counts_per_rev = 1111"),  # an int beyond a float's range was an internal error
        ("delta-4axis", "box: {min: [-0.6,", "box: {min: ['-0.6',", "workcell.box.min.0 = '-0.6': must be a number, not"),
        ("scara-600", "kind: scara", "kind: robot", "<p>:10: robot.kind = 'robot': must be one of 'gantry', 'delta', 'scara'"),
        ("scara-600", "  z_mass: 1.5", "  z_mass: 1.5\n  colour: red",
         "unknown key 'robot.colour': not a field of this section (check spelling; keys are case-sensitive; fields here: kind, link1"),
        ("scara-600", "gear_ratio: 80.0, ", "", "robot.joints.0.drive.gear_ratio: required field is missing; expected: N: motor angle"),
    ],
)
def test_profile_errors_name_field_value_and_rule(name, old, new, expect):
    with pytest.raises(ProfileError) as ei:
        parse_profile(_edit(name, old, new), "<p>")
    msg = str(ei.value)
    assert expect in msg
    assert "\n" not in msg and "Input should be a valid dictionary" not in msg


@pytest.mark.parametrize("rated,peak,ok", [(20, 8.36, False), (8.36, 8.36, True), (2.39, 8.36, True)])
def test_rated_torque_above_peak_is_refused(rated, peak, ok):
    text = _edit("delta-su2018", "rated_torque: 2.39", f"rated_torque: {rated}").replace("peak_torque: 8.36", f"peak_torque: {peak}", 1)
    if ok:
        assert parse_profile(text).robot.joint_specs()[0].drive.rated_torque == rated
        return
    with pytest.raises(ProfileError) as ei:
        parse_profile(text, "<p>")
    msg = str(ei.value)
    assert "robot.joints.drive: rated_torque = 20 N·m is above peak_torque = 8.36 N·m" in msg
    assert "cannot exceed its peak" in msg and "\n" not in msg


def test_number_fields_are_strict_in_the_library_too():
    """The models themselves take an int or a float for a number field and refuse a flag or text (pydantic's lax
    mode took ``True`` as 1.0 and ``'0.5'`` as 0.5), whoever builds them."""
    from pydantic import ValidationError

    from pickplace_cli.model.controller import Controller, DriveJoint
    from pickplace_cli.model.profile import Capacity

    assert Capacity(velocity=5, acceleration=100.0).velocity == 5.0
    for bad in (True, "5", b"5", "fast"):
        with pytest.raises(ValidationError, match="must be a number"):
            Capacity(velocity=bad, acceleration=100.0)
    with pytest.raises(ValidationError, match="must be a number, not text"):
        DriveJoint(name="A1", unit="counts", counts_per_rev="1048576")
    with pytest.raises(ValidationError, match="must be a number, not a flag"):
        Controller(cycle=True)


def test_numbers_in_exponent_form_are_numbers():
    """YAML 1.2 reads 4.18e2, 15e-5 and 1E6 as numbers; PyYAML's YAML 1.1 rules read them as text (no dot or no
    exponent sign), which a number field refused as "a number in quotes". They load as the numbers they are; a
    number in quotes is still refused."""
    from pickplace_cli.model.profile import resolve_profile_path

    text = open(resolve_profile_path("delta-su2018")).read()
    assert "torque_rate: 418.0" in text and "rotor_inertia: 1.5e-4" in text
    base = parse_profile(text, "d.yaml")
    same = parse_profile(text.replace("torque_rate: 418.0", "torque_rate: 4.18e2")
                         .replace("rotor_inertia: 1.5e-4", "rotor_inertia: 15e-5"), "d.yaml")
    assert same.robot.joint_specs() == base.robot.joint_specs()
    with pytest.raises(ProfileError, match="must be a number, not text"):
        parse_profile(text.replace("torque_rate: 418.0", "torque_rate: '4.18e2'"), "d.yaml")


def test_text_that_looks_like_an_exponent_number_stays_text():
    """A name written 1e5 (a number in YAML 1.2's eyes) stays the text it was in a text field."""
    from pickplace_cli.model.profile import resolve_profile_path

    text = open(resolve_profile_path("delta-su2018")).read()
    lines = text.splitlines()
    k = next(i for i, ln in enumerate(lines) if ln.startswith("name:"))
    lines[k] = "name: 1e5"
    prof = parse_profile("\n".join(lines) + "\n", "d.yaml")
    assert prof.name == "1e5" and isinstance(prof.name, str)
