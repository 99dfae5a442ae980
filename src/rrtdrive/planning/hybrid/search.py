"""The Hybrid A* search (Dolgov, Thrun, Montemerlo & Diebel 2008) over one query.

States are continuous poses ``(x, y, yaw)`` with a gear; a state is closed per
cell of ``xy_resolution``, heading bin of ``yaw_resolution`` and gear, the first
to be expanded there wins. Successors are the :class:`PrimitiveSet` arcs whose
body poses (at most ``check_spacing`` apart) pass the checker's body test with
the query's clearance (three covering discs first, then six, then the exact
rectangle where the discs cannot decide). ``f = g + w h`` with the
:class:`~rrtdrive.planning.hybrid.heuristic.Heuristic`. From expanded nodes,
every few expansions (each one near the goal), an *analytic expansion* (:mod:`.shots`) tries
the obstacle-free shortest paths to the exact goal pose and keeps the first whose
body is clear: Dubins forward, Reeds-Shepp with reverse.

No decision reads the clock: the expansion budget bounds the search, the
wall-clock limit only stops it early (reported as such). Ties in ``f`` are
broken by insertion order.
"""

from __future__ import annotations

import functools
import heapq
import math
import operator
from collections.abc import Callable, Iterator, Sequence
from dataclasses import dataclass
from typing import TypeVar

import numpy as np

from rrtdrive.planning.hybrid.body import BodyTest, disc_reach
from rrtdrive.planning.hybrid.config import HybridConfig
from rrtdrive.planning.hybrid.heuristic import Heuristic
from rrtdrive.planning.hybrid.primitives import PrimitiveSet

# The analytic expansions live in .shots; re-exported here, where they always were.
from rrtdrive.planning.hybrid.shots import (
    Piece,
    Shots,
    analytic_shots,
    walk_hits,
    walk_poses,
    walks_hit,
)
from rrtdrive.types import Pose

__all__ = [
    "Piece",
    "SearchOutcome",
    "Shots",
    "HybridSearch",
    "analytic_shots",
    "walk_hits",
    "walk_poses",
    "walks_hit",
]

T = TypeVar("T")


@dataclass(frozen=True)
class SearchOutcome:
    """How a search ended.

    Attributes
    ----------
    reason : str
        ``"solved"``, ``"exhausted"`` (open list empty), ``"no_approach"`` (the search from
        the goal ran out: see :mod:`.query`), ``"expansions"`` (budget
        spent), ``"time"`` (wall-clock cap hit) or ``"rejected"`` (``max_solutions``
        goal connections found, none accepted).
    expansions, nodes, shots, connections : int
        Nodes expanded, nodes created, analytic shots tried, goal connections found.
    turn_moves : int
        Moves of the multi-point turn that solved the query (:mod:`.turn`; 0: none did).
    """

    reason: str
    expansions: int
    nodes: int
    shots: int
    connections: int
    turn_moves: int = 0

    @classmethod
    def total(cls, reason: str, outcomes: Sequence[SearchOutcome]) -> SearchOutcome:
        """One outcome for several searches: ``reason``, and every count summed."""
        return cls(
            reason,
            sum(o.expansions for o in outcomes),
            sum(o.nodes for o in outcomes),
            sum(o.shots for o in outcomes),
            sum(o.connections for o in outcomes),
            sum(o.turn_moves for o in outcomes),
        )


@dataclass(frozen=True)
class _OpenArcs:
    """Primitives of one length as the search loop reads them (plain lists)."""

    length: float
    #: How far each covering disc can move along them (:meth:`BodyTest.reach`).
    reach: list[float]
    #: Each primitive's cost before gear and steering changes.
    costs: list[float]
    #: Each primitive's end pose ``[x, y, dyaw]`` from a pose at the origin heading +x.
    ends: list[list[float]]


def _edge_costs(p: PrimitiveSet, reverse_cost: float, steer_cost: float, kappa_max: float) -> list:
    """Each primitive's cost before gear and steering changes."""
    gear_factor = np.where(p.gears < 0, reverse_cost, 1.0)
    return (p.length * (gear_factor + steer_cost * np.abs(p.kappas) / kappa_max)).tolist()


@functools.lru_cache(maxsize=64)
def _arc_tables(
    primitives: PrimitiveSet,
    long_primitives: tuple[PrimitiveSet, ...],
    reverse_cost: float,
    steer_cost: float,
    kappa_max: float,
    disc_offsets: tuple[float, ...],
) -> tuple[list[_OpenArcs], _OpenArcs]:
    """The loop's tables of a search's primitives, built once (shared: never written).

    The open arcs, longest first: the long ones, then the step arcs themselves, each
    with its sweep's reach (:func:`~.body.disc_reach`), costs and local end poses; and
    the step arcs as taken with a body test.
    """
    kappa = float(np.abs(primitives.kappas).max()) if len(primitives) else 0.0
    sets = sorted((*long_primitives, primitives), key=lambda p: -p.length)
    opened = [
        _OpenArcs(p.length, disc_reach(disc_offsets, p.length, kappa),
                  _edge_costs(p, reverse_cost, steer_cost, kappa_max), p.local[:, -1, :].tolist())
        for p in sets
    ]  # fmt: skip
    tested = _OpenArcs(
        primitives.length, [], _edge_costs(primitives, reverse_cost, steer_cost, kappa_max),
        primitives.local[:, -1, :].tolist(),
    )  # fmt: skip
    return opened, tested


class HybridSearch:
    """One Hybrid A* query: the primitives, the heuristic, the checker and the budget.

    Parameters
    ----------
    body : BodyTest
        The body test (the map's checker with the query's clearance).
    start, goal : Pose
        Rear-axle poses.
    heuristic : Heuristic
        Cost-to-go estimate to ``goal``.
    primitives : PrimitiveSet
        The successors' arcs.
    long_primitives : sequence of PrimitiveSet
        Longer copies of ``primitives`` (same curvatures and gears), taken instead
        from a node whose discs have room for their reach (:attr:`HybridConfig.long_steps`).
    shots : callable
        Analytic expansions (:func:`analytic_shots`).
    config : HybridConfig
        Costs, resolutions and shot schedule.
    kappa_max : float
        The car's curvature limit (scales the steering costs).
    bounds : tuple of float
        The map's bounds (the closing grid's origin).
    """

    def __init__(
        self,
        body: BodyTest,
        start: Pose,
        goal: Pose,
        heuristic: Heuristic,
        primitives: PrimitiveSet,
        shots: Shots,
        config: HybridConfig,
        kappa_max: float,
        bounds: tuple[float, float, float, float],
        long_primitives: Sequence[PrimitiveSet] = (),
    ) -> None:
        self.body, self.start, self.goal = body, start, goal
        self.heuristic, self.prims, self.shots = heuristic, primitives, shots
        self.cfg, self.kappa_max = config, kappa_max
        self.xmin, self.ymin = bounds[0], bounds[1]
        self.ny = int(math.ceil((bounds[3] - bounds[1]) / config.xy_resolution)) + 2
        self.nyaw = config.yaw_bins
        # Node storage (parallel lists: appends are the hot path).
        self.x: list[float] = []
        self.y: list[float] = []
        self.yaw: list[float] = []
        self.g: list[float] = []
        self.gear: list[int] = []
        self.kappa: list[float] = []
        self.parent: list[int] = []
        self.step: list[float] = []
        self.expansions = 0
        self.shots_tried = 0
        self.connections = 0
        #: Node -> how many connections its shot gave, every one rejected (shots that
        #: ran to their end only): what a repeat of this search reads (:meth:`replay`).
        self.shot_counts: dict[int, int] = {}
        #: Node -> the rows of the primitive that made it (:meth:`chain`; read-only use).
        self._edge_made: dict[int, np.ndarray] = {}
        # The open list, closed cells and best costs: made by the first run().
        self._heap: list[tuple[float, int]]
        self._closed: set[int]
        self._best: dict[int, float]
        self._earlier: HybridSearch | None = None
        self._same_below = 0  # nodes [0, this) are the earlier search's, checked
        # The primitives as the loop reads them: built once per primitive set and costs.
        self._open, self._tested = _arc_tables(
            primitives, tuple(long_primitives), config.reverse_cost, config.steer_cost,
            kappa_max, body.disc_offsets,
        )  # fmt: skip

    def replay(self, earlier: HybridSearch) -> None:
        """Take the shots' outcomes from ``earlier``, a search of the same query and settings.

        A search run again with the same body test, shots and ``accept`` (the ramp
        margin's pass where the query's clearance caps both passes alike) repeats
        the earlier one: a node the same as the earlier search's (it and every node
        before it equal, field by field: :meth:`_known`) gets the same shot, whose
        connections ``accept`` rejected there, and rejects here. Those are counted,
        not tried again (the shots and the ramp fits were most of the time).

        Parameters
        ----------
        earlier : HybridSearch
            A search of the same query and settings that has run.
        """
        self._earlier = earlier

    def _known(self, i: int) -> int | None:
        """The connections of node ``i``'s shot in the earlier search, or ``None`` to shoot.

        Only while this search's nodes up to ``i`` are the earlier one's (its
        chain and pose are then the same); once they differ, never again.
        """
        earlier = self._earlier
        assert earlier is not None
        count = earlier.shot_counts.get(i)
        if count is None or i < self._same_below:
            return count
        a, b = self._same_below, i + 1
        # kappa from node 1: the root's is NaN (never read by a chain).
        same = (
            self.x[a:b] == earlier.x[a:b] and self.y[a:b] == earlier.y[a:b]
            and self.yaw[a:b] == earlier.yaw[a:b] and self.gear[a:b] == earlier.gear[a:b]
            and self.parent[a:b] == earlier.parent[a:b] and self.step[a:b] == earlier.step[a:b]
            and self.kappa[max(a, 1):b] == earlier.kappa[max(a, 1):b]
        )  # fmt: skip
        if not same:
            self._earlier = None
            return None
        self._same_below = b
        return count

    def reguide(self, heuristic: Heuristic) -> None:
        """Go on with ``heuristic``: every node's estimate and the open nodes' order anew.

        The nodes, their costs and the closed bins stay; the next :meth:`run` resumes
        with the open nodes ranked by ``g + weight * heuristic``.

        Parameters
        ----------
        heuristic : Heuristic
            The new cost-to-go estimate.
        """
        self.heuristic = heuristic
        if not self.x:
            return
        h_at, w = heuristic.scalar(), self.cfg.heuristic_weight
        self._hval = [h_at(x, y, yaw) for x, y, yaw in zip(self.x, self.y, self.yaw, strict=True)]
        self._heap = [(self.g[i] + w * self._hval[i], i) for _, i in self._heap]
        heapq.heapify(self._heap)

    def key(self, x: float, y: float, yaw: float, gear: int) -> int:
        """The closing bin of a state: its cell, heading bin and gear.

        Parameters
        ----------
        x, y, yaw : float
            Rear-axle pose (metres, radians; any yaw, wrapped).
        gear : int
            ``+1`` forward, ``-1`` reverse.

        Returns
        -------
        int
        """
        res = self.cfg.xy_resolution
        ix = int((x - self.xmin) // res)
        iy = int((y - self.ymin) // res)
        iyaw = int(((yaw % (2.0 * math.pi)) / (2.0 * math.pi)) * self.nyaw) % self.nyaw
        return (((ix * self.ny + iy) * self.nyaw + iyaw) << 1) | (gear < 0)

    def _add(
        self, x: float, y: float, yaw: float, g: float, gear: int, kappa: float, par: int
    ) -> int:
        self.x.append(x)
        self.y.append(y)
        self.yaw.append(yaw)
        self.g.append(g)
        self.gear.append(gear)
        self.kappa.append(kappa)
        self.parent.append(par)
        self.step.append(self.prims.length)
        return len(self.x) - 1

    def chain(self, i: int) -> list[Piece]:
        """The pieces from the start to node ``i``, one per primitive, merged per gear.

        Every primitive's rows are :func:`arc_poses` from its parent (evaluated for
        all primitives at once, with the same arithmetic), the last one its node's
        exact pose.

        Parameters
        ----------
        i : int
            A node's index (0 is the start: no pieces).

        Returns
        -------
        list of Piece
        """
        nodes = []
        while i >= 0:
            nodes.append(i)
            i = self.parent[i]
        nodes.reverse()
        if len(nodes) < 2:
            return []
        a, b = nodes[:-1], nodes[1:]
        lengths = [self.step[k] for k in b]
        gb = [self.gear[k] for k in b]
        # Each node's primitive rows, made once: the chains of a search's shots share
        # their stems (the rows of an edge are its own arithmetic, in any batch).
        made = self._edge_made
        edge_rows: list[np.ndarray | None] = [made.get(k) for k in b]
        new = [e for e, r in enumerate(edge_rows) if r is None]
        for length in sorted({lengths[e] for e in new}):
            idx = [e for e in new if lengths[e] == length]
            block = self._edge_rows([a[e] for e in idx], [b[e] for e in idx], length)
            for e, r in zip(idx, block, strict=True):
                edge_rows[e] = made[b[e]] = r
        # Consecutive primitives of one gear: one piece (junction rows not repeated).
        pieces: list[Piece] = []
        first = 0
        for e in range(1, len(b) + 1):
            if e == len(b) or gb[e] != gb[first]:
                rest = [edge_rows[k][1:] for k in range(first + 1, e)]
                pieces.append(Piece(gb[first], np.vstack([edge_rows[first], *rest])))
                first = e
        return pieces

    def _edge_rows(self, a: list[int], b: list[int], length: float) -> np.ndarray:
        """Rows ``(E, n + 1, 4)`` of the primitives of one ``length`` from nodes ``a`` to ``b``."""
        n = max(1, math.ceil(length / self.cfg.sample_spacing - 1e-9))
        s = length * np.arange(n + 1) / n
        xa = np.array([self.x[k] for k in a])
        ya = np.array([self.y[k] for k in a])
        yawa = np.array([self.yaw[k] for k in a])
        kb = np.array([self.kappa[k] for k in b])
        gear = np.array([self.gear[k] for k in b], dtype=np.int64)
        rows = np.empty((len(b), n + 1, 4))
        yaws = yawa[:, None] + (gear * kb)[:, None] * s[None, :]
        rows[..., 2] = yaws
        rows[..., 3] = kb[:, None]
        line = np.abs(kb) < 1e-12
        if line.any():
            gs = gear[line, None] * s[None, :]
            rows[line, :, 0] = xa[line, None] + gs * np.cos(yawa[line])[:, None]
            rows[line, :, 1] = ya[line, None] + gs * np.sin(yawa[line])[:, None]
        arc = ~line
        if arc.any():
            k, y0 = kb[arc, None], yawa[arc, None]
            rows[arc, :, 0] = xa[arc, None] + (np.sin(yaws[arc]) - np.sin(y0)) / k
            rows[arc, :, 1] = ya[arc, None] - (np.cos(yaws[arc]) - np.cos(y0)) / k
        rows[:, -1, 0] = [self.x[k] for k in b]
        rows[:, -1, 1] = [self.y[k] for k in b]
        rows[:, -1, 2] = [self.yaw[k] for k in b]
        return rows

    def _shot(self, i: int) -> Iterator[list[Piece]]:
        """The clear analytic expansions from node ``i``, shortest first.

        Lazy: a candidate is sampled and tested only when the one before it was
        rejected (the connection the search accepts ends the shot).
        """
        self.shots_tried += 1
        pose = Pose(self.x[i], self.y[i], self.yaw[i])
        for pieces in self.shots(pose):
            if self.body.all_free(np.vstack([p.rows[:, :3] for p in pieces])):
                yield pieces

    def run(
        self,
        accept: Callable[[list[Piece]], T | None],
        max_expansions: int,
        expired: Callable[[], bool],
    ) -> tuple[T | None, SearchOutcome]:
        """Search until ``accept`` takes a start-to-goal connection or the budget ends.

        Parameters
        ----------
        accept : callable
            ``accept(pieces)``: the final result made from a connection (every
            piece in driving order), or ``None`` to reject it and search on.
        max_expansions : int
            Largest number of node expansions in all (a later call resumes the
            search and may raise it).
        expired : callable
            The wall-clock safety cap.

        Returns
        -------
        (result or None, SearchOutcome)
        """
        cfg, prims, body = self.cfg, self.prims, self.body
        w = cfg.heuristic_weight
        if not self.x:  # the first call; a later one resumes where the last stopped
            start = self.start
            h0 = self.heuristic.at(start.x, start.y, start.yaw)
            root = self._add(start.x, start.y, start.yaw, 0.0, 0, math.nan, -1)
            self._heap = [(w * h0, root)]
            self._closed = set()
            self._best = {}
            self._hval = [h0]
            self._since_shot = cfg.shot_interval
            self._shot_from: set[tuple[int, int, int]] = set()
            # Each node's closing bin (a successor's is known when it is made).
            self._keys = [self.key(start.x, start.y, start.yaw, 1)]
        heap, closed, best, hval = self._heap, self._closed, self._best, self._hval
        keys = self._keys
        since_shot = self._since_shot
        gears = prims.gears.tolist()
        kappas = prims.kappas.tolist()
        # The key's gear bit of each primitive, and each one's steering-change cost after
        # a node of each curvature (the same expression, evaluated once per curvature
        # the loop meets: a query that the root's shot answers needs none).
        reverse_bit = [int(g < 0) for g in gears]
        kmax = self.kappa_max
        scc = cfg.steer_change_cost
        steer_after: dict[float, list[float]] = {}
        h_at = self.heuristic.scalar()
        shot_interval, shot_distance = cfg.shot_interval, cfg.shot_distance
        gear_change_cost = cfg.gear_change_cost
        # The node lists and key(), bound to locals (the same arithmetic: the hot loop).
        xs, ys, yaws, gs, gear_of, kappa_of, parent = (
            self.x, self.y, self.yaw, self.g, self.gear, self.kappa, self.parent
        )  # fmt: skip
        res, xmin, ymin, ny, nyaw = cfg.xy_resolution, self.xmin, self.ymin, self.ny, self.nyaw
        two_pi = 2.0 * math.pi
        inf = math.inf
        disc_room, open_sets, steps, tested = body.disc_room, self._open, self.step, self._tested
        rows_free, rows_from = body.rows_free, prims.rows_from
        shot_from, shot_cell, shot_bin = self._shot_from, cfg.shot_cell, cfg.shot_bin
        heappop, heappush, ge = heapq.heappop, heapq.heappush, operator.ge
        expansions, max_solutions = self.expansions, cfg.max_solutions
        reason = "exhausted"
        while heap:
            _f, i = heappop(heap)
            k = keys[i]
            if k in closed:
                continue
            if expansions >= max_expansions:
                heappush(heap, (_f, i))  # not expanded: a later call takes it
                reason = "expansions"
                break
            if expired():
                reason = "time"
                break
            closed.add(k)
            expansions += 1
            xi, yi, yawi, gi, geari = xs[i], ys[i], yaws[i], gs[i], gear_of[i]
            since_shot += 1
            h = hval[i]
            # h = inf (no way to the goal from here, a start a caller gave directly):
            # int(inf) raised OverflowError; its children are pruned, so it runs out.
            interval = min(shot_interval, max(1, int(h / shot_distance))) if h < inf else 1
            if since_shot >= interval:
                since_shot = 0
                # A shot from near a pose whose shots all failed runs into the same
                # obstacles (the retries after a failure shoot every time: small moves
                # decide in tight spots).
                sk = None
                if shot_cell > 0.0:
                    iyaw = int(yawi % two_pi // shot_bin)
                    sk = (int(xi // shot_cell), int(yi // shot_cell), iyaw)
                found = 0
                if sk not in shot_from:
                    known = None if self._earlier is None else self._known(i)
                    if known is not None:
                        # The earlier search's shot from this very node: rejected, counted.
                        self.shots_tried += 1
                        for _ in range(known):
                            found += 1
                            self.connections += 1
                            if self.connections >= max_solutions:
                                self.expansions, self._since_shot = expansions, since_shot
                                return None, self._outcome("rejected")
                    else:
                        chain = None  # the node's pieces, made once for all its connections
                        for pieces in self._shot(i):
                            found += 1
                            self.connections += 1
                            if chain is None:
                                chain = self.chain(i)
                            out = accept(chain + pieces)
                            if out is not None:
                                self.expansions, self._since_shot = expansions, since_shot
                                return out, self._outcome("solved")
                            if self.connections >= max_solutions:
                                self.expansions, self._since_shot = expansions, since_shot
                                return None, self._outcome("rejected")
                    self.shot_counts[i] = found
                if not found and sk is not None:
                    shot_from.add(sk)
            ki = kappa_of[i]
            # The steering-change costs after this curvature (none after the root's NaN).
            steer = steer_after.get(ki)
            if steer is None and ki == ki:
                steer = steer_after[ki] = [scc * abs(kj - ki) / kmax for kj in kappas]
            # The longest primitives whose sweep the node's discs have room for need no
            # body test (free_within); with room for none, the step arcs and the test.
            room = disc_room(xi, yi, yawi)
            for arcs in open_sets:
                if all(map(ge, room, arcs.reach)):
                    break
            else:
                arcs = tested
            c0, s0 = math.cos(yawi), math.sin(yawi)
            costs = arcs.costs
            # Closed bins, unreachable cells and dearer duplicates go before the body test.
            # The end poses: PrimitiveSet.poses_from's last rows, the same arithmetic.
            cand: list[tuple[int, int, float, float, float, float, float]] = []
            for j, (lx, ly, dy) in enumerate(arcs.ends):
                ex, ey, eyaw = xi + c0 * lx - s0 * ly, yi + s0 * lx + c0 * ly, yawi + dy
                # self.key(ex, ey, eyaw, gears[j]), inlined
                iyaw = int(((eyaw % two_pi) / two_pi) * nyaw) % nyaw
                kj = (
                    (((int((ex - xmin) // res) * ny + int((ey - ymin) // res)) * nyaw + iyaw) << 1)
                    | reverse_bit[j]
                )  # fmt: skip
                if kj in closed:
                    continue
                hj = h_at(ex, ey, eyaw)
                if hj == inf:
                    continue
                cost = gi + costs[j]
                if geari and gears[j] != geari:
                    cost += gear_change_cost
                if steer is not None:
                    cost += steer[j]
                if cost >= best.get(kj, inf):
                    continue
                cand.append((j, kj, cost, hj, ex, ey, eyaw))
            if not cand:
                continue
            if arcs is tested:
                if len(cand) == len(gears):
                    free = rows_free(rows_from(xi, yi, yawi), len(cand)).tolist()
                else:
                    keep = [c[0] for c in cand]
                    free = rows_free(rows_from(xi, yi, yawi, keep), len(cand)).tolist()
                cand = [c for c, ok in zip(cand, free, strict=True) if ok]
            step_len = arcs.length
            for j, kj, cost, hj, ex, ey, eyaw in cand:
                best[kj] = cost
                n = len(xs)
                xs.append(ex)
                ys.append(ey)
                yaws.append(eyaw)
                gs.append(cost)
                gear_of.append(gears[j])
                kappa_of.append(kappas[j])
                parent.append(i)
                steps.append(step_len)
                hval.append(hj)
                keys.append(kj)
                heappush(heap, (cost + w * hj, n))
        self.expansions, self._since_shot = expansions, since_shot
        return None, self._outcome(reason)

    def _outcome(self, reason: str) -> SearchOutcome:
        return SearchOutcome(
            reason, self.expansions, len(self.x), self.shots_tried, self.connections
        )
