"""Tree growth of the improved RRT-Connect (paper Sec. 3.1): obtuse parents, adaptive step, links.

:class:`ObtuseTree` chooses parents by Eq. 11; :func:`extend` and
:func:`greedy_connect` (with the adaptive step) grow it; :func:`link` joins a
passage sample by one straight edge; :func:`grow_until_meet` is the
bidirectional loop of one pair of trees.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence

import numpy as np

from rrtdrive.collision import CollisionChecker
from rrtdrive.planning.base import GrowingTree
from rrtdrive.planning.sampling import SampleSource

__all__ = [
    "EdgeFree",
    "ObtuseTree",
    "extend",
    "fast_edge_test",
    "greedy_connect",
    "grow_until_meet",
    "join_through",
    "link",
    "link_candidates",
    "rooted_edge_test",
    "tree_path",
]

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

    Parameters
    ----------
    root : numpy.ndarray
        Root position ``(x, y)`` (the start or the goal).
    capacity : int
        Initial capacity; the arrays double when full.
    virtual_parent : numpy.ndarray, optional
        A position behind the root along its heading, the root's parent in Eq. 11
        (``None``: the root has none).

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
        """Append ``point`` (any ``(x, y)`` sequence) with ``parent``; return its index.

        Parameters
        ----------
        point : sequence of float
            Position ``(x, y)``.
        parent : int
            Index of its parent node.
        cost : float, optional
            Its path cost (``None``: the parent's plus the straight distance).

        Returns
        -------
        int
        """
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

        Parameters
        ----------
        q : numpy.ndarray
            The point to extend towards, ``(x, y)``.
        obtuse : bool
            Apply Eq. 11 (else the nearest node).

        Returns
        -------
        int
            The node's index; -1 when only a root with a virtual parent qualifies and
            its angle is acute.
        """
        q3 = self._q3
        q3[0] = q[0]
        q3[1] = q[1]
        r = self._forms[:, : self.size] @ q3
        near = r[0]
        i = int(near.argmin())
        if not obtuse:
            return i
        # The nearest node, when obtuse, is the answer: every node before it is
        # farther, every one after it no nearer (argmin takes the first minimum).
        if r[1, i] > 0.0:
            return i
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

    Parameters
    ----------
    checker : CollisionChecker
        The growth checker.

    Returns
    -------
    callable
        ``edge_free(a, b) -> bool``.

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


def rooted_edge_test(
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

    Parameters
    ----------
    tree, towards_root, target, step, edge_free
        As :func:`extend` (``step`` is ``p``).
    obtuse : bool
        Choose the first node by Eq. 11 (else the nearest).
    adaptive : bool
        Double the step after the first.
    expired : callable, optional
        ``expired() -> bool``, asked after each step; True gives up (-1).

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

    Parameters
    ----------
    tree : ObtuseTree
        The tree to join.
    q : numpy.ndarray
        The point to join, ``(x, y)``.
    step : float
        The growth step ``p``, metres.
    obtuse : bool
        Obtuse nodes first; a root with a virtual parent only when obtuse.
    candidates : int
        How many of the nearest nodes to keep.

    Returns
    -------
    numpy.ndarray
        Node indices (possibly empty).
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

    Parameters
    ----------
    tree, towards_root, step, edge_free
        As :func:`extend`.
    q : numpy.ndarray
        The point to join, ``(x, y)``.
    obtuse, candidates
        As :func:`link_candidates`.
    order : numpy.ndarray, optional
        Node indices to try, in order (``None``: :func:`link_candidates`).

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


def tree_path(ts: ObtuseTree, i_s: int, tg: ObtuseTree, i_g: int) -> np.ndarray:
    """The raw path from the start root to node ``i_s``, then from ``i_g`` to the goal root.

    ``i_s`` and ``i_g`` hold the same point; it appears once.
    """
    return np.vstack([ts.branch(i_s)[::-1], tg.branch(i_g)[1:]])


def join_through(
    ts: ObtuseTree,
    tg: ObtuseTree,
    q: np.ndarray,
    step: float,
    edge_free: EdgeFree,
    *,
    obtuse: bool = True,
) -> np.ndarray | None:
    """Join both trees to the point ``q`` by straight free edges (passage sampling).

    The goal tree's candidates are looked up first; the start tree is linked
    only when both have some, the goal tree only when the start tree's link
    succeeded (a start-tree link stays in the tree either way).

    Returns
    -------
    numpy.ndarray or None
        The raw path through ``q``, or ``None`` when either link fails.
    """
    near_g = link_candidates(tg, q, step, obtuse=obtuse)
    near_s = link_candidates(ts, q, step, obtuse=obtuse) if len(near_g) else near_g
    if len(near_s):
        i_s = link(ts, False, q, step, edge_free, order=near_s)
        if i_s >= 0:
            i_g = link(tg, True, q, step, edge_free, order=near_g)
            if i_g >= 0:
                return tree_path(ts, i_s, tg, i_g)
    return None


def grow_until_meet(
    ts: ObtuseTree,
    tg: ObtuseTree,
    samples: SampleSource,
    rng: np.random.Generator,
    edge_free: EdgeFree,
    *,
    step: float,
    obtuse: bool,
    adaptive: bool,
    passages: np.ndarray | None,
    passage_bias: float,
    iterations: int,
    max_iterations: int,
    expired: Callable[[], bool],
    root_patience: int = 0,
) -> tuple[np.ndarray | None, int]:
    """Bidirectional growth of one pair of trees until they meet or the budget ends.

    Each iteration first, with probability ``passage_bias`` (when there are
    ``passages``), tries to join both trees through a random passage cell
    (:func:`join_through`); then extends one tree towards a sample
    (:meth:`ObtuseTree.choose_parent`, :func:`extend`) and greedily connects the
    other to the new node (:func:`greedy_connect`); then the trees swap roles.

    Parameters
    ----------
    ts, tg : ObtuseTree
        The start tree (edges driven parent to child) and the goal tree (child to parent).
    samples : SampleSource
        Where samples come from.
    rng : numpy.random.Generator
        The only source of randomness.
    edge_free : callable
        The growth's edge test.
    step : float
        Unit step ``p``.
    obtuse, adaptive : bool
        The obtuse-parent and adaptive-step components.
    passages : numpy.ndarray or None
        Passage cells (:meth:`rrtdrive.collision.CollisionChecker.passage_cells`).
    passage_bias : float
        Share of iterations that try a passage cell first.
    iterations : int
        Iterations already used by earlier pairs of trees.
    max_iterations : int
        Iteration budget of the whole query.
    expired : callable
        True once the safety cap is reached (the query then ends as ``timeout``).
    root_patience : int
        Beyond the paper: the pair gives up after this many of its iterations when
        either tree is still only its root (0: never).

    Returns
    -------
    found : numpy.ndarray or None
        The raw start-to-goal path through both trees, ``None`` when the budget ended
        (or a root never grew: ``len(ts) == 1`` or ``len(tg) == 1``).
    iterations : int
        Iterations used so far, this pair's included.
    """
    ta, tb = ts, tg
    give_up = iterations + root_patience if root_patience > 0 else max_iterations
    while iterations < max_iterations and not expired():
        if iterations >= give_up and (ts.size == 1 or tg.size == 1):
            break
        iterations += 1
        if passages is not None and rng.random() < passage_bias:
            # Beyond the paper: a point on a narrow passage's centre line, joined
            # straight to both trees; the iteration goes on with a regular sample
            # when that fails.
            q = passages[rng.integers(len(passages))]
            found = join_through(ts, tg, q, step, edge_free, obtuse=obtuse)
            if found is not None:
                return found, iterations
        q_rand = samples.draw_xy(rng)
        i_near = ta.choose_parent(q_rand, obtuse)
        i_new = extend(ta, ta is tg, i_near, q_rand, step, edge_free)
        if i_new >= 0:
            j = greedy_connect(
                tb, tb is tg, ta.nodes[i_new], step, edge_free,
                obtuse=obtuse, adaptive=adaptive, expired=expired,
            )  # fmt: skip
            if j >= 0:
                i_s, i_g = (i_new, j) if ta is ts else (j, i_new)
                return tree_path(ts, i_s, tg, i_g), iterations
        ta, tb = tb, ta
    return None, iterations
