"""Where the shipped profiles and tables are: inside the installed package (package data mapped from
the top-level ``profiles/`` and ``tables/`` folders by pyproject.toml), or in the source checkout."""

from __future__ import annotations

from pathlib import Path


def data_dir(kind: str) -> Path:
    """Folder of the shipped ``profiles`` or ``tables``."""
    from importlib import resources

    try:
        root = resources.files(f"pickplace_cli.{kind}")
        path = Path(str(root))
        if path.is_dir():
            return path
    except (ModuleNotFoundError, TypeError):
        pass
    return Path(__file__).resolve().parent.parent / kind
