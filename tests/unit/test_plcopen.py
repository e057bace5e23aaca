"""``plan --plcopen-xml``: the Structured Text exports as a PLCopen XML (TC6 v2.01) project.

* valid against the TC6 v2.01 schema (lxml), when the schema file is at hand (tests/data/plcopen/README.md);
* read back with a second reader (xml.etree, not the writer's string building) and compared with the plan: every
  array's values are the table's columns as the CSV of the same plan writes them (12 significant digits: within
  1e-11 relative), the POU kinds, names and variable types as the ST declares them, and the ST body the same text;
* deterministic: the same move gives the same bytes (a fixed creationDateTime, no clock).
"""

from __future__ import annotations

import os
import re
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np
import pytest
from typer.testing import CliRunner

from pickplace_cli.cli import app

ROOT = Path(__file__).resolve().parents[2]
NS = {"p": "http://www.plcopen.org/xml/tc6_0201", "x": "http://www.w3.org/1999/xhtml"}
ADEPT = ("--from", "-0.1525,0,-0.8", "--to", "0.1525,0,-0.8")


def _schema_path() -> Path | None:
    for p in (os.environ.get("PICKPLACE_TC6_XSD"), ROOT / "tests" / "data" / "plcopen" / "tc6_xml_v201.xsd"):
        if p and Path(p).is_file():
            return Path(p)
    return None


def _plan(tmp_path, name: str, *args: str) -> Path:
    out = tmp_path / name
    res = CliRunner().invoke(app, ["plan", *ADEPT, *args, "-q", "-o", str(out)], catch_exceptions=False)
    assert res.exit_code == 0, res.stderr
    return out


CASES = {
    "cam-fb": ("-f", "cam-st", "--tolerance", "1e-4"),
    "pvt-gvl": ("-f", "pvt-st", "--st-dialect", "codesys", "--tolerance", "1e-4"),
    "cam-codesys-objects": ("-f", "cam-st", "--tolerance", "1e-4", "--cam-object", "codesys"),
    "cam-table-twincat-objects": ("-f", "cam-table-st", "--tolerance", "1e-4", "--cam-object", "twincat"),
}


@pytest.mark.parametrize("case", sorted(CASES))
def test_project_is_valid_tc6_and_reads_back_as_the_plan(case, tmp_path):
    args = CASES[case]
    xml = _plan(tmp_path, f"{case}.xml", *args, "--plcopen-xml")
    st = _plan(tmp_path, f"{case}.st", *args).read_text()
    raw = xml.read_bytes()
    assert raw == _plan(tmp_path, f"{case}-again.xml", *args, "--plcopen-xml").read_bytes()  # deterministic
    root = ET.fromstring(raw)
    assert root.tag == f"{{{NS['p']}}}project"
    assert root.find("p:fileHeader", NS).get("creationDateTime") == "2000-01-01T00:00:00"
    # every POU of the ST, of its kind, with its body
    kinds = {"FUNCTION_BLOCK": "functionBlock", "PROGRAM": "program"}
    declared = re.findall(r"^(FUNCTION_BLOCK|PROGRAM) (\w+)$", st, re.M)
    pous = root.findall("p:types/p:pous/p:pou", NS)
    assert [(p.get("pouType"), p.get("name")) for p in pous] == [(kinds[k], n) for k, n in declared]
    for pou in pous:
        body = pou.find("p:body/p:ST/x:p", NS).text
        assert body and body in st and body.strip().endswith(";")
    # every variable's values against the ST's declarations (exact) and the plan's CSV table (12 digits)
    variables = {}
    for var in root.iter(f"{{{NS['p']}}}variable"):
        values = var.findall("p:initialValue/p:arrayValue/p:value/p:simpleValue", NS)
        if values:
            variables[var.get("name")] = np.array([float(v.get("value")) for v in values])
    st_arrays = {}
    for name, body in re.findall(r"^\s+(\w+) : ARRAY\[[^\]]*\] OF (?:LREAL|DINT) := \[(.*?)\];", st, re.M | re.S):
        st_arrays[name] = np.array([float(x) for x in re.sub(r"\(\*.*?\*\)", "", body, flags=re.S).split(",")])
    assert st_arrays and set(variables) == set(st_arrays)
    for name in st_arrays:
        assert np.array_equal(variables[name], st_arrays[name]), name
    fmt = args[args.index("-f") + 1][:-3]
    csv_args = [a for a in args if a not in ("--st-dialect", "codesys", "--cam-object", "twincat")]
    csv_args[csv_args.index("-f") + 1] = fmt
    csv = _plan(tmp_path, f"{case}.csv", *csv_args).read_text().splitlines()
    names = [h.split("[")[0] for h in csv[0].split(",")]
    data = np.array([[float(x) for x in line.split(",")] for line in csv[1:]])
    for k, col in enumerate(names):
        match = [v for n, v in variables.items() if _same_column(n, col)]
        assert len(match) == 1, (col, sorted(variables))
        assert np.allclose(match[0], data[:, k], rtol=1e-11, atol=1e-11 * np.max(np.abs(data[:, k]))), col


@pytest.mark.skipif(_schema_path() is None, reason="the TC6 v2.01 schema is not at hand: tests/data/plcopen/README.md")
@pytest.mark.parametrize("case", sorted(CASES))
def test_project_validates_against_the_tc6_v201_schema(case, tmp_path):
    """lxml validates each project against tc6_xml_v201.xsd (the POUs, typed variables, array values, ST bodies)."""
    from lxml import etree

    xsd = etree.XMLSchema(etree.parse(str(_schema_path())))
    raw = _plan(tmp_path, f"{case}.xml", *CASES[case], "--plcopen-xml").read_bytes()
    assert xsd.validate(etree.fromstring(raw)), xsd.error_log
    broken = raw.replace(b' creationDateTime="2000-01-01T00:00:00"', b"")
    assert not xsd.validate(etree.fromstring(broken))  # (the schema does reject: creationDateTime is required)


def _same_column(var: str, col: str) -> bool:
    """The ST variable that holds the CSV column ``col`` (FB outputs, the codesys list, or the cam objects' arrays)."""
    v = var.upper()
    c = col.upper()
    plain = {"T": "FTIME", "DT": "FDT", "MASTER": "FMASTER"}.get(c)
    if plain is not None:
        return v in (plain, f"PP_PVT_{plain}", f"PP_CAM_{plain}")
    if c.endswith(("_VEL", "_ACC")):
        joint, what = c[:-4], {"_VEL": "_V", "_ACC": "_A"}[c[-4:]]
        return v in (c, f"PP_PVT_{c}", f"PP_CAM_{c}", joint + what)
    return v in (f"{c}_POS", f"PP_PVT_{c}_POS", f"PP_CAM_{c}_POS", f"{c}_Y")


def test_plcopen_xml_outside_the_st_formats_is_a_usage_error(tmp_path):
    res = CliRunner().invoke(app, ["plan", *ADEPT, "-f", "cam", "--plcopen-xml", "-q", "-o", str(tmp_path / "x.csv")])
    assert res.exit_code == 2 and "--plcopen-xml" in res.stderr
