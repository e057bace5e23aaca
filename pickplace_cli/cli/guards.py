"""Checks every command makes on its files before any work: no output is a file the command reads."""

from __future__ import annotations

from typing import Iterable, Optional


def refuse_overwriting_inputs(outputs: Iterable[tuple[str, Optional[str]]],
                              inputs: Iterable[tuple[str, Optional[str]]], profile: Optional[str] = "") -> None:
    """ExportError (exit 1, one line) when an output (option, path) is a file the command reads: an input (option,
    path) or the profile ``profile`` resolves to (a file, or a shipped name; "" when the command reads none). A
    profile that cannot be resolved is left to the profile's own error."""
    from ..model.errors import PickplaceError
    from ..model.files import refuse_inputs_as_outputs

    inputs = list(inputs)
    if profile != "":
        from ..model.profile import resolve_profile_path

        try:
            inputs.append(("-p", str(resolve_profile_path(profile))))
        except PickplaceError:
            pass
    refuse_inputs_as_outputs(outputs, inputs)


#: an output file's suffix → the trajectory format it names
SUFFIX_FORMATS = {".csv": "csv", ".tsv": "csv", ".txt": "csv", ".json": "json", ".mcap": "mcap", ".st": "pvt-st"}
#: the formats a suffix agrees with when -f names one (a table a motion kernel runs is a CSV or an ST file)
SUFFIX_AGREES = {"csv": ("csv", "pvt", "cam", "cam-table"), "json": ("json",), "mcap": ("mcap",),
                 "pvt-st": ("pvt-st", "cam-st", "cam-table-st")}


def output_format(ctx, fmt, output: Optional[str], option: str = "fmt"):
    """The trajectory format: ``-f`` when given, else the one ``-o FILE``'s suffix names (``traj.mcap`` → mcap,
    ``.json`` → json, ``.csv``/``.tsv``/``.txt`` → csv; another suffix or none: csv). Usage errors (exit 2): a ``-f``
    that contradicts the suffix (``-f mcap -o traj.csv``), and binary MCAP to standard output that is a terminal."""
    import os
    import sys

    from .app import OutputFormat, _usage

    source = ctx.get_parameter_source(option)
    given = source is not None and source.name != "DEFAULT"
    named = None
    if output not in (None, "-") and not str(output).startswith("/dev/"):
        named = SUFFIX_FORMATS.get(os.path.splitext(str(output))[1].lower())
    if named is not None and given and fmt.value not in SUFFIX_AGREES[named]:
        want = {"pvt-st": "st", "cam-st": "st", "cam-table-st": "st", "pvt": "csv", "cam": "csv",
                "cam-table": "csv"}.get(fmt.value, fmt.value)
        said = "Structured Text" if named == "pvt-st" else named
        _usage(f"-f {fmt.value} -o {output}: the file's suffix says {said}; give -o with a .{want} suffix "
               f"or a -f that writes {said}")
    if named == "pvt-st" and not given:  # which table the drive runs is the user's to say, not a CSV under .st
        _usage(f"-o {output}: the file's suffix says Structured Text; give the table it holds with -f pvt-st, cam-st "
               "or cam-table-st, or -o with a .csv suffix for the trajectory")
    if named is not None and not given:
        fmt = OutputFormat(named)
    if fmt == OutputFormat.mcap and output in (None, "-") and sys.stdout is not None and sys.stdout.isatty():
        _usage("-f mcap: MCAP is binary; not written to a terminal: give -o FILE.mcap or redirect standard output")
    return fmt


def suffix_format(ctx, fmt, output: Optional[str], suffixes: dict[str, str], option: str):
    """The format of a command with its own ``-f`` choices (``build-table``, ``compare``): ``-f`` when given, else the
    one ``-o FILE``'s suffix names in ``suffixes`` (``.json`` → json); a ``-f`` that contradicts a suffix of
    ``suffixes`` is a usage error (exit 2). Another suffix, or none, keeps ``-f``'s default."""
    import os

    from .app import _usage

    source = ctx.get_parameter_source(option)
    given = source is not None and source.name != "DEFAULT"
    named = None
    if output not in (None, "-") and not str(output).startswith("/dev/"):
        named = suffixes.get(os.path.splitext(str(output))[1].lower())
    if named is None:
        return fmt
    if given and fmt.value != named:
        _usage(f"-f {fmt.value} -o {output}: the file's suffix says {named}; give -o with a suffix of "
               f"{fmt.value} or -f {named}")
    return type(fmt)(named)


def available_cores() -> int:
    """The cores this process may run on (its CPU affinity, which a container or ``taskset`` narrows), at least 1."""
    import os

    try:
        return max(len(os.sched_getaffinity(0)), 1)
    except (AttributeError, OSError):  # pragma: no cover - a platform without affinity
        return os.cpu_count() or 1


def cap_workers(workers: int, refuse_negative: str = "") -> int:
    """``-j N`` capped at the cores this process may use (more processes only share them), with a one-line note on
    stderr; 0 (automatic) is returned as it is, a negative value too or, given ``refuse_negative`` (the rule), a
    TaskError (exit 1)."""
    import sys

    if workers < 0 and refuse_negative:
        from ..model.errors import TaskError

        raise TaskError(f"workers = {workers}: {refuse_negative}")

    cores = available_cores()
    if workers > cores:
        sys.stderr.write(f"pickplace: note: -j {workers}: {cores} core{'s' if cores > 1 else ''} available; running "
                         f"{cores} worker process{'es' if cores > 1 else ''}\n")
        return cores
    return workers
