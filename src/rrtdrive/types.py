"""Plain data types shared by every part of rrtdrive.

Everything here is a frozen dataclass validated on construction; bulk geometry
travels as numpy arrays.
"""

from __future__ import annotations

import enum
import math
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

import numpy as np

from rrtdrive.arrays import ReadOnlyArrays, read_only_array
from rrtdrive.values import brief_repr, is_finite_number

if TYPE_CHECKING:  # the diagnosis module imports this one
    from rrtdrive.planning.diagnosis import Diagnosis

__all__ = [
    "read_only_array",
    "InputError",
    "InputWarning",
    "Pose",
    "VehicleParams",
    "Path",
    "Tree",
    "PlanStatus",
    "PlanResult",
    "Budget",
]


class InputError(ValueError):
    """Bad user input; the message names the offending field."""


class InputWarning(UserWarning):
    """Input that is valid but probably not what the user meant; names the field.

    The CLI prints it as one ``warning:`` line on stderr and goes on.
    """


def require_finite(name: str, *values: float) -> None:
    """Raise :class:`InputError` naming ``name`` unless every value is a finite real number.

    Parameters
    ----------
    name : str
        Field name used in the error message.
    *values : float
        Values to check.

    Examples
    --------
    >>> require_finite("size", 10**400)
    Traceback (most recent call last):
    ...
    rrtdrive.types.InputError: size: must be finite, got 1000000000...(401 digits)
    """
    for v in values:
        if isinstance(v, bool) or not isinstance(v, (int, float, np.integer, np.floating)):
            raise InputError(f"{name}: expected a number, got {brief_repr(v)}")
        if not is_finite_number(v):
            raise InputError(f"{name}: must be finite, got {brief_repr(v)}")


def require_positive(name: str, value: float) -> None:
    """Raise :class:`InputError` unless ``value`` is a finite number > 0."""
    require_finite(name, value)
    if value <= 0:
        raise InputError(f"{name}: must be > 0, got {brief_repr(value)}")


def require_int(name: str, value: object, minimum: int = 1, maximum: int | None = None) -> int:
    """Raise :class:`InputError` naming ``name`` unless ``value`` is an integer in range.

    Booleans are rejected (``True`` is an ``int`` to Python, never to a user).

    Parameters
    ----------
    name : str
        Field name used in the error message.
    value : object
        The value to check.
    minimum, maximum : int
        Inclusive bounds (``maximum=None``: no upper bound).

    Returns
    -------
    int
        ``value`` as a plain ``int``.

    Examples
    --------
    >>> require_int("runs", 3)
    3
    >>> require_int("runs", 0)
    Traceback (most recent call last):
    ...
    rrtdrive.types.InputError: runs: must be an integer >= 1, got 0
    """
    if (
        isinstance(value, (bool, np.bool_))
        or not isinstance(value, (int, np.integer))
        or value < minimum
        or (maximum is not None and value > maximum)
    ):
        bound = f">= {minimum}" if maximum is None else f"in {minimum}..{maximum}"
        raise InputError(f"{name}: must be an integer {bound}, got {brief_repr(value)}")
    return int(value)


@dataclass(frozen=True)
class Pose:
    """A planar pose of the rear-axle centre: position in metres, yaw in radians (CCW from +x).

    Parameters
    ----------
    x, y : float
        Position of the rear-axle centre in metres.
    yaw : float
        Where the nose points, in radians counter-clockwise from +x (not wrapped).
    """

    x: float
    y: float
    yaw: float

    def __post_init__(self) -> None:
        require_finite("pose", self.x, self.y, self.yaw)
        object.__setattr__(self, "x", float(self.x))
        object.__setattr__(self, "y", float(self.y))
        object.__setattr__(self, "yaw", float(self.yaw))

    @classmethod
    def from_seq(cls, values: object, name: str = "pose") -> Pose:
        """Build a pose from a ``[x, y, yaw]`` sequence, naming ``name`` in errors."""
        if not isinstance(values, (list, tuple, np.ndarray)) or len(values) != 3:
            raise InputError(f"{name}: expected [x, y, yaw], got {brief_repr(values)}")
        require_finite(name, *values)
        return cls(float(values[0]), float(values[1]), float(values[2]))

    def as_tuple(self) -> tuple[float, float, float]:
        """Return ``(x, y, yaw)``."""
        return (self.x, self.y, self.yaw)

    @property
    def xy(self) -> np.ndarray:
        """Position as a length-2 array."""
        return np.array([self.x, self.y])


#: The largest turning radius a car may have, metres (a lorry's is about 12 m; at 1e6 m
#: the planners' arc samples ran to gigabytes).
MAX_TURNING_RADIUS = 1e4


@dataclass(frozen=True)
class VehicleParams:
    """The car of the paper (Table 2): the single source of truth for every module.

    Parameters
    ----------
    length, width : float
        Body size in metres.
    wheelbase : float
        Distance rear axle to front axle in metres.
    min_turning_radius : float
        Minimum turning radius of the rear axle in metres; the binding path limit.
    max_steer : float
        Actuator limit of the front-wheel angle in radians.
    max_steer_rate : float or None
        Largest rate of the front-wheel angle in rad/s (default 0.4, CommonRoad's
        vehicles' value): the simulated ego's steering angle slews toward the command
        at no more than this, and the controllers know it (docs/metrics.md
        "Drivability"). ``None`` or ``inf`` (kept as ``None``): the angle follows the
        command at once (instant steering, the car before issue 12).

    Examples
    --------
    >>> v = VehicleParams()
    >>> round(v.kappa_max, 4), round(v.rear_overhang, 3)
    (0.1667, 0.895)
    """

    length: float = 4.30
    width: float = 1.80
    wheelbase: float = 2.51
    min_turning_radius: float = 6.0
    max_steer: float = math.radians(30.0)
    max_steer_rate: float | None = 0.4

    def __post_init__(self) -> None:
        for name in ("length", "width", "wheelbase", "min_turning_radius", "max_steer"):
            require_positive(f"vehicle.{name}", getattr(self, name))
        rate = self.max_steer_rate
        if isinstance(rate, (np.integer, np.floating)):
            rate = float(rate)  # numpy numbers, as the other fields take them
            object.__setattr__(self, "max_steer_rate", rate)
        if rate is not None and (
            isinstance(rate, (bool, np.bool_))
            or not isinstance(rate, (int, float))
            or math.isnan(rate)
            or rate <= 0
        ):
            raise InputError(
                f"vehicle.max_steer_rate: must be > 0 rad/s, inf or None, got {rate!r}"
            )
        if rate == math.inf:  # one car, one value: equal to None's, and so in JSON (null)
            object.__setattr__(self, "max_steer_rate", None)
        # Paths are rows 0.25 m apart, bodies checked 0.1 m apart; a slower actuator's
        # turns run for kilometres (1e-12 rad/s: an 8 GiB allocation; an audit).
        for name, least, unit, why in (
            ("length", 0.5, "m", "paths are sampled every 0.25 m"),
            ("min_turning_radius", 0.5, "m", "paths are sampled every 0.25 m"),
            ("max_steer_rate", 0.01, "rad/s", "a slower actuator's turns run for "
             "kilometres; None or inf for instant steering"),
        ):  # fmt: skip
            value = getattr(self, name)
            if value is not None and value < least:
                raise InputError(
                    f"vehicle.{name}: at least {least:g} {unit} ({why}), got {value!r}"
                )
        if self.min_turning_radius > MAX_TURNING_RADIUS:
            # Arcs of such a radius are sampled over kilometres (gigabytes of poses).
            raise InputError(
                f"vehicle.min_turning_radius: at most {MAX_TURNING_RADIUS:g} m, "
                f"got {self.min_turning_radius:g}"
            )
        if self.wheelbase >= self.length:
            raise InputError(
                f"vehicle.wheelbase: must be shorter than the length {self.length}, "
                f"got {self.wheelbase}"
            )
        if self.max_steer >= math.pi / 2:
            raise InputError(f"vehicle.max_steer: must be below pi/2, got {self.max_steer}")
        if self.wheelbase / math.tan(self.max_steer) > self.min_turning_radius + 1e-9:
            raise InputError(
                "vehicle.min_turning_radius: the steering limit cannot reach it "
                f"(wheelbase / tan(max_steer) = "
                f"{self.wheelbase / math.tan(self.max_steer):.3f} m > {self.min_turning_radius} m)"
            )

    @property
    def rear_overhang(self) -> float:
        """Distance from the rear axle back to the rear bumper (symmetric body)."""
        return (self.length - self.wheelbase) / 2.0

    @property
    def front_extent(self) -> float:
        """Distance from the rear axle forward to the front bumper."""
        return self.length - self.rear_overhang

    @property
    def kappa_max(self) -> float:
        """Largest admissible path curvature, 1 / min_turning_radius."""
        return 1.0 / self.min_turning_radius

    @property
    def steer_for_kappa_max(self) -> float:
        """Steering angle that drives the curvature limit, atan(L * kappa_max)."""
        return math.atan(self.wheelbase * self.kappa_max)


@dataclass(frozen=True, eq=False)
class Path(ReadOnlyArrays):
    """A sampled path: rows ``[x, y, yaw, kappa, gear]`` of the rear-axle centre.

    ``gear`` is +1 driving forward and -1 in reverse; ``yaw`` is where the car's
    nose points in both gears (so a reversing car travels along ``yaw + pi``);
    ``kappa = tan(delta) / L`` is the steering's curvature in both gears. Where the
    gear changes (a cusp) the position row repeats with the new gear, so the cusp
    adds nothing to the travelled length and every gear segment starts and ends
    at the cusp pose.

    Parameters
    ----------
    samples : array_like
        Shape ``(N, 5)``, or ``(N, 4)`` rows ``[x, y, yaw, kappa]`` that get gear +1
        (every forward-only producer); empty for a failed plan.
    waypoints : array_like
        Shape ``(M, 2)``: the control points or polyline vertices the path came from.

    Attributes
    ----------
    samples : numpy.ndarray
        Shape ``(N, 5)``, read-only; ``(0, 5)`` for a failed plan.
    waypoints : numpy.ndarray
        Shape ``(M, 2)``, read-only.

    Examples
    --------
    >>> xs = np.linspace(0.0, 5.0, 6)
    >>> fwd = np.column_stack([xs, 0 * xs, 0 * xs, 0 * xs, 1 + 0 * xs])
    >>> back = np.column_stack([xs[::-1], 0 * xs, 0 * xs, 0 * xs, -1 + 0 * xs])
    >>> p = Path(np.vstack([fwd, back]), np.zeros((0, 2)))
    >>> p.cusps.tolist(), p.segments(), p.length, p.is_forward_only
    ([6], [(0, 6), (6, 12)], 10.0, False)
    >>> Path(fwd[:, :4], np.zeros((0, 2))).samples.shape
    (6, 5)
    """

    samples: np.ndarray
    waypoints: np.ndarray

    def __post_init__(self) -> None:
        try:
            s = np.asarray(self.samples, dtype=float)
        except (TypeError, ValueError):
            raise InputError(
                f"path.samples: expected rows of numbers, got {brief_repr(self.samples)}"
            ) from None
        if s.size == 0:
            s = np.zeros((0, 5))
        elif s.ndim != 2 or s.shape[1] not in (4, 5):
            raise InputError(
                f"path.samples: expected rows [x, y, yaw, kappa, gear] (or [x, y, yaw, kappa]), "
                f"got shape {s.shape}"
            )
        elif s.shape[1] == 4:
            s = np.column_stack([s, np.ones(len(s))])
        else:
            s = s.copy()
            bad = np.flatnonzero((s[:, 4] != 1.0) & (s[:, 4] != -1.0))
            if len(bad):
                raise InputError(
                    "path.gear: must be +1 (forward) or -1 (reverse), got "
                    f"{float(s[bad[0], 4])!r} in row {int(bad[0])}"
                )
        try:  # a copy: the caller's array stays theirs to change
            w = np.array(self.waypoints, dtype=float)
        except (TypeError, ValueError):
            got = brief_repr(self.waypoints)
            raise InputError(f"path.waypoints: expected [x, y] pairs, got {got}") from None
        if w.size == 0:
            w = np.zeros((0, 2))
        elif w.ndim != 2 or w.shape[1] != 2:
            raise InputError(f"path.waypoints: expected [x, y] pairs, got shape {w.shape}")
        for name, a in (("samples", s), ("waypoints", w)):
            if not np.isfinite(a).all():
                row, col = (int(v) for v in np.argwhere(~np.isfinite(a))[0])
                raise InputError(
                    f"path.{name}: must be finite, got {float(a[row, col])!r} in row {row}, "
                    f"column {col}"
                )
        s.setflags(write=False)
        w.setflags(write=False)
        object.__setattr__(self, "samples", s)
        object.__setattr__(self, "waypoints", w)

    def __repr__(self) -> str:
        # numpy printed up to a thousand numbers in full (20 161 characters for 195 rows).
        return (
            f"Path(rows={len(self.samples)}, length={self.length:.2f} m, "
            f"cusps={len(self.cusps)}, waypoints={len(self.waypoints)})"
        )

    @classmethod
    def empty(cls) -> Path:
        """An empty path ``(0, 5)``, used by failed plans."""
        return cls(np.zeros((0, 5)), np.zeros((0, 2)))

    def __len__(self) -> int:
        return len(self.samples)

    @property
    def xy(self) -> np.ndarray:
        """Sample positions, shape ``(N, 2)``."""
        return self.samples[:, :2]

    @property
    def gears(self) -> np.ndarray:
        """Gear per row, shape ``(N,)`` of ints: +1 forward, -1 reverse."""
        return self.samples[:, 4].astype(np.int64)

    @property
    def cusps(self) -> np.ndarray:
        """Indices of the rows where the gear changes (the first row of each new gear)."""
        g = self.samples[:, 4]
        return np.flatnonzero(g[1:] != g[:-1]) + 1

    @property
    def is_forward_only(self) -> bool:
        """True when every row is in gear +1 (also for an empty path)."""
        return bool(np.all(self.samples[:, 4] > 0))

    def segments(self) -> list[tuple[int, int]]:
        """Row slices ``(start, stop)`` of the gear segments, in order.

        Each segment is one gear, drivable on its own; consecutive segments share
        the cusp position (the last row of one repeats as the first of the next).
        An empty path has no segments.
        """
        if len(self.samples) == 0:
            return []
        bounds = [0, *self.cusps.tolist(), len(self.samples)]
        return [(int(a), int(b)) for a, b in zip(bounds[:-1], bounds[1:], strict=True)]

    @property
    def length(self) -> float:
        """Travelled length of the sampled polyline in metres (a cusp row adds 0)."""
        if len(self.samples) < 2:
            return 0.0
        return float(np.sum(np.hypot(*np.diff(self.samples[:, :2], axis=0).T)))

    @property
    def max_curvature(self) -> float:
        """Largest absolute curvature over the samples (0 for an empty path)."""
        return float(np.max(np.abs(self.samples[:, 3]))) if len(self.samples) else 0.0

    def arc_length(self) -> np.ndarray:
        """Cumulative travelled length at each sample, starting at 0."""
        if len(self.samples) == 0:
            return np.zeros(0)
        steps = np.hypot(*np.diff(self.samples[:, :2], axis=0).T)
        return np.concatenate([[0.0], np.cumsum(steps)])


@dataclass(frozen=True, eq=False)
class Tree(ReadOnlyArrays):
    """A search tree for plotting: node positions and parent indices (-1 for the root).

    Parameters
    ----------
    nodes : numpy.ndarray
        Node positions ``(N, 2)`` (kept as a read-only copy).
    parents : numpy.ndarray
        ``(N,)`` index of each node's parent in ``nodes``, -1 for a root.
    """

    nodes: np.ndarray
    parents: np.ndarray

    def __post_init__(self) -> None:
        object.__setattr__(self, "nodes", read_only_array(self.nodes, float).reshape(-1, 2))
        object.__setattr__(self, "parents", read_only_array(self.parents, np.int64).reshape(-1))
        n, parents = len(self.nodes), self.parents
        if len(parents) != n or np.any((parents < -1) | (parents >= n)):
            raise InputError(
                f"tree.parents: expected one index in [-1, {n}) per node ({n}), "
                f"got {brief_repr(parents.tolist())}"
            )

    def __len__(self) -> int:
        return len(self.nodes)

    def edges(self) -> np.ndarray:
        """Segments ``(E, 2, 2)`` from each non-root node to its parent."""
        child = np.flatnonzero(self.parents >= 0)
        return np.stack([self.nodes[child], self.nodes[self.parents[child]]], axis=1)


class PlanStatus(enum.Enum):
    """Outcome of a planning query (after OMPL's PlannerStatus)."""

    SOLVED = "solved"
    NO_PATH_IN_BUDGET = "no_path_in_budget"
    PROVEN_UNREACHABLE = "proven_unreachable"
    INVALID_START = "invalid_start"
    INVALID_GOAL = "invalid_goal"
    POSTPROCESS_FAILED = "postprocess_failed"
    #: The wall-clock safety cap (:attr:`Budget.max_time_s`) stopped the query before
    #: its counted budgets did: the outcome depends on the machine's speed.
    TIMEOUT = "timeout"

    @property
    def success(self) -> bool:
        """True only for :attr:`SOLVED`."""
        return self is PlanStatus.SOLVED


@dataclass(frozen=True)
class Budget:
    """Limits on a query: counted budgets decide, the wall clock is only a safety cap.

    A seeded query's outcome is decided by counts alone (``max_iterations`` here;
    each planner's post-processing has its own counted limits, e.g. the improved
    planner's repair rounds, tree paths and Dubins fallback candidates), so it is
    the same on any machine. ``max_time_s`` is a safety cap: a query that reaches
    it stops with :attr:`PlanStatus.TIMEOUT` (never a solved path or another
    failure), because what it would have returned depends on the machine's speed.

    Parameters
    ----------
    max_iterations : int
        Largest number of sampling iterations (the budget that decides).
    max_time_s : float
        Wall-clock safety cap in seconds (per-map set-up excluded); the default is
        set high enough that queries finish by count on slow machines too: the
        slowest budgeted query known (fuzzed map fz891, Hybrid A* forward, 20 000
        expansions) took 36.6 s of CPU on a machine about 3x slower than the one
        where it took 12 s (session 34), so 120 s leaves over 3x that.

    Examples
    --------
    >>> Budget().max_iterations, Budget().max_time_s
    (20000, 120.0)
    """

    max_iterations: int = 20_000
    max_time_s: float = 120.0

    def __post_init__(self) -> None:
        # Plain Python numbers: a numpy scalar kept as given fails json.dumps later.
        its = require_int("budget.max_iterations", self.max_iterations)
        require_positive("budget.max_time_s", self.max_time_s)
        object.__setattr__(self, "max_iterations", its)
        object.__setattr__(self, "max_time_s", float(self.max_time_s))


@dataclass(frozen=True, eq=False)
class PlanResult(ReadOnlyArrays):
    """What every planner returns, successful or not (never ``None``).

    Attributes
    ----------
    status : PlanStatus
        Outcome; ``status.success`` is the success flag (given as text, its value).
    planner : str
        Registered planner name.
    path : Path
        Final sampled path (empty on failure).
    raw_path : numpy.ndarray
        The tree path before any post-processing, shape ``(K, 2)``.
    trees : tuple of Tree
        Search trees for plotting (one or two).
    nodes : int
        Total number of tree nodes.
    iterations : int
        Sampling iterations used.
    planning_time_s : float
        Wall time of the query, per-map set-up excluded.
    message : str
        Human-readable reason on failure, or a short summary.
    stats : dict
        Extra per-planner statistics (floats and ints): the result's own copy, a plain
        dict (``json.dumps`` takes it).
    setup_time_s : float
        Wall time of the per-map set-up this query triggered (connectivity labels,
        sampling cells, expanded obstacles, passage cells), outside ``planning_time_s``
        and outside the budget; near 0 (its cache look-ups, under a millisecond) when
        the map's checker had it all already.
    diagnosis : rrtdrive.planning.diagnosis.Diagnosis or None
        On a failure, the constraint that makes the query hard or impossible, in
        the user's terms (:func:`rrtdrive.planning.diagnosis.diagnose`); ``None``
        on success or when no finding applies.
    """

    status: PlanStatus
    planner: str
    path: Path
    raw_path: np.ndarray
    trees: tuple[Tree, ...]
    nodes: int
    iterations: int
    planning_time_s: float
    message: str = ""
    stats: dict[str, float] = field(default_factory=dict)
    setup_time_s: float = 0.0
    diagnosis: Diagnosis | None = None

    def __post_init__(self) -> None:
        # Read-only arrays and a dict of its own: a result is not changed through
        # another object that shares its data.
        if not isinstance(self.status, PlanStatus):
            try:  # its value as text ("solved"), as the JSON and bench rows spell it
                object.__setattr__(self, "status", PlanStatus(self.status))
            except ValueError:
                raise InputError(
                    f"result.status: must be one of {', '.join(k.value for k in PlanStatus)}, "
                    f"got {brief_repr(self.status)}"
                ) from None
        raw = np.zeros((0, 2)) if self.raw_path is None else self.raw_path
        object.__setattr__(self, "raw_path", read_only_array(raw, float))
        object.__setattr__(self, "stats", dict(self.stats))

    def __repr__(self) -> str:
        # The arrays and trees run to thousands of characters: the outcome in one line.
        return (
            f"PlanResult({self.status.value}, planner={self.planner!r}, "
            f"length={self.path.length:.2f} m, rows={len(self.path)}, nodes={self.nodes}, "
            f"iterations={self.iterations}, planning_time_s={self.planning_time_s:.4f})"
        )

    @property
    def success(self) -> bool:
        """True when a path was found and passed the planner's own checks.

        For ``improved-rrt-connect`` and ``hybrid-a-star`` that is the car's whole body,
        curvature and headings; the baselines (``rrt``, ``rrt-connect``, ``rrt-star``)
        check their tree's edges only and return raw paths that ``rrtdrive.verify``
        fails (README, "Planners").
        """
        return self.status.success
