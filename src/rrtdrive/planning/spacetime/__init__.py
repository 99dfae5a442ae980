"""Space-time planning: the improved RRT-Connect against the predicted motion of other vehicles.

The paper plans among static obstacles. Here other vehicles move, and a pose is
only in conflict with a vehicle if both are there *at the same time*. The ego's
time at a place comes from its speed profile, so the checks below give every
point of the plane an arrival time and test the ego there against the other
vehicles' predicted poses at that time, with a safety buffer:

* :class:`Prediction` - the other vehicles' predicted body-centre poses on a
  time grid (built in :mod:`rrtdrive.sim.prediction`; plain arrays here, so
  planning never imports the simulator).
* :class:`ArrivalTiming` - the arrival time of a tree node from the nominal
  speed profile (accelerate at ``accel`` from the start speed to ``v_max``)
  over its progress along the road; tree edges and nodes carry these times.
* :func:`profile_times` - the exact arrival times along a sampled path from the
  controller's speed profile (curvature limit, acceleration and deceleration
  limits), used by the exact path test.
* :class:`SpaceTimeChecker` - a :class:`rrtdrive.checking.Checker` whose pose and
  motion answers also require every ego pose to keep ``buffer`` from every other
  vehicle's swept body over the pose's time band (map and grid data are the
  static checker's).
* :class:`SpaceTimeRRTConnect` - :class:`~rrtdrive.planning.improved.ImprovedRRTConnect`
  run on a :class:`SpaceTimeChecker`: tree growth, direct connection, pruning,
  sharp-angle repair and the B-spline guarantee loop all see moving vehicles.

The conflict test is conservative: the ego body is covered by three discs
(:func:`rrtdrive.vehicle.cover_discs`), grown by half the pose spacing; each
other vehicle by the capsule around its centre line, stretched along its heading
over the time band ``[t - margin(t), t + margin(t)]`` (exact for motion along
the heading, which both predictors produce). A pose conflicts when a disc comes
closer than ``buffer(t)`` to a capsule.

Modules: ``prediction`` (:class:`Prediction`), ``safety`` (:class:`SafetyConfig`),
``timing`` (:class:`ArrivalTiming`, :func:`profile_times`), ``conflicts``
(:func:`traffic_conflicts`), ``checker`` (:class:`SpaceTimeChecker`), ``planner``
(:class:`SpaceTimeProblem`, :class:`SpaceTimePlan`, :class:`SpaceTimeRRTConnect`).
"""

from __future__ import annotations

from rrtdrive.planning.spacetime.checker import SpaceTimeChecker
from rrtdrive.planning.spacetime.conflicts import traffic_conflicts
from rrtdrive.planning.spacetime.planner import (
    STATIC_ONLY,
    SpaceTimePlan,
    SpaceTimeProblem,
    SpaceTimeRRTConnect,
)
from rrtdrive.planning.spacetime.prediction import Prediction
from rrtdrive.planning.spacetime.safety import SafetyConfig
from rrtdrive.planning.spacetime.timing import ArrivalTiming, profile_times

__all__ = [
    "Prediction",
    "SafetyConfig",
    "ArrivalTiming",
    "profile_times",
    "traffic_conflicts",
    "SpaceTimeChecker",
    "SpaceTimeProblem",
    "SpaceTimePlan",
    "SpaceTimeRRTConnect",
    "STATIC_ONLY",
]
