"""Tunables of the Hybrid A* planner: :class:`HybridConfig`."""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

from rrtdrive.planning.options import MAX_RADIUS_FACTOR, MAX_STEP_M, MIN_SPACING_M, check_known
from rrtdrive.types import InputError, require_finite, require_int, require_positive

__all__ = ["CURVES", "TIGHT_SOLUTIONS_FACTOR", "HybridConfig", "hybrid_with"]

#: The kinds of returned segments (:attr:`HybridConfig.curve`).
CURVES = ("clothoid", "arcs")
#: How many times ``max_solutions`` a tight search (:meth:`HybridConfig.tightened`) may
#: reject: it turns at full lock, where the ramps' re-fit has the least room.
TIGHT_SOLUTIONS_FACTOR = 4


@dataclass(frozen=True)
class HybridConfig:
    """Parameters of :class:`~rrtdrive.planning.hybrid.HybridAStar`, validated on construction.

    Parameters
    ----------
    xy_resolution : float
        Side of the position cells in metres: a search state is closed per cell,
        heading bin and gear (Dolgov et al. 2008: states continuous, closing discrete).
    yaw_resolution : float
        Width of a heading bin in radians (5 degrees).
    step : float
        Arc length of a motion primitive in metres; longer than a cell diagonal,
        so every successor leaves its parent's cell.
    long_steps : tuple of float
        Longer primitives, as multiples of ``step``, expanded from a node whose
        covering discs have room for their whole sweep (so their successors need no
        body test, :meth:`~rrtdrive.planning.hybrid.body.BodyTest.free_within`): the
        longest that fits is taken instead of the ``step`` arcs. Open aisles are
        crossed in fewer expansions; near obstacles the search is unchanged. ``()``:
        never. On the 30 + 30 random queries of ``experiments/coverage.py`` with
        reverse, ``(2, 4)`` cut the median expansions from 110 / 174 to 58 / 125.
    curvatures : int
        Number of steering curvatures, odd, spread evenly over
        ``[-kappa_search, kappa_search]`` (the middle one straight).
    radius_factor : float
        The search's primitives and analytic shots turn with radius
        ``radius_factor / kappa_max`` (>= 1: a little room below the car's limit).
    reverse_cost : float
        Cost per metre driven in reverse, as a multiple of a forward metre (>= 1).
    gear_change_cost : float
        Cost of a change of gear (a cusp), in metres.
    steer_change_cost : float
        Cost of a change of steering curvature between consecutive primitives, in
        metres per ``kappa_max`` of change (keeps the path from zig-zagging).
    steer_cost : float
        Cost per metre driven with curvature ``kappa_max``, scaled by ``|kappa| / kappa_max``.
    heuristic_weight : float
        Weight ``w >= 1`` of the heuristic in ``f = g + w h`` (1: admissible
        heuristic, near-optimal paths; more: fewer expansions) of the first search
        and the coarse one. 2: on the 30 + 30 random queries of
        ``experiments/coverage.py`` with reverse, the median expansions fell from
        58 / 125 (1.5) to 52 / 98 at the same median lengths (a car that must turn
        round first expands every heading near the start before the heuristic pulls
        it on; a larger weight leaves that plateau sooner).
    retry_weight : float
        The weight of the searches that run where the first one failed (the finer,
        tight and wide ones: tight spots). Greedier searches there hug the obstacles,
        and the ramps of their connections then cut into the clearance: random start
        7 forward, keeping 0.05 m, had all 16 connections rejected at weight 2 and
        its first accepted at 1.5; the parallel-parking gaps' finer searches needed
        804 expansions (median of 10 seeds) at 2 and 451 at 1.5.
    reeds_shepp_heuristic : bool
        With reverse, also take the Reeds-Shepp length into the heuristic (as the
        Dubins length is forward). Off by default: on the first 10 random goals of
        ``experiments/random_goals.py`` it cost 2.3x the time (22.1 vs 9.6 s in all,
        median 196 vs 121 expansions), each call about 0.2 ms.
    switch_after : int
        Expansions of the search from the start before a query still open is
        searched from the goal back to the start with the rest of the budget (0:
        never). From the goal, a tight bay or a goal against a wall is a way out;
        forward only, a search from the goal that runs out of states proves that
        no forward drive can arrive.
    shot_interval : int
        Largest number of expansions between analytic shots at the goal.
    shot_distance : float
        Shots are tried every ``clip(h / shot_distance, 1, shot_interval)``
        expansions, ``h`` the node's heuristic in metres: every expansion near the goal.
    shot_cell, shot_bin : float
        No shot is tried from a pose in the same ``shot_cell`` metres square and
        ``shot_bin`` radians heading bin as a pose whose shots all failed: its words
        run into the same obstacles (0: shoot every time; the searches after a
        failure, in tight spots, always do: random start 34 of ``coverage.py --count
        100``, forward, lost its only connection to it). On the 30 + 30 random
        queries of ``experiments/coverage.py`` (interleaved, CPU time) 2 m / 20 deg
        cut the median time to 0.75 / 0.96 (reverse goals / starts) and 0.69 / 0.93
        (forward), with the same median expansions and lengths.
    body_clearance : float
        Distance the body keeps from every obstacle along the path (exact test),
        capped per query at the clearance of the start and goal poses themselves.
    check_spacing : float
        Largest gap between the poses given to the body test, metres.
    sample_spacing : float
        Largest gap between the returned path's samples, metres.
    curve : str
        What the returned segments are: ``"clothoid"`` (default) gives every gear
        segment continuous curvature within the sharpness bound (each jump of the
        arcs' steering angle becomes a ramp at the bound, the arcs' lengths and
        angles re-fitted so the segment ends exactly on its pose:
        :func:`~rrtdrive.planning.hybrid.ramps.ramped_segment`); a connection that
        cannot be made so, or collides once made so, is rejected and the search goes
        on. ``"arcs"``: the search's exact arcs (curvature jumps where two meet),
        with ``smooth`` and ``arc_fallback``, for comparison.
    smooth : bool
        With ``curve="arcs"``: try to smooth each gear segment into a B-spline
        with the improved planner's post-processor
        (:func:`~rrtdrive.planning.smoothing.make_drivable`). Off by default: on
        ``parking_lot`` its heading legs and swept-capsule edge test rejected the
        search's segments near obstacles (4 of 4 tried), at 50-140 ms each.
    ramp_chunks : bool
        With ``curve="clothoid"``: a gear segment whose whole fit fails is fitted
        again a stretch of 20 m or more at a time
        (:func:`~rrtdrive.planning.hybrid.ramp_chunks.ramped_in_chunks`): on long
        segments the whole fit strays metres from the checked arcs. ``False``: the
        whole fit alone (before session 39).
    arc_fallback : bool
        When a segment cannot be smoothed, keep its exact arcs (curvature
        piecewise constant, ``|kappa| <= kappa_max``, body checked exactly), as the
        Dubins fallback does; ``False``: such a path is rejected and the search goes on.
    max_solutions : int
        Goal connections tried (each one found by a shot and rejected by the
        smoothing or the ramps) before the search gives up.
    ramp_margin : float
        With ``curve="clothoid"``: when ``max_solutions`` ramped connections were
        rejected (the ramps cut a tight corner too close), the query is searched
        again with the rest of the budget keeping this much more body clearance
        (capped at the start's and goal's own); 0: no second search.
    refinements : int
        When a search ends without a path but with budget left (it ran out of
        states, or every goal connection was rejected), the query is searched again
        with the rest of the expansion budget at half the position cell, heading bin
        and primitive step, up to this many times (0: never). Tight gaps need it: in
        ``parallel-parking`` the gaps below about 1.59 car lengths (21 of 100 seeds)
        are not reachable at 0.5 m / 5 deg / 1 m steps (the car cannot leave a gap
        0.3 m deep behind it by 1 m steps) and are at 0.25 m / 2.5 deg / 0.5 m.
        A failure is "proven unreachable" only at the finest resolution tried.
    refine_share : float
        Share of the expansions left that each search of the ladder may spend when a
        later one (a finer, the snug or the tight search) may still follow it, in
        ``(0, 1]``; the last one gets the rest. Default 0.5: forward-only random start 34 of
        ``coverage.py --count 100`` (0.152 m clearance at the pose) has its first
        search run out of states in 3 expansions; the finer one keeping 0.15 m then
        needs 34 776 expansions, the tight one (0.05 m) 3 626, so with all the rest
        the finer one spent the 20 000 and the tight one never ran. The gear
        scenarios' plans (100 seeds each) are the same as with 1.
    coarse_after : float
        Share of the expansion budget the first search may spend; when it has spent
        it without a path (and without running out of states), the rest goes to a
        search at ``coarse_factor`` times the cell, heading bin and step (no finer
        retry after it; 0 or 1: never). Long forward-only drives need it: a car that
        must loop round on ``parking_lot`` expands 20 000 states at 0.5 m / 5 deg and
        still has no path, and finds one in 229-4 264 expansions at 2 m / 20 deg /
        4 m (6 of the 30 + 30 random queries of ``experiments/coverage.py``). A
        failure of the coarse search proves nothing (status ``no_path_in_budget``).
    coarse_factor : int
        How much coarser that search is (>= 2; its heading bin is capped at pi/4).
        When the coarse search ends without a path and with budget left, a search at
        half its factor (:meth:`middled`, when that is > 1) and then the tight one
        at that resolution spend the rest.
    min_clearance : float
        When the searches keeping ``body_clearance`` run out of states (a proof for
        paths that keep it), a search at the finest resolution keeps half-way between
        the two (the snug one; a kerbside gap of 1.4 car lengths parks keeping 0.10 m)
        and then one at the first resolution keeps only this much
        (``>= body_clearance``: never). A start pose with room around it but
        less ahead needs it: random start 7 of ``experiments/coverage.py`` (0.20 m
        clearance) cannot drive forward keeping 0.15 m, or 0.10 m, and can keeping
        0.05 m (230 expansions); OMPL's planners keep none.
    tight_radius_factor : float
        The searches keeping less than ``body_clearance`` (the snug and tight ones)
        turn with radius ``tight_radius_factor / kappa_max`` (``>= 1``; above
        ``radius_factor`` it has no effect): the car's own full lock by default. Their connections'
        steering ramps have less room there, so they may reject four times
        ``max_solutions``. OMPL's Dubins RRT turns at that radius: on the random
        sets of ``experiments/coverage.py`` (seed 2, forward only) it solved 6 goals
        and 6 starts that ours could not at 1.02 (session 22, ``docs/coverage_all.md``).
    wide_radius_factor : float
        When the first search ends with every goal connection rejected
        (``rejected``), a search at the first resolution turns with radius
        ``wide_radius_factor / kappa_max`` (``<= radius_factor``: never), before the
        finer ones (since session 13: a kerbside gap of 2.5 car lengths then takes
        652 expansions instead of 2 714). The
        ramps of a word of full-lock arcs need steering beyond ``delta_max`` to end on
        its pose: random goals 39 and 92 of ``coverage.py --count 100`` (with
        reverse) had all 32 connections' ramps fail at 1.02 and solve at 1.1 in 4 and
        1 expansions.
    turn_moves : int
        With reverse, when the search from the start has spent its first
        ``switch_after`` expansions without a path, a multi-point turn from the start
        is tried (:func:`~rrtdrive.planning.hybrid.turn.multi_point_turn`: full-lock
        moves forward and in reverse by turns, each followed by a shot at the goal),
        with at most this many moves each way round (0: never); where the turned car
        stands near the goal but no shot clears, a short search from it finishes
        (``switch_after`` expansions, the wide stage's radius). Each move and each
        finishing expansion counts as an expansion. A closed street 6.5 m wide, the
        goal the start turned round (``experiments/street_turns.py``): the search alone
        needs 24 482 expansions (more than the budget gives it); the turn, 6 moves.
    shortcut_tries : int
        After a connection is accepted, up to this many (anchor, anchor) pairs along it
        are tried for a shorter analytic word between them
        (:func:`~rrtdrive.planning.hybrid.shortcut.shortcut`); the shortened connection
        is built and checked like any other and kept only when accepted and shorter.
        0 (default): never.
    stub_tries : int
        With reverse, a path whose first or last gear segment is a stub (at most
        :data:`~rrtdrive.planning.hybrid.shortcut.STUB_M`) is tried without it: up to
        this many anchor poses at each end
        (:func:`~rrtdrive.planning.hybrid.shortcut.drop_end_stubs`), the result built
        and checked like any connection and kept when it costs less (length plus
        0.5 m a gear change). 0: never.
    abreast_turns : int
        With reverse, when the multi-point turn from the start fails and the goal
        faces more than 100 deg away from the start's heading (the car turns round), it
        is tried again, without its finishing search, from up to this many points on the
        straight drive from the start to abreast of the goal and near it
        (:func:`~rrtdrive.planning.hybrid.turn.abreast`; 0: never). Angled bays at
        45 deg off a 5 m aisle, entered against the row
        (``experiments/angled_bays.py``): 5 260 expansions and 91.5 m without, 417
        and 43.9 m with.
    lead_ins : int
        Where the goal (or, for the search from the goal, the start) is boxed in, so
        that both full-lock arcs out of it hit within 2 m, the shots also aim at this
        many points 1 m apart on the straight drive out of it and append the straight
        (:func:`~rrtdrive.planning.hybrid.leads.lead_ins`; 0: never). Leaving one
        garage bay for another across a 6 m aisle: 8 426 expansions without, 20 with
        (``experiments/garage_moves.py``).
    nudge_ends : bool
        After the searches proved the query unreachable on their lattice, search once
        more from the start and goal turned by a fraction of a degree over one step
        where that opens their straight drive out (:mod:`~rrtdrive.planning.hybrid.nudge`:
        a goal turned 0.46 deg in a slot 0.35 m wider than the car; ``False``: never).
    persist : bool
        When the first search had every goal connection rejected and so had the
        wider-turning and finer searches after it, search once more at the finest
        resolution, going on through rejected connections until the budget ends
        (``False``: stop there, with the rest of the budget unspent).
    lattice_after : int
        When the searches of one resolution have spent this many expansions (both
        ways together) without a path, both are guided from then on by the cost to go
        over a coarse lattice of poses with obstacles and headings
        (:class:`~rrtdrive.planning.hybrid.lattice.HeadingLattice`, built once per map,
        as set-up), the larger of it and their own estimate (0: never). A query the
        search answers sooner is unchanged.
    lattice_cell : float
        The lattice's cell side, metres (larger on a big map: ``lattice_nodes``).
    lattice_headings : int
        The lattice's heading steps per turn (4 to 72); its moves turn by one.
    lattice_nodes : int
        Most lattice nodes (cells x headings x gears, at most 5 000 000); a bigger map
        gets coarser cells.

    Examples
    --------
    >>> HybridConfig().step
    1.0
    >>> HybridConfig(curvatures=4)
    Traceback (most recent call last):
    ...
    rrtdrive.types.InputError: hybrid.curvatures: must be an odd integer >= 1, got 4
    """

    xy_resolution: float = 0.5
    yaw_resolution: float = math.radians(5.0)
    step: float = 1.0
    long_steps: tuple[float, ...] = (2.0, 4.0)
    curvatures: int = 5
    radius_factor: float = 1.02
    reverse_cost: float = 2.0
    gear_change_cost: float = 5.0
    steer_change_cost: float = 1.0
    steer_cost: float = 0.1
    heuristic_weight: float = 2.0
    retry_weight: float = 1.5
    reeds_shepp_heuristic: bool = False
    switch_after: int = 400
    shot_interval: int = 5
    shot_distance: float = 4.0
    shot_cell: float = 2.0
    shot_bin: float = math.radians(20.0)
    body_clearance: float = 0.15
    check_spacing: float = 0.1
    sample_spacing: float = 0.25
    curve: str = "clothoid"
    smooth: bool = False
    ramp_chunks: bool = True
    arc_fallback: bool = True
    max_solutions: int = 16
    ramp_margin: float = 0.1
    refinements: int = 1
    refine_share: float = 0.5
    coarse_after: float = 0.25
    coarse_factor: int = 4
    min_clearance: float = 0.05
    wide_radius_factor: float = 1.1
    tight_radius_factor: float = 1.0
    shortcut_tries: int = 0
    stub_tries: int = 12
    turn_moves: int = 12
    abreast_turns: int = 4
    lead_ins: int = 3
    nudge_ends: bool = True
    persist: bool = True
    lattice_after: int = 800
    lattice_cell: float = 0.5
    lattice_headings: int = 16
    lattice_nodes: int = 300_000

    def __post_init__(self) -> None:
        for name in (
            "xy_resolution", "yaw_resolution", "step", "shot_distance", "shot_bin",
            "check_spacing", "sample_spacing",
        ):  # fmt: skip
            require_positive(f"hybrid.{name}", getattr(self, name))
        # Bounds that keep the primitives' and shots' sampled arrays in memory: a
        # primitive is sampled every check_spacing metres, a turn's length is its radius's.
        for name in ("check_spacing", "sample_spacing"):
            if getattr(self, name) < MIN_SPACING_M:
                raise InputError(
                    f"hybrid.{name}: must be at least {MIN_SPACING_M:g} m, "
                    f"got {getattr(self, name)!r}"
                )
        if self.step <= self.xy_resolution * math.sqrt(2.0):
            diagonal = self.xy_resolution * math.sqrt(2.0)
            # Named by the field the user changed (a default is nobody's typo).
            if self.step == HybridConfig.step and self.xy_resolution != HybridConfig.xy_resolution:
                raise InputError(
                    f"hybrid.xy_resolution: the cell diagonal ({diagonal:.3f} m) must be "
                    f"shorter than the step ({self.step:g} m), got {self.xy_resolution!r}"
                )
            raise InputError(
                f"hybrid.step: must exceed the cell diagonal {diagonal:.3f} m, got {self.step!r}"
            )
        if self.shot_bin > math.pi:  # a heading bin wider than half a turn: degrees, surely
            raise InputError(
                f"hybrid.shot_bin: must be at most pi (radians), got {self.shot_bin!r}"
            )
        if self.yaw_resolution > math.pi / 4:
            raise InputError(
                f"hybrid.yaw_resolution: must be at most pi/4, got {self.yaw_resolution!r}"
            )
        if (
            isinstance(self.curvatures, bool)
            or not isinstance(self.curvatures, int)
            or self.curvatures < 1
            or self.curvatures % 2 == 0
        ):
            raise InputError(
                f"hybrid.curvatures: must be an odd integer >= 1, got {self.curvatures!r}"
            )
        turns = MAX_RADIUS_FACTOR  # a turn's samples grow with its radius
        for name, low, high in (
            ("radius_factor", 1.0, turns), ("reverse_cost", 1.0, math.inf),
            ("heuristic_weight", 1.0, math.inf), ("retry_weight", 1.0, math.inf),
            ("wide_radius_factor", 1.0, turns), ("tight_radius_factor", 1.0, turns),
        ):  # fmt: skip
            value = getattr(self, name)
            require_finite(f"hybrid.{name}", value)
            if value < low:
                raise InputError(f"hybrid.{name}: must be >= {low:g}, got {value!r}")
            if value > high:
                raise InputError(f"hybrid.{name}: must be at most {high:g}, got {value!r}")
        for name in (
        "gear_change_cost", "steer_change_cost", "steer_cost", "body_clearance", "ramp_margin",
        "min_clearance", "shot_cell",
    ):  # fmt: skip
            value = getattr(self, name)
            require_finite(f"hybrid.{name}", value)
            if value < 0:
                raise InputError(f"hybrid.{name}: must be >= 0, got {value!r}")
        if not isinstance(self.long_steps, tuple) or any(
            isinstance(f, bool)
            or not isinstance(f, (int, float))
            or not math.isfinite(f)
            or f <= 1.0
            for f in self.long_steps
        ):
            raise InputError(
                f"hybrid.long_steps: must be a tuple of finite multiples of step > 1, "
                f"got {self.long_steps!r}"
            )
        if self.curve not in CURVES:
            raise InputError(
                f"hybrid.curve: must be one of {', '.join(CURVES)}, got {self.curve!r}"
            )
        require_int("hybrid.shot_interval", self.shot_interval)
        require_int("hybrid.max_solutions", self.max_solutions)
        require_int("hybrid.switch_after", self.switch_after, minimum=0)
        require_int("hybrid.refinements", self.refinements, minimum=0)
        require_int("hybrid.shortcut_tries", self.shortcut_tries, minimum=0)
        require_int("hybrid.stub_tries", self.stub_tries, minimum=0)
        require_int("hybrid.turn_moves", self.turn_moves, minimum=0)
        require_int("hybrid.abreast_turns", self.abreast_turns, minimum=0)
        require_int("hybrid.lead_ins", self.lead_ins, minimum=0)
        require_int("hybrid.coarse_factor", self.coarse_factor, minimum=2, maximum=64)
        require_int("hybrid.lattice_after", self.lattice_after, minimum=0)
        require_int("hybrid.lattice_headings", self.lattice_headings, minimum=4, maximum=72)
        require_int("hybrid.lattice_nodes", self.lattice_nodes, minimum=1, maximum=5_000_000)
        require_positive("hybrid.lattice_cell", self.lattice_cell)
        require_finite("hybrid.refine_share", self.refine_share)
        if not 0.0 < self.refine_share <= 1.0:
            raise InputError(f"hybrid.refine_share: must lie in (0, 1], got {self.refine_share!r}")
        require_finite("hybrid.coarse_after", self.coarse_after)
        if not 0.0 <= self.coarse_after <= 1.0:
            raise InputError(
                f"hybrid.coarse_after: must be within [0, 1], got {self.coarse_after!r}"
            )
        # After coarse_factor and coarse_after: the coarse search's step is coarse_factor
        # times this one (its own config, with no coarse stage, is checked as given).
        factor = self.coarse_factor if self.coarsens else 1
        if self.step * factor > MAX_STEP_M:
            within = f" / coarse_factor = {MAX_STEP_M / factor:g} m" if factor > 1 else " m"
            raise InputError(
                f"hybrid.step: must be at most {MAX_STEP_M:g}{within}, got {self.step!r}"
            )
        for name in ("smooth", "arc_fallback", "reeds_shepp_heuristic", "persist"):
            if not isinstance(getattr(self, name), bool):
                raise InputError(
                    f"hybrid.{name}: expected true or false, got {getattr(self, name)!r}"
                )

    @property
    def least_clearance(self) -> float:
        """The least body clearance any of its searches keeps, metres (before the ends' cap)."""
        return min(self.body_clearance, self.min_clearance)

    def refined(self) -> HybridConfig:
        """The next finer search: half the cell, heading bin and step, one refinement fewer.

        Examples
        --------
        >>> fine = HybridConfig().refined()
        >>> fine.xy_resolution, fine.step, fine.yaw_bins, fine.refinements
        (0.25, 0.5, 144, 0)
        """
        return dataclasses.replace(
            self._scaled(0.5, refinements=max(0, self.refinements - 1)), **self._retry()
        )

    def tightened(self) -> HybridConfig:
        """The last search: :attr:`min_clearance` kept, no finer or coarser one after it.

        It turns at :attr:`tight_radius_factor` and may reject
        :data:`TIGHT_SOLUTIONS_FACTOR` times :attr:`max_solutions` connections (at full
        lock the ramps' re-fit has the least room).

        Examples
        --------
        >>> tight = HybridConfig().tightened()
        >>> tight.body_clearance, tight.xy_resolution, tight.refinements, tight.coarsens
        (0.05, 0.5, 0, False)
        >>> tight.radius_factor, tight.max_solutions
        (1.0, 64)
        """
        return self._last(
            body_clearance=self.min_clearance,
            radius_factor=min(self.radius_factor, self.tight_radius_factor),
            max_solutions=TIGHT_SOLUTIONS_FACTOR * self.max_solutions,
        )

    def widened(self) -> HybridConfig:
        """The last search after rejected connections: :attr:`wide_radius_factor`'s turns.

        Examples
        --------
        >>> HybridConfig().widened().radius_factor, HybridConfig().widened().refinements
        (1.1, 0)
        """
        return self._last(radius_factor=self.wide_radius_factor)

    @property
    def coarsens(self) -> bool:
        """Whether the first search hands the rest of its budget to a coarser one."""
        return 0.0 < self.coarse_after < 1.0

    def coarsened(self) -> HybridConfig:
        """The coarser search: ``coarse_factor`` times the cell, bin and step; last of all.

        Examples
        --------
        >>> coarse = HybridConfig().coarsened()
        >>> coarse.xy_resolution, coarse.step, coarse.yaw_bins, coarse.refinements
        (2.0, 4.0, 18, 0)
        >>> coarse.coarsens
        False
        """
        return self._scaled(float(self.coarse_factor), refinements=0)

    @property
    def has_middle(self) -> bool:
        """Whether a failed coarse search is followed by :meth:`middled`'s (factor > 2)."""
        return self.coarsens and self.coarse_factor > 2

    def middled(self) -> HybridConfig:
        """The search between the first and the coarse one: ``coarse_factor / 2`` times theirs.

        It runs when the coarse search ends without a path and without spending the
        rest (its proof holds at its resolution only): a goal whose only approach
        passes 0.05-0.15 m from a parked car (random goal 94 of ``coverage.py
        --count 100``, forward) is out of reach at 2 m / 20 deg, and its tight search
        at 1 m / 10 deg / 2 m steps finds the way in 4 301 expansions where the first
        resolution's spent 60 000 without one. Last of all, like :meth:`coarsened`'s.

        Examples
        --------
        >>> mid = HybridConfig().middled()
        >>> mid.xy_resolution, mid.step, mid.yaw_bins, mid.refinements, mid.coarsens
        (1.0, 2.0, 36, 0, False)
        """
        return dataclasses.replace(
            self._scaled(self.coarse_factor / 2.0, refinements=0), **self._retry()
        )

    def _scaled(self, factor: float, refinements: int) -> HybridConfig:
        """Cell, heading bin (at most pi/4) and step times ``factor``; no coarse stage."""
        return dataclasses.replace(
            self,
            xy_resolution=self.xy_resolution * factor,
            yaw_resolution=min(self.yaw_resolution * factor, math.pi / 4),
            step=self.step * factor,
            refinements=refinements,
            coarse_after=0.0,
        )

    def _last(self, **changes: float | int) -> HybridConfig:
        """``changes`` applied, and no finer or coarser search after this one."""
        return dataclasses.replace(
            self, refinements=0, coarse_after=0.0, **{**self._retry(), **changes}
        )

    def _retry(self) -> dict[str, Any]:
        """What a search after a failure changes: :attr:`retry_weight`, every shot tried."""
        return {"heuristic_weight": self.retry_weight, "shot_cell": 0.0}

    @property
    def yaw_bins(self) -> int:
        """Number of heading bins over a full turn.

        Examples
        --------
        >>> HybridConfig().yaw_bins
        72
        """
        return max(1, round(2.0 * math.pi / self.yaw_resolution))


def hybrid_with(base: HybridConfig, changes: Mapping[str, object], owner: str) -> HybridConfig:
    """``base`` with ``changes``; errors name the field as ``<owner>.<field>``.

    ``owner``: where the config sits, ``"planner"`` for ``hybrid-a-star``'s own (its
    fields are the planner's options) or ``"planner.hybrid"`` for the improved
    planner's escalation.

    Examples
    --------
    >>> hybrid_with(HybridConfig(), {"gear_change_cost": 10.0}, "planner.hybrid").gear_change_cost
    10.0
    >>> hybrid_with(HybridConfig(), {"gear_cost": 1}, "planner.hybrid")  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    rrtdrive.types.InputError: planner.hybrid.gear_cost: unknown field of HybridConfig ...
    """
    whose = "option for hybrid-a-star" if owner == "planner" else "field of HybridConfig"
    check_known(changes, [f.name for f in dataclasses.fields(HybridConfig)], owner, whose)
    try:
        return dataclasses.replace(base, **changes)  # type: ignore[arg-type]
    except InputError as exc:
        # HybridConfig names its fields "hybrid.<field>"; nested, say whose they are.
        if owner == "planner":
            raise
        raise InputError(f"planner.{exc}") from None
