"""Look-up table λ → (k1*, k2*) of the B-spline method [Li2018, Sec. 3.2]: the file, reading and interpolation.

Use (online): ``load_table()`` reads the shipped (or a given) table, ``Table.lookup(λ)`` interpolates linearly between
rows. The rows come from :mod:`~pickplace_cli.lookup.bspline_optimum` (the optimiser) through
:mod:`~pickplace_cli.lookup.bspline_build` (the build).
"""

from __future__ import annotations

import bisect
import csv
import functools
import io
import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Callable

import numpy as np

from ..model.errors import TableError
from .bspline_optimum import TableRow


COLUMNS = ("lambda", "k1", "k2", "a_max", "j_max", "v_max", "F", "a_min", "j_min")


DEFAULT_TABLE = "bspline-eta0.5.csv"


FIT_LAMBDA_MIN = 5.0


#: Li 2018 Table 2: g_{i,j} of k_i* = Σ_j g_{i,j} λ^j (Eq. 23)
LI2018_TABLE2 = (
    (0.579, -1.99e-2, 5.09e-4, -4.91e-6),
    (0.218, -1.09e-2, 4.15e-4, -5.41e-6),
)


# ------------------------------------------------------------------------------------------------ table


@dataclass(frozen=True)
class Table:
    """A λ → (k1*, k2*) table with its provenance (``meta``) and fitted cubic (Eq. 23)."""

    rows: tuple[TableRow, ...]
    meta: dict = field(default_factory=dict)
    source: str = "<memory>"

    def __post_init__(self) -> None:
        object.__setattr__(self, "_columns", {})  # column arrays, built once (a table is immutable)
        lam = self.lam
        if len(lam) < 1:
            raise TableError(f"{self.source}: a table needs at least one row")
        if np.any(np.diff(lam) <= 0):
            raise TableError(f"{self.source}: lambda must increase strictly from row to row")

    @property
    def lam(self) -> np.ndarray:
        return self.column("lam")

    def column(self, name: str) -> np.ndarray:
        """The column ``name`` as a read-only array (``lambda`` or ``lam``, ``k1``, ``k2``, …)."""
        attr = "lam" if name == "lambda" else name
        col = self._columns.get(attr)  # type: ignore[attr-defined]
        if col is None:
            col = np.array([getattr(r, attr) for r in self.rows])
            col.flags.writeable = False
            self._columns[attr] = col  # type: ignore[attr-defined]
        return col

    @property
    def eta(self) -> float | None:
        e = self.meta.get("eta")
        return None if e is None else float(e)

    def lookup(self, lam: float, eta: float | None = None) -> tuple[float, float]:
        """(k1, k2) at ``lam`` by linear interpolation between rows; TableError outside the range."""
        lo, hi = float(self.lam[0]), float(self.lam[-1])
        if not np.isfinite(lam):
            raise TableError(f"lambda = {lam!r}: not a finite width/height ratio")
        if not (lo - 1e-9 <= lam <= hi + 1e-9):
            raise TableError(
                f"lambda = b/h = {lam:.4g} is outside the table's range [{lo:g}, {hi:g}] ({self.source}); "
                "change --height, build a wider table (pickplace build-table), or give --k1 and --k2"
            )
        if eta is not None and self.eta is not None and abs(eta - self.eta) > 1e-9:
            raise TableError(
                f"eta = {eta:g}: the table {self.source} was built for eta = {self.eta:g}; "
                f"build one with `pickplace build-table --eta {eta:g}` or give --k1 and --k2"
            )
        lists = self._columns.get("lists")  # type: ignore[attr-defined]
        if lists is None:
            lists = self._columns["lists"] = tuple(self.column(c).tolist() for c in ("lam", "k1", "k2"))  # type: ignore[attr-defined]
        xp, k1, k2 = lists
        return _interp(lam, xp, k1), _interp(lam, xp, k2)

    def fit(self, lam_min: float | None = None, degree: int = 3) -> tuple[np.ndarray, np.ndarray, float]:
        """Least-squares cubic of Eq. (23) over the rows with λ ≥ ``lam_min`` (default: the ``fit_lambda_min``
        of the header, else 5): g1, g2 as (g_i0 … g_i3) and the max |residual| over those rows.

        Below λ ≈ 5 the optimum moves fast (k2 rises to 0.4 at λ = 1) and no cubic follows it; the table
        rows, not the fit, are what ``plan`` uses."""
        if lam_min is None:
            lam_min = float(self.meta.get("fit_lambda_min", FIT_LAMBDA_MIN))
        sel = self.lam >= lam_min - 1e-12
        if sel.sum() < degree + 1:
            sel = np.ones_like(sel)
        lam = self.lam[sel]
        k1, k2 = self.column("k1")[sel], self.column("k2")[sel]
        deg = min(degree, len(lam) - 1)  # a tiny table gets a lower-degree fit (zero higher coefficients)
        g1 = np.pad(np.polynomial.polynomial.polyfit(lam, k1, deg), (0, degree - deg))
        g2 = np.pad(np.polynomial.polynomial.polyfit(lam, k2, deg), (0, degree - deg))
        res = max(
            np.max(np.abs(np.polynomial.polynomial.polyval(lam, g1) - k1)),
            np.max(np.abs(np.polynomial.polynomial.polyval(lam, g2) - k2)),
        )
        return g1, g2, float(res)


# ------------------------------------------------------------------------------------------------- I/O


@functools.lru_cache(maxsize=1)
def default_table_path() -> Path:
    from ..model.resources import data_dir

    return data_dir("tables") / DEFAULT_TABLE


def write_meta(out, meta: dict) -> None:
    """The ``# key: value`` header lines of a table file, keys sorted (a list or tuple as comma-separated values)."""
    for key in sorted(meta):
        val = meta[key]
        val = ",".join(f"{x:g}" for x in val) if isinstance(val, (list, tuple)) else val
        out.write(f"# {key}: {val}\n")


def format_table(table: Table, version: str, extra_meta: dict | None = None) -> str:
    """CSV text: ``#`` provenance lines, a header, one row per λ (fixed format, deterministic)."""
    meta = dict(table.meta)
    meta.update(extra_meta or {})
    fit_min = float(meta.setdefault("fit_lambda_min", FIT_LAMBDA_MIN))
    g1, g2, res = table.fit(fit_min)
    out = io.StringIO()
    out.write("# pickplace look-up table: optimal time-ratio factors of the quintic B-spline method [Li2018, Eq. (20)-(23)]\n")
    out.write(f"# tool_version: {version}\n")
    write_meta(out, meta)
    out.write("# units: lambda = b/h (dimensionless); k1, k2 dimensionless; v_max, a_max, j_max, a_min, j_min are the\n")
    out.write("#   normalised peaks |v|, |a|, |j| of the path with b = 1 m, T = 1 s (m/s, m/s^2, m/s^3); F dimensionless\n")
    out.write("# a_min, j_min: min over (k1, k2) of a_max, j_max at that lambda (the normalisers of Eq. 20-21)\n")
    out.write(f"# fit_k1: {' '.join(f'{g:.9g}' for g in g1)}\n")
    out.write(f"# fit_k2: {' '.join(f'{g:.9g}' for g in g2)}\n")
    out.write(f"# fit: k_i = g_i0 + g_i1*lambda + g_i2*lambda^2 + g_i3*lambda^3 (Eq. 23), fitted on lambda >= {fit_min:g}, max |residual| = {res:.3g}\n")
    out.write(",".join(COLUMNS) + "\n")
    for r in table.rows:
        out.write(",".join(f"{x:.10g}" for x in (r.lam, r.k1, r.k2, r.a_max, r.j_max, r.v_max, r.F, r.a_min, r.j_min)) + "\n")
    return out.getvalue()


def read_numeric_table(text: str, source: str, check_header: Callable[[list[str], int], None]):
    """The common layout of the table files: ``# key: value`` metadata lines before the header, a CSV
    header, then rows of finite numbers. Returns (meta, header or None, [(line number, values)]).
    ``check_header(header, lineno)`` raises TableError for a header the caller cannot read."""
    meta: dict = {}
    header: list[str] | None = None
    rows: list[tuple[int, list[float]]] = []
    for lineno, line in enumerate(text.splitlines(), 1):
        s = line.strip()
        if not s:
            continue
        if s.startswith("#"):
            body = s[1:].strip()
            if ":" in body and header is None:
                key, _, val = body.partition(":")
                meta.setdefault(key.strip(), val.strip())
            continue
        cells = [c.strip() for c in next(csv.reader([s]))]
        if header is None:
            header = cells
            check_header(header, lineno)
            continue
        if len(cells) != len(header):
            raise TableError(f"{source}:{lineno}: {len(cells)} values, header has {len(header)} columns")
        try:
            vals = [float(c) for c in cells]
        except ValueError:
            raise TableError(f"{source}:{lineno}: not a number in row {s!r}") from None
        bad = [h for h, v in zip(header, vals) if not math.isfinite(v)]
        if bad:
            raise TableError(f"{source}:{lineno}: {bad[0]} = {vals[header.index(bad[0])]}: values must be finite")
        rows.append((lineno, vals))
    return meta, header, rows


def parse_table(text: str, source: str = "<table>") -> Table:
    """Read a table written by :func:`format_table`; TableError (with file:line) on anything wrong."""

    def check(header: list[str], lineno: int) -> None:
        missing = [c for c in ("lambda", "k1", "k2") if c not in header]
        if missing:
            raise TableError(f"{source}:{lineno}: header lacks column(s) {', '.join(missing)} (need {', '.join(COLUMNS)})")

    meta, header, numeric = read_numeric_table(text, source, check)
    rows: list[TableRow] = []
    nan = float("nan")
    for lineno, values in numeric:
        vals = dict(zip(header, values))  # type: ignore[arg-type]
        for name in ("k1", "k2"):
            if not 0 < vals[name] < 1:
                raise TableError(f"{source}:{lineno}: {name} = {vals[name]:g}: must lie strictly between 0 and 1")
        rows.append(TableRow(*(vals.get(c, nan) for c in COLUMNS)))
    if header is None or not rows:
        raise TableError(f"{source}: no table rows (expected a header '{','.join(COLUMNS)}' and data)")
    if "eta" not in meta:
        raise TableError(f"{source}: no '# eta: VALUE' header line: the table must say which η it was built for")
    try:
        meta["eta"] = float(meta["eta"])
    except ValueError:
        raise TableError(f"{source}: eta = {meta['eta']!r} in the header is not a number") from None
    return Table(tuple(rows), meta=meta, source=source)


_CACHE: dict[tuple, object] = {}


def _interp(x: float, xp: list[float], fp: list[float]) -> float:
    """``np.interp(x, xp, fp)`` for one x, bitwise (the same search and the same slope·(x − xp[j]) + fp[j] as
    numpy's compiled loop; tested), without numpy's per-call cost: the planner looks up one λ per move."""
    if x >= xp[-1]:
        return fp[-1]
    if x < xp[0]:
        return fp[0]
    j = bisect.bisect_right(xp, x) - 1
    if xp[j] == x:
        return fp[j]
    return (fp[j + 1] - fp[j]) / (xp[j + 1] - xp[j]) * (x - xp[j]) + fp[j]


#: the largest table file read [bytes] (the shipped ones are ~10 kB)
TABLE_MAX_BYTES = 16 << 20


def read_table_file(path: Path, parse: Callable[[str, str], object], source: str, build_hint: str):
    """Parse a table file once per (path, mtime, size) (shared by the Li and conveyor tables); TableError
    when it is missing (saying how to build it: ``build_hint``) or unreadable."""
    from ..model.files import require_regular_file

    require_regular_file(str(path), "table", TableError)  # a named pipe with no writer would block forever
    try:
        st = path.stat()
        key = (st.st_dev, st.st_ino, st.st_mtime_ns, st.st_size, source)  # the file itself, as it is now
        if key in _CACHE:
            return _CACHE[key]
        if st.st_size > TABLE_MAX_BYTES:
            raise TableError(f"table {path}: {st.st_size} bytes, more than {TABLE_MAX_BYTES} ({TABLE_MAX_BYTES >> 20} MiB): "
                             "a table has a few thousand rows; is this the right file?")
        with open(path, "rb") as fh:
            raw = fh.read(TABLE_MAX_BYTES + 1)
        if len(raw) > TABLE_MAX_BYTES:  # a device or a pipe that keeps growing
            raise TableError(f"table {path}: more than {TABLE_MAX_BYTES} bytes; is this the right file?")
        if b"\0" in raw:
            from ..model.text import utf16_hint

            raise TableError(f"table {path}: a binary file (NUL bytes), not a CSV table{utf16_hint(raw)}")
        text = raw.decode("utf-8")
    except FileNotFoundError:
        raise TableError(f"table {path}: no such file (build one with `{build_hint} -o {path}`)") from None
    except UnicodeDecodeError:
        raise TableError(f"table {path}: not a text (UTF-8) file") from None
    except OSError as exc:
        raise TableError(f"table {path}: cannot read: {exc.strerror or exc}") from None
    table = parse(text, source)
    _CACHE[key] = table
    return table


def load_table(path: str | Path | None = None) -> Table:
    """Read a table file (default: the shipped table); TableError when missing or corrupt."""
    p = Path(path) if path is not None else default_table_path()
    # the shipped table is named, not located: outputs (JSON summaries) must not depend on the checkout path
    source = f"{DEFAULT_TABLE} (shipped)" if path is None else str(p)
    return read_table_file(p, parse_table, source, "pickplace build-table")  # type: ignore[return-value]
