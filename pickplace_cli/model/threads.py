"""BLAS threads for the solvers' small matrices: one.

The time law (``--time optimal``) and the shape search (``--optimize shape``) solve many small problems (tens to a few
hundred unknowns). OpenBLAS starts a thread per core for each of their matrix operations by default; on a loaded
machine those threads wait for each other, and ``optimal`` was 5–10× slower than on one thread (Adept cycle:
1,262 ms against 130 ms at load 12; ``bench/bench_threads.py`` measures both in one run). :func:`single_blas_thread`
runs a function with the BLAS libraries held to one thread (threadpoolctl), unless the user set the thread count
(``OPENBLAS_NUM_THREADS``, ``MKL_NUM_THREADS``, ``OMP_NUM_THREADS``), which is then left as it is. The CLI also sets
``OPENBLAS_NUM_THREADS=1`` before numpy loads (``pickplace_cli.__main__``), for every command and its workers.
"""

from __future__ import annotations

import functools
import os
from typing import Callable, TypeVar

F = TypeVar("F", bound=Callable)

#: the variables by which a user chooses the BLAS thread count (then respected)
USER_VARIABLES = ("OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS", "BLIS_NUM_THREADS", "OMP_NUM_THREADS")

_CONTROLLER: list = []  # the threadpoolctl controller, made once (finding the libraries costs ~7 ms)


def _controller():
    if not _CONTROLLER:
        try:
            # the solvers' BLAS is scipy's own (its wheels bundle an OpenBLAS of their own, loaded with
            # scipy.linalg): load it first, or the controller would see numpy's alone and leave scipy's on every core
            import scipy.linalg  # noqa: F401
            import scipy.optimize  # noqa: F401
            from threadpoolctl import ThreadpoolController

            _CONTROLLER.append(ThreadpoolController())
        except Exception:  # noqa: BLE001 - threadpoolctl missing or unable to read the libraries: no pinning
            _CONTROLLER.append(None)
    return _CONTROLLER[0]


def single_blas_thread(fn: F) -> F:
    """Decorator: call ``fn`` with the BLAS libraries limited to one thread (see the module docstring); nested calls
    and a user's own thread count are left alone."""

    @functools.wraps(fn)
    def wrapper(*args, **kwargs):
        if _ACTIVE[0] or any(v in os.environ and v != "OPENBLAS_NUM_THREADS" for v in USER_VARIABLES) \
                or os.environ.get("OPENBLAS_NUM_THREADS") not in (None, "1"):
            return fn(*args, **kwargs)
        controller = _controller()
        if controller is None:
            return fn(*args, **kwargs)
        _ACTIVE[0] = True
        try:
            with controller.limit(limits=1, user_api="blas"):
                return fn(*args, **kwargs)
        finally:
            _ACTIVE[0] = False

    return wrapper  # type: ignore[return-value]


_ACTIVE = [False]
