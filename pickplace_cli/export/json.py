"""JSON export: the summary (or one per move) plus every column as an array (units in the column names)."""

from __future__ import annotations

import json
from typing import IO

from . import plan_columns


def write_json(samples, stream: IO[str], drive=None) -> None:
    """Write the samples as one JSON document: the summary and every column (units in the column names).

    Parameters
    ----------
    samples : Plan or Timeline
        A Plan (``summary``: its summary) or a Timeline (``summaries``: one per move, and a ``move[-]`` column).
    stream : text stream
        Where to write.
    drive : DriveMap, optional
        The drive view of each joint (its units from the profile's ``controller.joints``).

    Notes
    -----
    ``drive`` (a :class:`~pickplace_cli.export.drive.DriveMap`): its columns (``<name>[<unit>]``,
    ``<name>_vel[<unit>/s]``) follow the model's, and ``joints`` describes each joint's drive view."""
    names, data = plan_columns(samples)
    if drive is not None:
        import numpy as np

        dnames, ddata = drive.columns(samples)
        names, data = names + dnames, np.hstack([data, ddata])
    columns = {n: [float(f"{x:.12g}") for x in data[:, i]] for i, n in enumerate(names)}
    move = getattr(samples, "move", None)
    doc: dict = {}
    if hasattr(samples, "summary"):
        doc["summary"] = samples.summary()
    else:
        doc["summaries"] = list(samples.summaries)
    if move is not None:
        names = ["move[-]", *names]
        columns = {"move[-]": [int(m) for m in move], **columns}
    if drive is not None:
        doc["joints"] = drive.describe()
    doc["columns"] = names
    doc["samples"] = columns
    json.dump(doc, stream, allow_nan=False)
    stream.write("\n")
