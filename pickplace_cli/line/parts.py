"""The parts on the belt: detections read from a CSV file or a stream, or made by a seeded generator, and the
hold-and-reorder window for detections that arrive out of time order.

**Detection CSV** (a file, or standard input line by line as the rows arrive): a header, then one row per
part. Columns (any order; the unit in brackets may be left out, but when given it must be this one):
``t[s]`` the detection time (any clock; the results use the same clock), ``along[m]`` and ``across[m]`` where the
part was seen (line frame), optional ``angle[rad]`` (the part's angle about the vertical, carried to the results)
and optional ``id`` (text; default the row number); on a line with part types (``parts.types``) the column
``type`` names each part's type (one of the declared names; a row with another is refused, naming the row, the field
and the value). Blank lines and lines starting with ``#`` are skipped.

**Out of order.** Detections must come in time order. With ``parts.reorder`` = W > 0 s each detection is held
until one at least W s later has been read (or the input ends) and the held ones are passed on in time order,
so a detection up to W s late takes its place. A detection later than that (earlier than one already passed
on) is refused with one line naming the row and the rule; the rows around it go on.
"""

from __future__ import annotations

import heapq
import math
from dataclasses import dataclass
from typing import Iterable, Iterator

import numpy as np

from ..model.errors import TaskError

COLUMNS = {"t": "s", "along": "m", "across": "m", "angle": "rad", "id": "", "type": ""}
REQUIRED = ("t", "along", "across")
#: the longest line accepted in a detection file [characters]
MAX_LINE = 4096
#: the most parts one run may have (generated or read): each part's plan is kept for the results, about 0.14 MB a
#: part on a 3-Delta line, so this bounds a run at some 14 GB; a longer production is run in pieces
MAX_PARTS = 100_000


@dataclass(frozen=True)
class Detection:
    """A part seen at time ``t`` [s] at ``along``, ``across`` [m] (line frame); ``angle`` [rad] or None; ``row``:
    its row in the input (1 = the first data row; generated parts count from 1); ``type``: its part type's name (None
    on a line without types)."""

    id: str
    t: float
    along: float
    across: float
    angle: float | None = None
    row: int = 0
    type: str | None = None


@dataclass(frozen=True)
class BadRow:
    """A row that could not be used: ``error`` (one line) and the exit code (1)."""

    row: int
    error: str
    id: str = ""
    code: int = 1


def _header(line: str, source: str, types: list[str] | None = None) -> list[str]:
    names = []
    for cell in line.strip().split(","):
        cell = cell.strip()
        name, _, unit = cell.partition("[")
        name = name.strip()
        if name not in COLUMNS:
            raise TaskError(f"{source}:1: column {cell!r}: not a detection column (t[s], along[m], across[m], "
                            "angle[rad], id)")
        if unit:
            unit = unit.rstrip("]").strip()
            if unit != COLUMNS[name]:
                raise TaskError(f"{source}:1: column {cell!r}: {name} is in {COLUMNS[name] or 'text'}, not {unit!r} "
                                "(SI units)")
        if name in names:
            raise TaskError(f"{source}:1: column {name!r} appears twice")
        names.append(name)
    if types is None and "type" in names:
        raise TaskError(f"{source}:1: column 'type': the line file declares no part types (parts.types); leave the "
                        "column out or declare the types")
    if types is not None and "type" not in names:
        raise TaskError(f"{source}:1: header {line.strip()!r}: missing column 'type': the line file declares part types "
                        f"({', '.join(types)}), so every detection names its type")
    missing = [c for c in REQUIRED if c not in names]
    if missing:
        raise TaskError(f"{source}:1: header {line.strip()!r}: missing column {missing[0]!r} (a detection file has "
                        "t[s], along[m], across[m] and optionally angle[rad], id)")
    return names


def _row(cells: list[str], names: list[str], row: int, lineno: int, source: str,
         types: list[str] | None = None, half: float | None = None) -> Detection | BadRow:
    from ..model.text import plain_float

    where = f"row {row} ({source}:{lineno})"
    if len(cells) != len(names):
        return BadRow(row, f"{where}: {len(cells)} cells for {len(names)} columns ({', '.join(names)})")
    values: dict = {}
    for name, cell in zip(names, cells):
        cell = cell.strip()
        if name == "id":
            values["id"] = cell or str(row)
            continue
        if name == "type":
            values["type"] = cell
            continue
        if not cell and name == "angle":
            values[name] = None
            continue
        try:
            x = plain_float(cell)
        except ValueError:
            return BadRow(row, f"{where}: {name} = {cell!r}: must be a number in {COLUMNS[name]}", values.get("id", ""))
        if not math.isfinite(x):
            return BadRow(row, f"{where}: {name} = {cell!r}: must be a finite number ({COLUMNS[name]})", values.get("id", ""))
        if abs(x) > 1e9:
            return BadRow(row, f"{where}: {name} = {cell!r}: must lie within ±1e9 {COLUMNS[name]}", values.get("id", ""))
        values[name] = x
    if half is not None and abs(values["across"]) > half + 1e-12:
        return BadRow(row, f"{where}: across = {values['across']:g} m: not on the belt, within ±{half:g} m (belt.width / 2)",
                      values.get("id", ""))
    kind = values.get("type")
    if types is not None and kind not in types:
        return BadRow(row, f"{where}: type = {kind!r}: not a part type of the line file (parts.types: "
                           f"{', '.join(types)})", values.get("id", ""))
    return Detection(values.get("id", str(row)), values["t"], values["along"], values["across"], values.get("angle"), row,
                     kind)


def bounded_lines(readline, limit: int = MAX_LINE, source: str = "detections") -> Iterator[str]:
    """The lines of ``readline(n)`` (a text file's or a stream's, at most n characters a call), each at most
    ``limit`` + 1 characters: a longer line is given once, cut there, and its rest is read and dropped as it arrives
    (only when the next line is asked for), so it is one row, never one row per piece; a NUL byte in that rest is a
    TaskError (a binary input)."""
    lineno = 0
    while True:
        line = readline(limit + 1)
        if not line:
            return
        lineno += 1
        yield line
        if len(line) > limit and not line.endswith(("\n", "\r")):
            while True:  # the rest of the over-long line
                rest = readline(limit + 1)
                if "\0" in rest:
                    raise TaskError(f"{source}:{lineno}: NUL bytes: a binary file, not a detection CSV")
                if not rest or rest.endswith(("\n", "\r")) or len(rest) <= limit:
                    break


def read_detections(lines: Iterable[str], source: str = "detections",
                    types: list[str] | None = None, width: float | None = None) -> Iterator[Detection | BadRow]:
    """Detections (or BadRows) from CSV text lines, lazily (a stream is answered row by row). A missing or
    wrong header is a TaskError (nothing can be read); a bad row is a BadRow and reading goes on; more than
    :data:`MAX_PARTS` rows is a TaskError at the row after them. ``types``: the line's part types (None: none; then
    a ``type`` column is refused, else it is required and a row naming another type is a BadRow). ``width``: the belt's
    width [m]; a part farther across than half of it from the centre line is a BadRow (None: not tested)."""
    names = None
    row = 0
    for lineno, line in enumerate(lines, 1):
        if len(line) > MAX_LINE:
            if names is None:
                raise TaskError(f"{source}:{lineno}: a line of more than {MAX_LINE} characters: not a detection file")
            row += 1
            yield BadRow(row, f"row {row} ({source}:{lineno}): longer than {MAX_LINE} characters")
            continue
        text = line.strip()
        if not text or text.startswith("#"):
            continue
        if "\0" in text:
            from ..model.text import utf16_hint

            raise TaskError(f"{source}:{lineno}: NUL bytes: a binary file, not a detection CSV{utf16_hint(line)}")
        if names is None:
            names = _header(text, source, types)
            continue
        row += 1
        if row > MAX_PARTS:
            raise TaskError(f"{source}:{lineno}: more than {MAX_PARTS} detections in one run (the most a run keeps: "
                            "about 0.14 MB a part); run the rest as another run")
        yield _row(text.split(","), names, row, lineno, source, types, None if width is None else width / 2)
    if names is None:
        raise TaskError(f"{source}: no header: a detection file starts with t[s],along[m],across[m]")


def expected_parts(gen) -> float:
    """How many parts a generator spec makes: its count, or rate × duration (the mean of a Poisson stream)."""
    return float(gen.count) if gen.count is not None else float(gen.rate) * float(gen.duration)


def generate(gen, belt_width: float, types: dict | None = None) -> list[Detection]:
    """The parts of a generator spec (:class:`~pickplace_cli.line.spec.Generator`): arrival times (regular or
    Poisson), across uniform over the spread, along = ``detect_at``; the same seed gives the same parts. TaskError
    when it would make more than :data:`MAX_PARTS` (a Poisson stream's draws are capped there too). ``types``
    (name → :class:`~pickplace_cli.line.spec.PartType`): each part gets a type by the shares, drawn after every
    other number from the same seed (so a line without types makes the very same parts): type k when the uniform
    draw u lies in [S_(k−1), S_k), S_k the shares' running sum."""
    if expected_parts(gen) > MAX_PARTS:
        raise TaskError(f"parts.generate: {expected_parts(gen):.6g} parts, more than the {MAX_PARTS} a run may have "
                        "(about 0.14 MB a part): give a lower count, rate or duration")
    rng = np.random.default_rng(gen.seed)
    rate = float(gen.rate)
    if gen.count is not None:
        n = int(gen.count)
        if gen.arrival == "regular":
            t = np.arange(n) / rate
        else:
            t = np.cumsum(rng.exponential(1.0 / rate, n)) - 0.0
    else:
        horizon = float(gen.duration)
        if gen.arrival == "regular":
            t = np.arange(int(math.floor(horizon * rate - 1e-9)) + 1) / rate
            t = t[t < horizon]
        else:
            gaps = rng.exponential(1.0 / rate, int(horizon * rate * 1.5) + 20)
            t = np.cumsum(gaps)
            while t[-1] < horizon and len(t) <= 2 * MAX_PARTS:
                t = np.concatenate([t, t[-1] + np.cumsum(rng.exponential(1.0 / rate, len(t)))])
            t = t[t < horizon][:MAX_PARTS]
    spread = float(belt_width if gen.spread is None else gen.spread)
    across = rng.uniform(-spread / 2, spread / 2, len(t)) if spread > 0 else np.zeros(len(t))
    angle = rng.uniform(-math.pi, math.pi, len(t)) if gen.angles else None
    kinds = _draw_types(rng, types, len(t))
    along = float(gen.detect_at)
    return [Detection(str(k + 1), float(t[k]), along, float(across[k]), None if angle is None else float(angle[k]), k + 1,
                      kinds[k]) for k in range(len(t))]


def _draw_types(rng, types: dict | None, n: int) -> list:
    """n type names drawn by the shares (``generate``), or n times None without types."""
    if types is None:
        return [None] * n
    names = list(types)
    edges = np.cumsum([float(types[k].share) for k in names])
    edges[-1] = max(edges[-1], 1.0)  # the shares add up to 1 within 1e-9: every draw in [0, 1) has a type
    idx = np.searchsorted(edges, rng.random(n), side="right")
    return [names[min(int(i), len(names) - 1)] for i in idx]


def in_time_order(items: Iterable[Detection | BadRow], window: float = 0.0) -> Iterator[Detection | BadRow]:
    """Detections in time order: each held until one ``window`` s later is read (or the input ends); a
    detection earlier than one already passed on becomes a BadRow naming the rule; BadRows pass at once."""
    held: list = []  # heap of (t, row, detection)
    released = -math.inf
    released_row = None
    newest = -math.inf
    for item in items:
        if isinstance(item, BadRow):
            yield item
            continue
        if item.t < released:
            late = released - item.t
            rule = (f"detections must come in time order (parts.reorder = {window:g} s holds each one that long)"
                    if window > 0 else "detections must come in time order (set parts.reorder to a window in s to "
                                       "hold and re-order late ones)")
            yield BadRow(item.row, f"row {item.row} (part {item.id}): t = {item.t:.6g} s is {late:.6g} s earlier than "
                                   f"row {released_row}'s t = {released:.6g} s, already passed on: {rule}", item.id)
            continue
        heapq.heappush(held, (item.t, item.row, item))
        newest = max(newest, item.t)
        while held and held[0][0] <= newest - window:
            t, _, d = heapq.heappop(held)
            released, released_row = t, d.row
            yield d
    while held:
        t, _, d = heapq.heappop(held)
        yield d
