"""Writers: one module per format. Data goes to a stream or, atomically, to a file.

``atomic_output(path)`` writes to a temporary file in the target's directory and renames it over the
target only when the writer finished: a failed or interrupted run leaves the old file (or none), never a
truncated one. A symbolic link is followed (the file it points to is replaced; the link stays). A device,
named pipe or socket (``/dev/null``, ``/dev/stdout``, a FIFO a PLC gateway reads) cannot be replaced by a
rename, and must not be: it is written in place. A directory or an empty path is an ExportError.
"""

from __future__ import annotations

import os
import stat
import sys
import tempfile
from contextlib import contextmanager
from pathlib import Path
from typing import IO, Iterator

import numpy as np

from ..model.errors import ExportError

#: format of every float in text exports: fixed, deterministic, round-trips ~1e-12 relative
FLOAT_FORMAT = "%.12g"


#: the temporary files being written by :func:`atomic_output` (removed by :func:`remove_pending` when SIGTERM
#: stops the process at once, without unwinding)
PENDING: set[str] = set()
#: the output files a command said it will write (:func:`promise`) and has not finished yet: when standard output's
#: reader goes away (broken pipe) before they are written, the command says so and exits 1 instead of 0
PROMISED: set[str] = set()


def promise(path: str | Path | None) -> None:
    """Note that the command will write ``path``: a file written through a temporary file (not None or ``-``,
    standard output, nor a device, named pipe or /dev, /proc path, written in place: /dev/stdout, /dev/null)."""
    if path is None or str(path) == "-":
        return
    try:
        in_place = _output_target(path)[1]
    except ExportError:
        return
    if not in_place:
        PROMISED.add(str(path))


def unpromise(path: str | Path | None) -> None:
    """The command decided not to write ``path`` (e.g. a limit is exceeded without --report-only)."""
    PROMISED.discard(str(path))


def remove_pending() -> int:
    """Remove every temporary output file still being written (SIGTERM); → how many."""
    n = 0
    for tmp in list(PENDING):
        try:
            os.unlink(tmp)
            n += 1
        except OSError:
            pass
        PENDING.discard(tmp)
    return n


class _CheckedStdout:
    """stdout as :func:`atomic_output` yields it: a failed write or flush (``> /dev/full``: no space left) is an
    ExportError naming the output; a reader that went away stays a BrokenPipeError (the CLI exits 0). Every
    other attribute is the stream's."""

    def __init__(self, stream) -> None:
        self._stream = stream

    def write(self, data):
        try:
            return self._stream.write(data)
        except BrokenPipeError:
            raise
        except OSError as exc:
            raise ExportError(f"output -: write failed: {exc.strerror or exc}") from None

    def flush(self) -> None:
        try:
            self._stream.flush()
        except BrokenPipeError:
            raise
        except OSError as exc:
            raise ExportError(f"output -: write failed: {exc.strerror or exc}") from None

    def __getattr__(self, name: str):
        return getattr(self._stream, name)


@contextmanager
def atomic_output(path: str | Path | None, binary: bool = False) -> Iterator[IO]:
    """Write an output atomically: a context manager yielding the stream to write.

    Parameters
    ----------
    path : str or pathlib.Path or None
        The file; None or ``-``: standard output. A regular file is written to a temporary file beside it and
        renamed onto it (onto the file a symbolic link points to) only when the block ends without an error, so
        it is complete or unchanged; a device or named pipe is written in place.
    binary : bool
        A binary stream (MCAP) instead of a text stream (UTF-8, newlines written unchanged).

    Raises
    ------
    ExportError
        The file cannot be created or written (one line naming it).
    """
    if path is None or str(path) == "-":
        stream = _CheckedStdout(sys.stdout.buffer if binary else sys.stdout)
        yield stream  # type: ignore[misc]
        stream.flush()
        return
    target, in_place = _output_target(path)
    if in_place:
        try:
            fh = open(target, "wb" if binary else "w", newline="" if not binary else None, encoding=None if binary else "utf-8")
        except OSError as exc:
            raise ExportError(f"output {path}: cannot open for writing: {exc.strerror}") from None
        try:
            with fh:
                yield fh
                fh.flush()
            PROMISED.discard(str(path))
        except BrokenPipeError:  # the reader of a pipe went away: the CLI's own handling (exit 0)
            raise
        except OSError as exc:  # e.g. /dev/full: no space left
            raise ExportError(f"output {path}: write failed: {exc.strerror or exc}") from None
        return
    directory = target.parent
    try:
        fd, tmp = tempfile.mkstemp(prefix=f".{target.name}.", suffix=".tmp", dir=directory)
    except OSError as exc:
        raise ExportError(f"output {path}: cannot create a file in {directory}: {exc.strerror}") from None
    PENDING.add(tmp)
    try:
        with os.fdopen(fd, "wb" if binary else "w", newline="" if not binary else None, encoding=None if binary else "utf-8") as fh:
            yield fh
            fh.flush()
            os.fsync(fh.fileno())
        os.chmod(tmp, _mode_for(target))
        refuse_protected(target, path)  # (made read-only while this run wrote)
        os.replace(tmp, target)
        PENDING.discard(tmp)
        PROMISED.discard(str(path))
    except BaseException as exc:
        try:
            os.unlink(tmp)
        except FileNotFoundError:
            pass
        PENDING.discard(tmp)
        if isinstance(exc, OSError) and not isinstance(exc, BrokenPipeError):  # disk full, quota, I/O error
            raise ExportError(f"output {path}: write failed, nothing changed: {exc.strerror or exc}") from None
        raise


def _output_target(path: str | Path) -> tuple[Path, bool]:
    """(the file to write, whether to write it in place) for an output path; ExportError for a path that
    cannot be written (empty, a directory, a missing directory). Symbolic links are followed; a device,
    named pipe or socket — or anything under /dev or /proc, e.g. /dev/stdout, which may resolve to the
    caller's redirected file — is written in place."""
    given = str(path)
    if not given.strip():
        raise ExportError("output '': an empty path (give a file name, or - for standard output)")
    if given.startswith(("/dev/", "/proc/")):
        return Path(given), True
    target = Path(os.path.realpath(given)) if os.path.islink(given) else Path(given)
    try:
        mode = os.stat(target).st_mode
    except FileNotFoundError:
        mode = None
    except OSError as exc:
        raise ExportError(f"output {given}: {exc.strerror}") from None
    if mode is not None and stat.S_ISDIR(mode):
        raise ExportError(f"output {given}: is a directory (give a file name, e.g. {Path(given) / 'out.csv'})")
    if mode is not None and not stat.S_ISREG(mode):
        return target, True
    directory = target.parent if str(target.parent) else Path(".")
    if not directory.is_dir():
        raise ExportError(f"output {given}: directory {directory} does not exist")
    return target, False


def _mode_for(target: Path) -> int:
    """The existing file's mode, else what a plain open() would give (0666 less the umask)."""
    try:
        return target.stat().st_mode & 0o777
    except FileNotFoundError:
        umask = os.umask(0)
        os.umask(umask)
        return 0o666 & ~umask


def refuse_protected(target: Path, given: str | Path) -> None:
    """ExportError when the existing file ``target`` is write-protected: not writable by this user, or with no write
    permission bit at all (mode 0444, which root could write too). The atomic rename needs only the directory to be
    writable, so without this check ``-o`` would replace a file the user protected, where a shell redirect is
    refused."""
    try:
        mode = os.stat(target).st_mode
    except OSError:
        return
    if stat.S_ISREG(mode) and (not mode & 0o222 or not os.access(target, os.W_OK)):
        raise ExportError(f"output {given}: the file is write-protected (mode {stat.S_IMODE(mode):04o}); it is left as "
                          "it is: make it writable (chmod u+w) or give another file")


def check_writable(path: str | Path | None) -> None:
    """Fail early (before anything is computed or written) when ``path`` cannot be an output file: empty,
    a directory, in a directory that does not exist or cannot be written (read-only file system, no
    permission), or a device/FIFO that cannot be written."""
    if path is None or str(path) == "-":
        return
    target, in_place = _output_target(path)
    if not in_place:
        refuse_protected(target, path)
    # the temp file is created in the directory (the rename needs it writable); in place, the file itself
    where = target if in_place else (target.parent if str(target.parent) else Path("."))
    if not os.access(where, os.W_OK):
        raise ExportError(f"output {path}: {'not writable' if in_place else f'directory {where} is not writable'}")


def column_names(units, torque: bool = True, motor_speed: bool = True, motor_torque: bool = True) -> list[str]:
    """The header names (with units) of a trajectory with joints in ``units`` ("rad" or "m" each): t, tool
    position … jerk, q/qd/qdd per joint, then per joint the torque and motor columns that are present."""
    names = ["t[s]"]
    names += [f"{c}[m]" for c in "xyz"]
    names += [f"v{c}[m/s]" for c in "xyz"]
    names += [f"a{c}[m/s^2]" for c in "xyz"]
    names += [f"j{c}[m/s^3]" for c in "xyz"]
    for k, unit in enumerate(units, 1):
        names += [f"q{k}[{unit}]", f"qd{k}[{unit}/s]", f"qdd{k}[{unit}/s^2]"]
    for k, unit in enumerate(units, 1):
        for name, present, u in ((f"torque{k}", torque, "N" if unit == "m" else "N*m"),
                                 (f"motor_speed{k}", motor_speed, "rad/s"), (f"motor_torque{k}", motor_torque, "N*m")):
            if present:
                names.append(f"{name}[{u}]")
    return names


def plan_columns(plan) -> tuple[list[str], np.ndarray]:
    """Column names (with units, :func:`column_names`) and the (N, n_columns) data of a plan's sampled trajectory."""
    jt = plan.joint
    names = column_names(jt.units, jt.torque is not None, jt.motor_speed is not None, jt.motor_torque is not None)
    blocks = [plan.t[:, None], plan.p, plan.v, plan.a, plan.j]
    for i in range(len(jt.units)):
        blocks += [jt.q[:, i : i + 1], jt.qd[:, i : i + 1], jt.qdd[:, i : i + 1]]
    for i in range(len(jt.units)):
        for arr in (jt.torque, jt.motor_speed, jt.motor_torque):
            if arr is not None:
                blocks.append(arr[:, i : i + 1])
    return names, np.hstack(blocks)
