"""`pickplace line LINE.yaml`: a line of robots on one belt — who takes which part, picks/min, misses, motors over
the real sequence; sweeps over belt speed × robot count × strategy × seed."""

from __future__ import annotations

import contextlib
import os
import sys
from typing import Optional

import typer

from ..model.text import quoted
from .app import Panel, _handle_errors, _usage, app, note_exit


@app.command("line")
@_handle_errors
def line_cmd(
    line_file: str = typer.Argument(..., metavar="LINE.yaml", help="The line file: belt, robots, parts, strategy (YAML)."),
    detections: Optional[str] = typer.Option(
        None, "--detections", "-d", metavar="FILE|-",
        help="Detections CSV (t[s], along[m], across[m], optional angle[rad], id; type on a line with part types) "
             "instead of the file's parts; '-' = standard input, each detection answered as it is read.", rich_help_panel=Panel.MOVE),
    belt_speed: Optional[float] = typer.Option(None, "--belt-speed", help="Belt speed in m/s instead of the file's.", rich_help_panel=Panel.BELT),
    robots: Optional[int] = typer.Option(None, "--robots", help="Use only the first N robots of the file.", rich_help_panel=Panel.MOVE),
    strategy: Optional[str] = typer.Option(
        None, "--strategy", help="Strategy instead of the file's: upstream_first, quota, bands or skip (its defaults "
                                 "unless the file's is of that kind).", rich_help_panel=Panel.METHOD),
    seed: Optional[int] = typer.Option(None, "--seed", help="Seed of the file's part generator.", rich_help_panel=Panel.MOVE),
    output: str = typer.Option(
        "-", "--output", "-o",
        help="Per-part results: CSV (units in the header), or JSON lines with --json; '-' = stdout, row by row as the "
             "parts are answered. A file is written atomically at the end. In a sweep: the sweep's CSV.", rich_help_panel=Panel.OUTPUT),
    as_json: bool = typer.Option(False, "--json", help="Per-part results as JSON lines (robot, meeting, plan, or why "
                                                       "missed), then one line with the run's summary.", rich_help_panel=Panel.OUTPUT),
    robots_csv: Optional[str] = typer.Option(None, "--robots-csv", metavar="FILE",
                                             help="Per-robot results CSV (picks/min, utilisation, idle, RMS, peak use).", rich_help_panel=Panel.OUTPUT),
    summary_file: Optional[str] = typer.Option(None, "--summary", metavar="FILE",
                                               help="The run's summary (line and robots) as JSON.", rich_help_panel=Panel.OUTPUT),
    plot: Optional[str] = typer.Option(
        None, "--plot", metavar="FILE.png|svg",
        help="Figure: the parts along the belt against time and the robots' legs (a sweep: miss rate against belt "
             "speed). Needs pickplace-cli[plot].", rich_help_panel=Panel.STUDY),
    mcap: Optional[str] = typer.Option(None, "--mcap", metavar="FILE.mcap",
                                       help="Every robot's joint trajectory over the run (ROS 2 MCAP, topics "
                                            "/ROBOT/joint_states, /ROBOT/motor_states, /ROBOT/tool_pose).", rich_help_panel=Panel.OUTPUT),
    rate: Optional[float] = typer.Option(None, "--rate", help="Sample rate of --mcap in Hz. [default: the first robot's "
                                                              "profile]", rich_help_panel=Panel.OUTPUT),
    max_miss_rate: Optional[float] = typer.Option(
        None, "--max-miss-rate", help="Exit 4 when the share of missed parts exceeds this (0 … 1).", rich_help_panel=Panel.LIMITS),
    until: Optional[float] = typer.Option(
        None, "--until", metavar="PRECISION", rich_help_panel=Panel.BATCH,
        help="Run the file's generator until the miss rate's 95 % interval (batch means) is at most ± PRECISION wide "
             "(a share, e.g. 0.01 for ± 1 percentage point; 0.001 … 0.5) and 20 parts were missed, or until "
             "--until-max seconds of parts."),
    until_max: float = typer.Option(
        3600.0, "--until-max", metavar="SECONDS", rich_help_panel=Panel.BATCH,
        help="With --until: the longest feed in s of simulated time (1 … 1e5 s; at most 100,000 parts)."),
    quiet: bool = typer.Option(False, "--quiet", "-q", help="No table or progress bar on stderr.", rich_help_panel=Panel.OUTPUT),
    speeds: Optional[str] = typer.Option(
        None, "--speeds", help="Sweep: belt speeds in m/s, a list 0.2,0.5 or a range START:STOP:STEP.", rich_help_panel=Panel.STUDY),
    robot_counts: Optional[str] = typer.Option(None, "--robot-counts", help="Sweep: robot counts, e.g. 3,4 (the first "
                                                                            "N robots of the file).", rich_help_panel=Panel.STUDY),
    strategies: Optional[str] = typer.Option(None, "--strategies", help="Sweep: strategies, e.g. upstream_first,quota "
                                                                        "or all.", rich_help_panel=Panel.STUDY),
    seeds: Optional[str] = typer.Option(None, "--seeds", help="Sweep: generator seeds, e.g. 1,2,3 or 1:10.", rich_help_panel=Panel.STUDY),
    workers: int = typer.Option(0, "--workers", "-j", help="Sweep: local worker processes (0 = all cores; 1 = in this "
                                                          "process).", rich_help_panel=Panel.BATCH),
    scheduler: Optional[str] = typer.Option(None, "--scheduler", metavar="tcp://HOST:PORT",
                                            help="Sweep: run the cases on this Dask scheduler (pickplace-cli[dask]).", rich_help_panel=Panel.BATCH),
    resume: bool = typer.Option(False, "--resume", help="Sweep: continue from OUTPUT.partial.jsonl (needs -o FILE).", rich_help_panel=Panel.BATCH),
) -> None:
    """Run a line of robots along one belt: each part is offered to the robots in the strategy's order and taken
    by the first that can meet it in its window (a real plan: rendezvous, tracking, place, every limit checked);
    a part no robot can take is missed, with the reason. Prints a table per robot (picks/min, utilisation, idle,
    peak motor limit use, RMS torque over the run) on stderr. Exit codes: 0 ok (missed parts are results); 1 invalid
    input (line file, profile, a refused detection row: the other rows are still answered); 2 usage; 3 a motor's
    RMS torque over the run exceeds its rated torque; 4 a window, home or place point outside the workspace, a belt
    no robot can ever keep up with, or --max-miss-rate exceeded.
    """
    from ..line.spec import MAX_SEED
    from ..model.errors import TaskError

    sweep = any(x is not None for x in (speeds, robot_counts, strategies, seeds))
    if seed is not None and not 0 <= seed <= MAX_SEED:
        raise TaskError(f"seed = {quoted(str(seed))}: a seed is a whole number from 0 to 2^64 − 1")
    if max_miss_rate is not None and not (0.0 <= max_miss_rate <= 1.0):
        raise TaskError(f"max-miss-rate = {max_miss_rate!r}: must be a share between 0 and 1")
    if rate is not None and not (rate > 0 and rate <= 1e5):
        raise TaskError(f"rate = {rate!r}: must be a sample rate in Hz, > 0 and at most 1e5")
    if until is not None and not (1e-3 <= until <= 0.5):
        raise TaskError(f"until = {until!r}: the half-width of the miss rate's interval is a share from 0.001 to 0.5 "
                        "(0.01 = ± 1 percentage point)")
    if not (1.0 <= until_max <= 1e5):
        raise TaskError(f"until-max = {until_max!r} s: the longest run is from 1 to 1e5 s of simulated time")
    if strategy is not None and (strategy.strip() == "all" or "," in strategy):
        _usage(f"--strategy {strategy}: one strategy ({', '.join(_strategies())}); several are compared in a sweep "
               "with --strategies")
    if strategy is not None and strategy.strip() not in _strategies():
        raise TaskError(f"strategy = {strategy!r}: choose from {', '.join(_strategies())}")
    if until is not None and (sweep or detections is not None):
        _usage("--until runs the line file's generator longer; it is for a single run without --detections")
    if sweep:
        for name, given in (("--detections -", detections == "-"), ("--mcap", mcap), ("--robots-csv", robots_csv),
                            ("--summary", summary_file), ("--json", as_json)):
            if given:
                _usage(f"{name} is for a single run; a sweep writes its table (-o) and --plot")
        _sweep(line_file, detections, belt_speed, robots, strategy, seed, speeds, robot_counts, strategies, seeds,
               output, plot, workers, scheduler, resume, quiet)
        return
    if resume or scheduler or workers:
        _usage("--resume, --scheduler and --workers are for a sweep (--speeds, --robot-counts, --strategies, --seeds)")
    _single(line_file, detections, belt_speed, robots, strategy, seed, output, as_json, robots_csv, summary_file, plot,
            mcap, rate, max_miss_rate, quiet, (until, until_max))


# ------------------------------------------------------------------------------------------------ a single run


def _prepare(line_file, belt_speed, robots, strategy, seed):
    """(line, profiles) with the command line's overrides applied and checked."""
    from ..line.spec import MAX_BELT_SPEED, MIN_BELT_SPEED, check_rules, load_line
    from ..line.sweep import Case, case_line
    from ..model.errors import TaskError

    line = load_line(line_file)
    if robots is not None and not (1 <= robots <= len(line.robots)):
        raise TaskError(f"robots = {robots}: the line file has {len(line.robots)} robots; give 1 … {len(line.robots)}")
    if belt_speed is not None and not (MIN_BELT_SPEED <= belt_speed <= MAX_BELT_SPEED):
        raise TaskError(f"belt-speed = {belt_speed!r}: must be at least {MIN_BELT_SPEED:g} and at most "
                        f"{MAX_BELT_SPEED:g} m/s")
    kind = _strategy_names(strategy)[0] if strategy is not None else line.strategy.kind
    case = Case(float(belt_speed if belt_speed is not None else line.belt.speed),
                int(robots if robots is not None else len(line.robots)), kind, seed)
    line = case_line(line, case)
    check_rules(line, line_file)
    return line, _profiles(line, line_file)


def _profiles(line, line_file) -> dict:
    from ..line.spec import resolve_relative
    from ..model.profile import load_profile

    cache: dict = {}
    out = {}
    for r in line.robots:
        ref = resolve_relative(r.profile, line_file)
        if ref not in cache:
            cache[ref] = load_profile(ref)
        out[r.name] = cache[ref]
    return out


def _strategies() -> tuple:
    from ..line.spec import STRATEGIES

    return tuple(STRATEGIES)


def _strategy_names(text: str) -> list[str]:
    from ..line.spec import STRATEGIES
    from ..model.errors import TaskError

    names = list(STRATEGIES) if text.strip() == "all" else [s.strip() for s in text.split(",")]
    for n in names:
        if n not in STRATEGIES:
            raise TaskError(f"strategy = {n!r}: choose from {', '.join(STRATEGIES)} (or all)")
    return names


def _inputs_of(line, line_file, detections) -> list[str]:
    from ..line.spec import resolve_relative

    files = [line_file]
    if detections and detections != "-":
        files.append(detections)
    elif line.parts.detections:
        files.append(resolve_relative(line.parts.detections, line_file))
    return files


def _check_outputs(outputs: dict, inputs: list[str]) -> None:
    """Every output writable, none an input of the run, no two the same file."""
    import os

    from ..export import check_writable, promise
    from ..model.errors import ExportError

    seen = {}
    real_inputs = {os.path.realpath(p): p for p in inputs}
    for option, path in outputs.items():
        if path is None or path == "-":
            continue
        check_writable(path)
        real = os.path.realpath(path)
        if real in real_inputs and not path.startswith("/dev/"):
            raise ExportError(f"{option} {path}: is an input of this run ({real_inputs[real]}); give another file name")
        if real in seen and not path.startswith("/dev/"):
            raise ExportError(f"{option} {path}: also given to {seen[real]}; give each output its own file")
        seen[real] = option
        promise(path)


@contextlib.contextmanager
def _detection_lines(source: str):
    """The lines of a detection file, a named pipe or standard input (read as they arrive), each bounded
    (:func:`~pickplace_cli.line.parts.bounded_lines`: an over-long line is one row). A named pipe's writer is
    awaited for a bounded time, saying so on stderr, as ``check`` does."""
    from ..line.parts import bounded_lines
    from ..model.errors import TaskError

    name = "stdin" if source == "-" else source
    if source == "-":
        if sys.stdin is None:
            raise TaskError("detections = -: standard input is closed; give the detections on stdin or a file")
        try:
            fd = sys.stdin.fileno()
        except (AttributeError, ValueError, OSError):  # a test runner's stand-in
            fd = None
        if fd is None:
            yield bounded_lines(sys.stdin.readline, source=name)
            return
        from ..pipelines.warm import WarmLines

        reader = WarmLines(fd, None, None, sys.stdin.encoding or "utf-8")
        yield bounded_lines(reader.readline, source=name)
        return
    from ..model.files import open_for_reading

    fd = open_for_reading(source, "detections", TaskError,
                          notify=lambda text: sys.stderr.write(f"pickplace: {text}\n"))
    try:
        fh = open(fd, encoding="utf-8-sig", newline="", errors="surrogateescape")
    except OSError as exc:  # pragma: no cover - an open descriptor
        os.close(fd)
        raise TaskError(f"detections = {source}: cannot read it: {exc.strerror}") from None
    with fh:
        yield bounded_lines(fh.readline, source=name)


def _single(line_file, detections, belt_speed, robots, strategy, seed, output, as_json, robots_csv, summary_file,
            plot, mcap, rate, max_miss_rate, quiet, until=(None, 3600.0)) -> None:
    from ..export import atomic_output
    from ..line.engine import LineEngine
    from ..line.parts import generate, in_time_order, read_detections
    from ..line.report import PartsCsv, part_json, summary_json
    from ..line.spec import resolve_relative
    from ..model.errors import TaskError

    line, profiles = _prepare(line_file, belt_speed, robots, strategy, seed)
    if plot is not None:
        from ..export.plot import plot_format, require_matplotlib

        require_matplotlib()
        plot_kind = plot_format(plot, None)
    _check_outputs({"--output": output, "--robots-csv": robots_csv, "--summary": summary_file, "--plot": plot,
                    "--mcap": mcap}, _inputs_of(line, line_file, detections))
    engine = LineEngine(line, profiles)
    engine.check_speed()
    for w in engine.warnings:
        sys.stderr.write(f"pickplace: warning: {w}\n")
    source = detections if detections is not None else (
        resolve_relative(line.parts.detections, line_file) if line.parts.detections else None)
    if source is None and line.parts.generate is None:
        raise TaskError(f"{line_file}: parts: give a detection file (parts.detections, or --detections FILE|-) or a "
                        "generator (parts.generate)")
    if until[0] is not None and source is not None:
        _usage(f"--until runs the line file's generator longer; {line_file}'s parts come from a detection file "
               "(parts.detections): give parts.generate")
    streaming = output == "-"
    with contextlib.ExitStack() as stack:
        types = line.parts.types
        if source is not None:
            lines = stack.enter_context(_detection_lines(source))
            items = read_detections(lines, "stdin" if source == "-" else source, None if types is None else list(types),
                                    line.belt.width)
        elif until[0] is not None:
            items = _until_items(line, line_file, engine, *until)
        else:
            items = iter(generate(line.parts.generate, line.belt.width, types))
        out = stack.enter_context(atomic_output(output))
        writer = PartsCsv(out, typed=types is not None)
        if not as_json:
            writer.header()
        for res in engine.run(in_time_order(items, line.parts.reorder)):
            if res.code == 1:
                sys.stderr.write(f"pickplace: {res.reason}\n")
                note_exit(1)
            out.write(part_json(res) + "\n") if as_json else writer.row(res)
            if streaming and source == "-":
                out.flush()
        summary = engine.finish()
        if as_json:
            out.write(summary_json(summary, line.name, compact=True))
    if until[0] is not None:
        iv = summary.intervals.miss if summary.intervals is not None else None
        reached = iv is not None and iv.half <= until[0]
        summary.until = {"precision": until[0], "reached": reached, "max_s": until[1]}
        if not reached:
            sys.stderr.write(f"pickplace: warning: --until {until[0]:g}: the miss rate's interval is "
                             f"± {100 * iv.half if iv else 100:.2f} % after {summary.feed:.4g} s of parts (--until-max "
                             f"{until[1]:g} s): not as narrow as asked\n")
    _after(engine, summary, line, robots_csv, summary_file, plot, plot_kind if plot else None, mcap, rate, quiet)
    code = summary.exit_code()
    for v in summary.violations():
        sys.stderr.write(f"pickplace: {v}\n")
    if max_miss_rate is not None and summary.miss_rate > max_miss_rate:
        sys.stderr.write(f"pickplace: miss rate {100 * summary.miss_rate:.2f} % ({summary.missed} of {summary.parts} "
                         f"parts) exceeds --max-miss-rate {100 * max_miss_rate:g} %\n")
        code = max(code, 4)
    if code:
        raise typer.Exit(code)


#: with --until, the interval is first looked at after this many parts, then every ``UNTIL_STEP`` parts
UNTIL_FIRST, UNTIL_STEP = 400, 50
#: ... and it stops only once this many parts were missed (or Wilson's upper end is below the precision)
UNTIL_MISSES = 20


def _until_items(line, line_file, engine, precision: float, most: float):
    """The file's generator run for up to ``most`` s (at most MAX_PARTS parts), stopped as soon as the miss rate's
    batch-means interval is at most ± ``precision`` and ``UNTIL_MISSES`` parts were missed (or Wilson's interval
    lies below ``precision``), looked at every ``UNTIL_STEP`` parts from ``UNTIL_FIRST`` on."""
    from ..line.confidence import result_arrays, run_intervals
    from ..line.parts import MAX_PARTS, generate

    gen = line.parts.generate
    most = min(float(most), 0.999 * MAX_PARTS / float(gen.rate))
    gen = gen.model_copy(update={"count": None, "duration": most})
    for k, d in enumerate(generate(gen, line.belt.width, line.parts.types)):
        if k >= UNTIL_FIRST and k % UNTIL_STEP == 0:
            t, missed = result_arrays(engine.results)
            ivs = run_intervals(t, missed, 0.0)
            # a handful of misses makes an unreliable interval: also UNTIL_MISSES misses, or a rate known to be
            # below PRECISION outright (Wilson's upper end: a line that hardly misses)
            if ivs.miss is not None and ivs.miss.half <= precision and (
                    int(missed.sum()) >= UNTIL_MISSES or ivs.miss_wilson.high <= precision):
                return
        yield d


def _after(engine, summary, line, robots_csv, summary_file, plot, plot_kind, mcap, rate, quiet) -> None:
    """The table, and the files written after the run: robots CSV, summary JSON, figure, MCAP."""
    from ..export import atomic_output
    from ..line.report import print_table, summary_json, write_robots_csv

    if not quiet:
        from .render import console

        print_table(summary, console(stderr=True, highlight=False))  # no styling under NO_COLOR or TERM=dumb
    if robots_csv is not None:
        with atomic_output(robots_csv) as fh:
            write_robots_csv(summary, fh)
    if summary_file is not None:
        with atomic_output(summary_file) as fh:
            fh.write(summary_json(summary, line.name))
    if plot is not None:
        from ..line.figures import write_timeline

        with atomic_output(plot, binary=True) as fh:
            write_timeline(engine, summary, fh, plot_kind)
    if mcap is not None:
        from ..line.trajectories import robot_samples, sample_times, write_line_mcap

        hz = rate if rate is not None else float(engine.robots[0].profile.planning.rate)
        t = sample_times(summary.t_begin, summary.t_end, hz)
        samples = [robot_samples(run, t) for run in engine.runs]
        with atomic_output(mcap, binary=True) as fh:
            write_line_mcap(samples, summary.t_begin, fh)


# ------------------------------------------------------------------------------------------------------ sweeps


def _numbers(name: str, text: str, integer: bool = False) -> list:
    """A list ``a,b,c`` or a range ``start:stop:step`` (stop included when on the grid); whole numbers exactly when
    ``integer``."""
    import math

    from ..model.errors import TaskError
    from ..model.text import plain_float

    def number(x: str):
        x = x.strip()
        if integer and x.lstrip("+-").isdigit() and x.isascii():
            if len(x) > 40:
                raise ValueError(x)
            return int(x)
        return plain_float(x)

    try:
        if ":" in text:
            parts = [number(x) for x in text.split(":")]
            if len(parts) != 3 or parts[2] <= 0 or parts[1] < parts[0]:
                raise ValueError
            n = int(math.floor((parts[1] - parts[0]) / parts[2] + 1e-9)) + 1
            if n > 10000:
                raise TaskError(f"{name} = {quoted(text)}: {n} values; at most 10000")
            values = [parts[0] + k * parts[2] if integer and all(isinstance(p, int) for p in parts)
                      else round(parts[0] + k * parts[2], 12) for k in range(n)]
        else:
            values = [number(x) for x in text.split(",") if x.strip()]
        if not values or not all(math.isfinite(v) for v in values):
            raise ValueError
    except (ValueError, OverflowError):
        raise TaskError(f"{name} = {quoted(text)}: give numbers separated by commas, or START:STOP:STEP") from None
    if integer:
        if not all(v == int(v) for v in values):
            raise TaskError(f"{name} = {quoted(text)}: give whole numbers")
        values = [int(v) for v in values]
    return list(dict.fromkeys(values))


def _sweep(line_file, detections, belt_speed, robots, strategy, seed, speeds, robot_counts, strategies, seeds, output,
           plot, workers, scheduler, resume, quiet) -> None:
    import os

    from ..export import atomic_output
    from ..line.parts import BadRow, read_detections
    from ..line.spec import MAX_BELT_SPEED, MAX_SEED, MIN_BELT_SPEED, load_line, resolve_relative
    from ..line.sweep import cases, checkpoint_path, digest, run_sweep, write_sweep_csv
    from ..model.errors import TaskError

    base = load_line(line_file)
    v = _numbers("speeds", speeds) if speeds else [belt_speed if belt_speed is not None else base.belt.speed]
    if not all(MIN_BELT_SPEED <= x <= MAX_BELT_SPEED for x in v):
        raise TaskError(f"speeds = {quoted(speeds or '')}: every belt speed must be at least {MIN_BELT_SPEED:g} and at "
                        f"most {MAX_BELT_SPEED:g} m/s")
    n = _numbers("robot-counts", robot_counts, True) if robot_counts else [robots or len(base.robots)]
    if not all(1 <= x <= len(base.robots) for x in n):
        raise TaskError(f"robot-counts = {robot_counts!r}: the line file has {len(base.robots)} robots; give 1 … "
                        f"{len(base.robots)}")
    k = _strategy_names(strategies) if strategies else [strategy or base.strategy.kind]
    s = _numbers("seeds", seeds, True) if seeds else [seed]
    if seeds and any(not 0 <= x <= MAX_SEED for x in s):
        raise TaskError(f"seeds = {quoted(seeds)}: seeds are whole numbers from 0 to 2^64 − 1")
    if workers < 0:
        raise TaskError(f"workers = {workers}: must be 0 (all cores) or a positive number")
    if resume and output == "-":
        raise TaskError("--resume: needs -o FILE (the finished cases live in FILE.partial.jsonl)")
    plot_kind = None
    if plot is not None:
        from ..export.plot import plot_format, require_matplotlib

        require_matplotlib()
        plot_kind = plot_format(plot, None)
    _check_outputs({"--output": output, "--plot": plot}, _inputs_of(base, line_file, detections))
    profiles = _profiles(base, line_file)
    dets = None
    src = detections if detections is not None else (
        resolve_relative(base.parts.detections, line_file) if base.parts.detections else None)
    if src is not None:
        with _detection_lines(src) as lines:
            dets = list(read_detections(lines, src, None if base.parts.types is None else list(base.parts.types),
                                        base.belt.width))
        bad = next((d for d in dets if isinstance(d, BadRow)), None)
        if bad is not None:
            raise TaskError(bad.error)
    elif base.parts.generate is None:
        raise TaskError(f"{line_file}: parts: a sweep needs a detection file or a generator")
    all_cases = cases(v, n, k, s)
    axes = {"speeds": v, "robots": n, "strategies": k, "seeds": s, "detections": src}
    ckpt = checkpoint_path(output) if output != "-" else None
    tag = digest(base, axes)
    if not scheduler:
        from .guards import cap_workers

        workers = cap_workers(workers)
    from ..lookup.checkpoint import checkpoint_lock

    with checkpoint_lock(ckpt, "line sweep"), contextlib.ExitStack() as stack:  # one sweep owns the checkpoint
        from .build_table import _engine

        if ckpt is not None:
            from .app import _TERM_NOTES

            _TERM_NOTES.append(f"pickplace: finished cases are saved in {ckpt}; run the same command with --resume\n")
        executor, n_workers, tick = _engine(stack, scheduler, workers, quiet, len(all_cases), "runs", eta=False,
                                            label="line sweep")
        try:
            rows = run_sweep(base, profiles, all_cases, dets, n_workers, executor, tick, ckpt, resume, tag)
        except KeyboardInterrupt:
            if ckpt is not None and ckpt.exists():
                sys.stderr.write(f"pickplace: finished cases are saved in {ckpt}; run the same command with --resume\n")
            raise
        stack.close()  # the progress bar and the cluster's client end before the table is written
        with atomic_output(output) as fh:
            write_sweep_csv(rows, fh)
        if plot is not None:
            from ..line.figures import write_sweep_plot

            with atomic_output(plot, binary=True) as fh:
                write_sweep_plot(rows, fh, plot_kind, title=f"{base.name}: miss rate against belt speed")
        if ckpt is not None and ckpt.exists():
            os.unlink(ckpt)
    if not quiet:
        from ..line.sweep import seed_intervals

        for kind, n, speed, miss, picks in seed_intervals(rows):
            sys.stderr.write(f"{kind}, {n} robots, {speed:g} m/s: miss rate {100 * miss.estimate:.1f} ± "
                             f"{100 * miss.half:.1f} %, picks/min {picks.estimate:.1f} ± {picks.half:.1f} (95 %, "
                             f"{miss.method})\n")
    failed = [r for r in rows if r.get("error") and r.get("exit_code") != 4]
    for r in failed[:5]:
        sys.stderr.write(f"pickplace: case {r['strategy']}, {r['robots']} robots, {r['belt_speed']:g} m/s, seed "
                         f"{r['seed']}: {r['error']}\n")
    if failed:
        raise typer.Exit(max(r.get("exit_code", 1) for r in failed))
