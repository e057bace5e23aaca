"""Fuzz the CLI as users and their programs meet it: random batches over the three shipped profiles and every method,
the same rows streamed, hostile files (profiles, batches, checked trajectories), and signals at random moments.

    python bench/fuzz.py --seed 1 --minutes 20          # until the time is up (or --rows rows were sent)
    python bench/fuzz.py --seed 2 --rows 2000 --minutes 60

Every run of the CLI is a subprocess with a time cap. Counted, and printed at the end (and written to
``bench/results/fuzz.json``):

* ``rows``: batch rows sent to file and stream runs (each row is owed an answer); ``rows_signalled``: rows of the
  batches stopped by a signal;
* ``tracebacks``: runs whose stderr has a Python traceback;
* ``hangs``: runs that did not end within their cap (killed);
* ``rows_without_answer``: rows of a ``--json`` batch with no JSON line of their own (by row number) when the
  batch itself did not fail as a whole;
* ``wrong_exit_codes``: an exit status outside the documented set (0, 1, 2, 3, 4, 130, 143), a batch whose status
  is not the highest of its rows' codes, a row code outside (0, 1, 2, 3, 4), a hostile file that exits 0 or 3/4 where it
  must be refused, a streamed batch whose row codes differ from the same file's;
* ``left_running``: processes of a run's group still alive 5 s after its main process ended;
* ``multi_line_errors``: a refused hostile file with more than one error line (a profile may list several problems:
  those lines all start with ``pickplace: error:``, which is allowed).

Examples of every problem found (the command and the first lines of stderr) are kept in the results file.
"""

from __future__ import annotations

import argparse
import json
import os
import random
import signal
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from tests.procs import group  # noqa: E402 - the process table, as the tests read it
PROFILES = ("delta-su2018", "scara-600", "gantry")
METHODS = ("bspline", "ph", "superposition", "lame", "piecewise-poly", "bspline-vel")
#: the region random points are drawn from, per profile [m]: (min corner, max corner)
REGIONS = {
    "delta-su2018": ((-0.35, -0.35, -1.0), (0.35, 0.35, -0.65)),
    "scara-600": ((-0.1, -0.55, -0.18), (0.55, 0.55, -0.02)),
    "gantry": ((-0.9, -0.9, -0.9), (0.9, 0.9, 0.1)),
}
DOCUMENTED = {0, 1, 2, 3, 4, 130, 143}
#: a row's codes: those of the same single plan (2: an option the row's method cannot take, e.g. time = optimal with
#: bspline-vel, as `plan -m bspline-vel -t optimal` exits 2)
ROW_CODES = {0, 1, 2, 3, 4}
CAP_S = 240.0


class Tally:
    def __init__(self) -> None:
        self.counts = {k: 0 for k in ("runs", "rows", "rows_signalled", "tracebacks", "hangs", "rows_without_answer",
                                      "wrong_exit_codes", "left_running", "multi_line_errors")}
        self.examples: list[dict] = []

    def bad(self, kind: str, cmd: list[str], detail: str, n: int = 1) -> None:
        self.counts[kind] += n
        print(f"PROBLEM {kind}: {' '.join(cmd)}\n    {detail[-600:]}", file=sys.stderr, flush=True)
        if sum(1 for e in self.examples if e["kind"] == kind) < 10:
            self.examples.append({"kind": kind, "cmd": " ".join(cmd), "detail": detail[:800]})


def _cli(*args: str) -> list[str]:
    return [sys.executable, "-m", "pickplace_cli", *args]


def run(tally: Tally, args: list[str], stdin: str | None = None, cap: float = CAP_S, signal_after=None,
        cwd: Path | None = None):
    """Run the CLI; count tracebacks, hangs, undocumented exit codes and processes left running. → (code, out, err)
    or None after a hang."""
    cmd = _cli(*args)
    tally.counts["runs"] += 1
    proc = subprocess.Popen(cmd, stdin=subprocess.PIPE if stdin is not None else subprocess.DEVNULL,
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, start_new_session=True, cwd=cwd)
    try:
        if signal_after is not None:
            delay, sig, to_group = signal_after
            if stdin is not None:
                proc.stdin.write(stdin.encode("utf-8", "surrogateescape"))
                proc.stdin.flush()
            try:
                proc.wait(delay)
            except subprocess.TimeoutExpired:
                (os.killpg(proc.pid, sig) if to_group else proc.send_signal(sig))
            out, err = proc.communicate(None, timeout=cap)
        else:
            out, err = proc.communicate(stdin.encode("utf-8", "surrogateescape") if stdin is not None else None,
                                        timeout=cap)
    except subprocess.TimeoutExpired:
        tally.bad("hangs", cmd, f"no end within {cap:g} s")
        os.killpg(proc.pid, signal.SIGKILL)
        proc.wait()
        return None
    except BrokenPipeError:
        out, err = proc.communicate(timeout=cap)
    deadline = time.monotonic() + 5.0
    while group(proc.pid):
        if time.monotonic() > deadline:
            tally.bad("left_running", cmd, f"processes {group(proc.pid)}")
            os.killpg(proc.pid, signal.SIGKILL)
            break
        time.sleep(0.05)
    err_text = err.decode("utf-8", "replace")
    if "Traceback (most recent call last)" in err_text:
        tally.bad("tracebacks", cmd, err_text[-800:])
    if proc.returncode not in DOCUMENTED:
        tally.bad("wrong_exit_codes", cmd, f"exit {proc.returncode}: {err_text[-300:]}")
    return proc.returncode, out.decode("utf-8", "replace"), err_text


# ------------------------------------------------------------------------------------------------ random rows


def _point(rng: random.Random, profile: str) -> list[float]:
    lo, hi = REGIONS[profile]
    return [rng.uniform(a, b) for a, b in zip(lo, hi)]


def _cell(rng: random.Random, value: float) -> str:
    """A number as a user's file may write it: mostly plain, sometimes hostile."""
    r = rng.random()
    if r < 0.93:
        return f"{value:.4f}"
    return rng.choice(["", "nan", "inf", "-inf", "1e999", "abc", "0,15", "0.15_25", "１", " 0.1 ", "'0.1'", "\"0.1\"",
                       "1e-300", "-0", "0x10", "+0.1"])


def random_batch(rng: random.Random, profile: str, n: int) -> tuple[str, int]:
    """(CSV text, rows) of random moves in the profile's region; optional columns and cells sometimes hostile."""
    cols = ["from_x", "from_y", "from_z", "to_x", "to_y", "to_z"]
    extra = [c for c in ("height", "eta", "time") if rng.random() < 0.5]
    lines = [",".join(cols + extra)]
    for _ in range(n):
        p, q = _point(rng, profile), _point(rng, profile)
        cells = [_cell(rng, x) for x in p + q]
        for c in extra:
            if c == "height":
                cells.append(_cell(rng, rng.choice([rng.uniform(0.005, 0.08), rng.uniform(0.0, 0.5)])))
            elif c == "eta":
                cells.append(_cell(rng, rng.uniform(0.05, 0.95)))
            else:
                cells.append(rng.choice(["auto", "fit", "optimal", f"{rng.uniform(0.05, 1.5):.3f}", "", "Fit",
                                         " fit ", "0", "-1", "abc"]))
        lines.append(",".join(cells))
    ending = rng.choice(["\n", "\n", "\r\n", "\r"])
    return ending.join(lines) + ending, n


def batch_runs(rng: random.Random, tally: Tally, tmp: Path, profile: str, method: str, n: int) -> None:
    """One random batch as a file (-j 1 or 2) and the same rows streamed: every row answered, the batch's code the
    highest of its rows', the stream's row codes those of the file."""
    text, n = random_batch(rng, profile, n)
    src = tmp / "batch.csv"
    src.write_text(text, newline="")
    j = rng.choice(["1", "2"])
    base = ["plan", "-p", profile, "-m", method, "--json", "-q"]
    res = run(tally, base + ["--batch", str(src), "-j", j])
    tally.counts["rows"] += n
    codes_file = _check_rows(tally, base + ["--batch", str(src), "-j", j], res, n)
    res = run(tally, base + ["--batch", "-", "-j", rng.choice(["1", "2"])], stdin=text)
    tally.counts["rows"] += n
    codes_stream = _check_rows(tally, base + ["--batch", "-"], res, n)
    if codes_file is not None and codes_stream is not None and codes_file != codes_stream:
        diff = [(k, codes_file.get(k), codes_stream.get(k)) for k in sorted(set(codes_file) | set(codes_stream))
                if codes_file.get(k) != codes_stream.get(k)]
        tally.bad("wrong_exit_codes", base + ["--batch", "- (vs file)"], f"row codes differ: {diff[:5]}")


def _check_rows(tally: Tally, cmd: list[str], res, n: int):
    if res is None:
        tally.counts["rows_without_answer"] += n
        return None
    code, out, err = res
    docs = []
    for line in out.splitlines():
        try:
            docs.append(json.loads(line))
        except json.JSONDecodeError:
            tally.bad("wrong_exit_codes", cmd, f"not a JSON line on stdout: {line[:200]}")
    rows = {d["row"]: d["exit_code"] for d in docs if isinstance(d, dict) and "row" in d}
    whole = [d for d in docs if isinstance(d, dict) and "row" not in d]  # an error that ended the batch
    if whole or code == 2:
        return None  # the batch was refused as a whole (a header, a usage error): no row is owed an answer
    missing = [k for k in range(1, n + 1) if k not in rows]
    if missing:
        tally.bad("rows_without_answer", cmd, f"rows {missing[:10]} of {n} have no JSON line; exit {code}; "
                  f"{err[-300:]}", len(missing))
    if any(c not in ROW_CODES for c in rows.values()):
        tally.bad("wrong_exit_codes", cmd, f"row codes {sorted(set(rows.values()))}")
    if rows and code != max(rows.values()):
        tally.bad("wrong_exit_codes", cmd, f"batch exit {code}, rows' highest {max(rows.values())}")
    return rows


# ------------------------------------------------------------------------------------------------ hostile files


def hostile_profiles(rng: random.Random, tally: Tally, tmp: Path) -> None:
    """Mutated shipped profiles: refused (exit 1) with error lines only, or accepted; never a traceback or a hang."""
    from pickplace_cli.model.profile import resolve_profile_path

    name = rng.choice(PROFILES)
    text = resolve_profile_path(name).read_text()
    lines = text.splitlines()
    kind = rng.choice(["delete", "garbage", "control", "binary", "utf16", "deep", "number", "duplicate", "huge",
                       "rpm", "degrees", "alias", "tab"])
    if kind == "delete":
        del lines[rng.randrange(len(lines))]
        body = "\n".join(lines)
    elif kind == "garbage":
        k = rng.randrange(len(lines))
        lines[k] = lines[k] + rng.choice([" ]", " {", ": :", " - x", " !!python/object:os.system"])
        body = "\n".join(lines)
    elif kind == "control":
        k = rng.randrange(len(text))
        body = text[:k] + rng.choice(["\x0b", "\x0c", "\x07", "\x1b", "\ufffe", "\x00"]) + text[k:]
    elif kind == "binary":
        body = bytes(rng.randrange(256) for _ in range(400)).decode("latin-1")
    elif kind == "utf16":
        (tmp / "p.yaml").write_bytes(text.encode("utf-16"))
        body = None
    elif kind == "deep":
        body = "name: x\nrobot: " + "[" * 200 + "]" * 200
    elif kind == "number":
        import re

        nums = list(re.finditer(r"(?<![\w.])-?\d+\.?\d*(e-?\d+)?", text))
        m = rng.choice(nums)
        body = text[:m.start()] + rng.choice(["-1", "0", "1e308", "nan", ".inf", "abc", "yes", "null", "[1, 2]"]) + text[m.end():]
    elif kind == "duplicate":
        body = text + "\nname: again\n"
    elif kind == "huge":
        body = text + "\n# " + "x" * (2 << 20)
    elif kind == "rpm":
        body = text.replace("max_speed: 628.3", "max_speed: 3000")
    elif kind == "degrees":
        body = text.replace("position: [-0.6981317, 1.5707963]", "position: [-40, 90]").replace(
            "[-2.3038346, 2.3038346]", "[-132, 132]")
    elif kind == "alias":
        body = "a: &x [1]\nb: *x\n" + text
    else:
        body = text.replace("  ", "\t", 1)
    if body is not None:
        (tmp / "p.yaml").write_text(body, encoding="utf-8", errors="surrogateescape")
    args = ["plan", "--from", "-0.1525,0,-0.8", "--to", "0.1525,0,-0.8", "-p", str(tmp / "p.yaml"), "-q", "--json"]
    res = run(tally, args, cap=60)
    if res is None:
        return
    code, out, err = res
    if code not in (0, 1, 3, 4):
        tally.bad("wrong_exit_codes", args, f"{kind}: exit {code}: {err[-300:]}")
    if code == 1:
        lines = [ln for ln in err.splitlines() if ln.strip()]
        if not all(ln.startswith(("pickplace: error:", "pickplace: warning:")) for ln in lines):
            tally.bad("multi_line_errors", args, f"{kind}: {err[-500:]}")
        try:
            json.loads(out.strip().splitlines()[-1])
        except (json.JSONDecodeError, IndexError):
            tally.bad("wrong_exit_codes", args, f"{kind}: no JSON document on stdout with --json")


def hostile_batches(rng: random.Random, tally: Tally, tmp: Path) -> None:
    kind = rng.choice(["nul", "utf16", "long", "header", "quotes", "bom", "empty", "ragged", "units"])
    head = "from_x,from_y,from_z,to_x,to_y,to_z\n"
    row = "-0.1525,0,-0.8,0.1525,0,-0.8\n"
    data = {"nul": (head + row + "\0\0" + row).encode(), "utf16": (head + row).encode("utf-16"),
            "long": (head + "1" * 200_000 + "\n").encode(), "header": head.encode(),
            "quotes": (head + '"-0.1525,0,-0.8,0.1525,0,-0.8\n' + row).encode(),
            "bom": ("\ufeff" + head + row).encode(), "empty": b"",
            "ragged": (head + "-0.1525,0,-0.8\n" + row).encode(),
            "units": ("from_x[mm],from_y,from_z,to_x,to_y,to_z\n" + row).encode()}[kind]
    (tmp / "h.csv").write_bytes(data)
    args = ["plan", "--batch", str(tmp / "h.csv"), "-q", "--json"]
    res = run(tally, args, cap=60)
    if res is not None and res[0] not in (0, 1):
        tally.bad("wrong_exit_codes", args, f"{kind}: exit {res[0]}")


def hostile_checks(rng: random.Random, tally: Tally, tmp: Path, traj: Path) -> None:
    lines = traj.read_text().splitlines()
    kind = rng.choice(["quote", "longquote", "truncate", "units", "rpm", "nan", "backwards", "header"])
    if kind == "quote":
        lines.insert(3, '"abc,')
    elif kind == "longquote":
        lines.insert(3, '"' + "x" * 140_000)
    elif kind == "truncate":
        lines = lines[: rng.randrange(1, 6)]
    elif kind == "units":
        lines[0] = lines[0].replace("t[s]", "t[ms]")  # then t goes 0 … 0.18 ms: a valid, very fast trajectory
    elif kind == "rpm":
        lines[0] = lines[0].replace("q1[rad]", "q1[rpm]")
    elif kind == "nan":
        k = rng.randrange(1, len(lines))
        lines[k] = "nan," + lines[k].split(",", 1)[1]
    elif kind == "backwards":
        lines[5], lines[6] = lines[6], lines[5]
    else:
        lines[0] = "time,joint1,joint2,joint3"
    (tmp / "c.csv").write_text("\n".join(lines) + "\n")
    args = ["check", str(tmp / "c.csv"), "-q"]
    res = run(tally, args, cap=120)
    if res is None:
        return
    code, _, err = res
    if kind != "units" and code not in (1,):
        tally.bad("wrong_exit_codes", args, f"{kind}: exit {code} (a broken file must be refused): {err[-200:]}")
    if code == 1 and len([ln for ln in err.splitlines() if ln.strip()]) != 1:
        tally.bad("multi_line_errors", args, f"{kind}: {err[-500:]}")


# ------------------------------------------------------------------------------------------------ signals


def signal_runs(rng: random.Random, tally: Tally, tmp: Path) -> None:
    text, n = random_batch(random.Random(rng.random()), "delta-su2018", 300)
    src = tmp / "s.csv"
    src.write_text(text, newline="")
    sig = rng.choice([signal.SIGINT, signal.SIGTERM])
    streamed = rng.random() < 0.5
    args = ["plan", "--batch", "-" if streamed else str(src), "-q", "-j", "2", "-o", str(tmp / "s_out.csv")]
    (tmp / "s_out.csv").write_text("old\n")
    res = run(tally, args, stdin=text if streamed else None,
              signal_after=(rng.uniform(0.0, 3.0), sig, rng.random() < 0.5), cwd=tmp)
    tally.counts["rows_signalled"] += n
    if res is None:
        return
    code, _, err = res
    out = (tmp / "s_out.csv").read_text()
    if code in (130, 143) and out != "old\n":
        tally.bad("wrong_exit_codes", args, f"{sig.name}: exit {code} but the -o file changed")
    if list(tmp.glob(".s_out.csv.*")):
        tally.bad("left_running", args, f"{sig.name}: a temporary file left: {[p.name for p in tmp.glob('.s_out.csv.*')]}")
        for p in tmp.glob(".s_out.csv.*"):
            p.unlink()


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--minutes", type=float, default=20.0, help="stop starting new runs after this long")
    ap.add_argument("--rows", type=int, default=10**9, help="stop after this many batch rows")
    ap.add_argument("--batch-rows", type=int, default=40, help="rows per random batch")
    args = ap.parse_args()
    rng = random.Random(args.seed)
    tally = Tally()
    t_end = time.monotonic() + 60 * args.minutes
    with tempfile.TemporaryDirectory() as d:
        tmp = Path(d)
        traj = tmp / "traj.csv"
        subprocess.run(_cli("plan", "--from", "-0.1525,0,-0.8", "--to", "0.1525,0,-0.8", "-q", "-o", str(traj)),
                       check=True)
        k = 0
        while time.monotonic() < t_end and tally.counts["rows"] < args.rows:
            profile, method = PROFILES[k % 3], METHODS[(k // 3) % len(METHODS)]
            batch_runs(rng, tally, tmp, profile, method, rng.randrange(1, args.batch_rows + 1))
            hostile_profiles(rng, tally, tmp)
            hostile_batches(rng, tally, tmp)
            hostile_checks(rng, tally, tmp, traj)
            if k % 3 == 0:
                signal_runs(rng, tally, tmp)
            k += 1
            print(json.dumps(tally.counts), flush=True)
    out = ROOT / "bench" / "results" / "fuzz.json"
    out.write_text(json.dumps({"seed": args.seed, "command": " ".join(sys.argv), "totals": tally.counts,
                               "examples": tally.examples}, indent=2) + "\n")
    print("totals:", json.dumps(tally.counts))
    for e in tally.examples[:20]:
        print(f"- {e['kind']}: {e['cmd']}\n    {e['detail'][:300]}")


if __name__ == "__main__":
    main()
