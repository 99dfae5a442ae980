"""Evaluators: every metric of SPEC §4 from an episode's path, trajectory and map.

:func:`evaluate` reads an :class:`~rrtdrive.sim.runner.Episode` (plain data) and
returns an :class:`EpisodeReport`; :func:`summarise` aggregates reports over
seeds. The definitions are in ``docs/metrics.md``. This package does not import
highway-env (the simulator's own collision flag was logged by the runner), nor,
at run time, the simulator package.

Modules: :mod:`~rrtdrive.evaluation.report` (config, report, outcome),
:mod:`~rrtdrive.evaluation.metrics` (the metric table, ``evaluate``),
:mod:`~rrtdrive.evaluation.success`, :mod:`~rrtdrive.evaluation.tracking`,
:mod:`~rrtdrive.evaluation.collisions`, :mod:`~rrtdrive.evaluation.traffic_metrics`,
:mod:`~rrtdrive.evaluation.comfort`, :mod:`~rrtdrive.evaluation.summary`.
"""

from __future__ import annotations

from rrtdrive.evaluation.collisions import (
    COLLISION_STOPPED_SPEED,
    vehicle_collisions,
)
from rrtdrive.evaluation.metrics import METRICS, Metric, MetricContext, evaluate
from rrtdrive.evaluation.report import OUTCOMES, EpisodeReport, EvalConfig, Outcome
from rrtdrive.evaluation.success import (
    SuccessTerms,
    failure_reason,
    success_terms,
)
from rrtdrive.evaluation.summary import summarise
from rrtdrive.evaluation.tracking import tracking_errors
from rrtdrive.evaluation.traffic_metrics import (
    TTC_HORIZON_S,
    TTC_LEAST_MIN_S,
    TTC_STEP_S,
    TTC_STOPPED_SPEED,
    min_vehicle_distance,
    progress,
    time_to_collision,
)

__all__ = [
    "EvalConfig",
    "EpisodeReport",
    "evaluate",
    "summarise",
    "tracking_errors",
    "time_to_collision",
    "vehicle_collisions",
    "min_vehicle_distance",
    "OUTCOMES",
    "Outcome",
    "SuccessTerms",
    "success_terms",
    "failure_reason",
    "METRICS",
    "Metric",
    "MetricContext",
    "progress",
    "TTC_HORIZON_S",
    "TTC_STEP_S",
    "TTC_STOPPED_SPEED",
    "TTC_LEAST_MIN_S",
    "COLLISION_STOPPED_SPEED",
]
