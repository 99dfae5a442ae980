"""Hybrid A* (Dolgov, Thrun, Montemerlo & Diebel 2008): a kinematic search that may reverse.

Modules: :mod:`.config` (:class:`HybridConfig`), :mod:`.primitives` (the arcs),
:mod:`.heuristic` (holonomic-with-obstacles and Dubins estimates),
:mod:`.body` (the body test with a sure-collision screen), :mod:`.search`
(the A* loop with analytic expansions), :mod:`.ramps` (continuous curvature for a
segment of arcs: steering ramps within the sharpness bound, exact end poses),
:mod:`.path` (gear segments made continuous in curvature and checked),
:mod:`.resolution` (the searches at one resolution: from the start, then
from the goal), :mod:`.query` (one query: the first search and the ladder after it),
:mod:`.planner` (the registered ``hybrid-a-star`` planner) and
:mod:`.escalation` (what the improved planner runs when its stages fail).
"""

from __future__ import annotations

from rrtdrive.planning.hybrid.config import HybridConfig
from rrtdrive.planning.hybrid.heuristic import (
    FreeCellGraph,
    Heuristic,
    HolonomicField,
    dubins_lengths,
)
from rrtdrive.planning.hybrid.path import (
    BuiltPath,
    GearSegment,
    Ramps,
    build_path,
    gear_segments,
)
from rrtdrive.planning.hybrid.planner import (
    NAME,
    HybridAStar,
    answer_stats,
    hybrid_result,
)
from rrtdrive.planning.hybrid.primitives import PrimitiveSet, arc_poses
from rrtdrive.planning.hybrid.query import HybridAnswer, hybrid_query
from rrtdrive.planning.hybrid.ramps import ramped_segment
from rrtdrive.planning.hybrid.resolution import free_cell_graph, reversed_in_time
from rrtdrive.planning.hybrid.search import HybridSearch, Piece, SearchOutcome, analytic_shots

__all__ = [
    "NAME",
    "HybridConfig",
    "HybridAStar",
    "HybridAnswer",
    "HybridSearch",
    "SearchOutcome",
    "Piece",
    "PrimitiveSet",
    "arc_poses",
    "FreeCellGraph",
    "HolonomicField",
    "Heuristic",
    "dubins_lengths",
    "BuiltPath",
    "GearSegment",
    "Ramps",
    "build_path",
    "gear_segments",
    "analytic_shots",
    "ramped_segment",
    "answer_stats",
    "free_cell_graph",
    "hybrid_query",
    "hybrid_result",
    "reversed_in_time",
]
