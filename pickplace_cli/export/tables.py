"""PVT and cam tables (:class:`~pickplace_cli.export.knots.KnotTable`) as CSV and as IEC 61131-3 Structured Text.

Values are in the drive's units when the profile declares them (``controller.joints``:
:class:`~pickplace_cli.export.drive.DriveMap`), else in the model's (rad or m). The master of a cam is time [s]
from the start, or the belt's travel [m] since the part's detection (a conveyor move): then the slave's
velocity and acceleration are per m and per m² of master travel (dy/dx = ẏ / belt speed).

==============  =========================================================================================
format          columns (CSV) / arrays (ST), per point
==============  =========================================================================================
pvt             ``t[s]``, ``dt[s]`` (time since the previous point), per joint ``NAME[u]``, ``NAME_vel[u/s]``
cam             ``master[s|m]``, per joint ``NAME[u]``, ``NAME_vel[u/x]``, ``NAME_acc[u/x^2]`` (XYVA points)
cam-table       ``master[s|m]`` (equidistant), per joint ``NAME[u]``
==============  =========================================================================================

Structured Text (:func:`format_table_st`): ``strict`` (IEC 61131-3, the default) is a ``FUNCTION_BLOCK`` whose
outputs hold the table as initialised arrays (``nPoints``, ``fMaster`` or ``fTime``/``fDt``, ``NAME_pos``,
``NAME_vel``, ``NAME_acc``), which any compiler accepts; ``codesys`` is a ``VAR_GLOBAL CONSTANT`` list of the same
arrays prefixed ``PP_<KIND>_`` (a CODESYS/TwinCAT global variable list). Either is copied into the kernel's own
structure by a loop, or written in the kernel's own cam types per joint (:mod:`~pickplace_cli.export.cam_objects`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..model.errors import ExportError
from .table_st import VALUES_PER_LINE, _comment, check_st_names, st_real


@dataclass(frozen=True)
class Master:
    """The cam's master axis: ``kind`` time (x = t [s]) or belt (x = ``speed`` · (``latency`` + t) [m])."""

    kind: str = "time"
    speed: float = 1.0  # m/s (belt)
    latency: float = 0.0  # s from the detection to the move's start (belt)

    @property
    def unit(self) -> str:
        return "s" if self.kind == "time" else "m"

    def x(self, t: np.ndarray) -> np.ndarray:
        return np.asarray(t, float) if self.kind == "time" else self.speed * (self.latency + np.asarray(t, float))

    def per(self, order: int) -> float:
        """d^order x / dt^order's reciprocal power: slave derivative w.r.t. x = time derivative / speed^order."""
        return 1.0 if self.kind == "time" else self.speed ** order


@dataclass(frozen=True)
class TableColumns:
    """The table as named columns: ``names`` (bare), ``units``, ``data`` (K, m), ``comment`` per column."""

    names: list[str]
    units: list[str]
    data: np.ndarray
    comments: list[str]


def table_columns(table, drive=None, joint_units=None, master: Master = Master()) -> TableColumns:
    """The columns of ``table`` (a KnotTable) in drive units (``drive``: a DriveMap) or the model's
    (``joint_units``: rad or m per joint)."""
    n = table.q.shape[1]
    if drive is not None:
        names, labels = list(drive.names), list(drive.labels)
        pos, vel = drive.position(table.q), drive.rate(table.qd)
        acc = None if table.qdd is None else drive.rate(table.qdd)
    else:
        names, labels = [f"q{i}" for i in range(1, n + 1)], list(joint_units)
        pos, vel, acc = table.q, table.qd, table.qdd
    cols: list[tuple[str, str, np.ndarray, str]] = []
    if table.kind == "pvt":
        dt = np.diff(table.t, prepend=table.t[0])
        cols += [("t", "s", table.t, "time of the point"), ("dt", "s", dt, "time since the previous point")]
        for i in range(n):
            cols += [(names[i], labels[i], pos[:, i], f"{names[i]} position"),
                     (f"{names[i]}_vel", f"{labels[i]}/s", vel[:, i], f"{names[i]} velocity")]
    else:
        xu = master.unit
        cols.append(("master", xu, master.x(table.t), "master: " + ("time" if master.kind == "time" else
                                                                  "belt travel since the detection")))
        for i in range(n):
            cols.append((names[i], labels[i], pos[:, i], f"{names[i]} position"))
            if table.kind == "cam":
                cols += [(f"{names[i]}_vel", f"{labels[i]}/{xu}", vel[:, i] / master.per(1), f"{names[i]} d/dmaster"),
                         (f"{names[i]}_acc", f"{labels[i]}/{xu}^2", acc[:, i] / master.per(2), f"{names[i]} d2/dmaster2")]
    return TableColumns([c[0] for c in cols], [c[1] for c in cols], np.column_stack([c[2] for c in cols]),
                        [c[3] for c in cols])


def format_table_csv(cols: TableColumns) -> str:
    """Header ``name[unit]`` and one row per point (``%.12g``, LF)."""
    from .csv import format_rows

    head = ",".join(f"{n}[{u}]" for n, u in zip(cols.names, cols.units)) + "\n"
    return head + format_rows(cols.data)


_FB = {"pvt": "FB_PickplacePvt", "cam": "FB_PickplaceCam", "cam-table": "FB_PickplaceCamTable"}
_PREFIX = {"pvt": "PP_PVT", "cam": "PP_CAM", "cam-table": "PP_CAMTABLE"}
_ST_NAME = {"t": "fTime", "dt": "fDt", "master": "fMaster"}


def as_csv(values: np.ndarray) -> np.ndarray:
    """``values`` as the CSV writes them (12 significant digits): the time, step and master columns of the Structured
    Text then hold the CSV's numbers (a step of whole cycles 0.006 s, not its difference's 0.005999999999999998)."""
    return np.array([float(f"{v:.12g}") for v in np.asarray(values, float)])


def _st_name(name: str) -> str:
    if name in _ST_NAME:
        return _ST_NAME[name]
    for suffix in ("_vel", "_acc"):
        if name.endswith(suffix):
            return name
    return f"{name}_pos"


def _array(name: str, values: np.ndarray, comment: str) -> str:
    lits = [st_real(v) for v in values]
    lines = [", ".join(lits[i:i + VALUES_PER_LINE]) for i in range(0, len(lits), VALUES_PER_LINE)]
    return (f"    {name} : ARRAY[1..{len(lits)}] OF LREAL := [ (* {_comment(comment)} *)\n        "
            + ",\n        ".join(lines) + "];\n")


def format_table_st(table, cols: TableColumns, dialect: str = "strict", header: list[str] = ()) -> str:
    """Structured Text of the table (see the module docstring); ``header``: lines for the leading comment."""
    kind = table.kind
    n = len(table.t)
    strict = dialect == "strict"
    prefix = _PREFIX[kind]
    names = [_st_name(c) if strict else f"{prefix}_{_st_name(c).upper()}" for c in cols.names]
    count = "nPoints" if strict else f"{prefix}_POINTS"
    check_st_names([("table", _FB[kind]), ("table", count)] + [("column", x) for x in names], dialect)
    if len({x.upper() for x in names}) != len(names):
        raise ExportError("table: two columns share a Structured Text name (case-insensitively); rename a joint")
    out = ["(* pickplace " + {"pvt": "PVT table (position, velocity, time; cubic Hermite between points)",
                              "cam": "cam table: XYVA points (5th-order polynomial segments between points)",
                              "cam-table": "cam table: equidistant positions (linear between points)"}[kind] + "\n"]
    out += [_comment(f"   {line}\n") for line in header]
    out.append(f"   Dialect: {dialect} ({'IEC 61131-3: a FUNCTION_BLOCK whose outputs hold the arrays' if strict else 'CODESYS/TwinCAT: a global constant list'}).\n*)\n\n")
    decls = [f"    {count} : DINT := {n}; (* points *)\n"]
    decls += [_array(x, as_csv(cols.data[:, k]) if c in _ST_NAME else cols.data[:, k], f"{c} [{u}]: {d}")
              for k, (x, c, u, d) in enumerate(zip(names, cols.names, cols.units, cols.comments))]
    if strict:
        out.append(f"FUNCTION_BLOCK {_FB[kind]}\nVAR_OUTPUT\n" + "".join(decls) + "END_VAR\n"
                   f"{count} := {n};\nEND_FUNCTION_BLOCK\n")
    else:
        out.append("VAR_GLOBAL CONSTANT\n" + "".join(decls) + "END_VAR\n")
    return "".join(out)


def table_header(table, drive, master: Master, tolerance_units: str = "rad or m") -> list[str]:
    """The comment lines of a table export: points, samples, tolerance and the achieved error, units, master."""
    err = ", ".join(f"{e:.3g}" for e in table.max_error)
    lines = [f"points: {len(table.t)} (the trajectory has {table.samples} samples on its grid)",
             f"tolerance: {table.tolerance:g} {tolerance_units}; achieved max error per joint: {err} {tolerance_units}",
             f"master: {'time [s] from the start of the trajectory' if master.kind == 'time' else f'belt travel [m] since the detection ({master.speed:g} m/s)'}"]
    if drive is not None:
        lines.append("joints (drive units, d = sign * k * (q - offset)): " + "; ".join(
            f"{d['name']} [{d['label']}] sign {d['sign']:+d} offset {d['offset']:g}" for d in drive.describe()))
    return lines

