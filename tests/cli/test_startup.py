"""Start-up cost: which heavy modules the CLI loads before it does any work.

`import pickplace_cli.cli`, `pickplace --help` and `pickplace --version` must not import numpy, scipy,
pydantic, yaml, mcap, matplotlib, rich or dask (each costs 50–400 ms of a cold start); a subcommand's
--help must not import scipy, mcap, matplotlib or dask either. Each check runs in a fresh interpreter.
(Wall-clock targets — --help < 0.3 s, plan of the Adept cycle < 0.8 s — are measured by bench/bench_core.py,
not asserted here: timings depend on the machine and its load.)
"""

from __future__ import annotations

import json
import subprocess
import sys

import pytest

#: never at start-up
HEAVY = ("numpy", "scipy", "pydantic", "yaml", "mcap", "mcap_ros2", "matplotlib", "rich", "dask", "distributed",
         "toppra", "ruckig", "rosbags", "pandas")
#: not even for a subcommand's --help (numpy/pydantic may come with a command's option types)
HEAVY_FOR_SUBCOMMAND_HELP = ("scipy", "mcap", "mcap_ros2", "matplotlib", "dask", "distributed", "toppra", "ruckig")


def _loaded_after(snippet: str) -> dict:
    """Run ``snippet`` in a fresh interpreter; return the top-level packages it loaded (and its output)."""
    code = (
        "import sys, json\n"
        "base = set(sys.modules)\n"
        f"{snippet}\n"
        "mods = sorted({m.split('.')[0] for m in set(sys.modules) - base})\n"
        "sys.__stdout__.write('\\nMODULES=' + json.dumps(mods) + '\\n')\n"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    line = [x for x in out.stdout.splitlines() if x.startswith("MODULES=")][-1]
    return {"modules": json.loads(line[len("MODULES="):]), "stdout": out.stdout}


def _run_cli(args: list[str]) -> str:
    return (
        "from pickplace_cli.cli import app\n"
        f"try:\n    app({args!r})\nexcept SystemExit as exc:\n    assert exc.code in (0, None), exc.code\n"
    )


def test_import_cli_loads_no_heavy_module():
    res = _loaded_after("import pickplace_cli.cli")
    assert "pickplace_cli" in res["modules"]
    assert [m for m in HEAVY if m in res["modules"]] == []


@pytest.mark.parametrize("args", [["--help"], ["--version"], ["-h"]])
def test_help_and_version_load_no_heavy_module(args):
    res = _loaded_after(_run_cli(args))
    assert [m for m in HEAVY if m in res["modules"]] == []
    if args == ["--version"]:
        assert "pickplace " in res["stdout"]
    else:
        assert "Usage:" in res["stdout"]


def _subcommands() -> list[list[str]]:
    import typer.main

    from pickplace_cli.cli import app

    out = []
    group = typer.main.get_command(app)
    for name, cmd in sorted(group.commands.items()):  # type: ignore[attr-defined]
        out.append([name, "--help"])
        for sub in sorted(getattr(cmd, "commands", {}) or {}):
            out.append([name, sub, "--help"])
    return out


@pytest.mark.parametrize("args", _subcommands(), ids=lambda a: " ".join(a[:-1]))
def test_subcommand_help_loads_no_scipy_mcap_matplotlib_dask(args):
    res = _loaded_after(_run_cli(args))
    assert [m for m in HEAVY_FOR_SUBCOMMAND_HELP if m in res["modules"]] == []


def test_every_command_is_covered():
    names = {a[0] for a in _subcommands()}
    assert {"plan", "build-table", "check", "profile"} <= names


def test_default_plan_to_csv_loads_no_scipy(tmp_path):
    """`pickplace plan` of the Adept cycle on the default profile to CSV (the 0.8 s cold-start target) runs
    without scipy: the default method's spline is evaluated with numpy and the default duration's fit is solved in
    closed form (no root finder), as with --show-fit. The time-optimal law brings scipy.optimize in."""
    args = ["plan", "--from", "-0.1525,0,-0.8", "--to", "0.1525,0,-0.8", "-o", str(tmp_path / "a.csv"), "-q"]
    res = _loaded_after(_run_cli(args))
    assert "scipy" not in res["modules"] and "mcap" not in res["modules"]
    assert (tmp_path / "a.csv").read_text().startswith("t[s]")
    res = _loaded_after(_run_cli(args + ["-t", "auto", "--show-fit"]))
    assert "scipy" not in res["modules"]
    res = _loaded_after(_run_cli(args + ["-t", "optimal"]))
    assert "scipy" in res["modules"]


def test_show_fit_adds_the_fitted_duration(tmp_path):
    from typer.testing import CliRunner

    from pickplace_cli.cli import app

    base = ["plan", "--from", "-0.1525,0,-0.8", "--to", "0.1525,0,-0.8", "-t", "auto", "--json", "-q"]
    plain = json.loads(CliRunner().invoke(app, base).stdout)
    shown = json.loads(CliRunner().invoke(app, base + ["--show-fit"]).stdout)
    assert plain["fit_s"] is None
    assert 0 < shown["fit_s"] < shown["auto_s"] == plain["auto_s"] == shown["duration_s"]
