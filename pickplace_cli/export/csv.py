"""CSV export: one header row of ``name[unit]`` columns, then one row per sample from t = 0 to T."""

from __future__ import annotations

from typing import IO

import numpy as np

from . import FLOAT_FORMAT, plan_columns


def format_rows(data: np.ndarray, sep: str = ",", newline: str = "\n") -> str:
    """Rows of ``data`` as text with the fixed float format (deterministic)."""
    row_fmt = sep.join([FLOAT_FORMAT] * data.shape[1]) + newline
    data = data + 0.0  # no "-0" in the output
    return "".join(row_fmt % tuple(r) for r in data.tolist())


def write_csv(plan, stream: IO[str]) -> None:
    """Write the plan's samples: t, x, y, z, vx…, ax…, jx…, then q<i>, qd<i>, qdd<i> per joint."""
    names, data = plan_columns(plan)
    stream.write(",".join(names) + "\n")
    stream.write(format_rows(data))
