"""The process table as the tests read it (from /proc, no psutil): a process's parent and group, and whether it
still runs. Shared by the signal, fault-injection and data-safety tests and by bench/fuzz.py."""

from __future__ import annotations

import os
import time


def procs(field: int, value: int) -> list[int]:
    """The live processes whose /proc stat field ``field`` (after the name: 1 = parent, 2 = process group) is
    ``value`` (zombies excluded)."""
    out = []
    for entry in os.listdir("/proc"):
        if entry.isdigit():
            try:
                with open(f"/proc/{entry}/stat") as fh:
                    fields = fh.read().rsplit(")", 1)[1].split()
            except OSError:
                continue
            if int(fields[field]) == value and fields[0] != "Z":
                out.append(int(entry))
    return out


def children(pid: int) -> list[int]:
    return procs(1, pid)


def group(pgid: int) -> list[int]:
    return procs(2, pgid)


def alive(pid: int) -> bool:
    try:
        with open(f"/proc/{pid}/stat") as fh:
            return fh.read().rsplit(")", 1)[1].split()[0] != "Z"
    except OSError:
        return False


def kill_group(proc) -> None:
    """SIGKILL to the whole process group of ``proc`` (a Popen started with ``start_new_session=True``), gone or not,
    then reap it: the tests' clean-up, whatever the test left running."""
    import signal

    try:
        os.killpg(proc.pid, signal.SIGKILL)
    except ProcessLookupError:
        pass
    proc.wait()


def wait_started(proc, timeout: float = 120.0) -> None:
    """Wait until the program runs its own code: numpy mapped into the process, which the program imports only after
    its signal handlers are in place (a signal while the interpreter itself starts, before any of the program's
    code, is Python's to handle, and a busy machine can take seconds to get there)."""
    end = time.monotonic() + timeout
    while time.monotonic() < end and proc.poll() is None:
        try:
            with open(f"/proc/{proc.pid}/maps") as fh:
                if "numpy" in fh.read():
                    return
        except OSError:
            return
        time.sleep(0.02)
