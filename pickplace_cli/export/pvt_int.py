"""PVT in a drive's integer units (``plan -f pvt|pvt-st --pvt-integer``): what a drive in PVT mode takes as integers.

A drive's PVT buffer (CiA 402 interpolated position mode, sub-mode −2; Copley, Elmo, Kollmorgen AKD) takes per point
a segment time in whole milliseconds (one byte: 1 … 255 ms), a position in encoder counts (int32) and a velocity in
an integer unit; here counts per second (int32). This turns a PVT :class:`~pickplace_cli.export.knots.KnotTable` (its
points as chosen, in the model's units) into those integers:

* times: every point must lie on a whole millisecond (plan with a whole-millisecond ``--cycle``, e.g. 0.001); a
  segment longer than :data:`MAX_SEGMENT_MS` is split into equal whole-millisecond parts (as equal as whole
  milliseconds allow), the new points' position and velocity taken from that segment's own cubic, so the drive
  runs the same cubic;
* positions: ``d = sign · k · (q − offset)`` in counts (the profile's ``controller.joints``, every joint ``unit:
  counts``), rounded to the nearest count (ties to even), velocities ``sign · k · q̇`` in counts/s, rounded alike;
* a position or velocity outside int32 is an :class:`~pickplace_cli.model.errors.ExportError` (exit 1) naming the
  joint, the value, the time and the joint travel the encoder's 32 bits allow.

Rounding adds at most half a count to a position and h/2 · 4/27 · 0.5 count (h ≤ 0.255 s) through the velocity's
rounding to the cubic between points: well below one count.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..model.errors import ExportError
from .table_st import VALUES_PER_LINE, _comment, check_st_names

#: the longest segment a drive's PVT point holds [ms] (one byte)
MAX_SEGMENT_MS = 255
#: the range of a 32-bit signed integer (positions in counts, velocities in counts/s)
INT32_MIN, INT32_MAX = -(2 ** 31), 2 ** 31 - 1
#: how far from a whole millisecond a point's time may lie [ms] (float rounding of k · cycle)
WHOLE_MS = 1e-6


@dataclass(frozen=True)
class IntegerPvt:
    """The integer table: ``t_ms`` (K,) time of each point [ms], ``dt_ms`` (K,) since the previous point (0 first),
    ``pos`` (K, n) [counts], ``vel`` (K, n) [counts/s]; per joint ``names``; ``split`` segments split."""

    t_ms: np.ndarray
    dt_ms: np.ndarray
    pos: np.ndarray
    vel: np.ndarray
    names: tuple[str, ...]
    split: int


def _cubic(t0: float, t1: float, p0, v0, p1, v1, t: float) -> tuple[np.ndarray, np.ndarray]:
    """Position and velocity of the cubic Hermite segment (t0, p0, v0) → (t1, p1, v1) at ``t`` (p, v: (n,))."""
    h = t1 - t0
    s = (t - t0) / h
    pos = (2 * s**3 - 3 * s**2 + 1) * p0 + (s**3 - 2 * s**2 + s) * h * v0 + (-2 * s**3 + 3 * s**2) * p1 + (s**3 - s**2) * h * v1
    vel = ((6 * s**2 - 6 * s) * p0 + (-6 * s**2 + 6 * s) * p1) / h + (3 * s**2 - 4 * s + 1) * v0 + (3 * s**2 - 2 * s) * v1
    return pos, vel


def _whole_ms(t: np.ndarray) -> np.ndarray:
    ms = np.asarray(t, float) * 1000.0
    k = np.rint(ms)
    off = np.flatnonzero(np.abs(ms - k) > WHOLE_MS)
    if off.size:
        i = int(off[0])
        raise ExportError(f"pvt integer: point {i + 1} at t = {t[i]:.9g} s is not on a whole millisecond: the drive "
                          "takes segment times in whole ms; plan on a whole-millisecond cycle (--cycle 0.001)")
    return k.astype(np.int64)


def _split(t_ms: np.ndarray, q: np.ndarray, qd: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, int]:
    """Segments longer than MAX_SEGMENT_MS split in whole ms, the new points on the segment's own cubic [s]."""
    ts, qs, vs, split = [t_ms[0]], [q[0]], [qd[0]], 0
    for i in range(len(t_ms) - 1):
        d = int(t_ms[i + 1] - t_ms[i])
        if d < 1:
            raise ExportError(f"pvt integer: points {i + 1} and {i + 2} lie {d} ms apart: the drive needs ≥ 1 ms")
        parts = math.ceil(d / MAX_SEGMENT_MS)
        if parts > 1:
            split += 1
            cuts = [t_ms[i] + (d * k) // parts for k in range(1, parts)]
            for c in cuts:
                p, v = _cubic(t_ms[i] / 1e3, t_ms[i + 1] / 1e3, q[i], qd[i], q[i + 1], qd[i + 1], c / 1e3)
                ts.append(c)
                qs.append(p)
                vs.append(v)
        ts.append(t_ms[i + 1])
        qs.append(q[i + 1])
        vs.append(qd[i + 1])
    return np.array(ts, dtype=np.int64), np.array(qs), np.array(vs), split


def _int32(values: np.ndarray, what: str, unit: str, drive, t_ms: np.ndarray, joint_units) -> np.ndarray:
    """``values`` (K, n) rounded to integers; ExportError at the first one outside int32."""
    r = np.rint(values)
    bad = np.argwhere(~np.isfinite(values) | (r < INT32_MIN) | (r > INT32_MAX))
    if bad.size:
        i, j = (int(x) for x in bad[0])
        scale = abs(drive.scale[j])
        reach = INT32_MAX / scale
        joint_unit = joint_units[j]
        raise ExportError(
            f"{drive.names[j]} {what} = {values[i, j]:.6g} {unit} at t = {t_ms[i] / 1e3:.6g} s: past the drive's 32-bit "
            f"range ({INT32_MIN} … {INT32_MAX} {unit}); at {scale:.6g} counts per {joint_unit} of the joint (encoder "
            f"counts_per_rev × gear ratio / 2π) that is ±{reach:.6g} {joint_unit}{'' if what == 'position' else '/s'}"
            f"{' from controller.joints offset: set the offset nearer the motion, or a coarser count' if what == 'position' else ''}")
    return r.astype(np.int64)


def integer_pvt(table, drive, joint_units=None) -> IntegerPvt:
    """The :class:`IntegerPvt` of the PVT ``table`` (a KnotTable of kind pvt, model units) through ``drive`` (a
    DriveMap whose every unit is counts; ``joint_units``: rad or m per joint, for messages); ExportError when it
    cannot be (module docstring)."""
    if table.kind != "pvt":
        raise ExportError(f"pvt integer: a {table.kind} table; integer units are for PVT (--format pvt or pvt-st)")
    if drive is None or any(u != "counts" for u in drive.units):
        which = "no controller.joints section" if drive is None else ", ".join(
            f"{n} unit = {u}" for n, u in zip(drive.names, drive.units) if u != "counts")
        raise ExportError(f"pvt integer: positions in encoder counts need every controller.joints unit = counts "
                          f"(with counts_per_rev); the profile has {which}")
    t_ms, q, qd, split = _split(_whole_ms(table.t), np.asarray(table.q, float), np.asarray(table.qd, float))
    units = tuple(joint_units) if joint_units is not None else ("rad",) * len(drive.names)
    pos = _int32(drive.position(q), "position", "counts", drive, t_ms, units)
    vel = _int32(drive.rate(qd), "velocity", "counts/s", drive, t_ms, units)
    dt = np.diff(t_ms, prepend=t_ms[0])
    return IntegerPvt(t_ms, dt, pos, vel, tuple(drive.names), split)


def as_written(table, drive, joint_units=None):
    """The PVT ``table`` (a KnotTable, model units) as the drive receives it from :func:`integer_pvt`: its points
    (split segments included) with the positions and velocities rounded to whole counts and counts/s, back in the
    model's units (rad or m, per s): the table whose interpolation is judged, so the verdict is that of the integers
    written, not of the values before rounding."""
    from dataclasses import replace

    pvt = integer_pvt(table, drive, joint_units)
    return replace(table, t=pvt.t_ms / 1e3, q=drive.joint_position(pvt.pos.astype(float)),
                   qd=pvt.vel.astype(float) / np.asarray(drive.scale, float))


def format_integer_csv(pvt: IntegerPvt) -> str:
    """Header ``t[ms],dt[ms],NAME[counts],NAME_vel[counts/s],…`` and one row of integers per point (LF)."""
    head = ["t[ms]", "dt[ms]"]
    for n in pvt.names:
        head += [f"{n}[counts]", f"{n}_vel[counts/s]"]
    cols = [pvt.t_ms, pvt.dt_ms]
    for j in range(len(pvt.names)):
        cols += [pvt.pos[:, j], pvt.vel[:, j]]
    data = np.column_stack(cols)
    return ",".join(head) + "\n" + "".join(",".join(str(int(x)) for x in row) + "\n" for row in data)


def _dint_array(name: str, values: np.ndarray, comment: str) -> str:
    lits = [str(int(v)) for v in values]
    lines = [", ".join(lits[i:i + VALUES_PER_LINE]) for i in range(0, len(lits), VALUES_PER_LINE)]
    return (f"    {name} : ARRAY[1..{len(lits)}] OF DINT := [ (* {_comment(comment)} *)\n        "
            + ",\n        ".join(lines) + "];\n")


def format_integer_st(pvt: IntegerPvt, dialect: str = "strict", header: list[str] = ()) -> str:
    """Structured Text of the integer table: ``strict`` a ``FUNCTION_BLOCK FB_PickplacePvt`` whose outputs hold
    ``nPoints``, ``nTime``, ``nDt`` [ms], ``NAME_pos`` [counts], ``NAME_vel`` [counts/s] (``ARRAY[1..N] OF DINT``);
    ``codesys`` a ``VAR_GLOBAL CONSTANT`` list of the same arrays named ``PP_PVT_…``."""
    strict = dialect == "strict"
    cols = [("nTime", pvt.t_ms, "t [ms]: time of the point"), ("nDt", pvt.dt_ms, "dt [ms]: segment time (0 first)")]
    for j, n in enumerate(pvt.names):
        cols += [(f"{n}_pos", pvt.pos[:, j], f"{n} [counts]: position"),
                 (f"{n}_vel", pvt.vel[:, j], f"{n}_vel [counts/s]: velocity")]
    names = [c[0] if strict else f"PP_PVT_{c[0].upper()}" for c in cols]
    count = "nPoints" if strict else "PP_PVT_POINTS"
    check_st_names([("table", "FB_PickplacePvt"), ("table", count)] + [("column", x) for x in names], dialect)
    if len({x.upper() for x in names}) != len(names):
        raise ExportError("table: two columns share a Structured Text name (case-insensitively); rename a joint")
    out = ["(* pickplace PVT table in the drive's integer units (cubic Hermite between points): times in whole ms,\n"
           "   positions in encoder counts, velocities in counts/s (DINT)\n"]
    out += [_comment(f"   {line}\n") for line in header]
    out.append(f"   Dialect: {dialect} ({'IEC 61131-3: a FUNCTION_BLOCK whose outputs hold the arrays' if strict else 'CODESYS/TwinCAT: a global constant list'}).\n*)\n\n")
    n = len(pvt.t_ms)
    decls = [f"    {count} : DINT := {n}; (* points *)\n"]
    decls += [_dint_array(x, v, c) for x, (_, v, c) in zip(names, cols)]
    if strict:
        out.append("FUNCTION_BLOCK FB_PickplacePvt\nVAR_OUTPUT\n" + "".join(decls) + f"END_VAR\n{count} := {n};\n"
                   "END_FUNCTION_BLOCK\n")
    else:
        out.append("VAR_GLOBAL CONSTANT\n" + "".join(decls) + "END_VAR\n")
    return "".join(out)
