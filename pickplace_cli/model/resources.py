"""Where the shipped profiles and tables are: inside the installed package (pyproject.toml maps the
top-level ``profiles/`` and ``tables/`` folders to ``pickplace_cli/profiles`` and ``pickplace_cli/tables``),
or, when running from a source checkout, the top-level folders themselves."""

from __future__ import annotations

from pathlib import Path

_PACKAGE = Path(__file__).resolve().parents[1]


def data_dir(kind: str) -> Path:
    """Folder of the shipped ``profiles`` or ``tables``."""
    installed = _PACKAGE / kind
    if installed.is_dir():
        return installed
    return _PACKAGE.parent / kind
