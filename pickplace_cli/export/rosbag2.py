"""A rosbag2 directory around the MCAP file (``plan -f mcap --rosbag2 -o DIR``), as ``ros2 bag play`` and
``ros2 bag info`` want it: ``DIR/DIR_0.mcap`` (the ros2 flavour of :func:`~pickplace_cli.export.mcap.write_mcap`)
and ``DIR/metadata.yaml`` (rosbag2's bag information, version 5: ROS 2 Humble writes it, later releases read it),
with the storage ``mcap``, the start time and duration, and each topic's type and message count, read back from the
MCAP file's summary. The QoS of every topic is left empty, so ``ros2 bag play`` offers its defaults (reliable,
volatile), which ros2_control's JointTrajectoryController subscribes with.

The directory is written whole or not at all: into a temporary directory beside it, renamed onto ``DIR`` at the
end. ``DIR`` must not exist yet or be an empty directory (as ``ros2 bag record`` does, an existing bag is not
replaced).
"""

from __future__ import annotations

import os
import shutil
import tempfile
from pathlib import Path

from ..model.errors import ExportError

#: the rosbag2 metadata version written (ROS 2 Humble's)
METADATA_VERSION = 5


def check_bag_directory(path: str | Path | None) -> None:
    """ExportError (one line) when ``path`` cannot become a rosbag2 directory: no path or standard output, an
    existing file or non-empty directory, a parent directory that does not exist or cannot be written."""
    if path is None or str(path) in ("-", "") or str(path).startswith(("/dev/", "/proc/")):
        raise ExportError(f"output {path or '-'}: a rosbag2 bag is a directory: give -o DIR")
    target = Path(path)
    if target.exists() and (not target.is_dir() or any(target.iterdir())):
        what = "a directory that is not empty" if target.is_dir() else "an existing file"
        raise ExportError(f"output {path}: is {what}; a rosbag2 bag is written to a new or empty directory "
                          "(remove it or give another name)")
    parent = target.parent if str(target.parent) else Path(".")
    if not parent.is_dir():
        raise ExportError(f"output {path}: directory {parent} does not exist")
    if not os.access(parent, os.W_OK):
        raise ExportError(f"output {path}: directory {parent} is not writable")


def bag_metadata(mcap_path: Path) -> str:
    """rosbag2's ``metadata.yaml`` for the single MCAP file ``mcap_path`` (its summary: channels, schemas, counts,
    times), in a fixed order."""
    from mcap.reader import make_reader

    with open(mcap_path, "rb") as fh:
        summary = make_reader(fh).get_summary()
    if summary is None or summary.statistics is None:
        raise ExportError(f"output {mcap_path}: the MCAP file has no summary to describe")
    stats = summary.statistics
    start, end = int(stats.message_start_time), int(stats.message_end_time)
    counts = stats.channel_message_counts
    topics = []
    for cid in sorted(summary.channels):
        channel = summary.channels[cid]
        schema = summary.schemas[channel.schema_id]
        topics.append(
            "    - topic_metadata:\n"
            f"        name: {channel.topic}\n"
            f"        type: {schema.name}\n"
            f"        serialization_format: {channel.message_encoding}\n"
            '        offered_qos_profiles: ""\n'
            f"      message_count: {int(counts.get(cid, 0))}\n"
        )
    name = mcap_path.name
    total = int(stats.message_count)
    return (
        "rosbag2_bagfile_information:\n"
        f"  version: {METADATA_VERSION}\n"
        "  storage_identifier: mcap\n"
        f"  duration:\n    nanoseconds: {end - start}\n"
        f"  starting_time:\n    nanoseconds_since_epoch: {start}\n"
        f"  message_count: {total}\n"
        "  topics_with_message_count:\n" + "".join(topics) +
        '  compression_format: ""\n'
        '  compression_mode: ""\n'
        f"  relative_file_paths:\n    - {name}\n"
        f"  files:\n    - path: {name}\n"
        f"      starting_time:\n        nanoseconds_since_epoch: {start}\n"
        f"      duration:\n        nanoseconds: {end - start}\n"
        f"      message_count: {total}\n"
    )


def write_rosbag2(samples, directory: str | Path, **mcap_kwargs) -> None:
    """Write ``samples`` as the rosbag2 directory ``directory`` (the module docstring); ``mcap_kwargs`` go to
    :func:`~pickplace_cli.export.mcap.write_mcap` (compression, drive …; the flavour is ros2)."""
    from . import PROMISED
    from .mcap import write_mcap

    check_bag_directory(directory)
    flavor = mcap_kwargs.pop("flavor", "ros2")
    if flavor != "ros2":  # (McapFlavor is a str Enum)
        raise ExportError(f"mcap flavor = {getattr(flavor, 'value', flavor)}: a rosbag2 bag holds ROS 2 messages (ros2)")
    target = Path(directory)
    parent = target.parent if str(target.parent) else Path(".")
    stem = target.resolve().name
    try:
        tmp = Path(tempfile.mkdtemp(prefix=f".{stem}.", suffix=".tmp", dir=parent))
    except OSError as exc:
        raise ExportError(f"output {directory}: cannot create a directory in {parent}: {exc.strerror}") from None
    try:
        mcap_path = tmp / f"{stem}_0.mcap"
        with open(mcap_path, "wb") as fh:
            write_mcap(samples, fh, flavor="ros2", **mcap_kwargs)
            fh.flush()
            os.fsync(fh.fileno())
        (tmp / "metadata.yaml").write_text(bag_metadata(mcap_path), encoding="utf-8")
        os.chmod(tmp, 0o777 & ~_umask())
        if target.is_dir():  # empty (checked): rename() replaces an empty directory
            target.rmdir()
        os.rename(tmp, target)
        PROMISED.discard(str(directory))
    except BaseException as exc:
        shutil.rmtree(tmp, ignore_errors=True)
        if isinstance(exc, OSError):
            raise ExportError(f"output {directory}: write failed, nothing changed: {exc.strerror or exc}") from None
        raise


def _umask() -> int:
    mask = os.umask(0)
    os.umask(mask)
    return mask
