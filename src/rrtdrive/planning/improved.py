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
baselines' :class:`~rrtdrive.planning.rrt.SampleSource`).

Post-processing (Sec. 3.2, :mod:`rrtdrive.planning.smoothing`): pruning,
sharp-angle repair, control-point supplement, a clamped uniform B-spline and the
guarantee loop (headings at both ends, ``|kappa| <= kappa_max``, exact body clear
of the *original* map). A tree path that cannot be made drivable is dropped and
the trees are grown afresh, up to ``max_postprocess_attempts`` times.

Every component is switchable by name, see :data:`COMPONENTS`::

    ImprovedRRTConnect()                                  # everything on
    ImprovedRRTConnect(disable=("obtuse_parent",))        # ablation by name
    ImprovedRRTConnect(adaptive_step=False, step=4.0)     # or any config field
    ImprovedRRTConnect(ImprovedConfig(prune=False))       # or a whole config

Through the registry: ``make_planner("improved-rrt-connect", disable=["prune"])``.
"""

from __future__ import annotations

import dataclasses
import math
import time
import weakref
from collections.abc import Callable, Iterable, Sequence
from dataclasses import dataclass

import numpy as np

from rrtdrive.collision import CollisionChecker
from rrtdrive.maps import Obstacle
from rrtdrive.planning.base import (
    GrowingTree,
    PlanningProblem,
    Stopwatch,
    failure,
    precheck,
    register_planner,
)
from rrtdrive.planning.dubins import DubinsPath, dubins_paths
from rrtdrive.planning.rrt import SampleSource
from rrtdrive.planning.smoothing import SmoothingConfig, make_drivable
from rrtdrive.types import (
    Budget,
    InputError,
    Path,
    PlanResult,
    PlanStatus,
    Pose,
    Tree,
    require_finite,
    require_int,
    require_positive,
)

__all__ = [
    "COMPONENTS",
    "dubins_fallback",
    "ImprovedConfig",
    "ImprovedRRTConnect",
    "ObtuseTree",
    "expand_obstacles",
    "envelope_gaps",
    "expanded_checker",
    "default_expansion_lmin",
    "passage_cells",
    "extend",
    "fast_edge_test",
    "greedy_connect",
    "link",
    "link_candidates",
]

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
)

NAME = "improved-rrt-connect"


@dataclass(frozen=True)
class ImprovedConfig:
    """Parameters of :class:`ImprovedRRTConnect`, validated on construction.

    Parameters
    ----------
    step : float
        Unit step ``p`` in metres (paper: 5 m).
    direct_connect, obtuse_parent, adaptive_step : bool
        Components of :data:`COMPONENTS` (tree growth); all on by default.
    obstacle_expansion, prune, sharp_repair, supplement : bool
        Components of :data:`COMPONENTS` (expansion and post-processing); all on.
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
    dubins_radius_factor : float
        Turning radius of the fallback's arcs as a multiple of ``1 / kappa_max``
        (>= 1; default 1.05, a little room for tracking).
    passage_bias : float
        Share of iterations that sample passages, in ``[0, 1)``.
    expansion_a : float
        Growth ``a`` of an expanded rectangle's length and width in metres.
    expansion_lmin : float or None
        ``L_min`` in metres; ``None`` means :func:`default_expansion_lmin`
        (``W + 2 margin + sqrt(2) a``, 3.41 m for the paper's car), the smallest
        value that never narrows a gap the car's edge test could pass through.
    spline_degree : int
        2 (paper) or 3.
    supplement_delta : float
        Eq. 16 threshold ``delta`` in metres.
    supplement_n : float
        Eq. 16 distance multiple ``N`` in ``(0, 1)``.
    max_postprocess_attempts : int
        Tree paths tried before giving up with ``POSTPROCESS_FAILED``; after a
        failed post-processing the trees are grown afresh.
    max_repair_rounds : int
        Fit-check-repair rounds per tree path.
    body_clearance : float
        Distance in metres the car's body must keep from every obstacle along
        the final path (exact test), so that tracking error and a simulator's
        look-ahead collision test have room. Capped per query at the clearance
        the start and goal poses themselves have, so a car parked close to a
        wall can still leave and arrive.

    Examples
    --------
    >>> ImprovedConfig(step=4.0).step
    4.0
    >>> ImprovedConfig(step=-1.0)
    Traceback (most recent call last):
    ...
    rrtdrive.types.InputError: planner.step: must be > 0, got -1.0
    """

    step: float = 5.0
    direct_connect: bool = True
    obtuse_parent: bool = True
    adaptive_step: bool = True
    obstacle_expansion: bool = True
    prune: bool = True
    sharp_repair: bool = True
    supplement: bool = True
    passage_sampling: bool = True
    dubins_fallback: bool = True
    dubins_radius_factor: float = 1.05
    passage_bias: float = 0.1
    expansion_a: float = 1.0
    expansion_lmin: float | None = None
    spline_degree: int = 2
    supplement_delta: float = 5.66
    supplement_n: float = 0.5
    max_postprocess_attempts: int = 6
    max_repair_rounds: int = 24
    body_clearance: float = 0.15

    def __post_init__(self) -> None:
        require_positive("planner.step", self.step)
        for name in COMPONENTS:
            value = getattr(self, name)
            if not isinstance(value, bool):
                raise InputError(f"planner.{name}: expected true or false, got {value!r}")
        require_finite("planner.passage_bias", self.passage_bias)
        require_finite("planner.dubins_radius_factor", self.dubins_radius_factor)
        if self.dubins_radius_factor < 1.0:
            raise InputError(
                f"planner.dubins_radius_factor: must be >= 1, got {self.dubins_radius_factor!r}"
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
        if isinstance(self.spline_degree, bool) or self.spline_degree not in (2, 3):
            raise InputError(f"planner.spline_degree: must be 2 or 3, got {self.spline_degree!r}")
        require_positive("planner.supplement_delta", self.supplement_delta)
        require_finite("planner.supplement_n", self.supplement_n)
        if not 0.0 < self.supplement_n < 1.0:
            raise InputError(f"planner.supplement_n: must lie in (0, 1), got {self.supplement_n!r}")
        require_finite("planner.body_clearance", self.body_clearance)
        if self.body_clearance < 0:
            raise InputError(
                f"planner.body_clearance: must be >= 0, got {self.body_clearance!r}"
            )
        for name in ("max_postprocess_attempts", "max_repair_rounds"):
            require_int(f"planner.{name}", getattr(self, name))

    def without(self, *components: str) -> ImprovedConfig:
        """A copy with the named components switched off.

        Examples
        --------
        >>> ImprovedConfig().without("prune", "supplement").prune
        False
        """
        for name in components:
            if name not in COMPONENTS:
                raise InputError(
                    f"planner.disable: unknown component {name!r}; choose from {list(COMPONENTS)}"
                )
        return dataclasses.replace(self, **{name: False for name in components})


# ----------------------------------------------------------------------------- expansion


def endpoint_capped_clearance(
    checker: CollisionChecker, start: Pose, goal: Pose, wanted: float
) -> float:
    """``wanted``, lowered to the exact body clearance of the start or goal pose if smaller.

    A path cannot keep more room than its own end poses have; asking for it
    would make a car parked near a wall unplannable.
    """
    if wanted <= 0.0:
        return 0.0
    have = min(checker.body_clearance(start.as_tuple()), checker.body_clearance(goal.as_tuple()))
    return max(0.0, min(wanted, have * 0.999))


def default_expansion_lmin(width: float, margin: float, a: float) -> float:
    """Default ``L_min = W + 2 margin + sqrt(2) a``.

    Growing a rectangle by ``a`` in length and width moves each of its points by
    at most ``a / sqrt(2)`` (a corner, diagonally), so two grown neighbours lose at
    most ``sqrt(2) a`` of their gap. A pair whose envelope circles are more than
    ``L_min`` apart (and so the rectangles too) keeps a gap above ``W + 2 margin``,
    the width of the swept disc of the edge test: no gap the car could use is closed.

    Examples
    --------
    >>> round(default_expansion_lmin(1.8, 0.1, 1.0), 3)
    3.414
    """
    return width + 2.0 * margin + math.sqrt(2.0) * a


def envelope_gaps(
    obstacles: Iterable[Obstacle], bounds: Iterable[float] | None = None
) -> np.ndarray:
    """``L2`` of each obstacle: the smallest gap between its envelope circle and any other's.

    The envelope circle is centred on the rectangle with radius half its diagonal.
    When ``bounds`` are given, the map boundary counts as an obstacle too (the gap
    from the circle to each side of the bounds box), so expansion never closes a
    passage along the map's edge.

    Returns
    -------
    numpy.ndarray
        One gap per obstacle (``inf`` for a lone obstacle without bounds).

    Examples
    --------
    >>> obs = [Obstacle((0.0, 0.0), (6.0, 8.0)), Obstacle((20.0, 0.0), (6.0, 8.0))]
    >>> envelope_gaps(obs).tolist()
    [10.0, 10.0]
    """
    obs = list(obstacles)
    if not obs:
        return np.zeros(0)
    c = np.array([o.center for o in obs], dtype=float)
    r = np.array([math.hypot(*o.size) / 2.0 for o in obs])
    d = np.hypot(c[:, None, 0] - c[None, :, 0], c[:, None, 1] - c[None, :, 1])
    gap = d - r[:, None] - r[None, :]
    np.fill_diagonal(gap, np.inf)
    out = gap.min(axis=1)
    if bounds is not None:
        xmin, ymin, xmax, ymax = (float(b) for b in bounds)
        wall = (
            np.minimum.reduce([c[:, 0] - xmin, xmax - c[:, 0], c[:, 1] - ymin, ymax - c[:, 1]]) - r
        )
        out = np.minimum(out, wall)
    return out


def expand_obstacles(
    obstacles: Iterable[Obstacle],
    a: float,
    lmin: float,
    bounds: Iterable[float] | None = None,
) -> tuple[tuple[Obstacle, ...], np.ndarray]:
    """Adaptive obstacle expansion (paper Sec. 3.1.4): grow by ``a`` where ``L2 > L_min``.

    Parameters
    ----------
    obstacles : iterable of Obstacle
        The map's rectangles.
    a : float
        Growth of length and width in metres.
    lmin : float
        Smallest allowed passing distance ``L_min``.
    bounds : iterable of float, optional
        Map bounds; the boundary then counts as an obstacle (see :func:`envelope_gaps`).

    Returns
    -------
    obstacles : tuple of Obstacle
        The rectangles, grown or as they were, in the same order.
    grown : numpy.ndarray
        Boolean flag per rectangle.

    Examples
    --------
    >>> obs = [Obstacle((0.0, 0.0), (6.0, 8.0)), Obstacle((20.0, 0.0), (6.0, 8.0))]
    >>> new, grown = expand_obstacles(obs, 1.0, 3.4)
    >>> new[0].size, grown.tolist()
    ((7.0, 9.0), [True, True])
    """
    obs = list(obstacles)
    gaps = envelope_gaps(obs, bounds)
    grown = gaps > lmin
    out = tuple(o.grown(a) if g else o for o, g in zip(obs, grown.tolist(), strict=True))
    return out, grown


_EXPANDED: dict[tuple[object, ...], tuple[CollisionChecker | None, int]] = {}


def expanded_checker(
    checker: CollisionChecker, a: float, lmin: float
) -> tuple[CollisionChecker | None, int]:
    """The checker of the expanded obstacles, built once per map and parameters.

    Returns ``(None, 0)`` when no obstacle grows (the original checker serves).
    The cache is module level, keyed by the bounds, obstacles, car, checker
    configuration, ``a`` and ``L_min``.
    """
    key = (
        checker.bounds,
        checker.obstacles,
        checker.vehicle,
        checker.config,
        float(a),
        float(lmin),
    )
    hit = _EXPANDED.get(key)
    if hit is not None:
        return hit
    new, grown = expand_obstacles(checker.obstacles, a, lmin, checker.bounds)
    count = int(grown.sum())
    result: tuple[CollisionChecker | None, int]
    if count == 0 or a == 0.0:
        result = (None, 0)
    else:
        result = (CollisionChecker(checker.bounds, new, checker.vehicle, checker.config), count)
    if len(_EXPANDED) > 16:
        _EXPANDED.clear()
    _EXPANDED[key] = result
    return result


_PASSAGES: weakref.WeakKeyDictionary[CollisionChecker, dict[int, np.ndarray]] = (
    weakref.WeakKeyDictionary()
)


def passage_cells(
    checker: CollisionChecker, start: Sequence[float], width: float = 0.6
) -> np.ndarray:
    """Centres of the grid cells on the centre lines of narrow passages reachable from ``start``.

    A cell qualifies when its clearance is a local maximum across some grid
    direction (a ridge of the distance field, i.e. the medial axis) with walls
    on both sides (one clearance away along that direction the clearance nearly
    vanishes) and lies between the edge test's radius ``W/2 + margin`` and that
    plus ``width``: an edge through it can pass, but only just. Wide aisles, the
    gaps between parked cars (too narrow), convex corners and open space do not
    qualify. Beyond the paper;
    medial-axis sampling after Wilmarth, Amato & Stiller (ICRA 1999). Cached per
    checker and start component.

    Parameters
    ----------
    checker : CollisionChecker
        The map's checker.
    start : sequence of float
        A point of the component to keep (the start position).
    width : float
        How much wider than the edge test a passage may be, in metres.

    Returns
    -------
    numpy.ndarray
        ``(K, 2)`` cell centres (possibly empty).

    Examples
    --------
    >>> from rrtdrive.maps import builtin_map
    >>> from rrtdrive.planning.base import cached_checker
    >>> cells = passage_cells(cached_checker(builtin_map("narrow_gap")), (10.0, 20.0))
    >>> bool(np.any((np.abs(cells[:, 0] - 50.0) < 1.0) & (np.abs(cells[:, 1] - 50.0) < 0.2)))
    True
    """
    labels = checker.component_labels
    origin, h = checker.grid_origin, checker.resolution
    i = int(math.floor((start[0] - origin[0]) / h))
    j = int(math.floor((start[1] - origin[1]) / h))
    inside = 0 <= i < labels.shape[0] and 0 <= j < labels.shape[1]
    label = int(labels[i, j]) if inside else 0
    per_checker = _PASSAGES.setdefault(checker, {})
    key = (label, float(width))
    cached = per_checker.get(hash(key))
    if cached is not None:
        return cached
    cl = checker.clearance_grid
    nx, ny = cl.shape
    band = (cl >= checker.edge_radius) & (cl <= checker.edge_radius + width)
    if label:
        band &= labels == label
    ridge = np.zeros(cl.shape, dtype=bool)
    inner = cl[1:-1, 1:-1]
    for di, dj in ((1, 0), (0, 1), (1, 1), (1, -1)):
        # A local maximum of the clearance across direction (di, dj) ...
        a = cl[1 + di : nx - 1 + di, 1 + dj : ny - 1 + dj]
        b = cl[1 - di : nx - 1 - di, 1 - dj : ny - 1 - dj]
        peak = np.zeros(cl.shape, dtype=bool)
        peak[1:-1, 1:-1] = (inner >= a) & (inner >= b) & (inner > np.minimum(a, b))
        cand = np.argwhere(peak & band)
        if len(cand) == 0:
            continue
        # ... with walls on both sides: one clearance away, either way, the
        # clearance nearly vanishes (it does not beside a convex corner).
        c = cl[cand[:, 0], cand[:, 1]]
        k = np.round(c / (math.hypot(di, dj) * h)).astype(np.int64)
        both = np.ones(len(cand), dtype=bool)
        for sgn in (1, -1):
            ii = np.clip(cand[:, 0] + sgn * k * di, 0, nx - 1)
            jj = np.clip(cand[:, 1] + sgn * k * dj, 0, ny - 1)
            both &= cl[ii, jj] <= 0.3 * c
        ridge[cand[both, 0], cand[both, 1]] = True
    ij = np.argwhere(ridge)
    cells = origin + (ij + 0.5) * h
    xmin, ymin, xmax, ymax = checker.bounds
    cells = cells[
        (cells[:, 0] > xmin) & (cells[:, 0] < xmax) & (cells[:, 1] > ymin) & (cells[:, 1] < ymax)
    ]
    per_checker[hash(key)] = cells
    return cells


# ----------------------------------------------------------------------------- tree growth

EdgeFree = Callable[[Sequence[float], Sequence[float]], bool]


class ObtuseTree(GrowingTree):
    """A :class:`GrowingTree` that keeps each node's parent position for Eq. 11.

    :meth:`choose_parent` returns the nearest node whose angle (parent, node, q)
    is obtuse -- ``D(q_i, q) + D(q_i, q_k) < D(q_k, q)`` with ``D`` the squared
    distance -- or the nearest node when none is obtuse (Table 1). The root's
    parent is the ``virtual_parent``; a root that has one is only ever chosen
    when its angle is obtuse, so the tree leaves the start (enters the goal)
    along its heading, the purpose of the virtual parents (SPEC §3 item 2). A
    root without one is never obtuse but may be the nearest.

    Examples
    --------
    >>> t = ObtuseTree(np.array([0.0, 0.0]), virtual_parent=np.array([-5.0, 0.0]))
    >>> a = t.add(np.array([0.0, 5.0]), 0)
    >>> t.choose_parent(np.array([1.0, 3.0]))  # node 1 is nearer but acute; the root is obtuse
    0
    """

    def __init__(
        self, root: np.ndarray, capacity: int = 256, virtual_parent: np.ndarray | None = None
    ) -> None:
        super().__init__(root, capacity, virtual_parent)
        vp = (np.nan, np.nan) if virtual_parent is None else tuple(virtual_parent)
        # Columns [x, y, parent x, parent y] (rows of a (4, capacity) array, so
        # each is contiguous), for :attr:`ppos` and :func:`link_candidates`.
        self._cols = np.empty((4, capacity))
        self._cols[:, 0] = (root[0], root[1], vp[0], vp[1])
        self.dpar = np.empty(capacity)
        self.dpar[0] = (vp[0] - root[0]) ** 2 + (vp[1] - root[1]) ** 2
        # Eq. 11 as two linear forms in (q_x, q_y, 1), so that one matrix product
        # per query gives both (see choose_parent):
        #   row 0:  |x_i|^2 - 2 x_i.q        (|x_i - q|^2 less the constant |q|^2)
        #   row 1:  v_i.q - v_i.x_i,  v_i = x_i - x_k  (> 0 exactly when obtuse)
        # since D(q_i,q) + D(q_i,q_k) < D(q_k,q)  <=>  (q_i - q_k).(q - q_i) > 0.
        self._forms = np.empty((2, capacity, 3))
        self._set_forms(0, float(root[0]), float(root[1]), float(vp[0]), float(vp[1]))
        self._q3 = np.ones(3)

    def _set_forms(self, i: int, x: float, y: float, px: float, py: float) -> None:
        vx, vy = x - px, y - py  # NaN for a root without a parent: never obtuse
        self._forms[0, i] = (-2.0 * x, -2.0 * y, x * x + y * y)
        self._forms[1, i] = (vx, vy, -(vx * x + vy * y))

    @property
    def ppos(self) -> np.ndarray:
        """Parent position of every node (the root's virtual parent), shape ``(size, 2)``."""
        return self._cols[2:, : self.size].T

    def add(self, point: Sequence[float], parent: int, cost: float | None = None) -> int:
        """Append ``point`` (any ``(x, y)`` sequence) with ``parent``; return its index."""
        i = self.size
        if i == len(self.nodes):
            self.nodes = np.concatenate([self.nodes, np.empty_like(self.nodes)])
            self.parents = np.concatenate([self.parents, np.empty_like(self.parents)])
            self.cost = np.concatenate([self.cost, np.empty_like(self.cost)])
            self._cols = np.concatenate([self._cols, np.empty_like(self._cols)], axis=1)
            self.dpar = np.concatenate([self.dpar, np.empty_like(self.dpar)])
            self._forms = np.concatenate([self._forms, np.empty_like(self._forms)], axis=1)
        x, y = float(point[0]), float(point[1])
        px, py = self.nodes[parent].tolist()
        if cost is None:
            cost = float(self.cost[parent]) + math.hypot(x - px, y - py)
        self.nodes[i] = (x, y)
        self.parents[i] = parent
        self.cost[i] = cost
        self.size = i + 1
        self._cols[:, i] = (x, y, px, py)
        self.dpar[i] = (x - px) ** 2 + (y - py) ** 2
        self._set_forms(i, x, y, px, py)
        return i

    def choose_parent(self, q: np.ndarray, obtuse: bool = True) -> int:
        """Node to extend towards ``q``: Eq. 11 / Table 1 when ``obtuse``, else the nearest.

        Returns -1 when only a root with a virtual parent qualifies and its angle is acute.
        """
        q3 = self._q3
        q3[0] = q[0]
        q3[1] = q[1]
        r = self._forms[:, : self.size] @ q3
        near = r[0]
        if not obtuse:
            return int(near.argmin())
        # NaN (a root without parent) compares False: never obtuse.
        w = np.where(r[1] > 0.0, near, np.inf)
        i = int(w.argmin())
        if w[i] == np.inf:
            if self.virtual_parent is not None:
                # A root with a virtual parent grows only along its heading.
                near[0] = np.inf
            i = int(near.argmin())
            if near[i] == np.inf:
                return -1
        return i


def fast_edge_test(checker: CollisionChecker) -> EdgeFree:
    """The growth's edge test: ``checker.edge_free`` itself.

    The checker's sphere tracing looks at the far end of its capsule first, so
    most colliding tree extensions are answered with one clearance lookup; every
    answer is the checker's own, so the test is exactly as safe.

    Examples
    --------
    >>> from rrtdrive.maps import builtin_map
    >>> from rrtdrive.planning.base import cached_checker
    >>> c = cached_checker(builtin_map("overtake"))
    >>> test = fast_edge_test(c)
    >>> test((5.0, 44.0), (30.0, 44.0)), test((30.0, 44.0), (46.0, 44.0))
    (True, False)
    """
    return checker.edge_free


def _rooted(
    inner: EdgeFree, at_roots: EdgeFree, start: tuple[float, float], goal: tuple[float, float]
) -> EdgeFree:
    """``at_roots`` for edges with an end exactly at the start or goal, ``inner`` otherwise."""
    sx, sy = start
    gx, gy = goal

    def test(a: Sequence[float], b: Sequence[float]) -> bool:
        if (a[0] == sx and a[1] == sy) or (b[0] == gx and b[1] == gy):
            return at_roots(a, b)
        return inner(a, b)

    return test


def _edge(edge_free: EdgeFree, towards_root: bool, a: Sequence[float], b: Sequence[float]) -> bool:
    """Test the tree edge between parent ``a`` and child ``b`` in its driving direction."""
    return edge_free(b, a) if towards_root else edge_free(a, b)


def extend(
    tree: ObtuseTree,
    towards_root: bool,
    i_near: int,
    target: np.ndarray,
    step: float,
    edge_free: EdgeFree,
) -> int:
    """One step of at most ``step`` from node ``i_near`` towards ``target``.

    Parameters
    ----------
    tree : ObtuseTree
        The tree to grow.
    towards_root : bool
        True for the goal tree, whose edges are driven from child to parent.
    i_near : int
        Node to grow from.
    target : numpy.ndarray
        Point to grow towards.
    step : float
        Largest edge length ``p``.
    edge_free : callable
        ``edge_free(a, b)`` of the growth checker.

    Returns
    -------
    int
        Index of the new node, or -1 when the edge collides.
    """
    if i_near < 0:
        return -1
    ax, ay = tree.nodes[i_near].tolist()
    dx, dy = float(target[0]) - ax, float(target[1]) - ay
    dist = math.hypot(dx, dy)
    if dist < 1e-9:
        return -1
    f = 1.0 if dist <= step else step / dist
    q = (ax + dx * f, ay + dy * f)
    if not _edge(edge_free, towards_root, (ax, ay), q):
        return -1
    return tree.add(q, i_near)


def greedy_connect(
    tree: ObtuseTree,
    towards_root: bool,
    target: np.ndarray,
    step: float,
    edge_free: EdgeFree,
    *,
    obtuse: bool = True,
    adaptive: bool = True,
    expired: Callable[[], bool] | None = None,
) -> int:
    """Greedy connect of RRT-Connect with the adaptive step (paper Sec. 3.1.3).

    From the node chosen by :meth:`ObtuseTree.choose_parent` the tree steps
    straight towards ``target``: the first step is ``p``, every further step
    ``2p`` while it neither collides nor reaches the target (``p`` throughout when
    not ``adaptive``). A collision ends the loop.

    Returns
    -------
    int
        Index of the node at ``target``, or -1 when trapped.

    Examples
    --------
    >>> t = ObtuseTree(np.array([0.0, 0.0]))
    >>> greedy_connect(t, False, np.array([30.0, 0.0]), 5.0, lambda a, b: True)
    4
    >>> t.nodes[: len(t), 0].tolist()   # steps of 5, 10, 10, then the last 5
    [0.0, 5.0, 15.0, 25.0, 30.0]
    """
    j = tree.choose_parent(target, obtuse)
    if j < 0:
        return -1
    tx, ty = float(target[0]), float(target[1])
    p = step
    while True:
        ax, ay = tree.nodes[j].tolist()
        dx, dy = tx - ax, ty - ay
        dist = math.hypot(dx, dy)
        if dist < 1e-9:
            return j
        reached = dist <= p
        q = (tx, ty) if reached else (ax + dx * p / dist, ay + dy * p / dist)
        if not _edge(edge_free, towards_root, (ax, ay), q):
            return -1
        j = tree.add(q, j)
        if reached:
            return j
        if adaptive:
            p = 2.0 * step
        if expired is not None and expired():
            return -1


def link_candidates(
    tree: ObtuseTree, q: np.ndarray, step: float, *, obtuse: bool = True, candidates: int = 8
) -> np.ndarray:
    """Nodes to try for :func:`link`: the ``candidates`` nearest within ``4 step``, nearest first.

    With ``obtuse`` the obtuse ones (Eq. 11) come first.
    """
    d = tree.sq_dists(q)
    near = np.flatnonzero(d <= (4.0 * step) ** 2)
    if len(near) == 0:
        return near
    if len(near) > candidates:
        near = near[np.argpartition(d[near], candidates)[:candidates]]
    near = near[np.argsort(d[near])]
    if obtuse:
        e = tree.ppos[near] - q
        ok = d[near] + tree.dpar[near] < np.einsum("ij,ij->i", e, e)
        if tree.virtual_parent is not None:
            keep = (near != 0) | ok  # the root only along its heading
            near, ok = near[keep], ok[keep]
        near = near[np.argsort(~ok, kind="stable")]
    return near


def link(
    tree: ObtuseTree,
    towards_root: bool,
    q: np.ndarray,
    step: float,
    edge_free: EdgeFree,
    *,
    obtuse: bool = True,
    candidates: int = 8,
    order: np.ndarray | None = None,
) -> int:
    """Join ``q`` by one straight free edge from one of the nearest nodes (passage sampling).

    The nodes of :func:`link_candidates` (or ``order``) are tried in turn; the
    first free edge is stored as pieces of at most ``step`` (each a part of the
    free edge's swept capsule, hence free).

    Returns
    -------
    int
        Index of the node at ``q``, or -1 when no candidate has a free edge.

    Examples
    --------
    >>> t = ObtuseTree(np.array([0.0, 0.0]))
    >>> link(t, False, np.array([12.0, 0.0]), 5.0, lambda a, b: True)
    3
    """
    if order is None:
        order = link_candidates(tree, q, step, obtuse=obtuse, candidates=candidates)
    qx, qy = float(q[0]), float(q[1])
    for i in order.tolist():
        a = tree.nodes[i].copy()
        ax, ay = a.tolist()
        if not _edge(edge_free, towards_root, (ax, ay), (qx, qy)):
            continue
        pieces = max(1, math.ceil(math.hypot(qx - ax, qy - ay) / step - 1e-9))
        j = i
        for m in range(1, pieces + 1):
            j = tree.add(a + (q - a) * (m / pieces), j)
        return j
    return -1


# ----------------------------------------------------------------------------- planner


def _free_dubins(
    checker: CollisionChecker,
    start: Pose,
    goal: Pose,
    radius: float,
    clearance: float,
    check_spacing: float,
) -> DubinsPath | None:
    """The shortest Dubins word from ``start`` to ``goal`` whose body stays clear."""
    for cand in dubins_paths(start, goal, radius):
        dense = cand.sample(check_spacing)
        if bool(np.all(checker.poses_free(dense[:, :3], clearance=clearance))):
            return cand
    return None


def dubins_fallback(
    checker: CollisionChecker,
    start: Pose,
    goal: Pose,
    radius: float,
    clearance: float,
    raw_paths: Sequence[np.ndarray] = (),
    smoothing: SmoothingConfig | None = None,
    expired: Callable[[], bool] | None = None,
    sample_spacing: float = 0.25,
    check_spacing: float = 0.1,
) -> tuple[Path, str] | None:
    """A drivable path that ends in a Dubins path, when the tree paths alone fail.

    First the shortest Dubins path from ``start`` to ``goal`` that the exact body
    test clears. Then, for each tree path in ``raw_paths`` and each of its nodes
    from the last but one backwards, a *tail*: the node, with the heading of the
    tree edge into it, is joined to ``goal`` by a clear Dubins path, and the tree
    path up to the node is made drivable by :func:`make_drivable` with that pose
    as its goal; the two meet at the node with the same position and heading.
    Last, the mirror image, a *lead*: a clear Dubins path from ``start`` to a node
    (with the heading of the tree edge out of it, nodes in driving order), then the
    tree path from there made drivable.

    Parameters
    ----------
    checker : CollisionChecker
        The map's checker (exact test, with ``clearance``).
    start, goal : Pose
        Rear-axle poses.
    radius : float
        Turning radius of the Dubins arcs in metres.
    clearance : float
        Body clearance to keep (the planner's, capped at the end poses' own).
    raw_paths : sequence of numpy.ndarray
        Tree paths ``(K, 2)`` whose post-processing failed, for tails and leads.
    smoothing : SmoothingConfig, optional
        Post-processing settings for the tree part; no tails or leads without it.
    expired : callable, optional
        Stops the search for tails and leads when it returns True.
    sample_spacing, check_spacing : float
        Spacing of the returned samples and of the poses tested.

    Returns
    -------
    (Path, str) or None
        The path (rows ``x, y, yaw, kappa``; waypoints: the control points of the
        tree part, then the Dubins segment junctions) and a description, or
        ``None`` when nothing fits.
    """
    direct = _free_dubins(checker, start, goal, radius, clearance, check_spacing)
    if direct is not None:
        return Path(direct.sample(sample_spacing), direct.joints()), direct.word
    if smoothing is None:
        return None
    for raw in raw_paths:
        for i in range(len(raw) - 2, 0, -1):
            if expired is not None and expired():
                return None
            yaw = math.atan2(raw[i, 1] - raw[i - 1, 1], raw[i, 0] - raw[i - 1, 0])
            joint = Pose(float(raw[i, 0]), float(raw[i, 1]), yaw)
            tail = _free_dubins(checker, joint, goal, radius, clearance, check_spacing)
            if tail is None:
                continue
            head = make_drivable(raw[: i + 1], start, joint, checker, smoothing)
            if not head.ok:
                continue
            samples = np.vstack([head.samples, tail.sample(sample_spacing)[1:]])
            waypoints = np.vstack([head.control_points, tail.joints()[1:]])
            where = f"({joint.x:.1f}, {joint.y:.1f})"
            return Path(samples, waypoints), f"tree path to {where} + {tail.word}"
    for raw in raw_paths:
        for i in range(1, len(raw) - 1):
            if expired is not None and expired():
                return None
            yaw = math.atan2(raw[i + 1, 1] - raw[i, 1], raw[i + 1, 0] - raw[i, 0])
            joint = Pose(float(raw[i, 0]), float(raw[i, 1]), yaw)
            lead = _free_dubins(checker, start, joint, radius, clearance, check_spacing)
            if lead is None:
                continue
            rest = make_drivable(raw[i:], joint, goal, checker, smoothing)
            if not rest.ok:
                continue
            samples = np.vstack([lead.sample(sample_spacing)[:-1], rest.samples])
            waypoints = np.vstack([lead.joints()[:-1], rest.control_points])
            where = f"({joint.x:.1f}, {joint.y:.1f})"
            return Path(samples, waypoints), f"{lead.word} + tree path from {where}"
    return None


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
        Any :class:`ImprovedConfig` field, e.g. ``step=4.0`` or ``prune=False``.

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
        fields = {f.name for f in dataclasses.fields(ImprovedConfig)}
        unknown = sorted(set(options) - fields)
        if unknown:
            raise InputError(
                f"planner.{unknown[0]}: unknown option for {NAME}; allowed {sorted(fields)}"
            )
        if isinstance(disable, str):
            disable = (disable,)
        cfg = dataclasses.replace(base, **options) if options else base  # type: ignore[arg-type]
        self.config = cfg.without(*disable)

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
            Iteration and wall-time limits (both enforced for the growth; each
            post-processing is bounded by ``max_repair_rounds``).

        Returns
        -------
        PlanResult
            ``SOLVED`` with a verified path, or a failure status with a message.
            ``stats`` holds ``nodes``, ``iterations``, ``growth_time_s``,
            ``postprocess_time_s``, ``postprocess_attempts``, ``repair_rounds``,
            ``direct_connection``, ``expanded_obstacles``, ``expansion_used`` and,
            when solved, ``key_points``, ``control_points``, ``max_curvature``
            (exact, of the whole curve) and the repair counters ``fillets``,
            ``merges``, ``moves``, ``drops``, ``unprunes`` and ``edge_checks``.
        """
        watch = Stopwatch(budget)
        early = precheck(problem, NAME, watch)
        if early is not None:
            return early
        cfg = self.config
        checker = problem.checker
        start, goal = problem.start, problem.goal
        p = cfg.step
        smoothing = SmoothingConfig(
            kappa_max=problem.vehicle.kappa_max,
            degree=cfg.spline_degree,
            prune=cfg.prune,
            sharp_repair=cfg.sharp_repair,
            supplement=cfg.supplement,
            supplement_delta=cfg.supplement_delta,
            supplement_n=cfg.supplement_n,
            heading_leg=p,
            max_rounds=cfg.max_repair_rounds,
            clearance=endpoint_capped_clearance(checker, start, goal, cfg.body_clearance),
        )
        stats: dict[str, float] = {
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
        s_xy = np.array([start.x, start.y])
        g_xy = np.array([goal.x, goal.y])
        hs = np.array([math.cos(start.yaw), math.sin(start.yaw)])
        hg = np.array([math.cos(goal.yaw), math.sin(goal.yaw)])
        last_message = ""
        last_raw: np.ndarray | None = None
        failed_raws: list[np.ndarray] = []

        def finish(raw: np.ndarray, trees: tuple[Tree, ...], iterations: int) -> PlanResult | None:
            nonlocal last_message, last_raw
            t0 = time.perf_counter()
            res = make_drivable(raw, start, goal, checker, smoothing)
            stats["postprocess_time_s"] += time.perf_counter() - t0
            stats["postprocess_attempts"] += 1
            stats["repair_rounds"] += res.rounds
            last_raw = raw
            if not res.ok:
                last_message = res.message
                failed_raws.append(raw)
                return None
            stats["iterations"] = float(iterations)
            stats["key_points"] = float(len(res.key_points))
            stats["control_points"] = float(len(res.control_points))
            stats["max_curvature"] = res.max_curvature
            stats.update(res.stats)
            nodes = sum(len(t) for t in trees)
            elapsed = watch.elapsed()
            stats["growth_time_s"] = elapsed - stats["postprocess_time_s"]
            return PlanResult(
                status=PlanStatus.SOLVED,
                planner=NAME,
                path=Path(res.samples, res.control_points),
                raw_path=raw,
                trees=trees,
                nodes=nodes,
                iterations=iterations,
                planning_time_s=elapsed,
                message=(
                    f"solved: {len(res.key_points)} key points, {len(res.control_points)} "
                    f"control points, {res.rounds} fit round(s)"
                ),
                stats=stats,
            )

        # 1. Direct connection (Sec. 3.1.1): the straight edge is free and both
        #    headings point along it (within 90 degrees), so that the curve need
        #    not turn back.
        roots = (Tree(s_xy[None, :], np.array([-1])), Tree(g_xy[None, :], np.array([-1])))
        chord = g_xy - s_xy
        headings_allow = float(hs @ chord) > 0.0 and float(hg @ chord) > 0.0
        if (
            cfg.direct_connect
            and headings_allow
            and checker.edge_free(s_xy.tolist(), g_xy.tolist())
        ):
            stats["direct_connection"] = 1.0
            stats["nodes"] = 2.0
            out = finish(np.vstack([s_xy, g_xy]), roots, 0)
            if out is not None:
                return out

        # 2. The growth checker with the expanded obstacles (Sec. 3.1.4).
        grow = checker
        if cfg.obstacle_expansion and cfg.expansion_a > 0:
            lmin = cfg.expansion_lmin
            if lmin is None:
                lmin = default_expansion_lmin(
                    problem.vehicle.width, checker.config.margin, cfg.expansion_a
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
            edge_free = _rooted(
                edge_free, fast_edge_test(checker), (start.x, start.y), (goal.x, goal.y)
            )
        samples = SampleSource(problem, reject=True)
        passages: np.ndarray | None = None
        if cfg.passage_sampling and cfg.passage_bias > 0:
            passages = passage_cells(grow, (start.x, start.y))
            if len(passages) == 0:
                passages = None

        # 3. Bidirectional growth; a tree path that cannot be made drivable
        #    starts a fresh pair of trees (up to max_postprocess_attempts).
        iterations = 0
        total_nodes = 0
        trees: tuple[Tree, ...] = roots
        while stats["postprocess_attempts"] < cfg.max_postprocess_attempts:
            ts = ObtuseTree(s_xy, virtual_parent=s_xy - p * hs)
            tg = ObtuseTree(g_xy, virtual_parent=g_xy + p * hg)
            found: np.ndarray | None = None
            ta, tb = ts, tg
            while iterations < budget.max_iterations and not watch.expired():
                iterations += 1
                if passages is not None and rng.random() < cfg.passage_bias:
                    # Beyond the paper: a point on a narrow passage's centre line,
                    # joined straight to both trees; the iteration goes on with a
                    # regular sample when that fails.
                    q = passages[rng.integers(len(passages))]
                    near_g = link_candidates(tg, q, p, obtuse=cfg.obtuse_parent)
                    near_s = (
                        link_candidates(ts, q, p, obtuse=cfg.obtuse_parent)
                        if len(near_g)
                        else near_g
                    )
                    if len(near_s):
                        i_s = link(ts, False, q, p, edge_free, order=near_s)
                        if i_s >= 0:
                            i_g = link(tg, True, q, p, edge_free, order=near_g)
                            if i_g >= 0:
                                found = np.vstack([ts.branch(i_s)[::-1], tg.branch(i_g)[1:]])
                                break
                q_rand = samples.draw_xy(rng)
                i_near = ta.choose_parent(q_rand, cfg.obtuse_parent)
                i_new = extend(ta, ta is tg, i_near, q_rand, p, edge_free)
                if i_new >= 0:
                    j = greedy_connect(
                        tb, tb is tg, ta.nodes[i_new], p, edge_free,
                        obtuse=cfg.obtuse_parent, adaptive=cfg.adaptive_step,
                        expired=watch.expired,
                    )  # fmt: skip
                    if j >= 0:
                        i_s, i_g = (i_new, j) if ta is ts else (j, i_new)
                        found = np.vstack([ts.branch(i_s)[::-1], tg.branch(i_g)[1:]])
                        break
                ta, tb = tb, ta
            trees = (ts.freeze(), tg.freeze())
            total_nodes += len(ts) + len(tg)
            stats["nodes"] = float(total_nodes)
            if found is None:
                break
            out = finish(found, trees, iterations)
            if out is not None:
                return out

        stats["iterations"] = float(iterations)
        stats["growth_time_s"] = watch.elapsed() - stats["postprocess_time_s"]
        if cfg.dubins_fallback:
            t0 = time.perf_counter()
            fallback = dubins_fallback(
                checker, start, goal, cfg.dubins_radius_factor / problem.vehicle.kappa_max,
                smoothing.clearance, failed_raws[::-1], smoothing, watch.expired,
            )
            stats["dubins_time_s"] = time.perf_counter() - t0
            if fallback is not None:
                path, word = fallback
                stats["dubins_fallback"] = 1.0
                stats["max_curvature"] = float(np.abs(path.samples[:, 3]).max())
                why = last_message or "the trees did not meet"
                return PlanResult(
                    status=PlanStatus.SOLVED,
                    planner=NAME,
                    path=path,
                    raw_path=last_raw if last_raw is not None else np.vstack([s_xy, g_xy]),
                    trees=trees,
                    nodes=int(stats["nodes"]),
                    iterations=iterations,
                    planning_time_s=watch.elapsed(),
                    message=(
                        f"solved by the Dubins fallback ({word}; {path.length:.1f} m); "
                        f"the tree paths failed: {why}"
                    ),
                    stats=stats,
                )
        if stats["postprocess_attempts"] > 0 and last_message:
            return failure(
                NAME,
                PlanStatus.POSTPROCESS_FAILED,
                watch,
                f"{last_message} (after {int(stats['postprocess_attempts'])} tree path(s)"
                + ("; no clear Dubins path, tail or lead either)" if cfg.dubins_fallback else ")"),
                trees=trees,
                iterations=iterations,
                raw_path=last_raw,
                stats=stats,
            )
        reason = "time" if watch.expired() else "iteration"
        return failure(
            NAME,
            PlanStatus.NO_PATH_IN_BUDGET,
            watch,
            f"no path within the {reason} budget ({iterations} iterations, "
            f"{watch.elapsed():.3f} s)",
            trees=trees,
            iterations=iterations,
            stats=stats,
        )
