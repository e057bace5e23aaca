"""The manual and the README: the site builds in strict mode (a broken link, anchor or reference fails), and every
example runs and prints what is shown.

Examples, page by page, in a fresh temporary folder per page (``docs/development.md`` describes the conventions):

* a block with ``title="NAME"`` (not ``Output``) is written to the file NAME first;
* ``console``, ``bash`` and ``sh`` blocks run in bash: their ``$ `` lines are the commands (a trailing ``\\`` joins
  the next line), and the lines under a command are what it prints on stdout and stderr, compared with spaces
  collapsed; a shown line starting with ``…`` stands for any number of lines, one ending with ``…`` for the rest of
  a line. A block without ``$ `` lines runs each line as a command, its output not compared;
* ``python`` blocks run in this process; a following ``text title="Output"`` block is what they must print;
  ``pycon`` blocks run as doctests;
* ``<!-- example: skip (why) -->`` just before a block leaves it out.
"""

from __future__ import annotations

import contextlib
import doctest
import io
import os
import re
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
DOCS = ROOT / "docs"
PAGES = [ROOT / "README.md", *sorted(p for p in DOCS.rglob("*.md") if "hooks" not in p.parts)]
#: pages whose examples run for many seconds (a line simulated for a minute, belt schedules, the production recipe)
SLOW = {"commands/line.md", "pipelines.md", "getting-started.md"}

FENCE = re.compile(r"^(?P<indent>[ \t]*)```(?P<info>[^\n`]*)\n(?P<body>.*?)^(?P=indent)```[ \t]*$", re.M | re.S)
SKIP = re.compile(r"<!--\s*example:\s*skip\b[^>]*-->\s*$")
TITLE = re.compile(r'title="([^"]+)"')
SHELLS = ("console", "bash", "sh")


def _blocks(text: str):
    """(language, title, body dedented, skipped) of every fenced block, in order."""
    end = 0
    for m in FENCE.finditer(text):
        before = text[end:m.start()].rstrip()
        end = m.end()
        info = m.group("info").strip()
        indent = len(m.group("indent"))
        body = "\n".join(line[indent:] for line in m.group("body").splitlines())
        title = TITLE.search(info)
        yield info.split()[0] if info else "", title.group(1) if title else None, body, bool(SKIP.search(before))


def _commands(body: str) -> list[tuple[str, list[str] | None]]:
    """(command, lines shown under it or None when not compared) of a shell block."""
    lines = body.splitlines()
    prompted = any(line.startswith("$ ") for line in lines)
    out: list[tuple[str, list[str] | None]] = []
    i = 0
    while i < len(lines):
        line = lines[i]
        i += 1
        if prompted and not line.startswith("$ "):
            if out:
                out[-1][1].append(line)
            continue
        cmd = line[2:] if prompted else line
        while cmd.endswith("\\") and i < len(lines):
            cmd = cmd[:-1] + " " + lines[i].strip()
            i += 1
        if not prompted and (not cmd.strip() or cmd.lstrip().startswith("#")):
            continue
        out.append((cmd, [] if prompted else None))
    return out


def _norm(line: str) -> str:
    return " ".join(line.split())


def _matches(shown: list[str], actual: list[str]) -> bool:
    """Whether the actual lines fit the shown ones (``…`` lines are wildcards, ``…`` at a line's end a prefix)."""
    shown = [_norm(s) for s in shown if s.strip()]
    actual = [_norm(a) for a in actual if a.strip()]

    def fit(i: int, j: int) -> bool:
        if i == len(shown):
            return j == len(actual)
        s = shown[i]
        if s.startswith("…"):
            return any(fit(i + 1, k) for k in range(j, len(actual) + 1))
        if j == len(actual):
            return False
        a = actual[j]
        ok = a.startswith(s[:-1].rstrip()) if s.endswith("…") else a == s
        return ok and fit(i + 1, j + 1)

    return fit(0, 0)


def _env() -> dict:
    env = dict(os.environ)
    env["PATH"] = os.pathsep.join([os.path.dirname(sys.executable), env.get("PATH", "")])
    env.update(NO_COLOR="1", COLUMNS="200", PYTHONUNBUFFERED="1", LC_ALL="C.UTF-8")
    return env


def _run_page(page: Path, tmp: Path, monkeypatch) -> list[str]:
    """Run every example of ``page`` in ``tmp``; the failures, described."""
    if (DOCS / "line").is_dir():  # the line examples read (and write a figure beside) docs/line/deltas.yaml
        shutil.copytree(DOCS / "line", tmp / "docs" / "line")
    monkeypatch.chdir(tmp)
    failures = []
    blocks = list(_blocks(page.read_text(encoding="utf-8")))
    env = _env()
    namespace: dict = {"__name__": "__example__"}
    for n, (lang, title, body, skipped) in enumerate(blocks):
        if skipped or (lang == "text" and title == "Output") or (page.name == "README.md" and n == 0):
            continue  # (README's set-up commands: test_readme_starts_with_the_set_up_commands)
        if title is not None:
            (tmp / title).write_text(body + "\n", encoding="utf-8")
        elif lang in SHELLS:
            for cmd, shown in _commands(body):
                r = subprocess.run(["bash", "-c", cmd], cwd=tmp, env=env, stdin=subprocess.DEVNULL,
                                   stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, timeout=600)
                if shown is None and r.returncode != 0:
                    failures.append(f"$ {cmd}\nexit {r.returncode}:\n{r.stdout}")
                elif shown is not None and not _matches(shown, r.stdout.splitlines()):
                    failures.append(f"$ {cmd}\nshown:\n" + "\n".join(shown) + f"\nprinted:\n{r.stdout}")
        elif lang == "python":
            out = io.StringIO()
            with contextlib.redirect_stdout(out):
                exec(compile(body, f"{page.name} block {n}", "exec"), namespace)  # noqa: S102 - the example
            following = blocks[n + 1] if n + 1 < len(blocks) else None
            if following and following[0] == "text" and following[1] == "Output" \
                    and not _matches(following[2].splitlines(), out.getvalue().splitlines()):
                failures.append(f"python block {n}\nshown:\n{following[2]}\nprinted:\n{out.getvalue()}")
        elif lang == "pycon":
            test = doctest.DocTestParser().get_doctest(body, dict(namespace), f"{page.name} block {n}", str(page), 0)
            runner = doctest.DocTestRunner(optionflags=doctest.ELLIPSIS | doctest.NORMALIZE_WHITESPACE)
            report = io.StringIO()
            runner.run(test, out=report.write)
            if runner.failures:
                failures.append(report.getvalue())
    return failures


def _page_id(page: Path) -> str:
    return page.relative_to(ROOT).as_posix()


@pytest.mark.parametrize("page", [pytest.param(p, id=_page_id(p), marks=[pytest.mark.slow]
                                               if p.relative_to(DOCS if DOCS in p.parents else ROOT).as_posix() in SLOW
                                               else []) for p in PAGES])
def test_examples_print_what_is_shown(page, tmp_path, monkeypatch):
    failures = _run_page(page, tmp_path, monkeypatch)
    assert not failures, f"{_page_id(page)}: {len(failures)} example(s) differ\n\n" + "\n\n".join(failures)


def test_readme_starts_with_the_set_up_commands():
    """README's first block: the command that installs and runs the main job on the shipped default profile, and the
    one that runs the tests, which `.ci/run` calls verbatim."""
    lang, _, body, _ = next(_blocks((ROOT / "README.md").read_text(encoding="utf-8")))
    install, tests = body.splitlines()
    assert lang == "bash" and install.startswith("pip install . && pickplace plan ")
    assert tests == "pip install '.[test]' && python -m pytest"
    assert tests in (ROOT / ".ci" / "run").read_text(encoding="utf-8").splitlines()


def test_every_page_has_run_or_marked_examples():
    """Each shell or Python block is either run or skipped on purpose, and skips stay few."""
    skips = sum(skipped for p in PAGES for _, _, _, skipped in _blocks(p.read_text(encoding="utf-8")))
    runs = sum(lang in (*SHELLS, "python", "pycon") and not skipped
               for p in PAGES for lang, _, _, skipped in _blocks(p.read_text(encoding="utf-8")))
    assert runs >= 20 and skips <= runs // 3, (runs, skips)


@pytest.mark.parametrize("shown,printed,ok", [
    (["a  b", "…", "z"], ["a b", "x", "y", "z"], True),
    (["a", "…"], ["a"], True),
    (["a b…"], ["a b c"], True),
    (["a", "z"], ["a", "y", "z"], False),
    (["a b…"], ["a c"], False),
    (["a"], [], False),
])
def test_the_comparison_itself(shown, printed, ok):
    assert _matches(shown, printed) is ok


def test_manual_builds_in_strict_mode(tmp_path):
    """``mkdocs build --strict``: a broken link or anchor, a page outside the navigation, a reference mkdocstrings
    cannot resolve or an error of the generated pages fails the build."""
    r = subprocess.run([sys.executable, "-m", "mkdocs", "build", "--strict", "--quiet", "-f", str(ROOT / "mkdocs.yml"),
                        "-d", str(tmp_path / "site")], cwd=ROOT, capture_output=True, text=True, timeout=600,
                       env={**os.environ, "NO_MKDOCS_2_WARNING": "1"})
    assert r.returncode == 0, r.stdout + r.stderr
    site = tmp_path / "site"
    for page in ("index.html", "reference/cli.html", "reference/profile.html", "api.html", "performance.html"):
        assert (site / page).is_file(), page
    cli = (site / "reference/cli.html").read_text(encoding="utf-8")
    assert 'id="pickplace-plan"' in cli and "--limit-use" in cli and 'id="pickplace-profile-init"' in cli
    profile = (site / "reference/profile.html").read_text(encoding="utf-8")
    assert "gear_ratio" in profile and "rated_torque" in profile
    api = (site / "api.html").read_text(encoding="utf-8")
    assert "PlanOptions" in api and "check_file" in api


_LINK_LIKE = re.compile(r"\[[^\]`\n]*\]\s?\[[^\]`\n]*\]")  # Markdown's [text][id] / [text] [id]: autorefs resolves it


def _docstrings_outside_code(obj) -> list[str]:
    import inspect
    out = []
    members = [v for _, v in inspect.getmembers(obj) if inspect.isfunction(v) or isinstance(v, property)]
    for member in [obj, *members]:
        if not getattr(getattr(member, "fget", member), "__module__", "").startswith("pickplace_cli"):
            continue  # inherited from pydantic or the standard library: not this package's text
        doc = member.__doc__ or ""
        out.append(re.sub(r"``.*?``|`[^`]*`", "", doc, flags=re.S))
    return out


def test_api_docstrings_have_no_text_read_as_a_cross_reference():
    """A docstring's ``[0, 1] [m]`` reads as a Markdown reference link ``[text] [id]`` to mkdocs-autorefs, which
    fails the strict build on the versions that resolve it; the API page's docstrings write such text in backticks
    (this holds whatever version of the docs tools is installed)."""
    import pickplace_cli
    names = re.findall(r"^::: pickplace_cli\.(\w+)", (DOCS / "api.md").read_text(encoding="utf-8"), flags=re.M)
    assert names
    bad = [f"{name}: {m.group(0)}" for name in names for doc in _docstrings_outside_code(getattr(pickplace_cli, name))
           for m in _LINK_LIKE.finditer(doc)]
    assert not bad, bad
