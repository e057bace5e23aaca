"""``--help`` in panels: every option of every command names one of the panels (so a new option cannot slip in
without), and ``plan --help`` shows the common options (the move) first."""

from __future__ import annotations

import pytest
import typer
from typer.testing import CliRunner

from pickplace_cli.cli import app
from pickplace_cli.cli.app import Panel


def _commands():
    """(path, command) of every command of the app, sub-commands included."""
    root = typer.main.get_command(app)
    out = []

    def walk(cmd, path):
        import click  # noqa: F401 - typer's commands take a click context

        ctx = cmd.context_class(cmd)
        if hasattr(cmd, "list_commands"):
            for name in cmd.list_commands(ctx):
                walk(cmd.get_command(ctx, name), [*path, name])
        else:
            out.append((" ".join(path), cmd))

    walk(root, [])
    return out


COMMANDS = _commands()
#: commands whose options are given their panels where they are defined by another change (the line command)
PENDING: set = set()


def test_the_app_has_its_commands():
    names = {path for path, _ in COMMANDS}
    assert {"plan", "check", "build-table", "compare", "plot", "line", "profile show"} <= names


@pytest.mark.parametrize("path, cmd", [
    pytest.param(path, cmd, marks=pytest.mark.xfail(strict=True, reason="line's options get their panels in "
                                                    "cli/line.py")) if path in PENDING else (path, cmd)
    for path, cmd in COMMANDS], ids=[path for path, _ in COMMANDS])
def test_every_option_names_a_panel(path, cmd):
    missing = [p.opts[0] for p in cmd.params if p.param_type_name == "option"
               and getattr(p, "rich_help_panel", None) not in Panel.ORDER]
    assert not missing, f"{path}: options without a panel of Panel.ORDER: {missing}"


def test_plan_help_shows_the_move_first_and_the_panels_in_order():
    text = CliRunner().invoke(app, ["plan", "--help"], terminal_width=200).output
    heads = [line[:-1] for line in text.splitlines() if line.endswith(":") and not line.startswith(" ")]
    assert heads[0] == "Move" and heads[-1] == "Options", heads
    assert heads[:-1] == [p for p in Panel.ORDER if p in heads], heads
    assert {"Move", "Method and duration", "Belt and conveyor", "Output", "Controller and drive",
            "Limits and checks", "Batch and performance"} <= set(heads)
    move = text[text.index("\nMove:"):text.index("\nMethod and duration:")]
    assert "--from" in move and "--to" in move and "--profile" in move
