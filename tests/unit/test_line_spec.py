"""The line file (line/spec.py): pydantic validation and the rules across fields, each refusal one line naming the
field (with its file line), the value and the rule."""

from __future__ import annotations

import pytest

from pickplace_cli.line.spec import parse_line, robot_bands, upstream_order
from pickplace_cli.model.errors import ProfileError

BASE = """\
belt: {speed: 0.5, width: 0.3}
robots:
  - name: r1
    base: [0.6, 0.0, 0.8]
    window: [0.4, 0.8]
    place: {points: [[0.6, 0.35, 0.0]]}
  - name: r2
    base: [1.4, 0.0, 0.8]
    window: [1.2, 1.6]
    place: {tray: {origin: [1.4, 0.3, 0.0], rows: 2, columns: 3}}
parts:
  generate: {rate: 5.0, count: 10}
"""


def _err(text: str) -> str:
    with pytest.raises(ProfileError) as exc:
        parse_line(text, "l.yaml")
    msg = str(exc.value)
    assert "\n" not in msg
    return msg


def test_a_valid_file_and_its_defaults():
    line = parse_line(BASE, "l.yaml")
    assert line.strategy.kind == "upstream_first" and line.belt.direction == "+y"
    assert upstream_order(line) == [0, 1]
    assert robot_bands(line) == [(-0.15, 0.0), (0.0, 0.15)]


@pytest.mark.parametrize("edit, expected", [
    (("speed: 0.5", "speeed: 0.5"), "l.yaml:1: unknown key 'belt.speeed'"),
    (("speed: 0.5", "speed: -0.5"), "l.yaml:1: belt.speed = -0.5: Input should be greater than or equal to 0.001"),
    (("speed: 0.5", "speed: yes"), "belt.speed = true: must be a number, not a flag"),
    (("speed: 0.5", 'speed: "0.5"'), "belt.speed = '0.5': must be a number, not text (write the number without "
                                     "quotes)"),
    (("speed: 0.5", 'speed: "fast"'), "belt.speed = 'fast': must be a number"),
    (("window: [0.4, 0.8]", "window: [0.8, 0.4]"), "robots.0: window = [0.8, 0.4] m: needs start < end"),
    (("place: {points: [[0.6, 0.35, 0.0]]}", "place: {points: [[0.6, 0.35, 0.0]], belt: {point: [0, 0, 0], velocity: [0.1, 0]}}"),
     "robots.0.place: give exactly one of points, tray, belt (got points, belt)"),
    (("name: r2", "name: r1"), "robots: name 'r1' is used twice"),
    (("rate: 5.0, count: 10", "rate: 5.0"), "parts.generate: give one of count (parts) or duration (s)"),
    (("base: [0.6, 0.0, 0.8]", "base: [0.6, 0.0]"), "l.yaml:4: robots.0.base = [0.6, 0.0]: needs 3 values, got 2"),
])
def test_one_line_per_problem(edit, expected):
    assert expected in _err(BASE.replace(*edit, 1))


def test_strategy_rules():
    assert "strategy.kind = 'fastest': must be one of" in _err(BASE + "strategy: {kind: fastest}\n")
    assert "strategy.shares has 3 values for 2 robots" in _err(BASE + "strategy: {kind: quota, shares: [0.3, 0.3, 0.4]}\n")
    assert "must add up to 1 (they add up to 0.9)" in _err(BASE + "strategy: {kind: quota, shares: [0.5, 0.4]}\n")
    assert "strategy.bands of robot r2 = [0, 0.2] m: must lie on the belt, within ±0.15 m" in _err(
        BASE + "strategy: {kind: bands, bands: [[-0.15, 0], [0, 0.2]]}\n")
    assert "strategy.bands has 1 bands for 2 robots" in _err(BASE + "strategy: {kind: bands, bands: [[-0.15, 0]]}\n")


def test_windows_that_overlap_need_bands_that_do_not():
    text = BASE.replace("window: [1.2, 1.6]", "window: [0.7, 1.1]")
    msg = _err(text)
    assert msg.startswith("l.yaml: robots r1 and r2: windows [0.4, 0.8] and [0.7, 1.1] m overlap by 0.1 m along the "
                          "belt, and strategy upstream_first lets both work on the same stretch of belt")
    # bands keep them apart across the belt: accepted; with an overlap tolerance that makes the bands meet: refused
    assert parse_line(text + "strategy: {kind: bands}\n", "l.yaml").strategy.kind == "bands"
    assert "share part of the belt's width" in _err(text + "strategy: {kind: bands, overlap: 0.01}\n")


def test_yaml_aliases_and_binary_files_are_refused(tmp_path):
    from pickplace_cli.line.spec import load_line

    assert "YAML anchor &s is not allowed in a line file" in _err("belt: &s {speed: 0.5, width: 0.3}\nrobots: *s\n")
    p = tmp_path / "l.yaml"
    p.write_bytes(b"\xff\xfeb\x00e\x00")
    with pytest.raises(ProfileError) as exc:
        load_line(p)
    assert "binary file" in str(exc.value)


def test_numbers_in_exponent_form_are_numbers():
    """``5e-2`` (a YAML 1.2 number, text to YAML 1.1) is the number 0.05, as in a profile."""
    line = parse_line(BASE.replace("speed: 0.5", "speed: 5e-1", 1), "l.yaml")
    assert line.belt.speed == 0.5
