"""export/rosbag2.py (``plan --rosbag2 -o DIR``): the directory ``ros2 bag play`` reads, checked by a second reader.

``metadata.yaml`` is parsed with PyYAML and every number in it is compared with the messages ``rosbags`` reads from
the directory (``rosbags.rosbag2.Reader``: its own metadata parser and MCAP reader, nothing shared with the writer)
and deserialises with its ROS 2 Humble and Jazzy type stores. Counts and times are integers: compared exactly.
"""

from __future__ import annotations

import os
from pathlib import Path

import pytest
import yaml
from typer.testing import CliRunner

from pickplace_cli.cli import app
from pickplace_cli.export.mcap import EPOCH_NS

ADEPT = ("--from", "-0.1525,0,-0.8", "--to", "0.1525,0,-0.8")


def run(*args: str):
    return CliRunner().invoke(app, list(args), catch_exceptions=False)


@pytest.mark.parametrize("store", ["humble", "jazzy"])
@pytest.mark.parametrize("extra", [(), ("--round-trip", "--compression", "zstd")])
def test_bag_directory_read_by_rosbags(tmp_path, extra, store):
    from rosbags.rosbag2 import Reader
    from rosbags.typesys import Stores, get_typestore

    bag = tmp_path / "adept_bag"
    r = run("plan", *ADEPT, *extra, "-q", "--rosbag2", "-o", str(bag))
    assert r.exit_code == 0, r.stderr
    assert sorted(os.listdir(bag)) == ["adept_bag_0.mcap", "metadata.yaml"]
    assert not [p for p in os.listdir(tmp_path) if p != "adept_bag"]  # no temporary directory left
    info = yaml.safe_load((bag / "metadata.yaml").read_text())["rosbag2_bagfile_information"]
    assert info["version"] == 5 and info["storage_identifier"] == "mcap"
    assert info["relative_file_paths"] == ["adept_bag_0.mcap"] and info["files"][0]["path"] == "adept_bag_0.mcap"
    ts = get_typestore({"humble": Stores.ROS2_HUMBLE, "jazzy": Stores.ROS2_JAZZY}[store])
    times, counts = [], {}
    with Reader(bag) as reader:
        types = {c.topic: c.msgtype for c in reader.connections}
        for conn, ns, raw in reader.messages():
            ts.deserialize_cdr(raw, conn.msgtype)  # every message decodes with the distribution's definitions
            times.append(ns)
            counts[conn.topic] = counts.get(conn.topic, 0) + 1
    listed = {t["topic_metadata"]["name"]: t for t in info["topics_with_message_count"]}
    assert set(listed) == set(counts) >= {"/joint_trajectory", "/joint_states", "/motor_states", "/drive_states"}
    for topic, entry in listed.items():
        assert entry["message_count"] == counts[topic]
        assert entry["topic_metadata"]["type"] == types[topic] and entry["topic_metadata"]["serialization_format"] == "cdr"
    assert info["message_count"] == sum(counts.values()) == info["files"][0]["message_count"]
    assert info["starting_time"]["nanoseconds_since_epoch"] == min(times) == EPOCH_NS
    assert info["duration"]["nanoseconds"] == max(times) - min(times) == info["files"][0]["duration"]["nanoseconds"]
    assert counts["/joint_trajectory"] == (2 if extra else 1)


def test_bag_batch_is_one_bag(tmp_path):
    src = tmp_path / "moves.csv"
    src.write_text("from_x,from_y,from_z,to_x,to_y,to_z\n-0.1525,0,-0.8,0.1525,0,-0.8\n0.1525,0,-0.8,-0.1525,0,-0.8\n")
    bag = tmp_path / "b"
    r = run("plan", "--batch", str(src), "-q", "--rosbag2", "-o", str(bag))
    assert r.exit_code == 0, r.stderr
    info = yaml.safe_load((bag / "metadata.yaml").read_text())["rosbag2_bagfile_information"]
    counts = {t["topic_metadata"]["name"]: t["message_count"] for t in info["topics_with_message_count"]}
    assert counts["/joint_trajectory"] == 2


def test_bag_into_an_empty_directory_and_not_over_a_bag(tmp_path):
    bag = tmp_path / "bag"
    bag.mkdir()
    assert run("plan", *ADEPT, "-q", "--rosbag2", "-o", str(bag)).exit_code == 0
    before = (bag / "bag_0.mcap").read_bytes()
    r = run("plan", *ADEPT, "-q", "--rosbag2", "-o", str(bag))
    assert r.exit_code == 1 and r.stderr.count("\n") == 1 and "is a directory that is not empty" in r.stderr
    assert (bag / "bag_0.mcap").read_bytes() == before
    f = tmp_path / "file"
    f.write_text("x")
    r = run("plan", *ADEPT, "-q", "--rosbag2", "-o", str(f))
    assert r.exit_code == 1 and "an existing file" in r.stderr and f.read_text() == "x"


@pytest.mark.parametrize("args, says", [
    ((), "give -o DIR"),
    (("-o", "-"), "give -o DIR"),
    (("-f", "csv", "-o", "d"), "not with -f csv"),
    (("--mcap-flavor", "foxglove", "-o", "d"), "not with --mcap-flavor foxglove"),
])
def test_bag_usage_errors(tmp_path, args, says, monkeypatch):
    monkeypatch.chdir(tmp_path)
    r = run("plan", *ADEPT, "-q", "--rosbag2", *args)
    assert r.exit_code == 2 and says in r.stderr, r.stderr
    assert not Path("d").exists()


def test_bag_bytes_are_the_mcap_file(tmp_path):
    """The bag's MCAP is the file -f mcap writes (same bytes: deterministic, no wall clock)."""
    bag, single = tmp_path / "bag", tmp_path / "one.mcap"
    assert run("plan", *ADEPT, "-q", "--rosbag2", "-o", str(bag)).exit_code == 0
    assert run("plan", *ADEPT, "-q", "-o", str(single)).exit_code == 0
    assert (bag / "bag_0.mcap").read_bytes() == single.read_bytes()
