"""JSON export: the plan's summary plus every column as an array (units in the column names)."""

from __future__ import annotations

import json
from typing import IO

from . import plan_columns


def write_json(plan, stream: IO[str]) -> None:
    names, data = plan_columns(plan)
    doc = {
        "summary": plan.summary(),
        "columns": names,
        "samples": {n: [float(f"{x:.12g}") for x in data[:, i]] for i, n in enumerate(names)},
    }
    json.dump(doc, stream, allow_nan=False)
    stream.write("\n")
