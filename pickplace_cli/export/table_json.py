"""JSON export of the λ → (k1, k2) table (``pickplace build-table --format json``).

Document (keys sorted, deterministic)::

    {"format": "pickplace-table/1",
     "method": "bspline", "eta": 0.5, "weights": [0.5, 0.5],
     "provenance": {"eta": "0.5", "source": "...", "fit_k1": "...", ...},   # strings, as in the CSV header
     "units": {"lambda": "-", "k1": "-", ..., "a_max": "m/s^2", ...},
     "fit": {"lambda_min": 5.0, "k1": [g10, g11, g12, g13], "k2": [...], "max_residual": ...},
     "columns": ["lambda", "k1", "k2", "a_max", "j_max", "v_max", "F", "a_min", "j_min"],
     "rows": {"lambda": [...], "k1": [...], ...}}

Numbers are the doubles of the table, written with the shortest decimal that reads back exactly.
The peaks are of the normalised path (b = 1 m, T = 1 s) [Li2018, Eq. (17)-(21)].
"""

from __future__ import annotations

import json
import math
from typing import IO

from ..model.errors import ExportError
from ..lookup.bspline_table import COLUMNS, Table
from .table_st import provenance

#: units of the table's columns (peaks of the normalised path, b = 1 m, T = 1 s)
UNITS = {
    "lambda": "-",
    "k1": "-",
    "k2": "-",
    "a_max": "m/s^2",
    "j_max": "m/s^3",
    "v_max": "m/s",
    "F": "-",
    "a_min": "m/s^2",
    "j_min": "m/s^3",
}


def _num(x: float) -> float | None:
    x = float(x)
    return x if math.isfinite(x) else None  # a table read from a file may lack peak columns (NaN)


def table_document(table: Table, version: str | None = None, extra_meta: dict | None = None) -> dict:
    """The JSON-ready dict of ``table`` (see the module docstring)."""
    prov = dict(provenance(table, version, extra_meta))
    fit_min = float(prov.get("fit_lambda_min", 5.0))
    g1, g2, res = table.fit(fit_min)
    weights = table.meta.get("weights")
    if isinstance(weights, str):
        try:
            weights = [float(w) for w in weights.split(",")]
        except ValueError:
            raise ExportError(f"weights = {weights!r} in the table header: not two numbers") from None
    return {
        "format": "pickplace-table/1",
        "method": str(table.meta.get("method", "bspline")),
        "eta": table.eta,
        "weights": None if weights is None else [float(w) for w in weights],
        "provenance": prov,
        "units": UNITS,
        "fit": {
            "lambda_min": fit_min,
            "k1": [float(g) for g in g1],
            "k2": [float(g) for g in g2],
            "max_residual": res,
            "equation": "k_i = g_i0 + g_i1*lambda + g_i2*lambda^2 + g_i3*lambda^3 [Li2018, Eq. (23)]",
        },
        "columns": list(COLUMNS),
        "rows": {c: [_num(x) for x in table.column(c)] for c in COLUMNS},
    }


def format_table_json(table: Table, version: str | None = None, extra_meta: dict | None = None) -> str:
    """JSON text of ``table``: indented, keys sorted, one trailing newline."""
    return json.dumps(table_document(table, version, extra_meta), indent=1, sort_keys=True, allow_nan=False) + "\n"


def write_table_json(table: Table, stream: IO[str], version: str | None = None, extra_meta: dict | None = None) -> None:
    """Write :func:`format_table_json` of ``table`` to the text ``stream``."""
    stream.write(format_table_json(table, version, extra_meta))
