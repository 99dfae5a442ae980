"""Configuration of the improved RRT-Connect: :class:`ImprovedConfig` and its component names."""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

from rrtdrive.planning.hybrid.config import HybridConfig, hybrid_with
from rrtdrive.planning.improved.fallback import MAX_FALLBACK_CANDIDATES
from rrtdrive.planning.options import MAX_RADIUS_FACTOR, check_known, check_step
from rrtdrive.planning.smoothing import SmoothingConfig, smoothing_with
from rrtdrive.types import InputError, require_finite, require_int
from rrtdrive.values import did_you_mean

__all__ = [
    "NAME",
    "BEYOND_PAPER",
    "COMPONENTS",
    "ESCALATION_FIRST",
    "SMOOTHING_COMPONENTS",
    "PER_QUERY_SMOOTHING",
    "ImprovedConfig",
    "StageBudgets",
    "default_smoothing",
]

#: The planner's registered name.
NAME = "improved-rrt-connect"

#: Names of the switchable components, for ablations and the CLI.
COMPONENTS: tuple[str, ...] = (
    "direct_connect",
    "obtuse_parent",
    "adaptive_step",
    "obstacle_expansion",
    "prune",
    "sharp_repair",
    "supplement",
    "passage_sampling",
    "dubins_fallback",
    "escalation",
)

#: The components this planner adds to the paper's pipeline: off, with the degree-2
#: B-spline, it is the paper's (Table 3's arm: ``experiments/table3.py``).
BEYOND_PAPER: tuple[str, ...] = ("passage_sampling", "dubins_fallback", "escalation")

#: When the Hybrid A* escalation runs before the Dubins fallback
#: (:attr:`ImprovedConfig.escalation_first`).
ESCALATION_FIRST: tuple[str, ...] = ("reverse", "always", "never")

#: The components that are switches of the post-processor: fields of ``ImprovedConfig.smoothing``.
SMOOTHING_COMPONENTS: tuple[str, ...] = ("prune", "sharp_repair", "supplement")

#: Fields of :class:`SmoothingConfig` the planner sets per query: the car's ``kappa_max``
#: and ``wheelbase``, the step ``p`` as ``heading_leg`` and the capped ``body_clearance``
#: as ``clearance``. (``max_sharpness`` is the config's, or the car's
#: ``max_steer_rate / STEER_RATE_DESIGN_SPEED`` when that is smaller.)
PER_QUERY_SMOOTHING: tuple[str, ...] = ("kappa_max", "wheelbase", "heading_leg", "clearance")


def default_smoothing() -> SmoothingConfig:
    """The planner's post-processing defaults: :class:`SmoothingConfig` with 24 repair rounds.

    Examples
    --------
    >>> default_smoothing().max_rounds, default_smoothing().curve.value
    (24, 'clothoid')
    """
    return SmoothingConfig(max_rounds=24)


@dataclass(frozen=True)
class StageBudgets:
    """The RRT-Connect stages' counted budgets in one query (:meth:`ImprovedConfig.stage_budgets`).

    Attributes
    ----------
    iterations : int
        Growth iterations, over all pairs of trees.
    attempts : int
        Tree paths post-processed.
    candidates : int
        Dubins fallback joints tried as tails, and again as leads.
    root_patience : int
        Iterations a pair of trees may grow with its start or goal tree still only
        its root before the growth gives way (0: no limit).
    """

    iterations: int
    attempts: int
    candidates: int
    root_patience: int = 0


@dataclass(frozen=True)
class ImprovedConfig:
    """Parameters of :class:`ImprovedRRTConnect`, validated on construction.

    Parameters
    ----------
    step : float
        Unit step ``p`` in metres (paper: 5 m).
    direct_connect, obtuse_parent, adaptive_step : bool
        Components of :data:`COMPONENTS` (tree growth); all on by default.
    obstacle_expansion : bool
        Component of :data:`COMPONENTS` (obstacle expansion); on by default.
    passage_sampling : bool
        Beyond the paper: with probability ``passage_bias`` an iteration samples a
        point on a narrow passage's centre line (:func:`passage_cells`) and joins
        both trees to it by straight free edges. On by default (the tree growth of
        the paper alone rarely threads a gap barely wider than the car).
    dubins_fallback : bool
        Beyond the paper: when no tree path can be made drivable (or the trees
        never meet), try the shortest Dubins paths from the start pose to the goal
        pose (turning radius ``dubins_radius_factor / kappa_max``) and return the
        first that the exact body test clears with the body clearance. Solves goals
        that need a U-turn or a sharp approach in open space, which the tree paths
        with their straight legs cannot. On by default; it never runs when the
        paper's pipeline succeeds.
    escalation : bool
        Beyond the paper (issue 13): when the tree paths and the Dubins fallback
        fail (with reverse, before the fallback's tails and leads:
        ``escalation_first``; not for an invalid start or goal), run the Hybrid A* search
        (:func:`rrtdrive.planning.hybrid.escalate`; forward only, or reversing when
        ``problem.reverse``) with the query's iteration budget as its expansion
        budget and the time left as its cap, before reporting failure. On by
        default; it never runs when an earlier stage succeeds. Off for the paper's
        pipeline alone (``without("dubins_fallback", "escalation")``).
    rrt_share : float
        Beyond the paper (issue 13): with ``escalation`` on, the share of the
        growth iterations the RRT-Connect stages get before the escalation, in
        ``(0, 1]``: ``ceil(rrt_share * max_iterations)``; the escalation's Hybrid
        A* gets the iterations they left as its expansion budget
        (:meth:`stage_budgets`). Default 0.5 (10 000 of 20 000): the 50 seeds of
        every built-in map solve within it as with the whole budget (``narrow_gap``
        needs up to 6 023), while a growth whose trees never meet gives way sooner.
        1: the whole budget (the escalation then gets only what the growth left).
        Ignored with ``escalation`` off: the paper's pipeline alone keeps every budget.
    root_patience : int
        Beyond the paper: with ``escalation`` on, a pair of trees whose start or
        goal tree is still only its root after this many of the pair's iterations
        gives way to the next stage (0: never). A root grows only by edges within 90
        degrees of its pose's heading (the virtual parents), so a pose boxed in along it
        (a kerbside gap, a garage bay) leaves its tree a single node for the whole share: 128 of the
        129 pairs that failed on the 400 random queries and the 9 built-in maps x 20
        seeds x both gears (``kerbside``, ``garage``, ``reverse_bay``: 10 000
        iterations, ~140 ms each), while of the 1 428 pairs that met, the last root
        to grow did so after 3 503 iterations (``python experiments/root_growth.py
        --out results/root_growth_s18``). Default 4000. Where the boxing is provable
        before any iteration (:func:`~rrtdrive.planning.improved.boxed.root_boxed_in`),
        the growth does not start at all.
    narrow_fan, narrow_patience : float, int
        Beyond the paper, with ``root_patience`` on: a start or goal whose fan is
        narrow (less than ``narrow_fan`` of the directions within 90 degrees of its
        heading have room for a growth edge there,
        :func:`~rrtdrive.planning.improved.boxed.open_share`) gives way after
        ``narrow_patience`` iterations instead (0.22 and 400 by default; 0 for
        ``narrow_fan`` turns it off). Over the 760 queries of
        ``results/root_growth_s18`` (``python experiments/root_fans.py
        results/root_growth_s18/root_growth.json --out results/root_fans_s19``) the 128
        roots of failed pairs that never grew in 10 000 iterations (garage bays,
        kerbside, reverse_bay, random goals and starts 11 and 34) had at most 0.198 of
        their fan open, and the 2 986 roots that grew at least 0.241: 0.22 lies between.
        400 is above the 99th percentile of when roots grow (349).
    escalation_fallback_joints : int
        With ``escalation`` on, the Dubins fallback's tree nodes tried as tail
        joints, and again as lead joints (>= 0; without the escalation
        ``MAX_FALLBACK_CANDIDATES`` = 64). Default 7: each joint costs ~70 ms
        (clothoid-rounded Dubins words at six radii), so 64 + 64 took most of a
        failing query's time before the escalation; of the fallback solutions of
        ``parking_lot``'s 60 random queries all but one came within 7 (that one is
        then solved by the Hybrid A*; docs/coverage_all.md).
        The ``max_postprocess_attempts`` tree paths are all tried either way.
        Counts, not time: the stage that solves is the same on any machine.
    reverse_postprocess_attempts : int
        With ``escalation`` on and reversing allowed, the tree paths post-processed
        before the escalation (>= 1, at most ``max_postprocess_attempts``). Default
        1, the paper's pipeline (one pair of trees, one tree path): a query it
        solves is solved as before; one it does not goes to the Hybrid A* search with
        Reeds-Shepp shots, which on ``parking_lot``'s 30 + 30 random queries solved
        every query the tree paths 2-6 did (5 of 6 shorter) in a fraction of the
        time those tree paths took on the queries they did not solve
        (docs/planning.md).
    escalation_first : str
        When the Hybrid A* escalation runs before the Dubins fallback's tails and
        leads (after its direct Dubins path; the tails and leads then run only if
        the escalation fails): ``"reverse"`` (default) for queries that allow
        reversing, ``"always"`` or ``"never"`` (the whole fallback first, the order
        before session 8). With reverse the search's Reeds-Shepp shots reach what the
        tails and leads reach, mostly shorter, sooner: on ``parking_lot``'s 30 + 30
        random queries of ``experiments/coverage.py`` the tails and leads took
        85-92 % of the time before the escalation on the escalated queries
        (docs/planning.md). The direct Dubins path stays first: forward, without a
        cusp, cheap, and in stock ``parking-v0`` most of the fallback's solutions.
        Forward only, the whole fallback stays first.
    dubins_radius_factor : float
        Turning radius of the fallback's arcs as a multiple of ``1 / kappa_max``
        (>= 1; default 1.05, a little room for tracking).
    reverse_detour_ratio : float
        With reverse allowed, the direct Dubins path is kept before the escalation
        only when at most this multiple of the Reeds-Shepp distance (the shortest
        path with reversing at the same radius, obstacles aside); a longer one (a
        goal 0.1 m ahead and 1 mm aside: a 61 m loop forward, 8 m reversing) is
        kept only when the escalation finds nothing that costs less as its search
        weighs a path. ``inf`` keeps it always.
    reverse_detour_tree : bool
        Whether that rule also applies to the tree path (the paper's stage) with
        reverse allowed, the path measured against the distance around the obstacles
        too (default since session 37: a 186 m forward loop round the lot gives way
        to a 76 m path with one cusp; docs/planning.md). ``False``
        keeps the paper stage's answer as found, as before. Forward only it changes
        nothing.
    passage_bias : float
        Share of iterations that sample passages, in ``[0, 1)``.
    expansion_a : float
        Growth ``a`` of an expanded rectangle's length and width in metres.
    expansion_lmin : float or None
        ``L_min`` in metres; ``None`` means :func:`default_expansion_lmin`
        (``W + 2 margin + sqrt(2) a``, 3.41 m for the paper's car), the smallest
        value that never narrows a gap the car's edge test could pass through.
    max_postprocess_attempts : int
        Tree paths tried before giving up with ``POSTPROCESS_FAILED``; after a
        failed post-processing the trees are grown afresh.
    body_clearance : float
        Distance in metres the car's body must keep from every obstacle along
        the final path (exact test), so that tracking error and a simulator's
        look-ahead collision test have room. Capped per query at the clearance
        the start and goal poses themselves have, so a car parked close to a
        wall can still leave and arrive.
    smoothing : SmoothingConfig
        The post-processor (Sec. 3.2, :func:`default_smoothing`): the components
        ``prune``, ``sharp_repair`` and ``supplement`` (:data:`SMOOTHING_COMPONENTS`),
        the ``curve`` (``CurveKind.CLOTHOID``, continuous curvature with the
        steering rate per metre bounded by ``max_sharpness``, default; or
        ``CurveKind.BSPLINE``, the paper's), the spline ``degree`` (2, paper, or 3),
        Eq. 16's ``supplement_delta`` and
        ``supplement_n``, ``max_rounds`` fit-check-repair rounds per tree path (24)
        and the sampling and fillet settings. Its :data:`PER_QUERY_SMOOTHING`
        fields are set per query and must keep their defaults here.
    hybrid : HybridConfig
        The escalation's Hybrid A* search (default ``HybridConfig()``): its grid, steps,
        costs (``gear_change_cost``, ``reverse_cost``: also how a forward detour is
        weighed against the escalation's path) and the searches after the first.

    Examples
    --------
    >>> ImprovedConfig(step=4.0).step
    4.0
    >>> ImprovedConfig(step=-1.0)
    Traceback (most recent call last):
    ...
    rrtdrive.types.InputError: planner.step: must be > 0, got -1.0
    >>> ImprovedConfig().without("prune").smoothing.prune
    False
    """

    step: float = 5.0
    direct_connect: bool = True
    obtuse_parent: bool = True
    adaptive_step: bool = True
    obstacle_expansion: bool = True
    passage_sampling: bool = True
    dubins_fallback: bool = True
    escalation: bool = True
    rrt_share: float = 0.5
    root_patience: int = 4000
    narrow_fan: float = 0.22
    narrow_patience: int = 400
    escalation_fallback_joints: int = 7
    reverse_postprocess_attempts: int = 1
    escalation_first: str = "reverse"
    dubins_radius_factor: float = 1.05
    reverse_detour_ratio: float = 1.5
    reverse_detour_tree: bool = True
    passage_bias: float = 0.1
    expansion_a: float = 1.0
    expansion_lmin: float | None = None
    max_postprocess_attempts: int = 6
    body_clearance: float = 0.15
    smoothing: SmoothingConfig = field(default_factory=default_smoothing)
    hybrid: HybridConfig = field(default_factory=HybridConfig)

    def __post_init__(self) -> None:
        check_step(self.step)
        for name, kind in (("smoothing", SmoothingConfig), ("hybrid", HybridConfig)):
            if not isinstance(getattr(self, name), kind):
                got = type(getattr(self, name)).__name__
                raise InputError(f"planner.{name}: expected a {kind.__name__}, got {got}")
        for name in COMPONENTS:
            value = self.enabled(name)
            if not isinstance(value, bool):
                raise InputError(f"planner.{_path(name)}: expected true or false, got {value!r}")
        untouched = SmoothingConfig()
        for name in PER_QUERY_SMOOTHING:
            if getattr(self.smoothing, name) != getattr(untouched, name):
                raise InputError(
                    f"planner.smoothing.{name}: set per query (from the car, planner.step and "
                    f"planner.body_clearance); leave it at its default"
                )
        require_finite("planner.rrt_share", self.rrt_share)
        if not 0.0 < self.rrt_share <= 1.0:
            raise InputError(f"planner.rrt_share: must lie in (0, 1], got {self.rrt_share!r}")
        require_int("planner.escalation_fallback_joints", self.escalation_fallback_joints, 0)
        require_int("planner.root_patience", self.root_patience, 0)
        require_finite("planner.narrow_fan", self.narrow_fan)
        if not 0.0 <= self.narrow_fan <= 1.0:
            raise InputError(f"planner.narrow_fan: must lie in [0, 1], got {self.narrow_fan!r}")
        require_int("planner.narrow_patience", self.narrow_patience, 1)
        require_int("planner.reverse_postprocess_attempts", self.reverse_postprocess_attempts)
        if self.escalation_first not in ESCALATION_FIRST:
            raise InputError(
                f"planner.escalation_first: must be one of {', '.join(ESCALATION_FIRST)}, "
                f"got {self.escalation_first!r}"
            )
        require_finite("planner.passage_bias", self.passage_bias)
        require_finite("planner.dubins_radius_factor", self.dubins_radius_factor)
        if not 1.0 <= self.dubins_radius_factor <= MAX_RADIUS_FACTOR:
            raise InputError(
                f"planner.dubins_radius_factor: must lie in [1, {MAX_RADIUS_FACTOR:g}], "
                f"got {self.dubins_radius_factor!r}"
            )
        if self.reverse_detour_ratio != math.inf:  # inf: the direct Dubins path always first
            require_finite("planner.reverse_detour_ratio", self.reverse_detour_ratio)
        if self.reverse_detour_ratio < 1.0:
            raise InputError(
                f"planner.reverse_detour_ratio: must be >= 1, got {self.reverse_detour_ratio!r}"
            )
        if not isinstance(self.reverse_detour_tree, bool):
            raise InputError(
                f"planner.reverse_detour_tree: expected true or false, "
                f"got {self.reverse_detour_tree!r}"
            )
        if not 0.0 <= self.passage_bias < 1.0:
            raise InputError(f"planner.passage_bias: must lie in [0, 1), got {self.passage_bias!r}")
        require_finite("planner.expansion_a", self.expansion_a)
        if self.expansion_a < 0:
            raise InputError(f"planner.expansion_a: must be >= 0, got {self.expansion_a!r}")
        if self.expansion_lmin is not None:
            require_finite("planner.expansion_lmin", self.expansion_lmin)
            if self.expansion_lmin < 0:
                raise InputError(
                    f"planner.expansion_lmin: must be >= 0, got {self.expansion_lmin!r}"
                )
        require_finite("planner.body_clearance", self.body_clearance)
        if self.body_clearance < 0:
            raise InputError(
                f"planner.body_clearance: must be >= 0, got {self.body_clearance!r}"
            )
        require_int("planner.max_postprocess_attempts", self.max_postprocess_attempts)

    def stage_budgets(self, max_iterations: int, reverse: bool = False) -> StageBudgets:
        """The RRT-Connect stages' counted budgets for a query of ``max_iterations``.

        With ``escalation`` on, ``rrt_share`` of the iterations (rounded up),
        ``escalation_fallback_joints`` joints and every tree path, or
        ``reverse_postprocess_attempts`` of them when the query may reverse; off,
        every budget in full.

        Parameters
        ----------
        max_iterations : int
            The query's iteration budget.
        reverse : bool
            The query may change gear.

        Returns
        -------
        StageBudgets

        Examples
        --------
        >>> ImprovedConfig().stage_budgets(20_000)
        StageBudgets(iterations=10000, attempts=6, candidates=7, root_patience=4000)
        >>> ImprovedConfig().stage_budgets(20_000, reverse=True)
        StageBudgets(iterations=10000, attempts=1, candidates=7, root_patience=4000)
        >>> ImprovedConfig(escalation=False).stage_budgets(20_000, reverse=True)
        StageBudgets(iterations=20000, attempts=6, candidates=64, root_patience=0)
        """
        if not self.escalation:
            return StageBudgets(max_iterations, self.max_postprocess_attempts,
                                MAX_FALLBACK_CANDIDATES)  # fmt: skip
        attempts = self.max_postprocess_attempts
        if reverse:
            attempts = min(attempts, self.reverse_postprocess_attempts)
        return StageBudgets(
            iterations=min(max_iterations, math.ceil(self.rrt_share * max_iterations)),
            attempts=attempts,
            candidates=min(self.escalation_fallback_joints, MAX_FALLBACK_CANDIDATES),
            root_patience=self.root_patience,
        )

    def escalates_first(self, reverse: bool) -> bool:
        """Whether a query (reversing or not) runs the escalation before the Dubins fallback.

        Parameters
        ----------
        reverse : bool
            The query may change gear.

        Returns
        -------
        bool

        Examples
        --------
        >>> ImprovedConfig().escalates_first(True), ImprovedConfig().escalates_first(False)
        (True, False)
        >>> ImprovedConfig(escalation_first="never").escalates_first(True)
        False
        """
        return self.escalation_first == "always" or (
            self.escalation_first == "reverse" and bool(reverse)
        )

    def enabled(self, component: str) -> bool:
        """Whether the named component of :data:`COMPONENTS` is on.

        Parameters
        ----------
        component : str
            A name of :data:`COMPONENTS` (a smoothing one is read from :attr:`smoothing`).

        Returns
        -------
        bool

        Raises
        ------
        InputError
            For a name not in :data:`COMPONENTS`.

        Examples
        --------
        >>> ImprovedConfig().enabled("prune"), ImprovedConfig(obtuse_parent=False).enabled(
        ...     "obtuse_parent")
        (True, False)
        """
        _check_components((component,))
        owner = self.smoothing if component in SMOOTHING_COMPONENTS else self
        return getattr(owner, component)

    def without(self, *components: str) -> ImprovedConfig:
        """A copy with the named components switched off.

        Parameters
        ----------
        *components : str
            Names of :data:`COMPONENTS` (smoothing ones are switched off in :attr:`smoothing`).

        Returns
        -------
        ImprovedConfig

        Raises
        ------
        InputError
            For a name not in :data:`COMPONENTS`.

        Examples
        --------
        >>> cfg = ImprovedConfig().without("prune", "obtuse_parent")
        >>> cfg.smoothing.prune, cfg.obtuse_parent
        (False, False)
        """
        _check_components(components)
        mine: dict[str, Any] = {
            name: False for name in components if name not in SMOOTHING_COMPONENTS
        }
        theirs: dict[str, Any] = {
            name: False for name in components if name in SMOOTHING_COMPONENTS
        }
        if theirs:
            mine["smoothing"] = dataclasses.replace(self.smoothing, **theirs)
        return dataclasses.replace(self, **mine)

    def with_options(self, options: Mapping[str, object]) -> ImprovedConfig:
        """A copy with config fields replaced; ``smoothing``, ``hybrid``: mappings of fields too.

        A mapping is applied over this config's :attr:`smoothing`, so
        ``{"smoothing": {"max_rounds": 8}}`` changes only the rounds. Errors name
        the option, e.g. ``planner.smoothing.degree``.

        Parameters
        ----------
        options : mapping of str to object
            Field names of :class:`ImprovedConfig` and their new values.

        Returns
        -------
        ImprovedConfig

        Raises
        ------
        InputError
            For an unknown option or a bad value.

        Examples
        --------
        >>> cfg = ImprovedConfig().with_options({"step": 4.0, "smoothing": {"degree": 3}})
        >>> cfg.step, cfg.smoothing.degree, cfg.smoothing.max_rounds
        (4.0, 3, 24)
        """
        fields = [f.name for f in dataclasses.fields(ImprovedConfig)]
        check_known(options, fields, "planner", "option for improved-rrt-connect")
        changes = dict(options)
        smoothing, hybrid = changes.get("smoothing"), changes.get("hybrid")
        if isinstance(smoothing, Mapping):
            changes["smoothing"] = smoothing_with(self.smoothing, smoothing)
        if isinstance(hybrid, Mapping):
            changes["hybrid"] = hybrid_with(self.hybrid, hybrid, "planner.hybrid")
        return dataclasses.replace(self, **changes)  # type: ignore[arg-type]


def _path(component: str) -> str:
    """Where a component lives in the config, for error messages."""
    return f"smoothing.{component}" if component in SMOOTHING_COMPONENTS else component


def _check_components(components: tuple[str, ...]) -> None:
    for name in components:
        if name not in COMPONENTS:
            raise InputError(
                f"planner.disable: unknown component {name!r}{did_you_mean(name, COMPONENTS)}; "
                f"choose from {', '.join(COMPONENTS)}"
            )
