"""Run a command with its stderr on a pseudo-terminal and collect what it wrote there (styled output, NO_COLOR)."""

from __future__ import annotations

import os
import pty
import subprocess


def stderr_on_terminal(cmd: list[str], no_color: str | None = None, timeout: float = 60.0,
                       columns: int | None = None) -> bytes:
    """Everything ``cmd`` writes to its stderr, a pseudo-terminal with ``TERM=xterm-256color``; ``NO_COLOR`` set to
    ``no_color`` when given (removed from the environment otherwise); stdout to the null device. ``columns``: the
    terminal's width (its window size, as a resized terminal sets it; COLUMNS and LINES removed from the
    environment)."""
    leader, follower = pty.openpty()
    env = {k: v for k, v in os.environ.items() if k not in ("NO_COLOR", "TERM")}
    if columns is not None:
        import fcntl
        import struct
        import termios

        fcntl.ioctl(follower, termios.TIOCSWINSZ, struct.pack("HHHH", 40, columns, 0, 0))
        env.pop("COLUMNS", None)
        env.pop("LINES", None)
    env["TERM"] = "xterm-256color"
    if no_color:
        env["NO_COLOR"] = no_color
    chunks = []
    try:
        proc = subprocess.Popen(cmd, stdout=subprocess.DEVNULL, stderr=follower, env=env)
        os.close(follower)
        while True:
            try:
                data = os.read(leader, 65536)
            except OSError:  # the terminal's other end closed (Linux: EIO)
                break
            if not data:
                break
            chunks.append(data)
        proc.wait(timeout)
    finally:
        os.close(leader)
    return b"".join(chunks)
