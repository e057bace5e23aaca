"""``--keep-warm``'s line reader and warmer (pickplace_cli/pipelines/warm.py) on real pipes."""

from __future__ import annotations

import os
import threading
import time

import numpy as np
import pytest

from pickplace_cli.model.profile import load_profile
from pickplace_cli.model.task import Task
from pickplace_cli.pipelines.batch import BATCH_MAX_LINE, iter_batch
from pickplace_cli.pipelines.warm import WarmLines, Warmer
from pickplace_cli.planner import PlanOptions, plan


def _pipe_with(data: bytes) -> tuple[int, threading.Thread]:
    """A pipe's read end, ``data`` written (by a thread: more than the pipe's buffer) and the write end closed."""
    r, w = os.pipe()

    def write():
        os.write(w, data)
        os.close(w)

    t = threading.Thread(target=write, daemon=True)
    t.start()
    return r, t


def _lines(data: bytes, limit: int = -1) -> list[str]:
    r, _ = _pipe_with(data)
    try:
        reader = WarmLines(r, 0.01, lambda ready: None)
        out = []
        while (line := reader.readline(limit)) != "":
            out.append(line)
        return out
    finally:
        os.close(r)


def test_line_ends_as_a_text_file_reads_them():
    """\\n, \\r\\n and a lone \\r end a line (universal newlines, kept as read); the last line may have none."""
    assert _lines(b"a,b\nc\r\nd\re") == ["a,b\n", "c\r\n", "d\r", "e"]
    assert _lines(b"") == []
    assert _lines(b"\n\n") == ["\n", "\n"]


def test_undecodable_bytes_are_kept_as_surrogates_and_text_is_utf8():
    """As the CLI's stdin (errors=surrogateescape): iter_batch names the line that is not UTF-8."""
    assert _lines("é,ü\n".encode()) == ["é,ü\n"]
    assert _lines(b"\xff\xfe\n") == ["\udcff\udcfe\n"]


def test_limit_cuts_a_long_line_by_characters():
    assert _lines(b"abcdefgh", limit=3) == ["abc", "def", "gh"]
    assert _lines("ééééé\n".encode(), limit=2) == ["éé", "éé", "é\n"]


def test_a_line_longer_than_the_batch_limit_is_refused_as_from_stdin():
    from pickplace_cli.model.errors import TaskError

    r, _ = _pipe_with(b"from_x,from_y,from_z,to_x,to_y,to_z\n" + b"1" * (BATCH_MAX_LINE + 10) + b"\n")
    try:
        with pytest.raises(TaskError, match="a line of more than"):
            list(iter_batch(WarmLines(r, 0.01, lambda ready: None), "stdin"))
    finally:
        os.close(r)


def test_idle_is_called_while_waiting_and_ready_says_when_a_line_came():
    """No line for a while: idle(ready) every interval, ready() False; then a line: it is read at once."""
    r, w = os.pipe()
    calls: list[bool] = []
    reader = WarmLines(r, 0.005, lambda ready: calls.append(ready()))

    def later():
        time.sleep(0.1)
        os.write(w, b"x,y\n")

    t = threading.Thread(target=later)
    try:
        t.start()
        t0 = time.perf_counter()
        assert reader.readline() == "x,y\n"
        assert time.perf_counter() - t0 >= 0.09
        assert len(calls) >= 3 and not any(calls)  # ~20 intervals of 5 ms: at least a few, even on a slow machine
        os.write(w, b"a\nb\n")
        time.sleep(0.02)
        assert reader.readline() == "a\n"
        assert reader.ready()  # "b" is buffered: no wait, no idle call
        n = len(calls)
        assert reader.readline() == "b\n" and len(calls) == n
    finally:
        t.join()
        os.close(w)
        os.close(r)


def test_warmer_plans_the_last_move_and_changes_nothing():
    """The warm-up plans the remembered move (and formats its CSV), skips when a line is ready, and leaves no
    trace: the next plan of that move is identical."""
    prof = load_profile(None)
    opts = PlanOptions(rate=1000.0)
    task = Task([-0.1525, 0, -0.8], [0.1525, 0, -0.8], 0.025, 0.5)
    warmer = Warmer(prof, opts, "default", 0.005)
    warmer(lambda: False)
    assert warmer.warm_ups == 0  # nothing planned yet: nothing to warm
    before = plan(task, prof, opts)
    warmer.remember(before)
    warmer(lambda: True)
    assert warmer.warm_ups == 0  # a row is waiting: no warm-up
    warmer(lambda: False)
    warmer(lambda: False)
    assert warmer.warm_ups == 2
    after = plan(task, prof, opts)
    assert after.duration.seconds == before.duration.seconds
    assert (after.joint.q == before.joint.q).all()


def test_warmer_survives_a_move_that_fails():
    """A remembered move whose plan raises (here: outside the workcell with these options) is warmed quietly."""
    prof = load_profile(None)
    warmer = Warmer(prof, PlanOptions(rate=1000.0), None, 0.005)
    warmer.task = Task([-0.1525, 0, -0.8], [3.0, 0, -0.8], 0.025, 0.5)  # unreachable: plan raises
    warmer(lambda: False)
    assert warmer.warm_ups == 1


def test_plan_interrupt_is_polled_between_stages():
    """plan(interrupt=…) stops with PlanInterrupted once it says so, and changes nothing when it never does."""
    from pickplace_cli.planner import PlanInterrupted

    prof = load_profile(None)
    task = Task([-0.1525, 0, -0.8], [0.1525, 0, -0.78], 0.025, 0.5)
    opts = PlanOptions(rate=1000.0)
    polls = []

    def after(n):
        def interrupt():
            polls.append(n)
            return len(polls) >= n
        return interrupt

    with pytest.raises(PlanInterrupted):
        plan(task, prof, opts, interrupt=after(1))
    assert polls == [1]  # the first poll, after the path
    polls.clear()
    p = plan(task, prof, opts, interrupt=lambda: polls.append(0) or False)
    assert len(polls) >= 3  # path, samples, before the limit check
    ref = plan(task, prof, opts)
    assert p.duration.seconds == ref.duration.seconds and (p.joint.q == ref.joint.q).all()
    assert p.report.ok == ref.report.ok


def test_warmer_stops_when_a_line_comes_mid_plan():
    prof = load_profile(None)
    opts = PlanOptions(rate=1000.0)
    warmer = Warmer(prof, opts, "default", 0.005)
    warmer.remember(plan(Task([-0.1525, 0, -0.8], [0.1525, 0, -0.8], 0.025, 0.5), prof, opts))
    answers = iter([False, False, True])  # at the start, after the path: nothing; after the samples: a line
    warmer(lambda: next(answers, True))
    assert warmer.warm_ups == 1 and warmer.interrupted == 1


def test_a_character_cut_between_two_reads_is_not_counted_twice():
    """The limit counts characters: the bytes of a character not all read yet are not counted as surrogates (a
    line of exactly ``limit`` characters ending in a 4-byte character, its bytes split between two writes)."""
    r, w = os.pipe()
    reader = WarmLines(r, 0.005, lambda ready: None)
    emoji = "\U0001F600".encode()

    def later():
        time.sleep(0.05)
        os.write(w, emoji[2:] + b"\n")
        os.close(w)

    os.write(w, b"abcd" + emoji[:2])
    t = threading.Thread(target=later)
    t.start()
    try:
        assert reader.readline(5) == "abcd\U0001F600"
        assert reader.readline(5) == "\n"
        assert reader.readline(5) == ""
    finally:
        t.join()
        os.close(r)


def test_the_reader_decodes_with_the_encoding_given():
    r, _ = _pipe_with("é,ü\n".encode("latin-1"))
    try:
        assert WarmLines(r, 0.01, lambda ready: None, "latin-1").readline() == "é,ü\n"
    finally:
        os.close(r)


def test_warmer_plans_slow_modes_with_time_auto_and_skips_belt_moves():
    """--time fit/optimal and --optimize shape: the warm-up plans with --time auto, no shape search (those searches
    take 50 ms to 1 s and cannot stop midway); a plan with a moving end (a belt row) is not remembered."""
    prof = load_profile(None)
    for opts in (PlanOptions(time="optimal"), PlanOptions(time="fit", fit=True), PlanOptions(shape=True)):
        w = Warmer(prof, opts, None, 0.005)
        assert w.options.time == "auto" and not w.options.shape and not w.options.fit
    w = Warmer(prof, PlanOptions(time=0.3, rate=500.0, fit=False), None, 0.005)
    assert w.options.time == 0.3 and w.options.rate == 500.0  # a cheap mode is warmed as it is
    rest = plan(Task([-0.1525, 0, -0.8], [0.1525, 0, -0.8], 0.025, 0.5), prof, PlanOptions())
    w.remember(rest)
    moving = Task([-0.1525, 0, -0.8], [0.1525, 0, -0.8], 0.025, 0.5, v_to=np.array([0.2, 0.0, 0.0]))
    w.remember(type("P", (), {"task": moving})())
    assert w.task is rest.task


def test_warmer_stops_after_the_idle_limit_and_starts_again_with_the_next_row():
    """Nothing to warm before the first row; warm-ups while rows keep coming; none once ``idle_limit`` s have passed
    since the last row answered (failed rows count), until the next row (a fake clock)."""
    now = [100.0]
    prof = load_profile(None)
    warmer = Warmer(prof, PlanOptions(rate=1000.0), None, 0.005, idle_limit=60.0, clock=lambda: now[0])
    assert warmer(lambda: False) is False and warmer.warm_ups == 0  # no move yet: the reader may wait
    task = Task([-0.1525, 0, -0.8], [0.1525, 0, -0.8], 0.025, 0.5)
    warmer.remember(plan(task, prof, PlanOptions(rate=1000.0)))
    now[0] += 59.0
    assert warmer(lambda: False) is True and warmer.warm_ups == 1
    assert warmer(lambda: True) is True and warmer.warm_ups == 1  # a row waits: no warm-up, keep polling
    now[0] += 1.5  # 60.5 s since the last row
    assert warmer(lambda: False) is False and warmer.warm_ups == 1
    warmer.remember(None)  # a row that failed: a row all the same
    assert warmer(lambda: False) is True and warmer.warm_ups == 2
    assert warmer.task is task  # the move warmed is still the last one planned


def test_the_reader_stops_calling_idle_once_it_says_false_until_the_next_line():
    """idle → False: the reader blocks on the pipe without a timeout (no calls, no CPU) until a line comes; the
    next readline polls again."""
    r, w = os.pipe()
    calls: list[float] = []

    def idle(ready):
        calls.append(time.perf_counter())
        return len(calls) < 3  # the third call says: not before the next line

    reader = WarmLines(r, 0.002, idle)

    def later(data: bytes, after: float):
        time.sleep(after)
        os.write(w, data)

    try:
        t = threading.Thread(target=later, args=(b"x\n", 0.15))
        t.start()
        assert reader.readline() == "x\n"
        t.join()
        assert len(calls) == 3  # 75 intervals of 2 ms passed: only 3 calls
        t = threading.Thread(target=later, args=(b"y\n", 0.05))
        t.start()
        assert reader.readline() == "y\n"
        t.join()
        assert len(calls) >= 4  # polling again for the next line (idle now always says False: one call)
    finally:
        os.close(w)
        os.close(r)


def test_a_lone_cr_ends_a_line_at_once_and_a_following_lf_belongs_to_it():
    """Without idle (a stream without --keep-warm) the reader just waits; "a\\r" is a line as soon as it is read,
    and a "\\n" read later is the rest of that "\\r\\n" (no empty line); "\\r\\n" in one read is one line end."""
    r, w = os.pipe()
    reader = WarmLines(r)
    try:
        os.write(w, b"a\r")
        assert reader.readline() == "a\r"
        os.write(w, b"\nb\r\nc\rd\n")
        assert [reader.readline() for _ in range(3)] == ["b\r\n", "c\r", "d\n"]
        os.write(w, b"e\r")
        assert reader.readline() == "e\r"
        os.write(w, b"\n")
        os.close(w)
        w = -1
        assert reader.readline() == ""  # the \n of e's \r\n, then the end
    finally:
        if w >= 0:
            os.close(w)
        os.close(r)
