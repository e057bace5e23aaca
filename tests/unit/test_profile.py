"""profile.py: shipped profiles validate; every kind of bad profile is one line naming file:line, field, value."""

from __future__ import annotations

import pytest

from pickplace_cli.errors import ProfileError
from pickplace_cli.profile import load_profile, parse_profile, shipped_profiles

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
