"""The package's layout is its pipeline (issue 18, README "Development"): stages import downward only, no import
circle, no module over 700 lines, no function body over 100 lines. Read with the standard library's ``ast``:
every ``import`` counts, the lazy ones inside functions included."""

from __future__ import annotations

import ast
import tomllib
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
PKG = ROOT / "pickplace_cli"

#: the stages, lowest first: a module may import its own stage and any stage below, never one above
STAGES = {
    "model": 0,
    "robots": 1, "curves": 1,
    "lookup": 2,
    "paths": 3, "export": 3,
    "limits": 4,
    "timing": 5,
    "planner": 6,
    "pipelines": 7, "studies": 7,
    "line": 8,
    "cli": 9, "__main__": 9,
}
MAX_MODULE_LINES = 700
MAX_FUNCTION_LINES = 100


def _modules() -> dict[str, Path]:
    out = {}
    for p in PKG.rglob("*.py"):
        parts = p.relative_to(PKG).with_suffix("").parts
        if parts[-1] == "__init__":
            parts = parts[:-1]
        out[".".join(parts)] = p
    return out


MODULES = _modules()


def _stage(module: str) -> int:
    if module == "":
        return 0  # pickplace_cli/__init__.py as imported: the version only (its public names load lazily, below)
    return STAGES[module.split(".")[0]]


def _imports(module: str, path: Path) -> set[str]:
    """The package modules ``module`` imports (relative, absolute and lazy imports; ``from x import name``
    counts as an import of x.name when that is a module, else of x)."""
    package = module if path.name == "__init__.py" else module.rpartition(".")[0]
    found = set()
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
        targets = []
        if isinstance(node, ast.ImportFrom):
            if node.level:
                base = package.split(".") if package else []
                base = base[: len(base) - node.level + 1] if node.level > 1 else base
                target = ".".join([*base, *([node.module] if node.module else [])])
            elif (node.module or "").startswith("pickplace_cli"):
                target = node.module.removeprefix("pickplace_cli").lstrip(".")
            else:
                continue
            for alias in node.names:
                sub = f"{target}.{alias.name}" if target else alias.name
                targets.append(sub if sub in MODULES else target)
        elif isinstance(node, ast.Import):
            targets = [a.name.removeprefix("pickplace_cli").lstrip(".") for a in node.names
                       if a.name.startswith("pickplace_cli")]
        for t in targets:
            while t not in MODULES and "." in t:
                t = t.rpartition(".")[0]
            if t in MODULES and t != module:
                found.add(t)
    return found


GRAPH = {m: _imports(m, p) for m, p in MODULES.items()}


def test_every_module_has_a_stage():
    unplaced = sorted(m for m in MODULES if m and m.split(".")[0] not in STAGES)
    assert not unplaced, f"modules outside every stage of STAGES: {unplaced}"


def test_stages_import_downward_only():
    """(The package root re-exports the public API from every stage, lazily: :func:`test_package_root_is_lazy`.)"""
    upward = [f"{m} (stage {_stage(m)}) imports {t} (stage {_stage(t)})"
              for m, targets in sorted(GRAPH.items()) if m for t in sorted(targets) if _stage(t) > _stage(m)]
    assert not upward, "imports from a higher stage:\n" + "\n".join(upward)


def test_no_import_circle():
    """Tarjan's strongly connected components of the module graph: every component is one module. A package's
    ``__init__`` that re-exports its own modules is not a circle with them unless they import it back."""
    index, low, on, stack, comps, counter = {}, {}, set(), [], [], [0]

    def visit(v: str) -> None:
        index[v] = low[v] = counter[0]
        counter[0] += 1
        stack.append(v)
        on.add(v)
        for w in GRAPH[v]:
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            comp = []
            while True:
                w = stack.pop()
                on.discard(w)
                comp.append(w)
                if w == v:
                    break
            comps.append(comp)

    for v in sorted(GRAPH):
        if v not in index:
            visit(v)
    circles = []
    for comp in comps:
        if len(comp) > 1:
            a = sorted(comp)[0]
            b = next(t for t in sorted(GRAPH[a]) if t in comp)
            circles.append(f"{a} imports {b}, and {b} leads back to {a} (circle: {sorted(comp)})")
    assert not circles, "import circles:\n" + "\n".join(circles)


def test_modules_are_at_most_700_lines():
    long = {m or "__init__": n for m, p in MODULES.items() if (n := len(p.read_text(encoding="utf-8").splitlines())) > MAX_MODULE_LINES}
    assert not long, f"modules over {MAX_MODULE_LINES} lines: {long}"


def _body_lines(fn: ast.FunctionDef | ast.AsyncFunctionDef) -> int:
    """Lines of a function's body, its signature, decorators and docstring aside."""
    body = fn.body
    if len(body) > 1 and isinstance(body[0], ast.Expr) and isinstance(getattr(body[0], "value", None), ast.Constant) \
            and isinstance(body[0].value.value, str):
        body = body[1:]
    return fn.end_lineno - body[0].lineno + 1


def test_function_bodies_are_at_most_100_lines():
    long = []
    for m, p in sorted(MODULES.items()):
        for node in ast.walk(ast.parse(p.read_text(encoding="utf-8"))):
            if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)) and (n := _body_lines(node)) > MAX_FUNCTION_LINES:
                long.append(f"{m}.{node.name}: {n} lines")
    assert not long, f"function bodies over {MAX_FUNCTION_LINES} lines:\n" + "\n".join(long)


def test_every_package_is_installed():
    """pyproject.toml lists its packages by hand (two of them are data folders): a new stage must be added there,
    or a non-editable install lacks it."""
    listed = set(tomllib.loads((ROOT / "pyproject.toml").read_text())["tool"]["setuptools"]["packages"])
    packages = {"pickplace_cli" + (f".{m}" if m else "") for m, p in MODULES.items() if p.name == "__init__.py"}
    assert packages <= listed, f"packages missing from pyproject.toml: {sorted(packages - listed)}"


@pytest.mark.parametrize("entry", ["pickplace_cli.planner:plan", "pickplace_cli.cli:app", "pickplace_cli.cli:main"])
def test_documented_entry_points_still_import(entry):
    import importlib

    module, _, name = entry.partition(":")
    assert callable(getattr(importlib.import_module(module), name))


def test_cli_enums_mirror_the_library():
    """The CLI's str enums name the library's choices exactly: the methods are the library's own list (a module
    without numpy, so ``--help`` stays fast); the CSV dialects a mirror kept equal here."""
    from pickplace_cli.cli.app import CsvDialectName, MethodName
    from pickplace_cli.export.csv import CsvDialect
    from pickplace_cli.paths import Method

    assert MethodName is Method  # one list of methods (pickplace_cli.model.methods), not a mirror
    assert [d.value for d in CsvDialectName] == [d.value for d in CsvDialect]


def test_package_root_is_lazy():
    """The package root is the public API's facade: at import it runs no import of the package (its names load on
    first use through PEP 562's ``__getattr__``; the ``if TYPE_CHECKING:`` block, for type checkers and the API
    reference, names the same objects), and a module of the package takes nothing from it but ``__version__``."""
    import pickplace_cli

    tree = ast.parse((PKG / "__init__.py").read_text(encoding="utf-8"))
    eager = [ast.unparse(n) for n in tree.body if isinstance(n, (ast.Import, ast.ImportFrom))
             and not (isinstance(n, ast.ImportFrom) and n.module == "__future__")
             and not (isinstance(n, ast.ImportFrom) and n.module == "typing")]
    assert not eager, f"the package root imports at import time: {eager}"
    guarded = next(n for n in tree.body if isinstance(n, ast.If) and ast.unparse(n.test) == "TYPE_CHECKING")
    typed = {a.asname or a.name: (n.module or "") for n in guarded.body for a in n.names}
    assert typed == pickplace_cli._PUBLIC, \
        "the TYPE_CHECKING imports and _PUBLIC name different objects"
    assert set(pickplace_cli.__all__) == {"__version__", *pickplace_cli._PUBLIC}
    takers = []
    for m, p in MODULES.items():
        for node in ast.walk(ast.parse(p.read_text(encoding="utf-8"))):
            if isinstance(node, ast.ImportFrom) and m:
                package = m if p.name == "__init__.py" else m.rpartition(".")[0]
                depth = len(package.split(".")) if package else 0
                root = (node.level and not node.module and node.level == depth + 1) or node.module == "pickplace_cli"
                if root and any(a.name != "__version__" for a in node.names):
                    takers.append(f"{m}: {ast.unparse(node)}")
    assert not takers, "modules that import public names from the package root (import them from their modules):\n" \
        + "\n".join(takers)
