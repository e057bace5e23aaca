"""``plan --cam-object codesys|twincat`` (cam-st, cam-table-st): one cam object per joint in the controller's own types.

* Compiled by matiec (the strict IEC 61131-3 compiler of Beremiz/OpenPLC) with stand-in declarations of the vendor
  types written here from the vendors' documentation (CODESYS SM3_Basic: SMC_CAMXYVA, SMC_CAMTable_LREAL_<N>_1,
  MC_CAM_REF; TwinCAT Tc2_MC2_Camming: MC_CAM_REF, MC_MotionFunctionPoint and its enumerations), ``ADR``/``SIZEOF``
  (CODESYS/TwinCAT operators matiec lacks) replaced by 0 after checking that each names its own joint's object; the
  program run once in C, and what it filled read back (exact doubles).
* Each joint's cam rebuilt here with its documented interpolation, written independently of the exporter: XYVA and
  POLYNOM5_MM a 5th-order polynomial per segment solved from position, dY/dX and d²Y/dX² at both ends (a linear
  system); the equidistant tables straight lines (numpy.interp). The rebuilt cam is within the table's tolerance of the
  planned move (the robot's inverse kinematics of the plan), and the limits judged on the rebuilt motion hold.
"""

from __future__ import annotations

import json
import math
import re

import numpy as np
import pytest
from typer.testing import CliRunner

from pickplace_cli.cli import app

from .test_controller_tables import THERE, continuous_q, drive_scale, interpolate, piece_poly
from .test_st_matiec import GCC, MATIEC, compile_ok, run_c

pytestmark = [pytest.mark.skipif(MATIEC is None or GCC is None, reason="matiec (iec2c) or gcc not found")]

ADEPT = ("--from", "-0.1525,0,-0.8", "--to", "0.1525,0,-0.8")
TOLERANCE = 1e-4  # rad: the plans' --tolerance
SLACK = 1e-9  # rad: the 12-digit-free doubles in drive counts (k ≈ 4.2e6 counts/rad) rounded back to rad

#: the vendor types, as CODESYS (SM3_Basic) and Beckhoff (Tc2_MC2_Camming) document their fields; POINTER TO BYTE and
#: the array address (UDINT) stand in as UDINT, the enumerations by name (matiec has no valued enumerations)
CODESYS_TYPES = """TYPE
    SMC_CAMXYVA : STRUCT dX : LREAL; dY : LREAL; dV : LREAL; dA : LREAL; END_STRUCT;
""" + "".join(f"""    SMC_CAMTable_LREAL_{n}_1 : STRUCT Table : ARRAY[0..{n - 1}] OF LREAL; fEditorMasterMin : REAL;
        fEditorMasterMax : REAL; fEditorSlaveMin : REAL; fEditorSlaveMax : REAL; fTableMasterMin : REAL;
        fTableMasterMax : REAL; fTableSlaveMin : REAL; fTableSlaveMax : REAL; END_STRUCT;
""" for n in (128, 256)) + """    MC_CAM_REF : STRUCT wCamStructID : WORD; byType : BYTE; byVarType : BYTE; nTappets : INT; strCAMName : STRING;
        pce : UDINT; nElements : INT; xStart : LREAL; xEnd : LREAL; byInterpolationQuality : BYTE; END_STRUCT;
END_TYPE
"""
TWINCAT_TYPES = """TYPE
    MC_TableType : (MC_TABLETYPE_EQUIDISTANT, MC_TABLETYPE_NONEQUIDISTANT, MC_TABLETYPE_MOTIONFUNCTION);
    MC_MotionFunctionType : (MOTIONFUNCTYPE_NOTDEF, MOTIONFUNCTYPE_POLYNOM1, MOTIONFUNCTYPE_POLYNOM5,
        MOTIONFUNCTYPE_POLYNOM5_MM);
    MC_MotionPointType : (MOTIONPOINTTYPE_IGNORE, MOTIONPOINTTYPE_REST, MOTIONPOINTTYPE_VELOCITY,
        MOTIONPOINTTYPE_TURN, MOTIONPOINTTYPE_MOTION);
    MC_MotionFunctionPoint_ID : UDINT;
    MC_MotionFunctionPoint : STRUCT PointIndex : MC_MotionFunctionPoint_ID; FunctionType : MC_MotionFunctionType;
        PointType : MC_MotionPointType; RelIndexNextPoint : MC_MotionFunctionPoint_ID; MasterPos : LREAL;
        SlavePos : LREAL; SlaveVelo : LREAL; SlaveAcc : LREAL; SlaveJerk : LREAL; END_STRUCT;
    MC_CAM_REF : STRUCT pArray : UDINT; ArraySize : UDINT; TableType : MC_TableType; NoOfRows : UDINT;
        NoOfColumns : UDINT; END_STRUCT;
END_TYPE
"""
#: the C enumerators of the stand-ins (matiec names an enumerator TYPE__VALUE)
ENUM = {"MOTIONFUNCTYPE_POLYNOM5_MM": 3, "MOTIONPOINTTYPE_MOTION": 4, "MC_TABLETYPE_EQUIDISTANT": 0,
        "MC_TABLETYPE_MOTIONFUNCTION": 2}

CASES = {("codesys", "cam"): "cam-st", ("codesys", "cam-table"): "cam-table-st",
         ("twincat", "cam"): "cam-st", ("twincat", "cam-table"): "cam-table-st"}


def _plan(tmp_path, vendor: str, fmt: str) -> tuple[str, dict]:
    out = tmp_path / f"{vendor}-{fmt}.st"
    res = CliRunner().invoke(app, ["plan", *ADEPT, "-f", fmt, "--tolerance", str(TOLERANCE), "--cam-object", vendor,
                                   "-o", str(out), "--json"], catch_exceptions=False)
    assert res.exit_code == 0, res.stderr
    return out.read_text(), json.loads(res.stdout)


def _for_matiec(text: str, vendor: str) -> str:
    """The program with the stand-in types before it and ADR/SIZEOF (checked to name their own joint's object) as 0."""
    for op, field in (("ADR", r"(?:pce|pArray)"), ("SIZEOF", "ArraySize")):
        for joint, target in re.findall(rf"^\s+(\w+)_cam\.{field} := {op}\((\w+)\);$", text, re.M):
            assert target in (f"{joint}_xyva", f"{joint}_table", f"{joint}_points"), (joint, target)
    assert len(re.findall(r"\b(?:ADR|SIZEOF)\(", text)) == len(re.findall(r"_cam\.\w+ := (?:ADR|SIZEOF)\(\w+\);", text))
    body = re.sub(r"\b(?:ADR|SIZEOF)\(\w+\)", "0", text)
    return (CODESYS_TYPES if vendor == "codesys" else TWINCAT_TYPES) + body


def _harness(vendor: str, kind: str, joints: list[str], n: int) -> str:
    """C main: init the program, run it once, print bReady, then per joint its filled object (%a: exact doubles)."""
    P = "PRG_PICKPLACECAMS"
    lines = [f"static {P} p;", "int main(void) {", f"    {P}_init__(&p, 0);", f"    {P}_body__(&p);",
             '    printf("%d\\n", (int)p.BREADY.value);']
    for j in joints:
        J = j.upper()
        cam = f"p.{J}_CAM.value"
        if vendor == "codesys":
            lines.append(f'    printf("%d %d %d %a %a\\n", (int){cam}.BYTYPE, (int){cam}.BYVARTYPE, (int){cam}.NELEMENTS,'
                         f' {cam}.XSTART, {cam}.XEND);')
            if kind == "cam":
                fields = [f"p.{J}_XYVA.value.table[i].{f}" for f in ("DX", "DY", "DV", "DA")]
            else:
                lines.append(f'    printf("%d %a %a %a %a\\n", (int){cam}.BYINTERPOLATIONQUALITY, '
                             f"(double)p.{J}_TABLE.value.FEDITORSLAVEMIN, (double)p.{J}_TABLE.value.FEDITORSLAVEMAX, "
                             f"(double)p.{J}_TABLE.value.FTABLESLAVEMIN, (double)p.{J}_TABLE.value.FTABLESLAVEMAX);")
                fields = [f"p.{J}_TABLE.value.TABLE.table[i]"]
        else:
            lines.append(f'    printf("%d %d %d\\n", (int){cam}.TABLETYPE, (int){cam}.NOOFROWS, (int){cam}.NOOFCOLUMNS);')
            if kind == "cam":
                pt = f"p.{J}_POINTS.value.table[i]"
                lines.append(f"    for (int i = 0; i < {n}; i++) printf(\"%d %d %d %d \", (int){pt}.POINTINDEX, "
                             f"(int){pt}.FUNCTIONTYPE, (int){pt}.POINTTYPE, (int){pt}.RELINDEXNEXTPOINT);")
                lines.append('    printf("\\n");')
                fields = [f"{pt}.{f}" for f in ("MASTERPOS", "SLAVEPOS", "SLAVEVELO", "SLAVEACC", "SLAVEJERK")]
            else:
                fields = [f"p.{J}_TABLE.value.table[i][0]", f"p.{J}_TABLE.value.table[i][1]"]
        for f in fields:
            lines.append(f'    for (int i = 0; i < {n}; i++) printf("%a ", (double){f});\n    printf("\\n");')
    lines += ["    return 0;", "}"]
    return "\n".join(lines) + "\n"


def _floats(line: str) -> np.ndarray:
    return np.array([float.fromhex(v) for v in line.split()])


@pytest.mark.parametrize("vendor,kind", sorted(CASES))
def test_cam_objects_compile_fill_and_rebuild_within_tolerance(vendor, kind, tmp_path):
    """matiec compiles the program with 0 errors; run once, it fills every joint's object with the documented field
    values; each joint's cam, rebuilt here with the interpolation its object names, is within --tolerance (1e-4 rad)
    of the planned move (+1e-9 rad: the doubles in counts back in rad) at 40 points per segment."""
    from pickplace_cli.model.profile import load_profile
    from pickplace_cli.planner import PlanOptions, plan

    text, doc = _plan(tmp_path, vendor, CASES[(vendor, kind)])
    table = doc["table"]
    assert table["cam_object"] == vendor and table["limits_ok"] is True
    joints = re.findall(r"^    (\w+)_cam : MC_CAM_REF;", text, re.M)
    assert joints == ["A1", "A2", "A3"]  # the delta-su2018 profile's drive names
    n = table["points"]
    if vendor == "codesys" and kind == "cam-table":
        assert n in (128, 256)  # SMC_CAMTable_LREAL_128_1 / _256_1
    compile_ok(_for_matiec(text, vendor), tmp_path / "c")
    out = run_c(tmp_path / "c", _harness(vendor, kind, joints, n)).splitlines()
    assert out[0] == "1"  # bReady
    lines = iter(out[1:])
    x = None
    pos, vel, acc = [], [], []
    for _ in joints:
        head = next(lines).split()
        if vendor == "codesys":
            assert head[:3] == (["3", "6", str(n)] if kind == "cam" else ["1", "6", str(n)])
            x0, x1 = float.fromhex(head[3]), float.fromhex(head[4])
            if kind == "cam":
                cols = [_floats(next(lines)) for _ in range(4)]
                assert cols[0][0] == x0 and cols[0][-1] == x1
                jx, y, v, a = cols
            else:
                scaling = next(lines).split()
                assert scaling[0] == "1" and [float.fromhex(s) for s in scaling[1:]] == [0.0, 1.0, 0.0, 1.0]
                y = _floats(next(lines))
                jx = x0 + (x1 - x0) * np.arange(n) / (n - 1)  # equidistant from xStart to xEnd
                v = a = None
        else:
            assert head == ([str(ENUM["MC_TABLETYPE_MOTIONFUNCTION"]), str(n), "1"] if kind == "cam"
                            else [str(ENUM["MC_TABLETYPE_EQUIDISTANT"]), str(n), "2"])
            if kind == "cam":
                ints = np.array(next(lines).split(), dtype=int).reshape(n, 4)
                assert ints[:, 0].tolist() == list(range(1, n + 1))  # PointIndex 1..n, gapless
                assert set(ints[:, 1]) == {ENUM["MOTIONFUNCTYPE_POLYNOM5_MM"]}
                assert set(ints[:, 2]) == {ENUM["MOTIONPOINTTYPE_MOTION"]} and set(ints[:, 3]) == {1}
                jx, y, v, a, jerk = [_floats(next(lines)) for _ in range(5)]
                # SlaveJerk: d³Y/dX³ of the segment's own quintic at its start (the last point: the last segment's end)
                ref = []
                for k in range(n):
                    s = min(k, n - 2)
                    h = jx[s + 1] - jx[s]
                    c = piece_poly([(0.0, 0, y[s]), (h, 0, y[s + 1]), (0.0, 1, v[s]), (h, 1, v[s + 1]),
                                    (0.0, 2, a[s]), (h, 2, a[s + 1])])
                    at = 0.0 if k < n - 1 else h
                    ref.append(6 * c[3] + 24 * c[4] * at + 60 * c[5] * at * at)
                # 1e-6 of the largest: a third derivative from a 6x6 solve in counts (values ~1e6) loses digits
                assert np.allclose(jerk, ref, rtol=0, atol=1e-6 * np.max(np.abs(ref)))
            else:
                jx, y = _floats(next(lines)), _floats(next(lines))
                assert np.allclose(np.diff(jx), jx[-1] / (n - 1), rtol=1e-9, atol=0)  # equidistant master
                v = a = None
        assert len(y) == n
        x = jx if x is None else x
        assert np.array_equal(x, jx)  # one master for every joint
        pos.append(y)
        vel.append(v)
        acc.append(a)
    # what the program filled is the ST's constants (parsed here from the text), to the bit: the fill code copies
    # every value to its field (compared within 1e-12 relative, and in fact equal)
    const = {n: np.array([float(v) for v in re.sub(r"\(\*.*?\*\)", "", body, flags=re.S).split(",")])
             for n, body in re.findall(r"^    (\w+) : ARRAY\[[^\]]*\] OF LREAL := \[(.*?)\];", text, re.M | re.S)}
    for j, y, v, a in zip(joints, pos, vel, acc):
        pairs = [(y, const[f"{j}_y"])] + ([] if v is None else [(v, const[f"{j}_v"]), (a, const[f"{j}_a"])])
        if "fMaster" in const:
            pairs.append((x, const["fMaster"]))
        for got, want in pairs:
            assert np.allclose(got, want, rtol=1e-12, atol=0) and np.array_equal(got, want)
    scale, offset = drive_scale("delta-su2018")
    p = np.column_stack(pos) / scale + offset
    vv = None if kind == "cam-table" else np.column_stack(vel) / scale
    aa = None if kind == "cam-table" else np.column_stack(acc) / scale
    at = np.concatenate([np.linspace(x[k], x[k + 1], 40, endpoint=False) for k in range(n - 1)] + [x[-1:]])
    leg = plan(THERE, load_profile("delta-su2018"), PlanOptions())
    true = continuous_q("delta-su2018", [leg], 0.0, at, [x[-1]])  # re-timed tables: the same path in x[-1] s
    err = np.abs(interpolate(kind, x, p, vv, aa, at) - true).max(axis=0)
    assert np.all(err <= TOLERANCE + SLACK), err
    _judged_as_rebuilt(kind, x, p, vv, aa, at, table, interpolate(kind, x, p, vv, aa, at))


def _judged_as_rebuilt(kind, x, p, v, a, at, info: dict, mine: np.ndarray) -> None:
    """The library's rebuild of the values read back from C (export.interpolate.rebuild, the judge's interpolation)
    is the cam rebuilt here — XYVA/POLYNOM5_MM: at every point within 1e-9 rad (two forms of one quintic, values ~1 rad);
    equidistant: halfway between the setpoints the drive reads every cycle on the lines between the points — and the limit check
    of that rebuilt motion (limits.table.check_table, at the profile's limit use) holds every limit."""
    from pickplace_cli.export.interpolate import rebuild
    from pickplace_cli.export.knots import KnotTable
    from pickplace_cli.limits.table import check_table
    from pickplace_cli.model.headroom import apply_limit_use
    from pickplace_cli.model.profile import load_profile
    from pickplace_cli.planner import motion_model_static

    prof = apply_limit_use(load_profile("delta-su2018"))
    kt = KnotTable(kind, x, p, np.zeros_like(p) if v is None else v, a, TOLERANCE, np.zeros(p.shape[1]), len(x))
    read = info["step_cycle_s"]
    motion = rebuild(kt, read)
    if kind == "cam":
        assert np.max(np.abs(motion(at) - mine)) <= 1e-9
    else:
        # the drive's setpoints: the lines between the points read every cycle from the first point; between two
        # setpoints the one-cycle blends meet halfway, on the straight line from one setpoint to the next
        ts = x[0] + read * np.arange(int(round((x[-1] - x[0]) / read)) + 1)
        sp = np.column_stack([np.interp(ts, x, p[:, j]) for j in range(p.shape[1])])
        mid = (ts[:-1] + ts[1:]) / 2
        assert np.max(np.abs(motion(mid) - (sp[:-1] + sp[1:]) / 2)) <= 1e-9
    robot, specs, margin, box = motion_model_static(prof)[:4]
    report = check_table(motion, robot, specs, read, prof.planning.dwell, margin, box,
                         capacity=prof.capacity).rated(prof.limit_use)
    assert report.ok, [r.as_dict() for r in report.violations]


def test_a_codesys_table_larger_than_its_types_is_refused_in_one_line(tmp_path):
    """At the default tolerance (1e-6 rad) the equidistant table needs more points than SMC_CAMTable_LREAL_256_1
    holds: exit 1, one line naming the count and the limit, nothing written."""
    out = tmp_path / "cams.st"
    res = CliRunner().invoke(app, ["plan", *ADEPT, "-f", "cam-table-st", "--cam-object", "codesys", "-q", "-o",
                                   str(out)])
    assert res.exit_code == 1
    lines = res.stderr.strip().splitlines()
    assert len(lines) == 1 and re.search(r"cam-table: \d+ points needed; .* at most 256 \(SMC_CAMTable_LREAL_256_1\)",
                                         lines[0]), lines
    assert not out.exists()


@pytest.mark.parametrize("args", [("-f", "cam", "--cam-object", "codesys"),
                                  ("-f", "pvt-st", "--cam-object", "twincat"),
                                  ("-f", "cam-st", "--cam-object", "twincat", "--st-dialect", "codesys")])
def test_cam_object_usage_errors(args, tmp_path):
    """--cam-object outside cam-st/cam-table-st, or with --st-dialect codesys: usage (exit 2), nothing written."""
    out = tmp_path / ("x.csv" if args[1] == "cam" else "x.st")
    res = CliRunner().invoke(app, ["plan", *ADEPT, *args, "-q", "-o", str(out)])
    assert res.exit_code == 2 and "--cam-object" in res.stderr and not out.exists()


def test_table_summary_says_more_points_when_there_are_more():
    """Without a cycle an equidistant table at 1e-5 rad needs more points than the 1 kHz samples: the summary says
    '<n/samples> x more points than the samples' (not 'x fewer'), the ratio from the JSON's own counts."""
    res = CliRunner().invoke(app, ["plan", *ADEPT, "-f", "cam-table", "--tolerance", "1e-5", "-o", "/dev/null",
                                   "--json"])
    assert res.exit_code == 0, res.stderr
    info = json.loads(res.stdout)["table"]
    assert info["points"] > info["samples"] and info["master_step_cycles"] is None
    assert f"({info['points'] / info['samples']:.2f} x more points than the samples;" in res.stderr


def test_equidistant_table_on_a_cycle_has_one_point_per_cycle():
    """On a 1 ms cycle at the default tolerance (1e-6 rad: a ~0.2 ms step alone) the table's master step is one
    cycle: K + 1 points for a move of K cycles (K from the JSON's duration), not the tolerance's count."""
    res = CliRunner().invoke(app, ["plan", *ADEPT, "--cycle", "0.001", "-f", "cam-table", "-o", "/dev/null", "--json"])
    assert res.exit_code == 0, res.stderr
    info = json.loads(res.stdout)["table"]
    K = round(info["duration_s"] / 0.001)
    assert info["points"] == K + 1 and info["master_step_cycles"] == 1
    assert info["tolerance_points"] > 4 * info["points"]


def test_cli_cam_object_mirrors_the_library():
    """The CLI's --cam-object choices (kept numpy-free for --help) are the library's vendors plus none."""
    from pickplace_cli.cli.app import CamObject
    from pickplace_cli.export.cam_objects import CamVendor

    assert [c.value for c in CamObject] == ["none"] + [v.value for v in CamVendor]


def test_belt_cycle_cams_with_the_belt_as_master_rebuild_the_cycle_feed(tmp_path):
    """The whole belt cycle (--to-belt --round-trip on a 1 ms cycle) as CODESYS XYVA cams with the belt as master: each
    joint's cam, rebuilt here as a 5th-order polynomial per segment from its points' slave position, dY/dX and d²Y/dX²
    (solved independently of the exporter), at the belt travel of every cycle's sample (belt speed · (t + latency),
    from the time column of the same plan's --columns plc feed), is within --tolerance (1e-6 rad, in counts: k·1e-6)
    of the feed's counts (+1e-9 rad: the feed's counts are written to 5 decimals)."""
    belt = ("-p", "delta-4axis", "--from", "-0.15,0,-0.8,0", "--to", "0.15,-0.2,-0.8,1.2", "--to-belt", "0,0.5,0",
            "--latency", "0.05", "--round-trip", "--cycle", "0.001", "-q")
    st, feed = tmp_path / "cams.st", tmp_path / "feed.csv"
    run = CliRunner()
    res = run.invoke(app, ["plan", *belt, "-f", "cam-st", "--cam-object", "codesys", "--cam-master", "belt",
                           "-o", str(st)], catch_exceptions=False)
    assert res.exit_code == 0, res.stderr
    res = run.invoke(app, ["plan", *belt, "--columns", "plc", "-o", str(feed)], catch_exceptions=False)
    assert res.exit_code == 0, res.stderr
    text = st.read_text()
    const = {n: np.array([float(v) for v in re.sub(r"\(\*.*?\*\)", "", body, flags=re.S).split(",")])
             for n, body in re.findall(r"^    (\w+) : ARRAY\[[^\]]*\] OF LREAL := \[(.*?)\];", text, re.M | re.S)}
    x = const["fMaster"]
    assert np.all(np.diff(x) > 0)  # the belt only moves forward: a strictly increasing master [m]
    head = feed.read_text().splitlines()[0].split(",")
    data = np.loadtxt(feed, delimiter=",", skiprows=1)
    t = data[:, head.index("t[s]")]
    at = 0.5 * (t + 0.05)  # the belt's travel since the part's detection [m]
    assert x[0] == pytest.approx(at[0], abs=1e-12) and x[-1] == pytest.approx(at[-1], abs=1e-12)
    seg = np.clip(np.searchsorted(x, at, side="right") - 1, 0, len(x) - 2)
    for j in ("A1", "A2", "A3", "A4"):
        y, v, a = const[f"{j}_y"], const[f"{j}_v"], const[f"{j}_a"]
        rebuilt = np.empty_like(at)
        for s in np.unique(seg):
            h = x[s + 1] - x[s]
            c = piece_poly([(0.0, 0, y[s]), (h, 0, y[s + 1]), (0.0, 1, v[s]), (h, 1, v[s + 1]), (0.0, 2, a[s]),
                            (h, 2, a[s + 1])])
            u = at[seg == s] - x[s]
            rebuilt[seg == s] = np.polyval(c[::-1], u)
        gear = 25.0 if j != "A4" else 10.0  # delta-4axis: arms 25, the rotary axis 10 motor rad per joint rad
        k = gear * 1048576 / (2 * math.pi)  # 2^20 counts per motor revolution [counts/rad]
        err = np.abs(rebuilt - data[:, head.index(f"{j}[counts]")]).max() / k
        assert err <= 1e-6 + 1e-9, (j, err)
