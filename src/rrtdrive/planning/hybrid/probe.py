"""A failed forward-only query's last look: whether reversing finds a path.

A forward query that the planners gave up on without a finding of
:func:`~rrtdrive.planning.diagnosis.diagnose` told the user nothing they could act on
(a home garage whose bay, 7 m to the side of the start, the car cannot turn into
forward read "the turns ... are too close for the car"; --reverse solves it in 41 ms;
a new user's find). :func:`reverse_probe` runs a small, counted Hybrid A* search with
reversing allowed; when it finds a path, that is the finding: what the user can
change (``--reverse``), with the path's length and gear changes. It claims no proof
that no forward path exists: only that none was found.
"""

from __future__ import annotations

from rrtdrive.planning.base import PlanningProblem, Stopwatch
from rrtdrive.planning.diagnosis.findings import Diagnosis, DiagnosisKind
from rrtdrive.planning.hybrid.config import HybridConfig
from rrtdrive.planning.hybrid.path import path_of
from rrtdrive.planning.hybrid.query import hybrid_query
from rrtdrive.planning.smoothing import SmoothingConfig
from rrtdrive.types import Budget
from rrtdrive.values import counted

__all__ = ["PROBE_CAP_FLOOR_S", "PROBE_EXPANSIONS", "reverse_probe"]

#: The probe's expansion budget: counted, so its finding is the same on any machine
#: (about 0.6 s at the 6 400 a second of the home garage's forward search here, 20 000
#: in 3.1 s; bench_hybrid's 60 reversing random-lot queries need a median of 56 and at
#: most 3 067: ``python experiments/bench_hybrid.py``).
PROBE_EXPANSIONS = 4000
#: The probe's own safety cap is at least this long (seconds): capped by a short
#: ``--max-time``, a slow machine dropped the finding a fast one kept (a helper's audit:
#: home garage, 10 iterations, --max-time 0.06), though the query's own counts decided.
PROBE_CAP_FLOOR_S = 30.0


def reverse_probe(
    problem: PlanningProblem,
    config: HybridConfig,
    smoothing: SmoothingConfig | None,
    max_time_s: float,
    expansions: int = PROBE_EXPANSIONS,
) -> Diagnosis | None:
    """A ``needs_reverse`` finding when reversing finds the path forward did not.

    Parameters
    ----------
    problem : PlanningProblem
        A forward-only query that failed (one with ``reverse`` set gets ``None``).
    config : HybridConfig
        The failed planner's Hybrid A* settings.
    smoothing : SmoothingConfig, optional
        Its per-segment post-processor.
    max_time_s : float
        The query's safety cap; the probe's is the larger of it and
        :data:`PROBE_CAP_FLOOR_S` (a probe that meets it finds nothing: its answer would
        depend on the machine's speed, and 4 000 expansions take about 0.6 s).
    expansions : int
        The probe's budget.

    Returns
    -------
    Diagnosis or None
        ``needs_reverse`` with ``reverse_length_m``, ``reverse_cusps`` and
        ``probe_expansions``; ``None`` when the probe found no path with a gear change.
    """
    if getattr(problem, "reverse", False):
        return None
    budget = Budget(max_iterations=expansions, max_time_s=max(max_time_s, PROBE_CAP_FLOOR_S))
    watch = Stopwatch(budget)
    answer = hybrid_query(problem, budget, watch, config, True, smoothing)
    if answer.path is None or watch.capped:
        return None
    cusps = answer.path.segments - 1
    if cusps < 1:
        # A forward path after all (the probe searched on another lattice): not a
        # reason to reverse; the failure stands as the planner reported it.
        return None
    length = path_of(answer.path).length
    return Diagnosis(
        DiagnosisKind.NEEDS_REVERSE,
        f"driving forward no path was found; with reversing allowed, Hybrid A* finds one "
        f"of {length:.1f} m with {cusps} gear change(s) in "
        f"{counted(answer.outcome.expansions, 'expansions')} (try --reverse)",
        {
            "reverse_length_m": length,
            "reverse_cusps": float(cusps),
            "probe_expansions": float(answer.outcome.expansions),
        },
    )
