"""The Typer app, the option enums, and what every command shares: typed errors → one line and the exit code, point and number parsing."""

from __future__ import annotations

import functools
import sys
from enum import Enum
from typing import Callable, Optional

import typer

from .. import __version__
from ..model.methods import Method


def _usage_error_line(self, file=None) -> None:  # noqa: ARG001 - click's signature
    """click's usage errors (an unknown option, a missing one or its argument: exit 2) as one line, like every other
    error: ``pickplace: error: MESSAGE (see COMMAND --help)``, instead of click's four. A value that a typed option
    cannot take (``--rate abc``, ``-m foo``) is invalid input like a value out of range: exit 1, in the form
    ``--OPTION 'VALUE': RULE`` (:func:`_bad_value_line`)."""
    ctx = getattr(self, "ctx", None)
    hint = f" (see {ctx.command_path if ctx is not None else 'pickplace'} --help)"
    from ..model.text import shorten_quoted

    line = _bad_value_line(self)
    if line is not None:
        self.exit_code = 1
        typer.echo(f"pickplace: error: {shorten_quoted(line)}{hint}", err=True)
        return
    typer.echo(f"pickplace: error: {shorten_quoted(self.format_message())}{hint}", err=True)


def _bad_value_line(exc) -> str | None:
    """``--OPTION 'VALUE': RULE`` for click's error about a value given to a typed option or argument (not a missing
    one, not the tool's own usage errors, which name no parameter); None for any other usage error. The value is
    read from the command line as given (``--rate abc``, ``--rate=abc``, ``-rabc`` is not used by the tool)."""
    param = getattr(exc, "param", None)
    if param is None or type(exc).__name__ != "BadParameter":  # (MissingParameter is a subclass: kept exit 2)
        return None
    from ..model.text import quoted

    opts = list(getattr(param, "opts", ()) or ())
    shown = [n for n in opts if not n.startswith("--")] + [n for n in opts if n.startswith("--")][:1]
    name = "/".join(shown) if param.param_type_name == "option" else (param.name or "argument").upper()
    rule = str(getattr(exc, "message", "") or exc).strip()
    rule = rule[len("Value error, "):] if rule.startswith("Value error, ") else rule
    import re

    rule = re.sub(r"^Input should be a valid (number|integer), unable to parse string as an? \w+$",
                  lambda m: f"must be {'a' if m[1] == 'number' else 'an'} {m[1]}", rule)
    value = _given_value(opts)
    if value is None:  # (the rule names a choice's value itself)
        return f"{name}: {rule}"
    return f"{name} {quoted(value)}: {re.sub(r'^.* is not one of ', 'must be one of ', rule)}"


def _given_value(opts: list[str]) -> str | None:
    """The last value given on the command line (``sys.argv``) to the option spelled ``opts``, or None."""
    from pathlib import Path

    program = Path(sys.argv[0] if sys.argv else "")
    if program.name != "pickplace" and program.parent.name != "pickplace_cli":  # (called from another program)
        return None
    argv, found = sys.argv[1:], None
    for i, arg in enumerate(argv):
        if arg == "--":
            break
        if arg in opts and i + 1 < len(argv):
            found = argv[i + 1]
        for o in opts:
            if o.startswith("--") and arg.startswith(o + "="):
                found = arg[len(o) + 1:]
    return found


def _one_line_usage_errors() -> None:
    """Install :func:`_usage_error_line` on the UsageError class typer raises (recent typers carry their own copy
    of click: found through typer.BadParameter's bases, not by a module name)."""
    for cls in typer.BadParameter.__mro__:
        if cls.__name__ == "UsageError":
            cls.show = _usage_error_line  # type: ignore[method-assign]


_one_line_usage_errors()


class Panel:
    """The groups of a command's options in ``--help``, in the order they are shown (the common ones first); every
    option names one (``typer.Option(…, rich_help_panel=Panel.MOVE)``; tests/cli/test_help_panels.py)."""

    MOVE = "Move"
    METHOD = "Method and duration"
    BELT = "Belt and conveyor"
    OUTPUT = "Output"
    CONTROLLER = "Controller and drive"
    LIMITS = "Limits and checks"
    BATCH = "Batch and performance"
    STUDY = "Plot and study"
    ORDER = (MOVE, METHOD, BELT, OUTPUT, CONTROLLER, LIMITS, BATCH, STUDY)


def _options_by_panel(self, ctx, formatter) -> None:
    """A command's ``--help`` options in sections, one per :class:`Panel` in its order (plain text: the help is
    printed without rich), then ``Options`` for those without a panel (``--help``)."""
    args, panels = [], {}
    for param in self.get_params(ctx):
        record = param.get_help_record(ctx)
        if record is None:
            continue
        if param.param_type_name == "argument":
            args.append(record)
        elif param.param_type_name == "option":
            panels.setdefault(getattr(param, "rich_help_panel", None) or "Options", []).append(record)
    if args:
        with formatter.section("Arguments"):
            formatter.write_dl(args)
    order = [p for p in Panel.ORDER if p in panels] + [p for p in panels if p not in Panel.ORDER]
    for name in order:
        with formatter.section(name):
            formatter.write_dl(panels[name])


typer.core.TyperCommand.format_options = _options_by_panel  # type: ignore[method-assign]

app = typer.Typer(
    name="pickplace",
    help=(
        "Plan smooth, fast pick-and-place moves for high-speed robots and write the sampled joint "
        "trajectories (SI units: m, s, rad). Exit codes: 0 ok, 1 invalid input, 2 usage error, "
        "3 limit exceeded, 4 unreachable point, 130 interrupted, 143 terminated (SIGTERM)."
    ),
    no_args_is_help=True,
    add_completion=True,
    pretty_exceptions_enable=False,
    rich_markup_mode=None,
    context_settings={"help_option_names": ["-h", "--help"]},
)


class OutputFormat(str, Enum):
    csv = "csv"
    json = "json"
    mcap = "mcap"
    pvt = "pvt"
    pvt_st = "pvt-st"
    cam = "cam"
    cam_st = "cam-st"
    cam_table = "cam-table"
    cam_table_st = "cam-table-st"


class StDialect(str, Enum):
    """Mirror of pickplace_cli.export.st.StDialect."""

    strict = "strict"
    codesys = "codesys"


class CamMaster(str, Enum):
    time = "time"
    belt = "belt"


class TableEnd(str, Enum):
    """Before and after a drive's table: the drive holds its end points, or the controller goes on at their velocity."""

    hold = "hold"
    going = "continue"


class CamObject(str, Enum):
    """Mirror of pickplace_cli.export.cam_objects.CamVendor, plus none (one table of every joint)."""

    none = "none"
    codesys = "codesys"
    twincat = "twincat"


class CsvDialectName(str, Enum):
    """Mirror of pickplace_cli.export.csv.CsvDialect."""

    default = "default"
    twincat = "twincat"
    tsv = "tsv"


class TableMethod(str, Enum):
    bspline = "bspline"
    bspline_vel = "bspline-vel"


class McapFlavor(str, Enum):
    ros2 = "ros2"
    foxglove = "foxglove"


#: --max-shift default [m]
MAX_SHIFT = 0.01


class Compression(str, Enum):
    none = "none"
    zstd = "zstd"


#: --method: the library's own list of methods (its module imports no numpy, so --help stays fast)
MethodName = Method


class OptimizeWhat(str, Enum):
    none = "none"
    shape = "shape"


class TurnName(str, Enum):
    """Mirror of pickplace_cli.curves.rotation.TurnRule."""

    shortest = "shortest"
    ccw = "ccw"
    cw = "cw"
    as_given = "as-given"


class TurnDuring(str, Enum):
    """Mirror of pickplace_cli.curves.rotation.TurnWindow."""

    transfer = "transfer"
    whole = "whole"


def _err(message: str) -> None:
    """``pickplace: error: MESSAGE`` on stderr; a message of several problems (a profile's): one line each; a
    quoted value longer than 60 characters cut (:func:`~pickplace_cli.model.text.shorten_quoted`)."""
    from ..model.text import shorten_quoted

    sys.stderr.write("".join(f"pickplace: error: {shorten_quoted(line)}\n" for line in message.splitlines() or [""]))


def _one_warning(state: dict):
    """``warnings.showwarning`` for a command: the first warning as one line (numpy's RuntimeWarnings of a
    degenerate move, e.g. a division by zero, printed Python's way take two lines each, with a source line, and
    come by the dozen); the others are counted, not printed. The numbers they concern are still checked: a NaN
    duration is an error, a NaN peak a failed limit."""

    def show(message, category, filename, lineno, file=None, line=None):  # noqa: ARG001 - the signature
        import os

        if category.__name__ == "UnitWarning":  # a value in a likely wrong unit: every one, in its own words
            sys.stderr.write(f"pickplace: warning: {message}\n")
            return
        state["n"] = state.get("n", 0) + 1
        if state["n"] == 1:
            sys.stderr.write(f"pickplace: warning: {category.__name__}: {message} "
                             f"({os.path.basename(filename)}:{lineno}); further warnings not shown\n")

    return show


def _on_sigterm(signum, frame) -> None:  # noqa: ARG001 - signal handler signature
    """SIGTERM (``kill``, ``timeout``, ``docker stop``, systemd; to the process or its whole group): stop at once, in
    the handler, whatever the main thread is doing — remove the temporary ``-o`` files being written
    (:data:`pickplace_cli.export.PENDING`), say so in one line, kill the worker processes, reap them (so none outlives this
    process, even as a zombie that a slow init collects seconds later) and exit 143. Not by
    unwinding: a pool worker killed while sending a result leaves the pool's result pipe half-written, and a pool
    shut down in an orderly way then waits forever for the rest of it. A forked worker whose parent is alive
    leaves the signal to the parent (which kills it); an orphaned one dies of it."""
    import os
    import signal

    if os.getpid() != _MAIN_PID[0]:  # a forked worker (-j N, build-table)
        if os.getppid() == _MAIN_PID[0]:
            return
        signal.signal(signal.SIGTERM, signal.SIG_DFL)
        os.kill(os.getpid(), signal.SIGTERM)
        return
    try:
        from ..export import remove_pending

        remove_pending()
        _err("terminated (SIGTERM); no output file was changed")
        for note in _TERM_NOTES:
            sys.stderr.write(note)
        sys.stderr.flush()
        _kill_and_reap_children()
    finally:
        os._exit(143)


def _child_pids() -> set:
    """This process's child processes: the pool's workers multiprocessing knows of and, from /proc, any other (a
    worker forked the instant SIGTERM came, before the pool recorded it)."""
    import multiprocessing
    import os

    pids = {c.pid for c in multiprocessing.active_children() if c.pid}
    me = str(os.getpid())
    try:
        entries = [e for e in os.listdir("/proc") if e.isdigit()]
    except OSError:  # no /proc (not Linux): the ones multiprocessing knows
        return pids
    for entry in entries:
        try:
            with open(f"/proc/{entry}/stat") as fh:
                if fh.read().rsplit(")", 1)[1].split()[1] == me:
                    pids.add(int(entry))
        except (OSError, IndexError):
            continue
    return pids


def _kill_and_reap_children(timeout: float = 5.0) -> None:
    """SIGKILL to every child process, then reap them (within ``timeout`` s): gone when this process is, none left
    running or as a zombie for a slow init to collect seconds later."""
    import os
    import signal
    import time

    pids = _child_pids()
    for pid in pids:
        try:
            os.kill(pid, signal.SIGKILL)
        except ProcessLookupError:
            pass
    deadline = time.monotonic() + timeout
    for pid in pids:
        while True:
            try:
                if os.waitpid(pid, os.WNOHANG)[0]:
                    break
            except ChildProcessError:  # reaped already (by the pool's own thread)
                break
            if time.monotonic() > deadline:
                return
            time.sleep(0.002)


_MAIN_PID = [0]
#: lines to print when SIGTERM stops the command (build-table: where its finished rows are, for --resume)
_TERM_NOTES: list[str] = []


#: the method parameters given with ``--param NAME=VALUE`` (an error about one names ``--param``)
GIVEN_PARAMS: set[str] = set()


def named_by_option(message: str, command: Callable) -> str:
    """An error ``FIELD = VALUE: RULE`` about a value that ``command`` (a typer command function) takes as an option
    ``--FIELD`` (``_`` read as ``-``) names the option instead: ``--FIELD VALUE: RULE`` (``-j/--workers 3: …``).
    Other messages (a file's line, a batch row, a profile's field, a derived value such as λ) are returned as they
    are."""
    name, sep, rest = message.partition(" = ")
    import inspect

    takes_param = any("--param" in (getattr(p.default, "param_decls", None) or ())
                      for p in inspect.signature(command).parameters.values())
    bare = name[len("param "):] if name.startswith("param ") else name
    if sep and takes_param and (bare != name or bare in GIVEN_PARAMS):
        return f"--param {bare}={rest}"  # a method's parameter: as given, --param NAME=VALUE
    if not sep and takes_param and bare != name:
        return f"--param {bare}"
    if not sep or not name.replace("_", "").replace("-", "").isalnum():
        return message

    want = "--" + name.replace("_", "-")
    for param in inspect.signature(command).parameters.values():
        decls = getattr(param.default, "param_decls", None)
        if decls is None:  # (an argument, or not a typer parameter)
            continue
        names = [n for d in decls for n in d.split("/") if not n.startswith("--no-")] or ["--" + param.name.replace("_", "-")]
        if want in names:  # its short form and its first long one (``-j/--workers``, ``--v-from``)
            shown = [n for n in names if not n.startswith("--")] + [next(n for n in names if n.startswith("--"))]
            return f"{'/'.join(shown)} {rest}"
    return message


def _stdout_broken() -> bool:
    """Whether standard output is a pipe whose reader has gone (its write end polls POLLERR); True when that cannot be
    told (no poll, no descriptor)."""
    try:
        import select

        poller = select.poll()
        poller.register(sys.__stdout__.fileno(), select.POLLOUT)
        return any(ev & (select.POLLERR | select.POLLHUP | select.POLLNVAL) for _, ev in poller.poll(0))
    except (AttributeError, OSError, ValueError):
        return True


def _handle_errors(fn: Callable) -> Callable:
    """Turn the library's typed errors into one line on stderr and the documented exit code; SIGTERM stops the
    command with exit 143 (:func:`_on_sigterm`)."""

    @functools.wraps(fn)
    def wrapper(*args, **kwargs):
        import os
        import signal
        import threading

        from ..model.errors import PickplaceError

        GIVEN_PARAMS.clear()  # (this command's own --param, not an earlier one's in the same process)

        from ..export import PROMISED

        _JSON_ERRORS[0] = False
        _EXIT_SO_FAR[0] = 0
        _TERM_NOTES.clear()
        PROMISED.clear()
        import warnings

        previous = None
        if threading.current_thread() is threading.main_thread():
            _MAIN_PID[0] = os.getpid()
            previous = signal.signal(signal.SIGTERM, _on_sigterm)
        shown = warnings.showwarning
        warnings.showwarning = _one_warning({})
        try:
            return fn(*args, **kwargs)
        except PickplaceError as exc:  # (`plan --json`: stdout still carries one JSON document, like a batch row's)
            _fail_json(exc.exit_code, named_by_option(str(exc), fn))
        except KeyboardInterrupt:
            _err("interrupted; no output file was changed")
            raise typer.Exit(130) from None
        except BrokenPipeError:
            # the reader went away (e.g. `| head`): not an error of ours, unless a file the command was to write
            # (-o, --report) is left unwritten: a script that checks $? must not take it for written; and the
            # verdict decided so far (a limit exceeded: 3) is still the exit code
            unwritten = sorted(PROMISED)
            which = ("standard output was" if _stdout_broken() else
                     "a pipe it wrote to (a FIFO given as an output, not standard output) was")
            try:
                sys.stdout = None  # type: ignore[assignment]
                if unwritten:
                    _err(f"{', '.join(unwritten)}: not written: {which} closed by its reader (broken pipe) before the "
                         "command finished")
            finally:
                raise typer.Exit(max(_EXIT_SO_FAR[0], 1 if unwritten else 0)) from None
        except OSError as exc:  # an I/O failure no layer above named (the writers name their output themselves)
            _err(f"{exc.filename}: {exc.strerror or exc}" if exc.filename else f"I/O error: {exc.strerror or exc}")
            try:
                sys.stdout.flush()
            except (OSError, ValueError, AttributeError):
                sys.stdout = None  # type: ignore[assignment]  # a broken stdout: not flushed again at exit
            raise typer.Exit(1) from None
        except MemoryError:
            from ..export import remove_pending

            remove_pending()
            _fail_json(1, "out of memory; no output file was changed (a lower --rate or a shorter --time needs less)")
        except Exception as exc:  # noqa: BLE001 - never a traceback: one line naming what failed, exit 1
            if isinstance(exc, _CLICK_EXCEPTIONS):  # typer's exits and usage errors: click reports them
                raise
            from ..export import remove_pending

            remove_pending()
            detail = " ".join(str(exc).split())[:300]
            _fail_json(1, f"internal error ({type(exc).__name__}: {detail}); no output file was changed")
        finally:
            warnings.showwarning = shown
            if previous is not None:
                signal.signal(signal.SIGTERM, previous)

    return wrapper


#: exceptions typer and click raise through a command on purpose (exit codes, usage errors, an abort)
_CLICK_EXCEPTIONS = tuple({c for e in (typer.Exit, typer.Abort, typer.BadParameter) for c in e.__mro__
                           if c.__name__ in ("Exit", "Abort", "ClickException")})


def _fail_json(code: int, message: str) -> None:
    """One error line (and the JSON document of ``--json``), then exit ``code``."""
    from ..model.text import shorten_quoted

    message = shorten_quoted(message)
    _err(message)
    if _JSON_ERRORS[0]:
        import json

        try:
            sys.stdout.write(json.dumps({"exit_code": code, "error": message}) + "\n")
            sys.stdout.flush()
        except (OSError, ValueError, AttributeError):  # stdout itself failed (> /dev/full): the line on stderr says so
            sys.stdout = None  # type: ignore[assignment]  # (not flushed again at exit)
    raise typer.Exit(code) from None


#: the exit code a command has decided so far (a move's verdict, a batch's rows): when stdout's reader goes away
#: (broken pipe) the command still exits with it, so a limit that is exceeded is never reported as exit 0
_EXIT_SO_FAR = [0]


def note_exit(code: int) -> None:
    """Record that the command will exit with at least ``code`` (see ``_EXIT_SO_FAR``)."""
    _EXIT_SO_FAR[0] = max(_EXIT_SO_FAR[0], code)


#: set by `plan --json` (one move or a round trip) once its options are read: an error after that also
#: goes to stdout as {"exit_code", "error"}, so a script reading the summary always gets a JSON document
_JSON_ERRORS = [False]


def _version_callback(value: bool) -> None:
    if value:
        typer.echo(f"pickplace {__version__}")
        raise typer.Exit()


@app.callback()
def _root(
    version: bool = typer.Option(
        False, "--version", callback=_version_callback, is_eager=True, help="Print the version and exit."
    ),
) -> None:
    """pickplace: smooth pick-and-place trajectories (Li 2018 quintic B-splines) checked for a robot."""


def _usage(message: str) -> None:
    """A usage error (exit 2), reported like any other misuse of the options."""
    raise typer.BadParameter(message)


def _parse_point(name: str, text: str, unit: str = "m"):
    from ..model.errors import TaskError
    from ..model.text import quoted

    words = "metres" if unit == "m" else unit
    what = "coordinates" if unit == "m" else "components"
    parts = [p.strip() for p in text.split(",")]
    if len(parts) != 3 or not all(parts):
        example = "-0.1525,0,-0.8" if unit == "m" else "0,0.2,0"
        raise TaskError(f"{name} = {quoted(text)}: give three {what} X,Y,Z in {words}, e.g. {example}")
    from ..model.text import plain_float

    try:
        values = [plain_float(p) for p in parts]
    except ValueError:
        raise TaskError(f"{name} = {quoted(text)}: every {what[:-1]} must be a number in {words}") from None
    import math

    if not all(math.isfinite(v) for v in values):
        raise TaskError(f"{name} = {quoted(text)}: every coordinate must be a finite number (no NaN or inf)")
    return values


def _parse_pose(name: str, text: str) -> tuple[list, Optional[float]]:
    """--from/--to: X,Y,Z in m, optionally a fourth number THETA, the tool angle in rad about the base z axis (a
    robot with a rotary fourth axis) → (xyz, theta or None); TaskError naming the option, the text and the rule."""
    from ..model.errors import TaskError
    from ..model.text import quoted

    parts = [p.strip() for p in text.split(",")]
    if len(parts) == 4 and all(parts):
        from ..model.text import plain_float

        try:
            theta = plain_float(parts[3])
        except ValueError:
            raise TaskError(f"{name} = {quoted(text)}: the fourth number, the tool angle THETA, must be a number in rad") from None
        import math

        if not math.isfinite(theta):
            raise TaskError(f"{name} = {quoted(text)}: the tool angle THETA must be a finite number of radians (no NaN or inf)")
        return _parse_point(name, ",".join(parts[:3])), theta
    if len(parts) > 4 or (len(parts) == 4 and not all(parts)):
        raise TaskError(f"{name} = {quoted(text)}: give X,Y,Z in metres and optionally the tool angle THETA in rad, e.g. "
                        "-0.1525,0,-0.8,1.5708")
    return _parse_point(name, text), None


def _finite(name: str, value: Optional[float], rule: str = "> 0") -> Optional[float]:
    import math

    from ..model.errors import TaskError

    if value is None:
        return None
    if not math.isfinite(value) or (rule == "> 0" and value <= 0):
        raise TaskError(f"{name} = {value!r}: must be a finite number {rule}")
    return value


def _complete_profile(incomplete: str) -> list[str]:
    """Shell completion for --profile: the shipped profile names (files complete by the shell)."""
    try:
        from ..model.resources import data_dir

        names = sorted(p.stem for p in data_dir("profiles").glob("*.yaml"))
    except Exception:  # completion must never fail loudly
        return []
    return [n for n in names if n.startswith(incomplete)]


def _task_from_options(from_: str, to: str, profile: Optional[str], height: Optional[float], eta: Optional[float]):
    """(profile, task) from the shared move options of compare and plot (one-line errors)."""
    from ..model.errors import TaskError
    from ..model.profile import load_profile
    from ..model.task import Task

    p_from = _parse_point("from", from_)
    p_to = _parse_point("to", to)
    _finite("height", height)
    if eta is not None and not (0 < eta < 1):
        raise TaskError(f"eta = {eta!r}: the lift-off/set-down ratio η must lie strictly between 0 and 1")
    prof = load_profile(profile)
    task = Task(p_from, p_to, height if height is not None else prof.planning.height,
                eta if eta is not None else prof.planning.eta)
    return prof, task


def main() -> None:
    """Console-script entry point."""
    app()
