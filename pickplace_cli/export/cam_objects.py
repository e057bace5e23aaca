"""Per-axis cam objects in the shape a controller's cam function blocks take (``plan --cam-object``): one cam per slave
axis (joint) of a cam or cam-table, as IEC 61131-3 Structured Text that declares and fills them.

==========  ====================  ==============================================================================
vendor      table                 per joint NAME
==========  ====================  ==============================================================================
codesys     cam (XYVA points)     ``NAME_xyva : ARRAY[0..n-1] OF SMC_CAMXYVA`` (dX master, dY slave, dV = dY/dX,
                                  dA = d²Y/dX²) and ``NAME_cam : MC_CAM_REF`` (byType 3 = SMC_CAM_TYPE.XYVA,
                                  nElements, xStart, xEnd, pce := ADR(NAME_xyva)): 5th-order polynomial per segment
codesys     cam-table             ``NAME_table : SMC_CAMTable_LREAL_<N>_1`` (N = 128 or 256, the library's sizes:
                                  the table is sampled at exactly N equidistant points) and ``NAME_cam`` (byType 1 =
                                  SMC_CAM_TYPE.X, byVarType 6 = LREAL, byInterpolationQuality 1 = linear); the
                                  slave scaling left at 1 (fEditorSlave = fTableSlave = 0 .. 1)
twincat     cam (motion function) ``NAME_points : ARRAY[1..n] OF MC_MotionFunctionPoint`` (PointIndex 1..n,
                                  FunctionType MOTIONFUNCTYPE_POLYNOM5_MM: the 5th-order polynomial between two
                                  motion points, PointType MOTIONPOINTTYPE_MOTION, RelIndexNextPoint 1, MasterPos,
                                  SlavePos, SlaveVelo = dY/dX, SlaveAcc = d²Y/dX², SlaveJerk = d³Y/dX³ of the
                                  segment's polynomial) and ``NAME_cam : MC_CAM_REF`` (TableType
                                  MC_TABLETYPE_MOTIONFUNCTION, NoOfRows n, NoOfColumns 1)
twincat     cam-table             ``NAME_table : ARRAY[0..n-1, 0..1] OF LREAL`` (master, slave per row) and
                                  ``NAME_cam : MC_CAM_REF`` (TableType MC_TABLETYPE_EQUIDISTANT, NoOfRows n,
                                  NoOfColumns 2): linear interpolation (MC_INTERPOLATIONTYPE_LINEAR)
==========  ====================  ==============================================================================

Velocities and accelerations are derivatives with respect to the master (the slave's speed when the master runs at
one master unit per second): per s and s² with the time master, per m and m² of belt travel with the belt master.
Everything is in a ``PROGRAM PRG_PickplaceCams`` (its variables are reachable from the task as
``PRG_PickplaceCams.NAME_cam``, as ``MC_CamTableSelect``'s ``CamTable`` input needs): the values are constant arrays,
copied into the vendor structures by the program's first call (``bReady`` then TRUE), which also sets the
``MC_CAM_REF`` fields (``ADR``/``SIZEOF`` are the CODESYS/TwinCAT operators). The interpolation each object names is
the one the table was judged with (:func:`~pickplace_cli.export.interpolate.rebuild`: XYVA and POLYNOM5_MM are the
``cam`` quintic, the equidistant tables the ``cam-table`` lines).
"""

from __future__ import annotations

from enum import Enum

import numpy as np

from ..model.errors import ExportError
from .table_st import VALUES_PER_LINE, _comment, check_st_names, st_real


class CamVendor(str, Enum):
    """The controller whose cam objects are written."""

    codesys = "codesys"
    twincat = "twincat"


#: the sizes of CODESYS SoftMotion's equidistant LREAL cam tables (SMC_CAMTable_LREAL_<N>_1, SM3_Basic)
CODESYS_TABLE_SIZES = (128, 256)
#: CODESYS MC_CAM_REF.nElements is an INT
CODESYS_MAX_ELEMENTS = 32767
PROGRAM_NAME = "PRG_PickplaceCams"


def table_size(vendor: str, kind: str, points: int) -> int | None:
    """The number of points the vendor's equidistant table type holds for a table that needs ``points`` (None: any
    count); ExportError (one line: the size and the limit) when no type is large enough."""
    if vendor != CamVendor.codesys.value or kind != "cam-table":
        return None
    for size in CODESYS_TABLE_SIZES:
        if points <= size:
            return size
    raise ExportError(f"cam-table: {points} points needed; CODESYS SoftMotion's equidistant LREAL cam tables hold at "
                      f"most {CODESYS_TABLE_SIZES[-1]} (SMC_CAMTable_LREAL_{CODESYS_TABLE_SIZES[-1]}_1): give a larger "
                      "--tolerance, or use -f cam-st (XYVA points)")


def _joints(cols) -> list[tuple[str, int, int | None, int | None]]:
    """(name, position column, velocity column, acceleration column) per joint of a cam/cam-table's columns."""
    names = list(cols.names)
    out = []
    for k, n in enumerate(names):
        if n == "master" or n.endswith(("_vel", "_acc")):
            continue
        vel = names.index(f"{n}_vel") if f"{n}_vel" in names else None
        acc = names.index(f"{n}_acc") if f"{n}_acc" in names else None
        out.append((n, k, vel, acc))
    return out


def _const_array(name: str, values, comment: str, first: int = 0) -> str:
    lits = [st_real(v) for v in values]
    lines = [", ".join(lits[i:i + VALUES_PER_LINE]) for i in range(0, len(lits), VALUES_PER_LINE)]
    return (f"    {name} : ARRAY[{first}..{first + len(lits) - 1}] OF LREAL := [ (* {_comment(comment)} *)\n        "
            + ",\n        ".join(lines) + "];\n")


def slave_jerk(x: np.ndarray, y: np.ndarray, v: np.ndarray, a: np.ndarray) -> np.ndarray:
    """d³Y/dX³ at each point of the quintic segments through (y, v, a) on master ``x`` (the segment starting there; the
    last point: the end of the last segment)."""
    from .interpolate import TableMotion, _cam

    motion = TableMotion("cam", x, _cam(x, y[:, None], v[:, None], a[:, None]), x)
    return motion(x, 3)[:, 0]


def _data(cols, kind: str, vendor: str, unit: str, size: int | None):
    """(per-joint ST names and their constant arrays, master values) of the program."""
    x = cols.data[:, 0]
    if size is not None and size != len(x):
        raise ExportError(f"cam-table: {len(x)} points, but the CODESYS table type holds {size}")
    decls, joints = [], []
    first = 1 if (vendor == "twincat" and kind == "cam") else 0
    if not (vendor == "codesys" and kind == "cam-table"):
        from .tables import as_csv

        decls.append(_const_array("fMaster", as_csv(x), f"master [{unit}]", first))
    for name, p, v, a in _joints(cols):
        y = cols.data[:, p]
        u = cols.units[p]
        decls.append(_const_array(f"{name}_y", y, f"{name} slave position [{u}]", first))
        if kind == "cam":
            vv, aa = cols.data[:, v], cols.data[:, a]
            decls.append(_const_array(f"{name}_v", vv, f"{name} dY/dX [{u}/{unit}]", first))
            decls.append(_const_array(f"{name}_a", aa, f"{name} d2Y/dX2 [{u}/{unit}^2]", first))
            if vendor == "twincat":
                decls.append(_const_array(f"{name}_j", slave_jerk(x, y, vv, aa), f"{name} d3Y/dX3 [{u}/{unit}^3]",
                                          first))
        joints.append(name)
    return decls, joints, x


def _objects(kind: str, vendor: str, n: int, joints: list[str]) -> tuple[list[str], list[str]]:
    """(declarations of the vendor objects, the fill statements of the first call) per joint."""
    decl, fill = [], []
    for j in joints:
        cam = f"{j}_cam"
        if vendor == "codesys" and kind == "cam":
            decl += [f"    {j}_xyva : ARRAY[0..{n - 1}] OF SMC_CAMXYVA; (* {j}: XYVA points *)\n",
                     f"    {cam} : MC_CAM_REF; (* {j}: XYVA cam *)\n"]
            fill += [f"    FOR i := 0 TO {n - 1} DO\n",
                     f"        {j}_xyva[i].dX := fMaster[i];\n        {j}_xyva[i].dY := {j}_y[i];\n",
                     f"        {j}_xyva[i].dV := {j}_v[i];\n        {j}_xyva[i].dA := {j}_a[i];\n",
                     "    END_FOR;\n",
                     f"    {cam}.byType := 3; (* SMC_CAM_TYPE.XYVA *)\n",
                     f"    {cam}.byVarType := 6; (* LREAL *)\n",
                     f"    {cam}.nElements := {n};\n",
                     f"    {cam}.xStart := fMaster[0];\n    {cam}.xEnd := fMaster[{n - 1}];\n",
                     f"    {cam}.pce := ADR({j}_xyva);\n"]
        elif vendor == "codesys":
            decl += [f"    {j}_table : SMC_CAMTable_LREAL_{n}_1; (* {j}: equidistant slave positions *)\n",
                     f"    {cam} : MC_CAM_REF; (* {j}: equidistant cam *)\n"]
            fill += [f"    FOR i := 0 TO {n - 1} DO\n        {j}_table.Table[i] := {j}_y[i];\n    END_FOR;\n",
                     f"    {j}_table.fEditorSlaveMin := 0.0;\n    {j}_table.fEditorSlaveMax := 1.0;\n",
                     f"    {j}_table.fTableSlaveMin := 0.0;\n    {j}_table.fTableSlaveMax := 1.0;\n",
                     f"    {cam}.byType := 1; (* SMC_CAM_TYPE.X *)\n",
                     f"    {cam}.byVarType := 6; (* LREAL *)\n",
                     f"    {cam}.byInterpolationQuality := 1; (* linear *)\n",
                     f"    {cam}.nElements := {n};\n",
                     f"    {cam}.xStart := xStart;\n    {cam}.xEnd := xEnd;\n",
                     f"    {cam}.pce := ADR({j}_table);\n"]
        elif kind == "cam":
            decl += [f"    {j}_points : ARRAY[1..{n}] OF MC_MotionFunctionPoint; (* {j}: motion function *)\n",
                     f"    {cam} : MC_CAM_REF; (* {j}: motion function cam *)\n"]
            fill += [f"    FOR i := 1 TO {n} DO\n",
                     f"        {j}_points[i].PointIndex := DINT_TO_UDINT(i);\n",
                     f"        {j}_points[i].FunctionType := MOTIONFUNCTYPE_POLYNOM5_MM;\n",
                     f"        {j}_points[i].PointType := MOTIONPOINTTYPE_MOTION;\n",
                     f"        {j}_points[i].RelIndexNextPoint := 1;\n",
                     f"        {j}_points[i].MasterPos := fMaster[i];\n",
                     f"        {j}_points[i].SlavePos := {j}_y[i];\n",
                     f"        {j}_points[i].SlaveVelo := {j}_v[i];\n",
                     f"        {j}_points[i].SlaveAcc := {j}_a[i];\n",
                     f"        {j}_points[i].SlaveJerk := {j}_j[i];\n",
                     "    END_FOR;\n",
                     f"    {cam}.pArray := ADR({j}_points);\n    {cam}.ArraySize := SIZEOF({j}_points);\n",
                     f"    {cam}.TableType := MC_TABLETYPE_MOTIONFUNCTION;\n",
                     f"    {cam}.NoOfRows := {n};\n    {cam}.NoOfColumns := 1;\n"]
        else:
            decl += [f"    {j}_table : ARRAY[0..{n - 1}, 0..1] OF LREAL; (* {j}: master, slave per row *)\n",
                     f"    {cam} : MC_CAM_REF; (* {j}: position table *)\n"]
            fill += [f"    FOR i := 0 TO {n - 1} DO\n",
                     f"        {j}_table[i, 0] := fMaster[i];\n        {j}_table[i, 1] := {j}_y[i];\n",
                     "    END_FOR;\n",
                     f"    {cam}.pArray := ADR({j}_table);\n    {cam}.ArraySize := SIZEOF({j}_table);\n",
                     f"    {cam}.TableType := MC_TABLETYPE_EQUIDISTANT;\n",
                     f"    {cam}.NoOfRows := {n};\n    {cam}.NoOfColumns := 2;\n"]
    return decl, fill


_TITLE = {("codesys", "cam"): "CODESYS SoftMotion XYVA cams (MC_CAM_REF, SMC_CAMXYVA; 5th-order polynomial segments)",
          ("codesys", "cam-table"): "CODESYS SoftMotion equidistant cams (MC_CAM_REF, SMC_CAMTable_LREAL_N_1; linear)",
          ("twincat", "cam"): "TwinCAT NC motion-function cams (MC_CAM_REF, MC_MotionFunctionPoint POLYNOM5_MM)",
          ("twincat", "cam-table"): "TwinCAT NC equidistant position tables (MC_CAM_REF, master/slave rows; linear)"}


def format_cam_objects_st(kind: str, cols, vendor: str, master_unit: str, header: list[str] = ()) -> str:
    """Structured Text of one cam object per joint of the ``kind`` (cam, cam-table) table ``cols``
    (:class:`~pickplace_cli.export.tables.TableColumns`) for ``vendor`` (codesys, twincat); see the module docstring."""
    if kind not in ("cam", "cam-table"):
        raise ExportError(f"format = {kind!r}: cam objects are written for the cam formats (cam-st, cam-table-st)")
    if vendor not in (v.value for v in CamVendor):
        raise ExportError(f"cam object = {vendor!r}: must be one of {', '.join(v.value for v in CamVendor)}")
    n = cols.data.shape[0]
    if vendor == "codesys" and n > CODESYS_MAX_ELEMENTS:
        raise ExportError(f"cam: {n} points; CODESYS MC_CAM_REF.nElements (INT) holds at most {CODESYS_MAX_ELEMENTS}")
    size = table_size(vendor, kind, n)
    decls, joints, x = _data(cols, kind, vendor, master_unit, size)
    names = [("program", PROGRAM_NAME)] + [("joint", f"{j}_{s}") for j in joints for s in ("cam", "y", "v", "a", "j",
                                                                                            "xyva", "table", "points")]
    check_st_names(names)
    if len({j.upper() for j in joints}) != len(joints):
        raise ExportError("cam objects: two joints share a Structured Text name (case-insensitively); rename a joint")
    objects, fill = _objects(kind, vendor, n, joints)
    out = [f"(* pickplace {_TITLE[(vendor, kind)]}: one cam per joint\n"]
    out += [_comment(f"   {line}\n") for line in header]
    out.append(f"   Velocities and accelerations are derivatives with respect to the master [{master_unit}].\n"
               f"   Call {PROGRAM_NAME} once (bReady TRUE) before MC_CamTableSelect(CamTable := "
               f"{PROGRAM_NAME}.<joint>_cam).\n*)\n\n")
    out.append(f"PROGRAM {PROGRAM_NAME}\nVAR\n    bReady : BOOL; (* TRUE once the cams are filled *)\n")
    out += objects
    out.append("    i : DINT;\nEND_VAR\nVAR CONSTANT\n")
    if vendor == "codesys" and kind == "cam-table":
        out.append(f"    xStart : LREAL := {st_real(x[0])}; (* master at the first point [{master_unit}] *)\n"
                   f"    xEnd : LREAL := {st_real(x[-1])}; (* master at the last point [{master_unit}] *)\n")
    out += decls
    out.append("END_VAR\nIF NOT bReady THEN\n")
    out += fill
    out.append("    bReady := TRUE;\nEND_IF;\nEND_PROGRAM\n")
    return "".join(out)
