"""CSV export: one row per sample from t = 0 to T, in one of three dialects.

==========  =========  ===========  =======  ===========================================================
dialect     separator  line end     header   for
==========  =========  ===========  =======  ===========================================================
default     ``,``      LF           yes      spreadsheets, pandas, ``pickplace check``
twincat     ``;``      CRLF         yes      Beckhoff TwinCAT / Windows PLC tools (header line also CRLF)
tsv         tab        LF           no       position tables read by motion controllers (numbers only)
==========  =========  ===========  =======  ===========================================================

Columns (see :func:`pickplace_cli.export.plan_columns`): ``t[s]``, tool ``x y z [m]``, ``vx… [m/s]``,
``ax… [m/s^2]``, ``jx… [m/s^3]``, per joint ``q<i> qd<i> qdd<i>`` and, when computed, ``torque<i>``,
``motor_speed<i>``, ``motor_torque<i>``. A batch (samples with a ``move`` array) gets a leading
``move[-]`` column: the move number of each sample as the samples give it, printed as an integer.
Floats use ``%.12g``; the decimal separator is always ``.``. :class:`CsvFormat` selects columns (``plan --columns``),
including the drive's view of each joint (:mod:`pickplace_cli.export.drive`: ``<name>[<unit>]``, ``<name>_vel``, the
sets ``plc``, ``drive``, ``drive_vel``). Samples on a controller's cycle (a plan's ``cycle``, a timeline's ``cycle``
[s]) have t = k·cycle; the numbers-only ``tsv`` dialect then writes t as the whole number k of cycles.
"""

from __future__ import annotations

from dataclasses import dataclass
from enum import Enum
from functools import lru_cache
from typing import IO, Any

import numpy as np

from ..model.errors import ExportError
from . import FLOAT_FORMAT, plan_columns

#: header name of the move index column of a batch (dimensionless index)
MOVE_COLUMN = "move[-]"


class CsvDialect(str, Enum):
    default = "default"
    twincat = "twincat"
    tsv = "tsv"


@dataclass(frozen=True)
class DialectSpec:
    sep: str
    newline: str
    header: bool
    columns: tuple[str, ...] | None = None  # the columns written (:func:`select_columns`); None: all
    drive: Any = None  # export.drive.DriveMap: the drive columns that may be selected


@dataclass(frozen=True)
class CsvFormat:
    """A dialect and the columns to write (``plan --columns``): header names without their units, or globs
    such as ``q?`` or ``motor_*``, in the order wanted; None writes every column. A batch's ``move`` column
    always comes first. Accepted wherever a dialect name is."""

    dialect: str = "default"
    columns: tuple[str, ...] | None = None
    drive: Any = None  # export.drive.DriveMap (profile controller.joints) or None


DIALECTS: dict[CsvDialect, DialectSpec] = {
    CsvDialect.default: DialectSpec(",", "\n", True),
    CsvDialect.twincat: DialectSpec(";", "\r\n", True),
    CsvDialect.tsv: DialectSpec("\t", "\n", False),
}


def dialect_spec(dialect: CsvDialect | str | CsvFormat) -> DialectSpec:
    """Separator, line end, header flag (and columns, for a :class:`CsvFormat`) of ``dialect``; ExportError for
    an unknown name."""
    columns = drive = None
    if isinstance(dialect, CsvFormat):
        dialect, columns, drive = dialect.dialect, dialect.columns, dialect.drive
    try:
        spec = DIALECTS[CsvDialect(dialect)]
        return spec if columns is None and drive is None else DialectSpec(spec.sep, spec.newline, spec.header, columns, drive)
    except ValueError:
        raise ExportError(f"csv dialect = {dialect!r}: must be one of {', '.join(d.value for d in CsvDialect)}") from None


#: rows printed per call of the fast printer (its temporaries: ~20 arrays of this many rows)
_FAST_BLOCK_ROWS = 4096
#: rows formatted per ``%`` call: one big format string per block is ~25 % faster than one per row
_BLOCK_ROWS = 512


def format_rows(data: np.ndarray, sep: str = ",", newline: str = "\n", int_columns: int = 0) -> str:
    """Rows of ``data`` as text with the fixed float format (deterministic); the first ``int_columns``
    columns are printed as integers."""
    n, m = data.shape
    if n == 0:
        return ""
    from .fastfloat import format_block

    # the same bytes as the % below, ~2.6 x faster (None without orjson); in blocks of rows: bounded temporaries
    blocks = [format_block(data[i : i + _FAST_BLOCK_ROWS], int_columns) for i in range(0, n, _FAST_BLOCK_ROWS)]
    if blocks[0] is not None:
        text = "".join(blocks)
        if sep != ",":
            text = text.replace(",", sep)
        if newline != "\n":
            text = text.replace("\n", newline)
        return text
    fmts = ["%d"] * int_columns + [FLOAT_FORMAT] * (m - int_columns)
    row_fmt = sep.join(fmts) + newline
    flat = (data + 0.0).ravel().tolist()  # + 0.0: no "-0" in the output
    block = row_fmt * _BLOCK_ROWS
    parts = []
    for start in range(0, n, _BLOCK_ROWS):
        rows = min(_BLOCK_ROWS, n - start)
        fmt = block if rows == _BLOCK_ROWS else row_fmt * rows
        parts.append(fmt % tuple(flat[start * m : (start + rows) * m]))
    return "".join(parts)


def parse_columns(text: str) -> tuple[str, ...]:
    """``--columns`` text: comma-separated names or globs (blanks around a name ignored); ExportError when none is
    given or one is empty (``t,,q1``, a trailing comma: a typo, not silently dropped)."""
    parts = [c.strip() for c in text.split(",")]
    if not any(parts):
        raise ExportError(f"columns = {text!r}: give at least one column name (e.g. t,q1,q2,q3)")
    if not all(parts):
        where = parts.index("") + 1
        raise ExportError(f"columns = {text!r}: name {where} of {len(parts)} is empty; give comma-separated names "
                          "(e.g. t,q1,q2,q3)")
    return tuple(parts)


@lru_cache(maxsize=64)
def select_columns(names: tuple[str, ...], columns: tuple[str, ...]) -> tuple[int, ...]:
    """The indices into ``names`` (header names with units) of ``columns`` (names without units, or globs
    such as ``q?``), in the order given, each glob's matches in the header's order. ExportError for a name
    that matches nothing or a column selected twice."""
    import fnmatch

    bare = [n.split("[", 1)[0] for n in names]
    out: list[int] = []
    for c in columns:
        if c in names:  # a header name with its unit, as printed
            hits = [names.index(c)]
        else:
            hits = [i for i, b in enumerate(bare) if fnmatch.fnmatchcase(b, c)]
        if not hits:
            base = c.split("[", 1)[0]
            move = " (a batch's move column is always written, first)" if fnmatch.fnmatchcase("move", base) else ""
            if "[" in c and base in bare:  # the right name with another unit (q1[deg], torque1[N·m])
                raise ExportError(f"columns = {c!r}: no such column; the header writes {names[bare.index(base)]} "
                                  "(give the name without its unit, or the unit as in the header)")
            raise ExportError(f"columns = {c!r}: no such column{move}; the columns are {', '.join(bare)} "
                              "(names without units, or as in the header; globs such as q? or q[12] allowed)")
        for i in hits:
            if i in out:
                raise ExportError(f"columns = {','.join(columns)!r}: {bare[i]} is selected twice")
            out.append(i)
    return tuple(out)


def csv_columns(samples, columns: tuple[str, ...] | None = None, drive=None) -> tuple[list[str], np.ndarray, int]:
    """Column names, data (N, n_columns) and the number of leading integer columns (1 with ``move``);
    ``columns``: only those (:func:`select_columns`; the sets of :func:`~pickplace_cli.export.drive.expand_columns`),
    the ``move`` column still first; ``drive`` (a DriveMap): its columns may be selected (never written by default)."""
    names, data = plan_columns(samples)
    if columns is not None:
        from .drive import expand_columns

        if drive is not None:
            dnames, ddata = drive.columns(samples)
            names, data = names + dnames, np.hstack([data, ddata])
        idx = select_columns(tuple(names), expand_columns(tuple(columns), drive, samples.joint.q.shape[1]))
        names, data = [names[i] for i in idx], data[:, idx]
    move = getattr(samples, "move", None)
    if move is None:
        return names, data, 0
    move = np.asarray(move)
    if move.shape != (data.shape[0],):
        raise ExportError(f"move: shape {move.shape} must be ({data.shape[0]},), one move index per sample")
    if move.size and not np.array_equal(move, np.round(move)):
        raise ExportError("move: indices must be whole numbers")
    return [MOVE_COLUMN, *names], np.hstack([move.astype(float)[:, None], data]), 1


def csv_header(samples, dialect: CsvDialect | str | CsvFormat = CsvDialect.default, move: bool | None = None) -> str:
    """The header line of ``samples`` in ``dialect`` ("" for a dialect without header). ``move``: add the
    ``move[-]`` column (default: when the samples have ``move``)."""
    spec = dialect_spec(dialect)
    if not spec.header:
        return ""
    names, _data, n_int = csv_columns(samples, spec.columns, spec.drive)
    if move and not n_int:
        names = [MOVE_COLUMN, *names]
    elif move is False and n_int:
        names = names[1:]
    return spec.sep.join(names) + spec.newline


def csv_rows(samples, dialect: CsvDialect | str | CsvFormat = CsvDialect.default, move: int | None = None) -> str:
    """The data lines of ``samples`` in ``dialect``. ``move``: a move number for a leading ``move`` column
    on every row (for writing a batch one plan at a time); otherwise the samples' own ``move``, if any."""
    spec = dialect_spec(dialect)
    names, data, n_int = csv_columns(samples, spec.columns, spec.drive)
    cycle = sample_cycle(samples)
    if cycle is not None and not spec.header and "t[s]" in names:  # numbers only: t as whole cycles k
        k = names.index("t[s]")
        data = data.copy()
        data[:, k] = np.rint(data[:, k] / cycle)
    if move is not None:
        if n_int:
            data = data[:, 1:]
        data = np.hstack([np.full((data.shape[0], 1), float(int(move))), data])
        n_int = 1
    return format_rows(data, spec.sep, spec.newline, n_int)


def sample_cycle(samples) -> float | None:
    """The controller cycle [s] the samples are on (a Plan's ``cycle.cycle``, a Timeline's ``cycle``), else None."""
    c = getattr(samples, "cycle", None)
    return getattr(c, "cycle", c) if c is not None else None


def write_csv(samples, stream: IO[str], dialect: CsvDialect | str | CsvFormat = CsvDialect.default) -> None:
    """Write the samples as CSV: [move,] t, x, y, z, vx…, ax…, jx…, then q<i>, qd<i>, qdd<i> per joint, torques.

    Parameters
    ----------
    samples : Plan or Timeline
        What to write; every column's unit is in its header (``t[s]``, ``x[m]``, ``q1[rad]``, ``torque1[N*m]`` …).
    stream : text stream
        Where to write (opened with ``newline=""``, as :func:`atomic_output` does).
    dialect : CsvDialect or str or CsvFormat
        ``default`` (``,`` LF, header), ``twincat`` (``;`` CRLF, header) or ``tsv`` (tab, no header).

    Notes
    -----

    ``stream`` is a text stream opened with ``newline=""`` (as :func:`~pickplace_cli.export.atomic_output`
    does) so that the dialect's line ends are written unchanged. A batch can also be written one plan at a
    time: ``csv_header(first_plan, dialect, move=True)`` once, then ``csv_rows(plan, dialect, move=k)``."""
    stream.write(csv_header(samples, dialect))
    stream.write(csv_rows(samples, dialect))
