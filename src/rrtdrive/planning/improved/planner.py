"""The improved RRT-Connect planner: one query as a sequence of named steps.

:class:`ImprovedRRTConnect` runs the shared preamble
(:func:`~rrtdrive.planning.result.run_query`), then :class:`_Query`: the direct
connection, the growth checker, the passage cells, the growth and smoothing of
up to ``max_postprocess_attempts`` tree paths, the Dubins fallback, the
Hybrid A* escalation and the failure. With the escalation on, the RRT-Connect
stages run on ``rrt_share`` of the growth iterations and ``escalation_fallback_joints``
fallback joints (:meth:`ImprovedConfig.stage_budgets`) and the escalation on the
iterations left (it is the planner's only way to reverse). With reverse allowed
(:meth:`ImprovedConfig.escalates_first`): ``reverse_postprocess_attempts`` tree
paths, the direct Dubins path, the escalation, then the fallback's tails and leads.
"""

from __future__ import annotations

import dataclasses
import functools
import math
import time
from collections.abc import Iterable

import numpy as np

from rrtdrive.collision import CollisionChecker
from rrtdrive.planning.base import PlanningProblem, Stopwatch, register_planner
from rrtdrive.planning.diagnosis import Diagnosis
from rrtdrive.planning.hybrid.escalation import ESCALATES_FROM, escalate, with_kept_clearance
from rrtdrive.planning.hybrid.probe import reverse_probe
from rrtdrive.planning.improved import ending
from rrtdrive.planning.improved.boxed import boxed_end, open_share, stuck_root_words
from rrtdrive.planning.improved.config import NAME, ImprovedConfig, StageBudgets
from rrtdrive.planning.improved.detour import DETOURS, detour_words, measured_detour, shorter_answer
from rrtdrive.planning.improved.expansion import (
    default_expansion_lmin,
    endpoint_capped_clearance,
    expanded_checker,
)
from rrtdrive.planning.improved.growth import (
    EdgeFree,
    ObtuseTree,
    fast_edge_test,
    grow_until_meet,
    rooted_edge_test,
)
from rrtdrive.planning.result import run_query, solved, straight_ahead_result
from rrtdrive.planning.sampling import SampleSource
from rrtdrive.planning.smoothing import make_drivable
from rrtdrive.planning.smoothing.config import smoothing_for_car
from rrtdrive.types import Budget, InputError, Path, PlanResult, PlanStatus, Tree

__all__ = ["NAME", "ImprovedRRTConnect"]


@register_planner(NAME)
class ImprovedRRTConnect:
    """Improved RRT-Connect (paper Sec. 3) returning only drivable, verified paths.

    Parameters
    ----------
    config : ImprovedConfig, optional
        Full configuration; keyword ``options`` override its fields.
    disable : iterable of str, optional
        Components of :data:`COMPONENTS` to switch off.
    **options
        Any :class:`ImprovedConfig` field, e.g. ``step=4.0`` or ``adaptive_step=False``;
        ``smoothing`` may be a mapping of :class:`SmoothingConfig` fields applied
        over the config's own, e.g. ``smoothing={"degree": 3, "prune": False}``
        (see :meth:`ImprovedConfig.with_options`).

    Raises
    ------
    InputError
        For an unknown option or component, or an invalid value (the message names it).

    Examples
    --------
    >>> from rrtdrive.maps import builtin_map
    >>> from rrtdrive.planning.base import PlanningProblem
    >>> from rrtdrive.types import Budget
    >>> planner = ImprovedRRTConnect(disable=("obstacle_expansion",))
    >>> res = planner.solve(PlanningProblem.from_map(builtin_map("overtake")),
    ...                     np.random.default_rng(0), Budget())
    >>> res.success, bool(res.path.max_curvature <= 1 / 6)
    (True, True)
    """

    name = NAME
    reverses: bool = True  #: It honours ``PlanningProblem.reverse`` (without the escalation: no)

    def __init__(
        self,
        config: ImprovedConfig | None = None,
        *,
        disable: Iterable[str] = (),
        **options: object,
    ) -> None:
        base = config if config is not None else ImprovedConfig()
        if not isinstance(base, ImprovedConfig):
            raise InputError(
                f"planner.config: expected an ImprovedConfig, got {type(base).__name__}"
            )
        cfg = base.with_options(options) if options else base
        if isinstance(disable, str):
            disable = (disable,)
        if not isinstance(disable, Iterable):
            raise InputError(
                f"planner.disable: expected component names, got {type(disable).__name__}"
            )
        self.config = cfg.without(*disable)
        self.reverses = self.config.escalation

    def __repr__(self) -> str:
        return f"ImprovedRRTConnect({self.config!r})"

    def solve(
        self, problem: PlanningProblem, rng: np.random.Generator, budget: Budget
    ) -> PlanResult:
        """Plan from ``problem.start`` to ``problem.goal``; never returns ``None``.

        Parameters
        ----------
        problem : PlanningProblem
            Map, checker, start and goal.
        rng : numpy.random.Generator
            The only source of randomness.
        budget : Budget
            The iteration budget decides the growth (each post-processing is
            bounded by ``smoothing.max_rounds``, the Dubins fallback by its
            candidate count); with the escalation on, the RRT-Connect stages get
            ``rrt_share`` of the iterations and ``escalation_fallback_joints``
            candidates, and the Hybrid A* escalation the iterations left as
            expansions. Reaching the safety cap ``max_time_s`` ends the query as ``timeout``.

        Returns
        -------
        PlanResult
            ``SOLVED`` with a verified path, or a failure status with a message.
            ``stats`` holds ``nodes``, ``iterations``, ``growth_time_s``,
            ``postprocess_time_s``, ``postprocess_attempts``, ``repair_rounds``,
            ``direct_connection``, ``expanded_obstacles``, ``expansion_used``,
            ``rrt_iterations`` (the stages' iteration budget); after an escalation
            ``rrt_stages_time_s`` and ``escalation_time_s``; when solved by the
            tree path, ``key_points``, ``control_points``, ``max_curvature``
            (exact, of the whole curve) and the repair counters ``fillets``,
            ``merges``, ``moves``, ``drops``, ``unprunes`` and ``edge_checks``;
            solved, ``body_clearance_m`` (:func:`~.escalation.with_kept_clearance`).
        """
        # Built on first use, so that run_query has checked the problem before it is read.
        query = functools.cache(lambda: _Query(problem, self.config))
        def run(watch: Stopwatch) -> PlanResult:
            return with_kept_clearance(query().run(rng, budget, watch), query().smoothing.clearance)

        def probe() -> Diagnosis | None:
            return reverse_probe(problem, self.config.hybrid, query().smoothing, budget.max_time_s)

        return run_query(
            NAME, problem, budget, run, lambda: query().prepare(), rng=rng,
            tree_edges=not self.config.escalation,  # Hybrid A* searches without them
            probe=probe if self.config.escalation else None, reverses=self.reverses,
            keeps=self._least_clearance(),
        )

    def _least_clearance(self) -> float:
        """The least body clearance its paths keep: its own, or its escalation's less."""
        own = self.config.body_clearance
        return min(own, self.config.hybrid.least_clearance) if self.config.escalation else own


class _Query:
    """Working state of one query: its settings, counters and the tree paths tried."""

    def __init__(self, problem: PlanningProblem, cfg: ImprovedConfig) -> None:
        self.problem = problem
        self.cfg = cfg
        self.watch: Stopwatch  # set by run(), before any stage reads it
        self._growth: tuple[CollisionChecker, EdgeFree, np.ndarray | None] | None = None
        self._growth_stats: dict[str, float] = {}
        self.checker = checker = problem.checker
        self.start, self.goal = start, goal = problem.start, problem.goal
        # The config's post-processor with the query's PER_QUERY_SMOOTHING fields.
        self.smoothing = smoothing_for_car(
            cfg.smoothing, problem.vehicle, heading_leg=cfg.step,
            clearance=endpoint_capped_clearance(checker, start, goal, cfg.body_clearance),
        )  # fmt: skip
        self.stats: dict[str, float] = {
            "nodes": 0.0,
            "iterations": 0.0,
            "growth_time_s": 0.0,
            "postprocess_time_s": 0.0,
            "postprocess_attempts": 0.0,
            "repair_rounds": 0.0,
            "direct_connection": 0.0,
            "expanded_obstacles": 0.0,
            "expansion_used": 0.0,
        }
        self.s_xy = np.array([start.x, start.y])
        self.g_xy = np.array([goal.x, goal.y])
        self.hs = np.array([math.cos(start.yaw), math.sin(start.yaw)])
        self.hg = np.array([math.cos(goal.yaw), math.sin(goal.yaw)])
        self.last_message = ""
        self.last_raw: np.ndarray | None = None
        self.failed_raws: list[np.ndarray] = []
        self.fallback_tried = ""  # "direct": the direct Dubins path alone; "all"
        self.iterations = 0
        self.stuck_root = ""  # "start" / "goal": that tree never left its root (root_patience)
        self.root_proof = False  # stuck_root proven before any iteration (root_boxed_in)
        self.patience = 0  # the pairs' root_patience (narrow_patience for a narrow fan)
        self.limits: StageBudgets  # the stages' counted budgets, set per query by run()
        self.trees: tuple[Tree, ...] = (
            Tree(self.s_xy[None, :], np.array([-1])),
            Tree(self.g_xy[None, :], np.array([-1])),
        )

    def prepare(self) -> None:
        """Per-map set-up before the stopwatch starts: the growth checker and its passages.

        Both are cached on the map's checker, so only a map's first query pays for them.
        """
        grow, edge_free, self._growth_stats = self.growth_edge_test()
        self._growth = (grow, edge_free, self.passages(grow))

    def run(self, rng: np.random.Generator, budget: Budget, watch: Stopwatch) -> PlanResult:
        """The steps in order; the first that solves the query ends it."""
        self.watch = watch
        self.limits = limits = self.cfg.stage_budgets(budget.max_iterations, self.problem.reverse)
        self.stats["rrt_iterations"] = float(limits.iterations)
        out = self.direct_connection()
        if out is not None:
            return out
        if self._growth is None:
            self.prepare()
        assert self._growth is not None  # prepare() made it
        _, edge_free, passages = self._growth
        # The expansion counters describe the growth: they count once the query grows trees.
        self.stats.update(self._growth_stats)
        samples = SampleSource(self.problem, reject=True)
        out = self.grow_and_smooth(rng, budget, edge_free, samples, passages)
        if out is not None:
            if self.problem.reverse and self.cfg.reverse_detour_tree and self.escalates_first:
                return self.shortened(out, budget, "tree path")
            return out
        self.stats["iterations"] = float(self.iterations)
        self.stats["growth_time_s"] = self.watch.elapsed() - self.stats["postprocess_time_s"]
        # The safety cap cut the growth short: a timeout (no fallback, whose answer
        # would depend on how far the growth got on this machine).
        fallback = self.cfg.dubins_fallback and not self.watch.capped
        if self.escalates_first:
            # With reverse: the direct Dubins path (cheap, forward, no cusp), then the
            # Hybrid A* search (Reeds-Shepp shots), which answers sooner than the
            # fallback's tails and leads (~70 ms a joint); those only after it.
            if fallback:
                out = self.fallback(joints=False)
                if out is not None:
                    return self.shortened(out, budget, "direct Dubins path")
            out = self.escalation(budget)
            if out.success or not fallback or out.status not in ESCALATES_FROM:
                return out
            if self.watch.capped:
                return self.failure()
            return self.fallback(escalated=out, direct=False) or self.fallback_failed(out)
        if fallback:
            out = self.fallback()
            if out is not None:
                return out
        if self.cfg.escalation:
            return self.escalation(budget)
        return self.failure()

    @property
    def escalates_first(self) -> bool:
        """Whether the escalation runs before the Dubins fallback's tails and leads."""
        return self.cfg.escalation and self.cfg.escalates_first(self.problem.reverse)

    def shortened(self, out: PlanResult, budget: Budget, kind: str) -> PlanResult:
        """``out``, or the escalation's shorter path when ``out`` is a forward detour.

        A detour is longer than ``reverse_detour_ratio`` times the Reeds-Shepp distance
        at the fallback's radius and, for a tree path, the distance around the obstacles
        (:data:`~.detour.DETOURS`, :func:`~.detour.measured_detour`); the escalation's
        timeout is its own answer (what it finds depends on the machine's speed).
        """
        stat, with_obstacles = DETOURS[kind]
        length, limit = out.path.length, self.cfg.reverse_detour_ratio
        radius = self.cfg.dubins_radius_factor / self.problem.vehicle.kappa_max
        watch = self.watch if with_obstacles else None  # None: the Reeds-Shepp distance alone
        ratio, around = measured_detour(length, self.problem, radius, limit, watch, self.cfg.hybrid)
        self.stats[stat] = out.stats[stat] = ratio  # the kept answer says it too
        if ratio <= limit:
            return out
        escalated = self.escalation(budget, detour_words(kind, length, ratio, around))
        if escalated.status is PlanStatus.TIMEOUT:
            return escalated
        elapsed, hybrid = self.watch.elapsed(), self.cfg.hybrid
        return shorter_answer(escalated, out, elapsed, self.problem.reverse, hybrid)

    def escalation(self, budget: Budget, before: str | None = None) -> PlanResult:
        """The Hybrid A* escalation on the iterations the RRT-Connect stages left.

        ``before``: what those stages left, when not a failure (see :func:`escalate`).
        """
        watch, hybrid = self.watch, self.cfg.hybrid
        t_rrt = self.stats["rrt_stages_time_s"] = watch.elapsed()
        failed = self.failure()
        left = budget.max_iterations - self.iterations
        if left < 1:  # the growth spent the whole budget (rrt_share 1)
            return failed
        rest = dataclasses.replace(budget, max_iterations=left)
        out = escalate(failed, self.problem, rest, watch, self.smoothing,
                       config=hybrid, before=before)  # fmt: skip
        if out is not failed:
            out.stats["escalation_time_s"] = watch.elapsed() - t_rrt
        return out

    def smooth(
        self, raw: np.ndarray, trees: tuple[Tree, ...], iterations: int
    ) -> PlanResult | None:
        """Post-process one tree path (Sec. 3.2); the solved result, or ``None`` on failure."""
        stats = self.stats
        t0 = time.perf_counter()
        res = make_drivable(raw, self.start, self.goal, self.checker, self.smoothing)
        stats["postprocess_time_s"] += time.perf_counter() - t0
        stats["postprocess_attempts"] += 1
        stats["repair_rounds"] += res.rounds
        self.last_raw = raw
        if not res.ok:
            self.last_message = res.message
            self.failed_raws.append(raw)
            return None
        stats["iterations"] = float(iterations)
        stats["key_points"] = float(len(res.key_points))
        stats["control_points"] = float(len(res.control_points))
        stats["max_curvature"] = res.max_curvature
        if not math.isnan(res.max_sharpness):
            stats["max_sharpness"] = res.max_sharpness
        stats.update(res.stats)
        elapsed = self.watch.elapsed()
        stats["growth_time_s"] = elapsed - stats["postprocess_time_s"]
        if self.smoothing.clothoid:
            message = (
                f"solved: {len(res.key_points)} key points, {int(res.stats['fillets'])} "
                f"clothoid turns, {res.rounds} fit round(s)"
            )
        else:
            message = (
                f"solved: {len(res.key_points)} key points, {len(res.control_points)} "
                f"control points, {res.rounds} fit round(s)"
            )
        path = Path(res.samples, res.control_points)
        return solved(
            NAME, self.watch, path, raw, trees, iterations, message, stats,
            planning_time_s=elapsed,
        )  # fmt: skip

    def direct_connection(self) -> PlanResult | None:
        """Direct connection (Sec. 3.1.1): smooth the straight start-goal edge if it serves.

        It serves when it is free and both headings point along it (within 90
        degrees), so that the curve need not turn back.
        """
        s_xy, g_xy = self.s_xy, self.g_xy
        chord = g_xy - s_xy
        headings_allow = float(self.hs @ chord) > 0.0 and float(self.hg @ chord) > 0.0
        if not (
            self.cfg.direct_connect
            and headings_allow
            and self.checker.edge_free(s_xy.tolist(), g_xy.tolist())
        ):
            return None
        self.stats["direct_connection"] = 1.0
        self.stats["nodes"] = 2.0
        out = self.smooth(np.vstack([s_xy, g_xy]), self.trees, 0)
        # A goal a hair ahead is too close for the heading legs and turns.
        clearance = self.smoothing.clearance
        return out or straight_ahead_result(NAME, self.problem, self.watch, clearance, self.stats)

    def growth_edge_test(self) -> tuple[CollisionChecker, EdgeFree, dict[str, float]]:
        """The growth checker, its edge test (Sec. 3.1.4) and the expansion counters.

        The checker of the expanded obstacles when both end poses are free in it;
        its edge test checks edges at the roots on the map itself. The counters are
        ``expanded_obstacles`` and ``expansion_used`` (both 0 without expansion).
        """
        cfg, checker = self.cfg, self.checker
        stats = {"expanded_obstacles": 0.0, "expansion_used": 0.0}
        start, goal = self.start, self.goal
        grow = checker
        if cfg.obstacle_expansion and cfg.expansion_a > 0:
            lmin = cfg.expansion_lmin
            if lmin is None:
                lmin = default_expansion_lmin(
                    self.problem.vehicle.width, checker.config.margin, cfg.expansion_a
                )
            expanded, count = expanded_checker(checker, cfg.expansion_a, lmin)
            stats["expanded_obstacles"] = float(count)
            if expanded is not None and (
                expanded.pose_free(start.as_tuple()) and expanded.pose_free(goal.as_tuple())
            ):
                grow = expanded
                stats["expansion_used"] = 1.0
        edge_free = fast_edge_test(grow)
        if grow is not checker:
            # Edges at the roots are checked on the map itself: the expansion is to keep
            # the tree off obstacles on its way, never to shut the start or goal in.
            edge_free = rooted_edge_test(
                edge_free, fast_edge_test(checker), (start.x, start.y), (goal.x, goal.y)
            )
        return grow, edge_free, stats

    def passages(self, grow: CollisionChecker) -> np.ndarray | None:
        """The passage cells of the growth checker, ``None`` when off or there are none."""
        cfg = self.cfg
        if not (cfg.passage_sampling and cfg.passage_bias > 0):
            return None
        cells = grow.passage_cells((self.start.x, self.start.y))
        return cells if len(cells) else None

    def grow_and_smooth(
        self,
        rng: np.random.Generator,
        budget: Budget,
        edge_free: EdgeFree,
        samples: SampleSource,
        passages: np.ndarray | None,
    ) -> PlanResult | None:
        """Grow a pair of trees until they meet, then smooth their tree path.

        A tree path that cannot be made drivable starts a fresh pair of trees (up
        to the stages' ``attempts``; all ``iterations`` together are at most theirs).
        """
        cfg, stats, p = self.cfg, self.stats, self.cfg.step
        boxed = self.boxed_root()
        if boxed:
            # Proven before any iteration (boxed.root_boxed_in): no edge at that root can
            # ever pass, so the pair would only wait out root_patience for nothing.
            self.stuck_root, self.root_proof = boxed, True
            stats["stuck_root"] = stats["root_boxed_in"] = 1.0
            return None
        self.patience = self.root_patience()
        total_nodes = 0
        while stats["postprocess_attempts"] < self.limits.attempts:
            ts = ObtuseTree(self.s_xy, virtual_parent=self.s_xy - p * self.hs)
            tg = ObtuseTree(self.g_xy, virtual_parent=self.g_xy + p * self.hg)
            found, self.iterations = grow_until_meet(
                ts, tg, samples, rng, edge_free,
                step=p, obtuse=cfg.obtuse_parent, adaptive=cfg.adaptive_step,
                passages=passages, passage_bias=cfg.passage_bias,
                iterations=self.iterations, max_iterations=self.limits.iterations,
                expired=self.watch.expired, root_patience=self.patience,
            )  # fmt: skip
            self.trees = (ts.freeze(), tg.freeze())
            total_nodes += len(ts) + len(tg)
            stats["nodes"] = float(total_nodes)
            if found is None:
                if self.iterations < self.limits.iterations and not self.watch.expired():
                    # root_patience: a root never grew (the budget was not spent).
                    self.stuck_root = "start" if len(ts) == 1 else "goal"
                    stats["stuck_root"] = 1.0
                return None
            out = self.smooth(found, self.trees, self.iterations)
            if out is not None:
                return out
        return None

    def boxed_root(self) -> str:
        """``"start"`` or ``"goal"`` when that root provably cannot grow, else ``""``.

        Only beyond the paper (``root_patience`` on) and with the obtuse parents, whose
        virtual parents keep a root's edges within 90 degrees of its heading.
        """
        if self.limits.root_patience <= 0 or not self.cfg.obtuse_parent:
            return ""
        return boxed_end(self.checker, self.start, self.goal)

    def root_patience(self) -> int:
        """The pairs' patience: ``narrow_patience`` when the start's or goal's fan is narrow.

        ``stats["start_open_share"]`` and ``stats["goal_open_share"]`` are the fans'
        open shares (:func:`~rrtdrive.planning.improved.boxed.open_share`),
        ``stats["narrow_root"]`` 1 when either is below ``narrow_fan``.
        """
        cfg, patience = self.cfg, self.limits.root_patience
        if patience <= 0 or not cfg.obtuse_parent or cfg.narrow_fan <= 0.0:
            return patience
        for end, pose in (("start", self.start), ("goal", self.goal)):
            self.stats[f"{end}_open_share"] = open_share(self.checker, pose)
        if min(self.stats["start_open_share"], self.stats["goal_open_share"]) >= cfg.narrow_fan:
            return patience
        self.stats["narrow_root"] = 1.0
        return min(patience, cfg.narrow_patience)

    def stuck_words(self) -> str:
        """Why the stuck root's tree never grew, for the messages."""
        end = self.stuck_root
        share = self.stats[f"{end}_open_share"] if self.stats.get("narrow_root") else None
        return stuck_root_words(end, self.root_proof, self.patience, share)

    def fallback(
        self, escalated: PlanResult | None = None, *, direct: bool = True, joints: bool = True
    ) -> PlanResult | None:
        """Beyond the paper: the Dubins fallback over the failed tree paths, newest first.

        ``direct``: try the direct Dubins path; ``joints``: the tails and leads.
        ``escalated``: the failed Hybrid A* escalation it runs after (with reverse,
        :meth:`ImprovedConfig.escalates_first`), whose counts and stats it keeps.
        """
        return ending.fallback_result(self, escalated, direct=direct, joints=joints)

    def fallback_failed(self, escalated: PlanResult) -> PlanResult:
        """The failed escalation's result, saying that the Dubins fallback after it failed too."""
        return ending.fallback_failed(self, escalated)

    def failure(self) -> PlanResult:
        """The honest failure: the safety cap, post-processing failed, or no path in the budget."""
        return ending.failure_result(self)
