"""Golden files of every export format, compared by decoded content (``--update-golden`` rewrites them).

Decoded content: MCAP → header, schemas, channels, metadata and every message decoded (ROS 2 by rosbags,
JSON by json) with its log/publish time and sequence; CSV/TSV → separator, line ends, header and the
numbers; Structured Text and JSON tables → the text with every number compared numerically.

Inputs are frozen closed-form samples and a closed-form table (``tests/golden/samples.py``), so the
golden files test the formats and do not move when the planner or the shipped table changes (the unit
tests compare the exports of real plans with their in-memory values).

Numeric tolerance: rtol 1e-9 with atol 1e-9 (in the unit of the value): the closed-form inputs may
differ in the last bits across numpy/libm builds (sin, arctan2), so bytes are not compared; a real
change (a wrong column, a changed formula) is far above 1e-9. Non-numeric content (names, units,
schemas, topics, times in ns, counts) must match exactly.
"""

from __future__ import annotations

import dataclasses
import io
import json
import re
from pathlib import Path

import numpy as np
import pytest

from pickplace_cli.export.csv import write_csv
from pickplace_cli.export.mcap import mcap_bytes
from pickplace_cli.export.table_json import format_table_json
from pickplace_cli.export.table_st import format_table_st
from tests.golden.samples import synthetic, synthetic_batch, synthetic_table

DATA = Path(__file__).parent / "data"
RTOL = ATOL = 1e-9


def plain(obj):
    """rosbags message objects → plain dicts/lists/scalars."""
    if dataclasses.is_dataclass(obj):
        return {f.name: plain(getattr(obj, f.name)) for f in dataclasses.fields(obj)}
    if isinstance(obj, np.ndarray):
        return obj.tolist()
    if isinstance(obj, (list, tuple)):
        return [plain(x) for x in obj]
    if isinstance(obj, np.generic):
        return obj.item()
    return obj


def decode_mcap(data: bytes, tmp_path: Path) -> dict:
    from mcap.reader import make_reader

    reader = make_reader(io.BytesIO(data))
    header = reader.get_header()
    summary = reader.get_summary()
    doc = {
        "profile": header.profile,
        "library": header.library,
        "schemas": sorted((s.id, s.name, s.encoding, s.data.decode()) for s in summary.schemas.values()),
        "channels": sorted((c.id, c.topic, c.message_encoding, c.schema_id) for c in summary.channels.values()),
        "compression": sorted({ci.compression for ci in summary.chunk_indexes}),
        "metadata": {m.name: dict(m.metadata) for m in reader.iter_metadata()},
    }
    topics = {c.id: c.topic for c in summary.channels.values()}
    raw = [(topics[m.channel_id], m.log_time, m.publish_time, m.sequence, m.data) for _, _, m in reader.iter_messages(log_time_order=False)]
    if header.profile == "ros2":
        from rosbags.highlevel import AnyReader

        path = tmp_path / "decode.mcap"
        path.write_bytes(data)
        decoded = []
        with AnyReader([path]) as rb:
            for conn, _ns, blob in rb.messages():
                decoded.append(plain(rb.deserialize(blob, conn.msgtype)))
        # rosbags yields in log-time order; the mcap reader in file order: both are time-ordered here
        assert len(decoded) == len(raw)
        doc["messages"] = [(topic, lt, pt, seq) for topic, lt, pt, seq, _ in raw]
        doc["decoded"] = decoded
    else:
        doc["messages"] = [(topic, lt, pt, seq) for topic, lt, pt, seq, _ in raw]
        doc["decoded"] = [json.loads(blob) for *_, blob in raw]
    return json.loads(json.dumps(doc))  # tuples → lists, as in the golden JSON


def assert_same(actual, expected, where="$"):
    if isinstance(expected, dict):
        assert isinstance(actual, dict) and set(actual) == set(expected), (where, set(actual) ^ set(expected))
        for k in expected:
            assert_same(actual[k], expected[k], f"{where}.{k}")
    elif isinstance(expected, list):
        assert isinstance(actual, list) and len(actual) == len(expected), (where, len(actual), len(expected))
        for i, (a, e) in enumerate(zip(actual, expected)):
            assert_same(a, e, f"{where}[{i}]")
    elif isinstance(expected, float) or (isinstance(actual, float) and isinstance(expected, int) and not isinstance(expected, bool)):
        assert isinstance(actual, (int, float)) and abs(actual - expected) <= ATOL + RTOL * abs(expected), (where, actual, expected)
    else:
        assert actual == expected, (where, actual, expected)


_NUM = re.compile(r"[-+]?(?:\d+\.\d*|\.\d+|\d+)(?:[eE][-+]?\d+)?")


def decode_text(text: str) -> dict:
    """Text with its numbers taken out: the skeleton (exact) and the numbers (with tolerance)."""
    numbers = [float(m) for m in _NUM.findall(text)]
    return {"skeleton": _NUM.sub("#", text), "numbers": numbers}


def check_golden(name: str, produced: bytes, decode, update: bool) -> None:
    path = DATA / name
    if update:
        DATA.mkdir(exist_ok=True)
        path.write_bytes(produced)
        pytest.skip(f"rewrote {path}")
    assert path.exists(), f"{path} missing: run pytest --update-golden"
    assert_same(decode(produced), decode(path.read_bytes()))


def csv_bytes(samples, dialect: str) -> bytes:
    buf = io.StringIO(newline="")
    write_csv(samples, buf, dialect)
    return buf.getvalue().encode()


CASES = {
    "plan_ros2.mcap": lambda: mcap_bytes(synthetic()),
    "batch_ros2.mcap": lambda: mcap_bytes(synthetic_batch()),
    "nodrives_ros2_zstd.mcap": lambda: mcap_bytes(synthetic(drives=False), compression="zstd"),
    "plan_foxglove.mcap": lambda: mcap_bytes(synthetic(), flavor="foxglove"),
    "batch_foxglove.mcap": lambda: mcap_bytes(synthetic_batch(), flavor="foxglove"),
    "plan_default.csv": lambda: csv_bytes(synthetic(), "default"),
    "plan_twincat.csv": lambda: csv_bytes(synthetic(), "twincat"),
    "plan.tsv": lambda: csv_bytes(synthetic(), "tsv"),
    "batch_default.csv": lambda: csv_bytes(synthetic_batch(), "default"),
    "nodrives_twincat.csv": lambda: csv_bytes(synthetic(drives=False), "twincat"),
    "table.st": lambda: format_table_st(synthetic_table(), "GOLDEN").encode(),
    "table.json": lambda: format_table_json(synthetic_table(), "GOLDEN").encode(),
}


@pytest.mark.parametrize("name", sorted(CASES))
def test_golden(name, update_golden, tmp_path):
    produced = CASES[name]()
    if name.endswith(".mcap"):
        decode = lambda b: decode_mcap(b, tmp_path)  # noqa: E731
    else:
        decode = lambda b: decode_text(b.decode())  # noqa: E731
    check_golden(name, produced, decode, update_golden)


def test_decoded_comparison_can_fail(tmp_path):
    """The decoded comparison sees a changed value, a changed name and a changed line end."""
    base = decode_mcap(mcap_bytes(synthetic()), tmp_path)
    changed = json.loads(json.dumps(base))
    k = next(i for i, m in enumerate(changed["messages"]) if m[0] == "/joint_states" and i > 10)
    changed["decoded"][k]["position"][1] += 1e-6
    with pytest.raises(AssertionError):
        assert_same(changed, base)
    text = csv_bytes(synthetic(), "twincat").decode()
    with pytest.raises(AssertionError):
        assert_same(decode_text(text.replace("\r\n", "\n")), decode_text(text))
    with pytest.raises(AssertionError):
        assert_same(decode_text(text.replace("q1[rad]", "q1[deg]")), decode_text(text))
