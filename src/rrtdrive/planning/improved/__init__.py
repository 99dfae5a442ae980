"""The improved RRT-Connect of Li, Huang & Pan (2023), paper Sec. 3, with guaranteed drivable paths.

Tree growth (Sec. 3.1): bidirectional RRT-Connect with

* **direct connection** – when the straight start->goal edge is free and both
  headings point along it (within 90 degrees), the growth is skipped;
* **obtuse-angle parent choice** (Eq. 11, Table 1) – the nearest node whose angle
  between its parent and the sample is obtuse, else the nearest node; the roots get
  virtual parents one step behind the start and one step beyond the goal along
  their headings, and a root grows only where its angle is obtuse, so the car
  leaves and arrives along its headings;
* **adaptive step** – the greedy connect takes a first step ``p``, then ``2p``;
* **adaptive obstacle expansion** – rectangles whose envelope circles keep a gap
  ``L2 > L_min`` to every other obstacle (and to the map boundary) grow by ``a`` in
  length and width, in a second checker used for tree growth only (edges at the
  start and goal are checked on the map itself);
* **passage sampling** (beyond the paper) – a share of the iterations samples
  the centre line of narrow passages and joins both trees to it straight.

Samples are uniform over the free cells reachable from the start (the
baselines' :class:`~rrtdrive.planning.sampling.SampleSource`).

Post-processing (Sec. 3.2, :mod:`rrtdrive.planning.smoothing`): pruning,
sharp-angle repair, control-point supplement, a clamped uniform B-spline and the
guarantee loop (headings at both ends, ``|kappa| <= kappa_max``, exact body clear
of the *original* map). A tree path that cannot be made drivable is dropped and
the trees are grown afresh, up to ``max_postprocess_attempts`` times.

Every component is switchable by name, see :data:`COMPONENTS`::

    ImprovedRRTConnect()                                  # everything on
    ImprovedRRTConnect(disable=("obtuse_parent",))        # ablation by name
    ImprovedRRTConnect(adaptive_step=False, step=4.0)     # or any config field
    ImprovedRRTConnect(smoothing={"degree": 3})           # post-processor fields
    ImprovedRRTConnect(ImprovedConfig(step=4.0))          # or a whole config

Through the registry: ``make_planner("improved-rrt-connect", disable=["prune"])``.

Modules: :mod:`.config` (:class:`ImprovedConfig`, :data:`COMPONENTS`),
:mod:`.expansion` (obstacle expansion), passage cells from the checker's grid cache,
:mod:`.growth` (the obtuse tree and its growth), :mod:`.fallback` (the Dubins
fallback) and :mod:`.planner` (:class:`ImprovedRRTConnect`).
"""

from __future__ import annotations

from rrtdrive.planning.improved.config import (
    BEYOND_PAPER,
    COMPONENTS,
    PER_QUERY_SMOOTHING,
    SMOOTHING_COMPONENTS,
    ImprovedConfig,
    default_smoothing,
)
from rrtdrive.planning.improved.expansion import (
    default_expansion_lmin,
    endpoint_capped_clearance,
    envelope_gaps,
    expand_obstacles,
    expanded_checker,
)
from rrtdrive.planning.improved.fallback import dubins_fallback
from rrtdrive.planning.improved.growth import (
    EdgeFree,
    ObtuseTree,
    extend,
    fast_edge_test,
    greedy_connect,
    link,
    link_candidates,
)
from rrtdrive.planning.improved.planner import NAME, ImprovedRRTConnect

__all__ = [
    "BEYOND_PAPER",
    "COMPONENTS",
    "SMOOTHING_COMPONENTS",
    "PER_QUERY_SMOOTHING",
    "NAME",
    "default_smoothing",
    "dubins_fallback",
    "EdgeFree",
    "ImprovedConfig",
    "ImprovedRRTConnect",
    "ObtuseTree",
    "expand_obstacles",
    "envelope_gaps",
    "expanded_checker",
    "default_expansion_lmin",
    "endpoint_capped_clearance",
    "extend",
    "fast_edge_test",
    "greedy_connect",
    "link",
    "link_candidates",
]
