"""The ``pickplace`` program (console script and ``python -m pickplace_cli``).

Everything here runs before the CLI and its libraries are imported (typer, numpy … take 0.1–0.5 s, longer on a busy
machine), so that a signal at any moment of the start-up is handled like one during the work:

* Ctrl-C (SIGINT) and SIGTERM: one line, exit 130 / 143, never a traceback or a bare ``rc -15``. Once a command runs,
  its own handlers take over (``cli.app._handle_errors``: temporary outputs removed, workers killed); before that
  nothing has been written, so there is nothing to clean up.
* A standard error whose reader went away (``plan … -o e.csv 2>&1 | head -3``) loses the messages, not the work:
  writes to it are dropped from then on (:class:`_QuietStderr`), the command still writes its files and exits with
  its own code.
* The BLAS libraries numpy and scipy load run one thread each unless the user set their thread count: the solver's
  matrices are small, and a thread pool per process made ``--time optimal`` 5–10× slower on a loaded machine
  (``bench/bench_threads.py``). Set ``OPENBLAS_NUM_THREADS`` (or ``OMP_NUM_THREADS``) to choose otherwise.
"""

from __future__ import annotations

import os
import signal
import sys

#: the exit codes of the two signals (128 + the signal's number, as a shell reports them)
EXIT_SIGINT = 130
EXIT_SIGTERM = 143
INTERRUPTED = "pickplace: error: interrupted; no output file was changed\n"
TERMINATED = "pickplace: error: terminated (SIGTERM); no output file was changed\n"

#: environment variables that set the BLAS thread count (the first three are read by OpenBLAS, MKL and BLIS)
BLAS_THREAD_VARIABLES = ("OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS", "BLIS_NUM_THREADS", "OMP_NUM_THREADS")


class _QuietStderr:
    """``sys.stderr`` that survives its reader going away: the first write that fails with a broken pipe points file
    descriptor 2 at /dev/null (so nothing written later, by this process or its workers, and no flush at exit fails)
    and drops the message. Every other attribute is the stream's."""

    def __init__(self, stream) -> None:
        self._stream = stream

    def _silence(self) -> None:
        try:
            null = os.open(os.devnull, os.O_WRONLY)
            os.dup2(null, self._stream.fileno())
            os.close(null)
        except (OSError, ValueError, AttributeError):
            pass

    def write(self, data):
        try:
            return self._stream.write(data)
        except BrokenPipeError:
            self._silence()
            return len(data)

    def flush(self) -> None:
        try:
            self._stream.flush()
        except BrokenPipeError:
            self._silence()
            try:
                self._stream.flush()
            except OSError:
                pass

    def __getattr__(self, name: str):
        return getattr(self._stream, name)


def _say(line: str) -> None:
    try:
        sys.stderr.write(line)
        sys.stderr.flush()
    except (OSError, ValueError, AttributeError):
        pass


def _early_sigterm(signum, frame) -> None:  # noqa: ARG001 - signal handler signature
    """SIGTERM before a command has installed its own handler: nothing is written yet; one line, exit 143. A forked
    worker (not this process) leaves the signal to its parent, which kills it."""
    if os.getpid() != _MAIN_PID[0]:
        return
    _say(TERMINATED)
    os._exit(EXIT_SIGTERM)


def _late_sigterm(signum, frame) -> None:  # noqa: ARG001 - signal handler signature
    """SIGTERM after the command finished, while the interpreter exits: one line, exit 143 (outputs stay as written)."""
    _say("pickplace: error: terminated (SIGTERM)\n")
    os._exit(EXIT_SIGTERM)


def _sigint(signum, frame) -> None:  # noqa: ARG001 - signal handler signature
    """Ctrl-C: a KeyboardInterrupt in this process (the commands turn it into one line and exit 130); a forked worker
    ignores it (Ctrl-C goes to the whole process group; the parent stops the work in order)."""
    if os.getpid() != _MAIN_PID[0]:
        return
    raise KeyboardInterrupt


_MAIN_PID = [0]


def _install() -> None:
    """Signal handlers, the quiet standard error and the BLAS thread default (see the module docstring)."""
    _MAIN_PID[0] = os.getpid()
    if signal.getsignal(signal.SIGINT) is not signal.SIG_IGN:  # a background job (`cmd &`) keeps ignoring Ctrl-C
        signal.signal(signal.SIGINT, _sigint)
    if signal.getsignal(signal.SIGTERM) is not signal.SIG_IGN:
        signal.signal(signal.SIGTERM, _early_sigterm)
    if sys.stderr is not None and not isinstance(sys.stderr, _QuietStderr):
        sys.stderr = _QuietStderr(sys.stderr)
    if not any(v in os.environ for v in BLAS_THREAD_VARIABLES):
        os.environ["OPENBLAS_NUM_THREADS"] = "1"  # read when numpy loads OpenBLAS (not yet: see the docstring)
        os.environ["MKL_NUM_THREADS"] = "1"


def _unreported_interrupt(exc: SystemExit) -> bool:
    """Whether exit ``exc`` is typer's silent exit 130 for a KeyboardInterrupt outside a command (while typer
    parsed the options or imported a command's modules): ``Exit(130) from KeyboardInterrupt``. A command's own
    exit 130 has already said so (``raise … from None``)."""
    ctx = exc.__context__
    return exc.code == EXIT_SIGINT and ctx is not None and isinstance(ctx.__cause__, KeyboardInterrupt)


def main() -> None:
    """Console-script entry point: install the start-up handlers, then run the CLI."""
    _install()
    try:
        from pickplace_cli.cli import main as cli_main

        cli_main()
    except KeyboardInterrupt:  # while the CLI's modules were imported
        _say(INTERRUPTED)
        os._exit(EXIT_SIGINT)
    except SystemExit as exc:
        if _unreported_interrupt(exc):
            _say(INTERRUPTED)
        raise
    finally:  # the command is over (its outputs are in place): a signal now only ends the exit
        _MAIN_PID[0] = -1
        if signal.getsignal(signal.SIGINT) is not signal.SIG_IGN:
            signal.signal(signal.SIGINT, signal.SIG_IGN)
        signal.signal(signal.SIGTERM, _late_sigterm)


if __name__ == "__main__":
    main()
