"""Tunables and outcome of the post-processor (:func:`.drivable.make_drivable`)."""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from rrtdrive.types import InputError, require_finite, require_int, require_positive

__all__ = ["MOVE_DIRECTIONS", "DEFAULT_CORNER_MOVES", "SmoothingConfig", "SmoothingResult"]

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
    degree : int
        B-spline degree, 2 (paper) or 3.
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
        Fillets are designed for ``kappa_safety * kappa_max``.
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
    degree: int = 2
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
        ):
            require_positive(f"smoothing.{name}", getattr(self, name))
        if self.degree not in (2, 3):
            raise InputError(f"smoothing.degree: must be 2 or 3, got {self.degree!r}")
        if not 0.0 < self.supplement_n < 1.0:
            raise InputError(
                f"smoothing.supplement_n: must lie in (0, 1), got {self.supplement_n!r}"
            )
        if not 0.0 < self.kappa_safety <= 1.0:
            raise InputError(
                f"smoothing.kappa_safety: must lie in (0, 1], got {self.kappa_safety!r}"
            )
        if not 0.0 < self.fillet_max_angle <= math.pi / 2:
            raise InputError("smoothing.fillet_max_angle: must lie in (0, pi/2]")
        require_int("smoothing.max_rounds", self.max_rounds)
        self._check_repair_constants()

    def _check_repair_constants(self) -> None:
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
    def design_radius(self) -> float:
        """Smallest fillet radius: ``max |kappa| = 1 / (R cos(phi/2)) <= safety * kappa_max``.

        Examples
        --------
        >>> round(SmoothingConfig().design_radius, 3)
        6.209
        """
        return 1.0 / (self.kappa_max * self.kappa_safety * math.cos(self.fillet_max_angle / 2.0))


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
        The final B-spline control points ``(M, 2)``.
    key_points : numpy.ndarray
        The key polygon after pruning, sharp-angle repair, heading legs and repairs.
    rounds : int
        Fit-check rounds used (1 when the first fit passed).
    max_curvature : float
        Largest ``|kappa|`` of the curve (exact per span for degree 2, dense samples for 3).
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
