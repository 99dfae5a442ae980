"""Configuration of the improved RRT-Connect: :class:`ImprovedConfig` and its component names."""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

from rrtdrive.types import InputError, require_finite, require_int, require_positive

__all__ = ["COMPONENTS", "ImprovedConfig"]

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
