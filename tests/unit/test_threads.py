"""BLAS threads of the solvers (model/threads.py): one inside a decorated call, as threadpoolctl's own report of the
loaded libraries says (the reference), the previous count after it, and a user's own setting left alone."""

from __future__ import annotations

import subprocess
import sys

import pytest

threadpoolctl = pytest.importorskip("threadpoolctl")

CODE = r"""
import json, os, sys
import numpy  # loads OpenBLAS
from threadpoolctl import threadpool_info
from pickplace_cli.model.threads import single_blas_thread

def blas():
    return sorted({i["num_threads"] for i in threadpool_info() if i["user_api"] == "blas"})

@single_blas_thread
def inner():
    return blas()

print(json.dumps({"before": blas(), "inside": inner(), "after": blas()}))
"""


def _run(env_threads: str | None) -> dict:
    import json
    import os

    env = {k: v for k, v in os.environ.items() if k not in ("OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS",
                                                               "OMP_NUM_THREADS", "BLIS_NUM_THREADS")}
    if env_threads is not None:
        env["OPENBLAS_NUM_THREADS"] = env_threads
    out = subprocess.run([sys.executable, "-c", CODE], env=env, capture_output=True, text=True, check=True).stdout
    return json.loads(out.strip().splitlines()[-1])


def test_one_blas_thread_inside_and_the_default_after():
    res = _run(None)
    if not res["before"]:
        pytest.skip("no BLAS library found by threadpoolctl")
    assert res["inside"] == [1]
    assert res["after"] == res["before"]


def test_a_users_thread_count_is_left_alone():
    res = _run("2")
    if not res["before"]:
        pytest.skip("no BLAS library found by threadpoolctl")
    assert res["before"] == res["inside"] == res["after"] == [2]


def test_the_cli_sets_one_thread_before_numpy_loads():
    """`python -m pickplace_cli` (and the console script) start with OPENBLAS_NUM_THREADS=1 unless the user set a
    count: threadpoolctl then reports 1 for every BLAS library (numpy's and scipy's)."""
    code = ("import sys, os\nfrom pickplace_cli.__main__ import _install\n_install()\nimport numpy, scipy.linalg\n"
            "from threadpoolctl import threadpool_info\n"
            "print(sorted({i['num_threads'] for i in threadpool_info() if i['user_api'] == 'blas'}))")
    import os

    env = {k: v for k, v in os.environ.items() if k not in ("OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS",
                                                               "OMP_NUM_THREADS", "BLIS_NUM_THREADS")}
    out = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True, check=True).stdout
    assert out.strip().splitlines()[-1] in ("[1]", "[]")


def test_scipys_own_blas_is_held_too_when_it_loads_with_the_solver():
    """A library user's first ``--time optimal`` loads scipy.optimize (and scipy's own OpenBLAS) inside the decorated
    call: every BLAS library threadpoolctl then reports, scipy's included, runs one thread inside the call."""
    code = r"""
import json
import numpy
from threadpoolctl import threadpool_info
from pickplace_cli.model.threads import single_blas_thread

@single_blas_thread
def solve():
    import scipy.optimize  # the solver's first use, as timing/optimal.py does
    return [(i["filepath"], i["num_threads"]) for i in threadpool_info() if i["user_api"] == "blas"]

print(json.dumps({"inside": solve(), "cores": len(__import__("os").sched_getaffinity(0))}))
"""
    import json
    import os

    env = {k: v for k, v in os.environ.items() if k not in ("OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS",
                                                               "OMP_NUM_THREADS", "BLIS_NUM_THREADS")}
    out = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True, check=True).stdout
    res = json.loads(out.strip().splitlines()[-1])
    if not res["inside"]:
        pytest.skip("no BLAS library found by threadpoolctl")
    assert all(n == 1 for _, n in res["inside"]), res["inside"]
