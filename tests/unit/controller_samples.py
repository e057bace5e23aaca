"""Small controller-table exports shared by the Structured Text tests (few points: blark's Earley parser is slow on
long array initialisers)."""

from __future__ import annotations

from functools import lru_cache

from pickplace_cli.export.drive import drive_map
from pickplace_cli.export.tables import Master, format_table_st, table_columns, table_header
from pickplace_cli.model.profile import load_profile
from pickplace_cli.model.task import Task
from pickplace_cli.pipelines.controller import table_of, timeline_of
from pickplace_cli.planner import PlanOptions, plan

ADEPT = Task([-0.1525, 0.0, -0.8], [0.1525, 0.0, -0.8], 0.025, 0.5)


@lru_cache(maxsize=None)
def adept_move(cycle: float = 0.004):
    prof = load_profile("delta-su2018")
    return prof, plan(ADEPT, prof, PlanOptions(cycle=cycle, fit=False))


def table_st_texts(dialect: str) -> dict[str, str]:
    """pvt, cam, cam-table of one Adept move (4 ms cycle) as Structured Text in ``dialect``, in drive units."""
    prof, move = adept_move()
    motion = timeline_of([move], prof, move.report.dwell, False)
    drive = drive_map(prof)
    out = {}
    for kind, tol in (("pvt", 1e-3), ("cam", 1e-3), ("cam-table", 2e-2)):
        table = table_of(kind, move.t, motion, tol)
        cols = table_columns(table, drive, move.joint.units, Master())
        out[kind] = format_table_st(table, cols, dialect, table_header(table, drive, Master()))
    return out
