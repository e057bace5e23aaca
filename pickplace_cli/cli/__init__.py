"""Command-line interface: parse → call the library → render. The only package that prints or exits.

One module per command (``plan``, ``check``, ``profile``, ``build_table``, ``compare``, ``plot``, ``line``), the Typer app
and what the commands share (``app``), the rendering (``render``) and ``plan --batch`` (``batch``).

Exit codes: 0 success · 1 invalid input (profile, table, values) · 2 usage error ·
3 a limit is exceeded · 4 a point of the move is unreachable / outside the workspace.

Heavy modules (numpy, scipy, pydantic, rich) are imported inside the commands so that ``--help`` and
``--version`` stay fast.
"""

from __future__ import annotations

# the commands register themselves on the app when imported, in the order --help lists them
from . import plan as _plan, check as _check, profile as _profile, build_table as _build_table  # noqa: F401
from . import compare as _compare, plot as _plot, line as _line  # noqa: F401
from .app import app, main

__all__ = ["app", "main"]
