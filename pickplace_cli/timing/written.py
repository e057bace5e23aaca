"""The time-optimal law as its file is read: a law whose peaks ``check`` would read past a limit from the written samples
is slowed until it reads within every one.

A time-optimal law (:mod:`pickplace_cli.timing.optimal`) runs its torque rate at the limit to the last sample, and its
jerk can change faster than a sample period where the law starts and stops (on the Adept cycle: from −7 300 m/s³ to 0
in the last 0.3 ms). The exact check is right about the motion, but a file at 1 kHz does not resolve that change: the
septic Hermite through its samples, which ``check`` reads it with (:mod:`pickplace_cli.limits.samples`), overshoots it
by up to a few per cent, beyond the reading's stated accuracy, and ``check`` refused files that ``plan`` called ok.

So ``plan --time optimal`` reads its own samples as the file holds them (12 significant digits, as the CSV writes
them) through ``check``'s reconstruction, with the same capacity rule, and holds every peak read, less check's finest
accuracy (``CHECK_RESOLUTION``, 0.1 %), to its limit: ``check`` states at least that accuracy and calls a row exceeded
only when its peak less its accuracy is beyond the limit, so it accepts the file. While a peak reads past, every time
of the law is stretched by ``k`` (the worst read utilisation's cube root first, a torque rate falling as 1/T³ but for
its gravity share; its square root after, as for the drive's tables), up to ``RETIMES`` times, and the exact check
runs again at the new duration. The law's shape is unchanged: only its duration grows (on a controller's cycle: to
whole cycles). A time-optimal law slowed past the uniform law of ``--time fit`` is replaced by that law when it is the
shorter as written (``planner._written_stage``). ``--time fit``, whose uniform law rides a motor limit too, is read
the same way (at 50 Hz ``check`` read the Adept cycle's file 70 % past the torque rate); so are the joint positions
alone when the file has no tool columns (``positions_only``). Every other rule is read the same way when the move has
few samples or the file holds the joint positions alone (:func:`reads_written`): a given duration is then judged
by the reading, not slowed (``stretch``).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Callable

import numpy as np

#: times the law may be slowed before its file counts as not holding (the first step the worst reading's cube root,
#: the others its square root with a margin that doubles each time, from 0.1 %: where the samples fall moves a
#: reading by up to ±2 % at 1 kHz, so a reading need not fall as the law slows; two readings covered most files
#: measured, 100 Hz to 10 kHz)
RETIMES = 10
#: a stretch that passes more than this above the largest one read past a limit is bisected (geometric midpoints,
#: at most ``BISECT`` readings) for a shorter one that passes: where the samples fall moves a reading, so the first
#: steps can overshoot (at 100 Hz the cube root slowed the Adept cycle × 1.48 where × 1.10 passes)
BISECT_TOL = 0.005
BISECT = 4
#: fewest samples ``check`` reads (a quintic spline has 6 coefficients): fewer are not read back
MIN_SAMPLES = 6


def written_values(x: np.ndarray) -> np.ndarray:
    """``x`` as the CSV holds it: every number rounded to 12 significant digits (``%.12g``, read back)."""
    from ..export.fastfloat import _rounded

    x = np.asarray(x, float)
    with np.errstate(all="ignore"):
        r, hard = _rounded(x + 0.0, 0)
    if hard.any():
        r[hard] = [float("%.12g" % v) for v in x[hard]]
    return r


def read_as_written(t: np.ndarray, tool: np.ndarray, q: np.ndarray, profile, not_held: str,
                    positions_only: bool = False, strict: bool = False):
    """The limit report of ``check``'s reading of the samples at ``t`` (N,) s of the tool's x … jz (N, 12) [m, m/s,
    m/s², m/s³] and the joint positions ``q`` (N, n) [rad or m] as this tool's CSV writes them (``profile`` at its
    limit use; ``not_held``: why the Cartesian capacity is not held, "" when it is): the reconstruction from all the
    samples, the one :func:`~pickplace_cli.limits.samples.check_samples` takes (which then also reads every other
    sample for the peaks' accuracy): its rows' peaks as read, their ``ok`` without any accuracy
    (:func:`hold_as_written` allows check's finest, ``CHECK_RESOLUTION``). ``positions_only``: the file holds the
    joint positions alone, which ``check`` reads through the quintic spline of their tool positions. ``strict``: also
    every other sample, as ``check`` reads them for the peaks' stated accuracy (``LimitRow.accuracy``: what
    ``check --strict`` judges a peak's resolution by)."""
    from ..limits.samples import _motion_report, _read_motion, derivative_problems, reading_stride, strided
    from ..robots import build_robot

    data = written_values(np.column_stack([t, tool, q]))
    t, tool, q = data[:, 0] - data[0, 0], data[:, 1:13], data[:, 13:]
    robot = build_robot(profile.robot)
    pos = robot.forward_kinematics(q)
    if positions_only or derivative_problems(t, tool):  # (never for this tool's own columns) positions alone
        tool = None
    if getattr(robot, "rotary", False):
        pos = np.column_stack([pos, robot.tool_angle(q)])
    k = reading_stride(t, pos, tool)
    if k > 1:  # so dense that the 12 digits' rounding would be read as jerk: one sample in k, as check reads it
        keep = strided(len(t), k)
        t, pos, tool = t[keep], pos[keep], None if tool is None else tool[keep]
    report = _read_motion(t, pos, robot, profile, 0.0, "the written samples", None, tool, not_held=not_held)
    if strict:  # the peaks' accuracy, as check_samples states it
        from ..limits.samples import HERMITE_DIVISOR, _half, _with_accuracy

        half = _half(len(t))
        if len(half) >= MIN_SAMPLES:
            share = 1.0 / HERMITE_DIVISOR if tool is not None else 1.0
            other = _motion_report(t[half], pos[half], robot, profile, 0.0, "the written samples", None,
                                   None if tool is None else tool[half], not_held=not_held)[0]
            report = _with_accuracy(report, [(other, share)])
    return report


def _past(read) -> list:
    """[(row, how far past)] of the timed rows whose peak, less ``check``'s finest accuracy (``CHECK_RESOLUTION`` of
    the peak), is beyond the allowed value: the rows ``check`` could call exceeded (how far: that reduced peak over the
    allowed value, > 1); and of a strict reading (rows with an accuracy: :func:`read_as_written`), the rows
    ``check --strict`` calls not resolved (how far: the peak plus its accuracy over the allowed value)."""
    from ..limits.samples import CHECK_RESOLUTION

    out = []
    for r in read.rows:
        if r.kind == "limit" and r.bound == "upper" and not r.not_held and r.allowed > 0:
            u = r.peak * (1.0 - CHECK_RESOLUTION) / r.allowed
            if r.accuracy is not None and not r.resolved:
                u = max(u, (r.peak + r.accuracy) / r.allowed)
            if u > 1.0:
                out.append((r, u))
    return out


@dataclass(frozen=True)
class Written:
    """What reading the written samples did: ``T`` [s] the duration they hold at (the planned one when ``k`` = 1),
    ``k`` the stretch, ``state`` (whatever ``sample`` returned at ``T``), ``read`` the reading's LimitReport there,
    ``note`` what was done ("" when nothing), ``past`` the rows of ``read`` still past their limit (:func:`_past`;
    none when the file holds)."""

    T: float
    k: float
    state: Any
    read: Any
    note: str
    past: tuple = ()
    refused: str = ""  # strict: why check --strict refuses the file whatever its peaks ("" when it does not)


class _Columns:
    """The failing "row" of a strict reading whose tool derivative columns (vx … jz) disagree with the positions by
    more than ``check --strict`` allows (:func:`~pickplace_cli.limits.samples.derivative_problems`): it refuses such
    a file, whatever its peaks."""

    def __init__(self, problems) -> None:
        from ..limits.samples import describe_problems

        self.text = describe_problems(problems)


def _columns_off(out, positions_only: bool) -> list:
    """[(_Columns, how far: the worst misfit over its allowance)] when the written tool columns of ``out`` (t, tool,
    q) disagree with their positions as ``check --strict`` tests them; [] when they agree (or are not written)."""
    from ..limits.samples import AGREE, SCALE_TOL, derivative_problems

    if positions_only:
        return []
    t, tool = out[0], out[1]
    data = written_values(np.column_stack([t, tool]))
    problems = derivative_problems(data[:, 0] - data[0, 0], data[:, 1:13])
    return ([(_Columns(problems), max(m / AGREE[k] if m >= 0 else abs(-m - 1.0) / SCALE_TOL for k, m in problems))]
            if problems else [])


def hold_as_written(T0: float, state: Any, sample: Callable[[float], tuple[Any, tuple]], profile, not_held: str,
                    cycle: float | None = None, rate: float | None = None, positions_only: bool = False,
                    strict: bool = False, stretch: bool = True) -> Written:
    """Stretch the law at duration ``T0`` [s] until ``check`` reads its samples within every limit (module
    docstring). ``state``: what ``sample`` returned at ``T0``; ``sample(T)`` → (state, (t, tool, q)) at duration T
    (the written samples). ``cycle`` [s]: durations in whole cycles. ``rate`` [Hz]: named in the note.
    ``positions_only``: the file holds the joint positions alone (:func:`read_as_written`). ``strict``: until
    ``check --strict`` accepts them too: every peak resolved by the samples (within its limit at its stated
    accuracy, or known to 1 %), and the tool's derivative columns agreeing with its positions (``Written.refused``
    says why not when the slowing gives up). ``stretch`` False: read at ``T0`` only (a duration the user gave), the
    rows read past their limit returned in ``Written.past``."""
    T, k = T0, 1.0
    t, tool, q = state[1]
    if len(t) < MIN_SAMPLES:  # check refuses such a file whatever it holds (a move needs 6 samples)
        return Written(T0, 1.0, state, None, f"written samples: {len(t)}, fewer than the {MIN_SAMPLES} check reads "
                       "a move from: not read back (write at a higher --rate)")
    read = read_as_written(t, tool, q, profile, not_held, positions_only, strict)
    first = None

    def fails(rd, st) -> list:
        return _past(rd) + (_columns_off(st[1], positions_only) if strict else [])

    def at_k(kk: float):
        TT = kk * T0
        if cycle is not None:
            TT = float(np.ceil(TT / cycle - 1e-9) * cycle)
        st = sample(TT)
        return TT / T0, TT, st, read_as_written(*st[1], profile, not_held, positions_only, strict)

    k_lo = 1.0  # the largest stretch read past a limit
    for attempt in range(RETIMES if stretch else 0):
        failing = fails(read, state)
        if not failing or any(r.kind != "limit" for r in read.violations):
            break
        k_lo = k
        worst = max(failing, key=lambda x: x[1])
        if not attempt:
            first = worst
        # a torque rate falls as 1/T³ but for its gravity share (1/T): the cube root first, the square root after,
        # with a growing margin (RETIMES)
        k, T, state, read = at_k(k * max(worst[1], 1.0 + 1e-4) ** (0.5 if attempt else 1.0 / 3.0)
                                 * (1.0 + (1e-3 * 2.0 ** (attempt - 1) if attempt else 1e-4)))
    if first is not None and not fails(read, state) and k / k_lo > 1.0 + BISECT_TOL:
        for _ in range(BISECT):  # the reading need not fall as fast as the cube root says: a shorter stretch
            got = at_k((k_lo * k) ** 0.5)
            if fails(got[3], got[2]) or any(r.kind != "limit" for r in got[3].violations):
                k_lo = got[0]
            else:
                k, T, state, read = got
            if k / k_lo <= 1.0 + BISECT_TOL:
                break
    now = fails(read, state)
    past = tuple(r for r, _ in now if not isinstance(r, _Columns))
    columns = next((r for r, _ in now if isinstance(r, _Columns)), None)
    refused = f"the written tool columns: {columns.text}" if columns is not None else ""
    at = (" (joint positions alone)" if positions_only else "") + (f" at {rate:g} Hz" if rate else "")
    who = "check --strict" if strict else "check"

    def reading(r) -> str:
        if isinstance(r, _Columns):
            return f"the tool columns off their positions ({r.text})"
        pm = f" ± {100 * r.accuracy / r.limit:.2f} %" if strict and r.accuracy is not None else ""
        return f"{r.joint} {r.quantity} at {100 * r.peak / r.limit:.2f} %{pm}"

    top = max((r for r in read.rows if r.kind == "limit" and not r.not_held and r.allowed > 0),
              key=lambda r: r.peak / r.allowed, default=None)
    note = ""
    if first is None and now:  # past as read, and not slowed (the reading also put a position past its range)
        note = (f"written samples{at}: {who}'s reading of them puts {reading(max(now, key=lambda x: x[1])[0])}: the "
                "file is not written as within its limits (write at a higher --rate)")
    elif first is None and strict and top is not None:  # read as check --strict reads it: nothing to slow
        note = f"written samples{at}: check --strict reads every peak resolved and within its limit ({reading(top)})"
    if first is not None:
        row, u = first
        if not now:
            held = f"where {who} reads every limit within it" + (f" ({reading(top)})" if top is not None else "")
        else:
            last = max(now, key=lambda x: x[1])[0]
            held = (f"and {who} still reads {reading(last)}: the file is not written as within its limits (write at "
                    "a higher --rate)")
        note = (f"written samples{at}: {who}'s reading of them put {reading(row)} (the samples are too far apart for "
                f"the law's fastest changes); "
                f"the law is slowed × {k:.5f}, T {T0:.6g} → {T:.6g} s, {held}"
                + ("; the tool columns (the default CSV), a faster --rate, or a drive's table (-f pvt, cam), need "
                   "less" if k > 1.01 and positions_only else
                   "; a faster --rate, or a drive's table (-f pvt, cam), needs less" if k > 1.01 else ""))
    return Written(T, k, state, read, note, past, refused)


#: a move written in fewer samples than this is read back as ``check`` reads it whatever its duration rule: with ~50
#: samples or fewer the reconstruction through them misread a peak of a plan within its limits by more than 1 % (random
#: moves of the shipped profiles, five methods, 60-1 000 Hz, ``bench/bench_written_sparse.py``: the most samples of a
#: misread file was 41)
WRITTEN_FEW = 100


def reads_written(options, samples: int) -> bool:
    """Whether the plan reads its written samples as ``check`` does (``planner._written_stage``; ``options``: its
    PlanOptions): a law at its limits (``fit``, ``optimal``), every rule with ``strict``, and every rule (a given
    duration too, which is then judged,
    not slowed) when the file holds the joint positions alone (their reconstruction misreads a peak by up to a few
    per cent at 1 kHz) or fewer than ``WRITTEN_FEW`` samples; never a drive's table (``read_written`` "")."""
    if not options.read_written:
        return False
    if options.time in ("optimal", "fit") or (options.strict and options.time in ("limits", "auto")):
        return True
    return options.read_written == "positions" or samples < WRITTEN_FEW


def as_read(report, past: tuple):
    """``report`` with each row of ``past`` (the written samples' reading, rows still past their limit as ``check``
    reads them) in place of its own: the reading's peak, time and accuracy, exceeded when that peak less ``check``'s
    finest accuracy is beyond the allowed value (the Cartesian capacity's rows too, added after the written stage)."""
    from dataclasses import replace

    from ..limits.report import LimitRow
    from ..limits.samples import CHECK_RESOLUTION

    read = {(r.joint, r.quantity): r for r in past}
    return replace(report, rows=tuple(
        LimitRow(r.joint, r.quantity, r.unit, read[k].peak, r.limit, read[k].peak / r.limit, read[k].t_peak,
                 read[k].peak * (1.0 - CHECK_RESOLUTION) <= r.allowed, r.kind, r.bound, r.target,
                 read[k].accuracy, r.not_held)
        if (k := (r.joint, r.quantity)) in read else r for r in report.rows))
