"""Benches at scale: grids of maps/scenarios × planners × controllers × seeds.

Runs execute in parallel on local processes or a Ray cluster; every finished run
is one fsynced JSON line, so an interrupted bench resumes where it stopped; the
summary (mean, std, 95 % CI per group) is written as markdown, CSV and plots.
Importing this package registers the OMPL comparators (``ompl-r2-rrtconnect``,
``ompl-rs-bitstar`` …) as planners; OMPL itself is imported only when they run.

Examples
--------
>>> from rrtdrive.bench import BenchConfig, run_bench
>>> cfg = BenchConfig(maps=("parking_lot",), planners=("rrt-connect", "rrt-star"),
...                   seeds=20, out="results/bench")          # doctest: +SKIP
>>> run_bench(cfg).executed                                   # doctest: +SKIP
40
"""

from __future__ import annotations

from rrtdrive.bench import ompl_planners as _ompl_planners  # noqa: F401  (registers OMPL rows)
from rrtdrive.bench.backends import WorkerStartupError
from rrtdrive.bench.config_file import load_toml
from rrtdrive.bench.core import BenchReport, run_bench
from rrtdrive.bench.grid import BenchConfig, RunSpec, expand
from rrtdrive.bench.store import ResultStore
from rrtdrive.bench.summary import summarise_rows

__all__ = [
    "BenchConfig",
    "BenchReport",
    "ResultStore",
    "RunSpec",
    "expand",
    "load_toml",
    "run_bench",
    "summarise_rows",
    "WorkerStartupError",
]
