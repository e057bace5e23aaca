"""Profiles that cannot hurt the machine (issue 16, part 3): aliases and anchors, deep nesting, huge and
binary files are refused in one line naming the file and the rule (exit 1), fast and in bounded memory;
and no mutation of a valid profile ends in anything but a valid profile or one ProfileError line."""

from __future__ import annotations

import time

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from typer.testing import CliRunner

from pickplace_cli.cli import app
from pickplace_cli.model.errors import ProfileError
from pickplace_cli.model.profile import load_profile, parse_profile, resolve_profile_path

LAUGHS = "\n".join(
    [f'a: &a [{",".join(["lol"] * 9)}]']
    + [f"{c}: &{c} [{','.join([f'*{p}'] * 9)}]" for p, c in zip("abcdefgh", "bcdefghi")]
)

BAD = {
    "recursive alias": ("a: &a [*a]\n", "anchor &a is not allowed"),
    "billion laughs": (LAUGHS, "anchor &a is not allowed"),
    "merge key": ("base: &b {x: 1}\nrobot:\n  <<: *b\n", "anchor &b is not allowed"),
    "deep nesting": ("a: " + "[" * 200 + "]" * 200 + "\n", "nested deeper than 32 levels"),
}


@pytest.mark.parametrize("case", BAD, ids=list(BAD))
def test_hostile_yaml_is_one_line_fast(case, tmp_path):
    text, rule = BAD[case]
    f = tmp_path / "p.yaml"
    f.write_text(text)
    t0 = time.perf_counter()
    with pytest.raises(ProfileError) as info:
        load_profile(f)
    assert time.perf_counter() - t0 < 1.0
    msg = str(info.value)
    assert rule in msg and str(f) in msg and "\n" not in msg


def test_huge_and_binary_files_are_refused_without_reading_them(tmp_path):
    big = tmp_path / "big.yaml"
    with open(big, "wb") as fh:
        fh.truncate(200 * 1024 * 1024)  # 200 MB sparse file of NULs: read at most 1 MiB of it
    t0 = time.perf_counter()
    with pytest.raises(ProfileError, match="larger than 1048576 bytes"):
        load_profile(big)
    assert time.perf_counter() - t0 < 1.0
    binf = tmp_path / "b.yaml"
    binf.write_bytes(b"name: x\x00\x01\x02")
    with pytest.raises(ProfileError, match="binary file"):
        load_profile(binf)
    bad = tmp_path / "c.yaml"
    bad.write_bytes(b"name: \xff\xfe")
    with pytest.raises(ProfileError, match="not a text"):
        load_profile(bad)


def test_cli_exit_1_one_line(tmp_path):
    f = tmp_path / "p.yaml"
    f.write_text(LAUGHS)
    r = CliRunner().invoke(app, ["plan", "-p", str(f), "--from", "0,0,-0.8", "--to", "0.1,0,-0.8"])
    assert r.exit_code == 1 and len(r.stderr.strip().splitlines()) == 1 and "Traceback" not in r.stderr


DEFAULT = resolve_profile_path("delta-su2018").read_text()


@settings(max_examples=300, deadline=None, derandomize=True, suppress_health_check=[HealthCheck.too_slow])
@given(st.lists(st.tuples(st.integers(0, len(DEFAULT) - 1), st.integers(0, 2),
                          st.sampled_from(list(":-[]{}&*!|>#'\"\n 0123456789.e,abcx\t%@`"))), min_size=1, max_size=6))
def test_fuzzed_profiles_are_valid_or_one_profile_error(edits):
    """Seeded mutations (replace / delete / insert a character) of the shipped default profile: the parse
    ends in a Profile or in one ProfileError — one line per problem, each naming the file — never another exception
    or a traceback."""
    text = DEFAULT
    for pos, op, ch in edits:
        pos = min(pos, len(text) - 1)
        text = text[:pos] + ch + text[pos + 1:] if op == 0 else (text[:pos] + text[pos + 1:] if op == 1 else text[:pos] + ch + text[pos:])
    try:
        parse_profile(text, "fuzz.yaml")
    except ProfileError as exc:
        assert all(line.startswith("fuzz.yaml") for line in str(exc).splitlines())


# ---------------------------------------------------------------- check input (issue 16, part 3)


def test_check_refuses_a_binary_trajectory(tmp_path):
    from typer.testing import CliRunner

    from pickplace_cli.cli import app

    f = tmp_path / "traj.csv"
    f.write_bytes(b"t,q1,q2,q3\n0,0,0,0\n\x00\x01\x02" * 10)
    r = CliRunner().invoke(app, ["check", str(f)])
    assert r.exit_code == 1 and "binary file (NUL bytes)" in r.output and "Traceback" not in r.output
    r = CliRunner().invoke(app, ["check", "-"], input=b"t,q1\n\xff\xfe\n")
    assert r.exit_code == 1 and "not a text (UTF-8) file" in r.output


def test_check_refuses_a_file_over_the_bound_in_one_line_without_reading_it_all(tmp_path, monkeypatch):
    """A file over CHECK_MAX_BYTES is one line naming the file and the bound; the read stops at bound + 1
    bytes (a /dev/zero-like endless stream does not hang)."""
    import pickplace_cli.pipelines.check as C
    from typer.testing import CliRunner

    from pickplace_cli.cli import app

    monkeypatch.setattr(C, "CHECK_MAX_BYTES", 1000)
    f = tmp_path / "big.csv"
    f.write_text("t,q1,q2,q3\n" + "0,0,0,0\n" * 500)
    r = CliRunner().invoke(app, ["check", str(f)])
    lines = [ln for ln in r.output.splitlines() if ln.strip()]
    assert r.exit_code == 1 and len(lines) == 1 and "larger than 1000 bytes" in lines[0] and str(f) in lines[0]
    r = CliRunner().invoke(app, ["check", "/dev/zero"])
    assert r.exit_code == 1 and "larger than" in r.output
