"""The public library API at the package root: every name of ``__all__`` is the object its module defines, loaded on
first use (``import pickplace_cli`` loads nothing heavy), and the package docstring's example plans what the command
line plans."""

from __future__ import annotations

import importlib
import json
import itertools
import subprocess
import sys
import textwrap

import pytest

import pickplace_cli


@pytest.mark.parametrize("name", sorted(pickplace_cli._PUBLIC))
def test_every_public_name_is_its_modules_object(name):
    module = importlib.import_module(f"pickplace_cli.{pickplace_cli._PUBLIC[name]}")
    assert getattr(pickplace_cli, name) is getattr(module, name)
    assert name in dir(pickplace_cli)


def test_an_unknown_name_is_an_attribute_error():
    with pytest.raises(AttributeError, match="no attribute 'planner_v2'"):
        pickplace_cli.planner_v2  # noqa: B018 - the attribute access is the test


def test_import_is_light():
    """A fresh interpreter: importing the package and reading its version loads neither numpy nor pydantic; the first
    public name loads its module."""
    code = ("import sys, pickplace_cli; v = pickplace_cli.__version__; light = 'numpy' not in sys.modules and "
            "'pydantic' not in sys.modules; pickplace_cli.Task; print(light, 'numpy' in sys.modules)")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout.split()
    assert out == ["True", "True"]


def test_docstring_example_plans_what_the_cli_plans(capsys):
    """The package docstring's example, run as written, against ``pickplace plan --json`` of the same move (a
    separate process): the same duration to the last bit the JSON carries (both are the same computation; a
    difference would be a public name bound to another object or option default)."""
    lines = pickplace_cli.__doc__.split("::", 1)[1].splitlines()[1:]
    block = [line for line in itertools.takewhile(lambda line: not line or line.startswith("    "), lines)]
    exec(compile(textwrap.dedent("\n".join(block)), "<pickplace_cli docstring>", "exec"), {})
    printed = capsys.readouterr().out
    cli = subprocess.run([sys.executable, "-m", "pickplace_cli", "plan", "--from", "-0.1525,0,-0.8", "--to",
                          "0.1525,0,-0.8", "--json"], capture_output=True, text=True)
    summary = json.loads(cli.stdout)
    assert printed == f"{summary['duration_s']:.4f} s, limits ok: {summary['limits_ok']}\n"


def test_errors_carry_the_exit_codes():
    """The documented exit codes (README, --help) on the public error classes."""
    codes = {"PickplaceError": 1, "ProfileError": 1, "TaskError": 1, "TableError": 1, "ExportError": 1,
             "UsageError": 2, "NoFeasibleDuration": 3, "UnreachableError": 4}
    assert {name: getattr(pickplace_cli, name).exit_code for name in codes} == codes
    assert all(issubclass(getattr(pickplace_cli, name), pickplace_cli.PickplaceError) for name in codes)


#: public functions whose docstrings are checked: numpydoc, every parameter documented (its unit in its text)
DOCUMENTED = ("plan", "load_profile", "parse_profile", "with_limit_use", "check_file", "atomic_output", "write_csv",
              "write_json", "write_mcap")


@pytest.mark.parametrize("name", DOCUMENTED)
def test_public_functions_document_every_parameter(name):
    """Parsed by griffe's numpydoc parser (the one the manual's API page uses): a Parameters section naming every
    parameter of the signature, a Returns or Raises section."""
    import inspect

    griffe = pytest.importorskip("griffe")
    fn = getattr(pickplace_cli, name)
    doc = griffe.Docstring(inspect.getdoc(fn), parser="numpy")
    sections = {s.kind.value: s for s in doc.parse()}
    assert "parameters" in sections, f"{name}: no Parameters section"
    documented = {p.name for p in sections["parameters"].value}
    documented |= {part.strip() for p in documented for part in p.split(",")}
    wanted = set(inspect.signature(fn).parameters) - {"self"}
    assert wanted <= documented, f"{name}: undocumented parameters {sorted(wanted - documented)}"
    assert "returns" in sections or "raises" in sections or name.startswith("write_")


@pytest.mark.parametrize("name", ["Task", "PlanOptions", "Plan", "LimitRow", "LimitReport", "Duration", "MoveCheck",
                                  "JointTrajectory", "CartesianTrajectory"])
def test_public_classes_document_their_fields(name):
    import dataclasses

    griffe = pytest.importorskip("griffe")
    cls = getattr(pickplace_cli, name)
    doc = griffe.Docstring(cls.__doc__, parser="numpy")
    names = set()
    for section in doc.parse():
        if section.kind.value in ("attributes", "parameters"):
            names |= {part.strip() for item in section.value for part in item.name.split(",")}
    fields = {f.name for f in dataclasses.fields(cls)}
    assert fields <= names, f"{name}: undocumented fields {sorted(fields - names)}"


def test_plan_docstring_example_runs():
    import doctest

    finder = doctest.DocTestFinder()
    runner = doctest.DocTestRunner(optionflags=doctest.ELLIPSIS)
    for test in finder.find(pickplace_cli.plan, "plan", globs={}):
        runner.run(test)
    result = runner.summarize(verbose=False)
    assert result.attempted >= 2 and result.failed == 0


@pytest.mark.parametrize("call, words", [
    (lambda api, t, p: api.plan(t, p, api.PlanOptions(rate=0)), "rate = 0 Hz: the output rate must be"),
    (lambda api, t, p: api.plan(t, p, api.PlanOptions(rate=float("nan"))), "rate = nan Hz"),
    (lambda api, t, p: api.plan(t, p, api.PlanOptions(rate="fast")), "rate = 'fast' Hz"),
    (lambda api, t, p: api.plan(t, p, api.PlanOptions(method="bogus")), "method = 'bogus': must be one of bspline"),
    (lambda api, t, p: api.plan(t, p, api.PlanOptions(time="optimal", law_smoothing=-1e-3)),
     "law_smoothing = -0.001: the time law's smoothing weight must be a finite number >= 0"),
    (lambda api, t, p: api.plan(t, p, api.PlanOptions(law_smoothing="some")), "law_smoothing = 'some'"),
    (lambda api, t, p: api.plan(t, 5), "profile = 5: must be a Profile"),
    (lambda api, t, p: api.plan("a move", p), "task = 'a move': must be a Task"),
    (lambda api, t, p: api.Task("0,0,-0.8", [0.1, 0, -0.8], 0.025), "from = '0,0,-0.8': needs three numbers"),
    (lambda api, t, p: api.Task([0, 0, -0.8], [0.1, 0, -0.8], None), "height = None: must be a finite number"),
    (lambda api, t, p: api.Task([0, 0, -0.8], [0.1, 0, -0.8], 0.025, "half"), "eta = 'half'"),
    (lambda api, t, p: api.check_file(__file__, None), "profile = None: must be a Profile"),
])
def test_library_errors_are_pickplace_errors(call, words):
    """Every bad argument of the library's entry points is a PickplaceError (exit code 1) with one line naming the
    field, the value and the rule, as docs/api.md says: never a bare ValueError, TypeError or AttributeError."""
    import pickplace_cli as api

    task = api.Task([-0.1525, 0, -0.8], [0.1525, 0, -0.8], 0.025)
    with pytest.raises(api.PickplaceError) as info:
        call(api, task, api.load_profile("delta-su2018"))
    assert type(info.value).__name__ == "TaskError" and info.value.exit_code == 1
    assert str(info.value).startswith(words) and "\n" not in str(info.value), str(info.value)


def test_a_profile_by_name_is_loaded(tmp_path):
    """plan() and check_file() take a profile's name (or file) as the CLI's --profile does: the same answer."""
    import pickplace_cli as api

    task = api.Task([-0.1525, 0, -0.8], [0.1525, 0, -0.8], 0.025)
    by_name = api.plan(task, "delta-su2018")
    assert by_name.duration.seconds == api.plan(task, api.load_profile("delta-su2018")).duration.seconds
    out = tmp_path / "t.csv"
    from typer.testing import CliRunner

    from pickplace_cli.cli import app

    assert CliRunner().invoke(app, ["plan", "--from", "-0.1525,0,-0.8", "--to", "0.1525,0,-0.8", "-q", "-o",
                                    str(out)]).exit_code == 0
    assert api.check_file(out, "delta-su2018")[0].report.ok
