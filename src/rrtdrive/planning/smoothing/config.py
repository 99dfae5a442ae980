"""Tunables and outcome of the post-processor (:func:`.drivable.make_drivable`)."""

from __future__ import annotations

import dataclasses
import enum
import math
from collections.abc import Mapping
from dataclasses import dataclass, field

import numpy as np

from rrtdrive.planning.options import MAX_RADIUS_FACTOR, check_known
from rrtdrive.types import (
    InputError,
    VehicleParams,
    require_finite,
    require_int,
    require_positive,
)

__all__ = [
    "MOVE_DIRECTIONS",
    "DEFAULT_CORNER_MOVES",
    "STEER_RATE_DESIGN_SPEED",
    "sharpness_bound",
    "smoothing_for_car",
    "CurveKind",
    "SmoothingConfig",
    "SmoothingResult",
    "smoothing_with",
]

#: Speed (m/s) at which a path of the default sharpness bound needs exactly the
#: actuator's largest steering rate: the bound is ``max_steer_rate / 2 m/s``.
STEER_RATE_DESIGN_SPEED = 2.0


def sharpness_bound(configured: float, max_steer_rate: float | None) -> float:
    """The query's ``max_sharpness``: the config's, or the car's rate / 2 m/s when smaller.

    The config's bound (0.2 rad/m by default, for CommonRoad's 0.4 rad/s) holds for a
    car without a rate limit too, so that the default paths are drivable by any
    actuator at least that fast; a slower actuator tightens it.

    Examples
    --------
    >>> sharpness_bound(0.2, None), sharpness_bound(0.2, 0.3), sharpness_bound(0.2, 1.0)
    (0.2, 0.15, 0.2)
    """
    if max_steer_rate is None or not math.isfinite(max_steer_rate):
        return configured
    return min(configured, max_steer_rate / STEER_RATE_DESIGN_SPEED)


def smoothing_for_car(
    smoothing: SmoothingConfig, vehicle: VehicleParams, **query: float
) -> SmoothingConfig:
    """``smoothing`` for ``vehicle``: its ``kappa_max``, ``wheelbase`` and sharpness bound.

    The bound is :func:`sharpness_bound`'s; a car steering slower than 0.04 rad/s
    brings it under the gentlest turns' sharpness (0.02), which may then be no
    gentler than the bound. ``query``: the query's other fields (``clearance``,
    ``heading_leg``). The improved planner's and Hybrid A*'s post-processors both.
    """
    bound = sharpness_bound(smoothing.max_sharpness, vehicle.max_steer_rate)
    return dataclasses.replace(
        smoothing, kappa_max=vehicle.kappa_max, wheelbase=vehicle.wheelbase,
        max_sharpness=bound, min_sharpness=min(smoothing.min_sharpness, bound), **query,
    )  # fmt: skip


class CurveKind(enum.Enum):
    """The curve the post-processor fits to the key polygon."""

    #: Straight legs joined by symmetric clothoid turns: continuous curvature and a
    #: bounded steering rate per metre (the default).
    CLOTHOID = "clothoid"
    #: The paper's clamped uniform B-spline of ``SmoothingConfig.degree`` (2 in the paper):
    #: curvature jumps where a leg meets a fillet.
    BSPLINE = "bspline"

#: Directions a corner can be moved in, each from its original place: "back" along its
#: outgoing line (the outgoing straight starts earlier), "ahead" on along its incoming
#: line (the incoming straight lasts longer), "behind" back along its incoming line
#: (the turn starts earlier), "out"/"in" along the bisector. Heading-leg corners move
#: only along their ray (the start's "ahead", the goal's "back").
MOVE_DIRECTIONS = frozenset({"back", "ahead", "behind", "out", "in"})

#: Moves tried, in order, for a corner whose rounded piece still collides (or whose
#: legs are too short): ``(direction, distance in m)``.
DEFAULT_CORNER_MOVES: tuple[tuple[str, float], ...] = (
    ("back", 1.5), ("ahead", 1.5), ("behind", 2.0), ("out", 1.0),
    ("back", 3.0), ("ahead", 3.0), ("behind", 4.0), ("out", 2.0),
    ("back", 5.0), ("ahead", 5.0), ("behind", 7.0), ("out", 3.5), ("in", 1.0),
    ("back", 8.0), ("ahead", 8.0), ("behind", 10.0), ("back", 12.0), ("ahead", 12.0),
)  # fmt: skip


@dataclass(frozen=True)
class SmoothingConfig:
    """Tunables of the post-processor.

    Parameters
    ----------
    kappa_max : float
        Largest admissible curvature in 1/m (the car's ``kappa_max``).
    curve : CurveKind or str
        ``CLOTHOID`` (default: continuous curvature, sharpness bounded by
        ``max_sharpness``) or ``BSPLINE`` (the paper's pipeline, of ``degree``); or
        its value as text, as a plan JSON's ``planner_options`` give it (``"bspline"``).
    degree : int
        B-spline degree, 2 (paper) or 3; only for ``curve=BSPLINE``.
    max_sharpness : float
        Largest steering rate per metre ``|d delta / ds|`` (rad/m, ``delta =
        atan(wheelbase kappa)``) of a ``CLOTHOID`` curve, checked exactly on the result:
        ``max_steer_rate / STEER_RATE_DESIGN_SPEED`` (0.2 rad/m for 0.4 rad/s).
    min_sharpness : float
        The gentlest clothoid turns used where the legs leave room (rad/m).
    gentle_radius_steps : tuple of float
        Multiples of a corner's radius its clothoid turn may widen to where the legs
        leave room (with the gentlest sharpness that fits): the turn with the longest
        tangent that fits is taken, so it cuts the corner as a spline would.
    wheelbase : float
        ``L`` in metres, for ``delta = atan(L kappa)`` (the car's).
    prune, sharp_repair, supplement : bool
        Switch the paper's steps on or off.
    supplement_delta, supplement_n : float
        Eq. 16 threshold ``delta`` (m) and distance multiple ``N``.
    heading_leg : float
        Initial length of the straight legs along the start and goal headings (m);
        they grow when the turn after them needs more room.
    sample_spacing : float
        Largest arc-length gap between output samples (m).
    check_spacing : float
        Largest gap between the poses given to the exact body test (m).
    kappa_safety : float
        Fillets and clothoid arcs are designed for ``kappa_safety * kappa_max``, the
        tightest clothoids for ``kappa_safety * max_sharpness``.
    fillet_max_angle : float
        Largest turn per fillet vertex (radians).
    max_rounds : int
        Largest number of fit-check-repair rounds.
    clearance : float
        Distance the body must keep from obstacles along the curve (exact test).
    radius_steps : tuple of float
        Fillet radii tried in turn at a corner that breaks a limit, as multiples
        of the design radius (:attr:`design_radius`), before the corner is moved.
    corner_moves : tuple of (str, float)
        Moves tried in turn after the fillets, each ``(direction, distance in m)``
        from the corner's original place; directions in :data:`MOVE_DIRECTIONS`.
    unprune_turn : float
        Turn limit (radians) of the hairpin-avoiding pruning: the second attempt
        after the paper's pure pruning, and the putting back of tree nodes.
    hairpin_turn : float
        Moving a heading corner or lengthening its leg may not sharpen its turn
        beyond this (radians), unless it is already sharper.
    unprune_hairpin_turn : float
        A too-short leg puts back the tree nodes around a corner turning more than
        this (radians).
    drop_hairpin_turn : float
        A corner is not dropped when that would leave a neighbour turning more than
        this (radians): no fillet could round it.
    end_gap : float
        Straight gap (m) kept between a fillet and the start or goal point, so the
        curve leaves and arrives along the given headings.
    """

    kappa_max: float = 1.0 / 6.0
    curve: CurveKind = CurveKind.CLOTHOID
    degree: int = 2
    max_sharpness: float = 0.2
    min_sharpness: float = 0.02
    gentle_radius_steps: tuple[float, ...] = (1.0, 1.5, 2.25, 3.5, 5.0)
    wheelbase: float = 2.51
    prune: bool = True
    sharp_repair: bool = True
    supplement: bool = True
    supplement_delta: float = 5.66
    supplement_n: float = 0.5
    heading_leg: float = 5.0
    sample_spacing: float = 0.25
    check_spacing: float = 0.1
    kappa_safety: float = 0.97
    fillet_max_angle: float = math.radians(10.0)
    max_rounds: int = 30
    clearance: float = 0.0
    radius_steps: tuple[float, ...] = (1.0, 1.6)
    corner_moves: tuple[tuple[str, float], ...] = DEFAULT_CORNER_MOVES
    unprune_turn: float = math.radians(100.0)
    hairpin_turn: float = math.radians(135.0)
    unprune_hairpin_turn: float = math.radians(120.0)
    drop_hairpin_turn: float = math.radians(150.0)
    end_gap: float = 0.05

    def __post_init__(self) -> None:
        for name in (
            "kappa_max",
            "supplement_delta",
            "heading_leg",
            "sample_spacing",
            "check_spacing",
            "max_sharpness",
            "min_sharpness",
            "wheelbase",
        ):
            require_positive(f"smoothing.{name}", getattr(self, name))
        if isinstance(self.curve, str) and self.curve in {k.value for k in CurveKind}:
            # The name as a plan JSON's planner_options and --planner-option spell it.
            object.__setattr__(self, "curve", CurveKind(self.curve))
        if not isinstance(self.curve, CurveKind):
            raise InputError(
                f"smoothing.curve: must be one of {', '.join(k.value for k in CurveKind)}, "
                f"got {self.curve!r}"
            )
        if self.min_sharpness > self.max_sharpness:
            raise InputError(
                f"smoothing.min_sharpness: must be <= max_sharpness {self.max_sharpness}, "
                f"got {self.min_sharpness!r}"
            )
        if self.degree not in (2, 3):
            raise InputError(f"smoothing.degree: must be 2 or 3, got {self.degree!r}")
        if not 0.0 < self.supplement_n < 1.0:
            raise InputError(
                f"smoothing.supplement_n: must lie in (0, 1), got {self.supplement_n!r}"
            )
        # At least 1 / MAX_RADIUS_FACTOR: the design radius is 1 / (kappa_safety kappa_max).
        if not 1.0 / MAX_RADIUS_FACTOR <= self.kappa_safety <= 1.0:
            raise InputError(
                f"smoothing.kappa_safety: must lie in [{1.0 / MAX_RADIUS_FACTOR:g}, 1], "
                f"got {self.kappa_safety!r}"
            )
        if not 0.0 < self.fillet_max_angle <= math.pi / 2:
            raise InputError("smoothing.fillet_max_angle: must lie in (0, pi/2]")
        require_int("smoothing.max_rounds", self.max_rounds)
        # A negative clearance let the exact body test call a pose 2 m inside a car free
        # (a mutation audit; only the Python API could set it, the planners set their own).
        require_finite("smoothing.clearance", self.clearance)
        if self.clearance < 0.0:
            raise InputError(f"smoothing.clearance: must be >= 0 (metres), got {self.clearance!r}")
        for name in ("prune", "sharp_repair", "supplement"):
            if not isinstance(getattr(self, name), bool):  # "no" is truthy: pruning on
                raise InputError(
                    f"smoothing.{name}: expected true or false, got {getattr(self, name)!r}"
                )
        self._check_repair_constants()

    def _check_repair_constants(self) -> None:
        steps = self.gentle_radius_steps
        if not isinstance(steps, tuple) or not steps or any(
            not isinstance(x, (int, float)) or not math.isfinite(x) or x < 1.0 for x in steps
        ):
            raise InputError(
                "smoothing.gentle_radius_steps: must be a non-empty tuple of numbers >= 1, "
                f"got {steps!r}"
            )
        if not isinstance(self.radius_steps, tuple) or not self.radius_steps:
            raise InputError(
                f"smoothing.radius_steps: must be a non-empty tuple, got {self.radius_steps!r}"
            )
        for step in self.radius_steps:
            require_positive("smoothing.radius_steps", step)
        if not isinstance(self.corner_moves, tuple):
            raise InputError(
                f"smoothing.corner_moves: must be a tuple, got {self.corner_moves!r}"
            )
        for move in self.corner_moves:
            if not (isinstance(move, tuple) and len(move) == 2 and move[0] in MOVE_DIRECTIONS):
                raise InputError(
                    "smoothing.corner_moves: each move must be (direction, distance) with a "
                    f"direction in {sorted(MOVE_DIRECTIONS)}, got {move!r}"
                )
            require_positive("smoothing.corner_moves", move[1])
        for name in (
            "unprune_turn",
            "hairpin_turn",
            "unprune_hairpin_turn",
            "drop_hairpin_turn",
        ):
            value = getattr(self, name)
            require_finite(f"smoothing.{name}", value)
            if not 0.0 < value <= math.pi:
                raise InputError(f"smoothing.{name}: must lie in (0, pi], got {value!r}")
        require_finite("smoothing.end_gap", self.end_gap)
        if self.end_gap < 0.0:
            raise InputError(f"smoothing.end_gap: must be >= 0, got {self.end_gap!r}")

    @property
    def clothoid(self) -> bool:
        """Whether the curve is made of clothoid turns."""
        return self.curve is CurveKind.CLOTHOID

    @property
    def design_radius(self) -> float:
        """Smallest turn radius: ``safety * kappa_max`` on the arc.

        A fillet's quadratic pieces peak at ``1 / (R cos(phi/2))``, so its radius is
        that much larger; a clothoid turn's arc has exactly ``1 / R``.

        Examples
        --------
        >>> round(SmoothingConfig(curve=CurveKind.BSPLINE).design_radius, 3)
        6.209
        >>> round(SmoothingConfig().design_radius, 3)
        6.186
        """
        if self.clothoid:
            return 1.0 / (self.kappa_max * self.kappa_safety)
        return 1.0 / (self.kappa_max * self.kappa_safety * math.cos(self.fillet_max_angle / 2.0))

    @property
    def tightest_sigma(self) -> float:
        """Sharpness ``dkappa/ds`` (1/m^2) of the tightest clothoids.

        Examples
        --------
        >>> round(SmoothingConfig().tightest_sigma, 5)
        0.07729
        """
        return self.kappa_safety * self.max_sharpness / self.wheelbase


@dataclass(frozen=True, eq=False)
class SmoothingResult:
    """Outcome of :func:`~rrtdrive.planning.smoothing.make_drivable`.

    Attributes
    ----------
    ok : bool
        True when ``samples`` meet every guarantee.
    samples : numpy.ndarray
        ``(N, 4)`` rows ``[x, y, yaw, kappa]`` (empty when not ok).
    control_points : numpy.ndarray
        The final B-spline control points ``(M, 2)``; for clothoid curves the key
        polygon whose corners the turns round (as ``key_points``).
    key_points : numpy.ndarray
        The key polygon after pruning, sharp-angle repair, heading legs and repairs.
    rounds : int
        Fit-check rounds used (1 when the first fit passed).
    max_curvature : float
        Largest ``|kappa|`` of the curve (exact per span for degree 2 and per turn for
        clothoids, dense samples for degree 3).
    max_sharpness : float
        Largest ``|d delta / ds|`` in rad/m, exact per clothoid; ``nan`` for a B-spline
        (whose curvature jumps at the knots for degree 2).
    message : str
        Why it failed, or an empty string.
    stats : dict
        Counters for the planner's statistics.
    """

    ok: bool
    samples: np.ndarray
    control_points: np.ndarray
    key_points: np.ndarray
    rounds: int
    max_curvature: float
    message: str = ""
    stats: dict[str, float] = field(default_factory=dict)
    max_sharpness: float = math.nan


def smoothing_with(base: SmoothingConfig, changes: Mapping[str, object]) -> SmoothingConfig:
    """``base`` with ``changes`` (a planner option ``smoothing={...}``).

    Parameters
    ----------
    base : SmoothingConfig
        The settings to start from.
    changes : mapping of str to object
        Field names of :class:`SmoothingConfig` and their new values.

    Returns
    -------
    SmoothingConfig

    Raises
    ------
    InputError
        Naming ``planner.smoothing.<field>`` for an unknown field or a bad value.

    Examples
    --------
    >>> smoothing_with(SmoothingConfig(), {"max_rounds": 8}).max_rounds
    8
    """
    fields = [f.name for f in dataclasses.fields(SmoothingConfig)]
    check_known(changes, fields, "planner.smoothing", "field of SmoothingConfig")
    try:
        return dataclasses.replace(base, **changes)  # type: ignore[arg-type]
    except InputError as exc:
        # SmoothingConfig names its fields "smoothing.<field>"; say whose they are.
        raise InputError(f"planner.{exc}") from None
