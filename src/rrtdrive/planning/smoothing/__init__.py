"""Smoothing: a tree path into a drivable curve (paper Sec. 3.2; SPEC §3 items 5–10).

The default curve (``SmoothingConfig.curve = CurveKind.CLOTHOID``, SPEC §3 item 10)
joins straight legs by symmetric clothoid turns (:mod:`.clothoid`,
:mod:`.clothoid_curve`): continuous curvature, 0 at both ends, and a steering rate
per metre ``|d delta / ds|`` at most ``max_sharpness``, checked exactly per turn.
``CurveKind.BSPLINE`` is the paper's B-spline pipeline described below.

The steps are small functions over arrays and a collision checker, so each can
be tested and switched off on its own:

* :func:`prune` – keep the farthest later node with a free edge (Sec. 3.2.1, step 1);
* :func:`repair_sharp_angles` – Eq. 12 with the Douglas–Peucker choice of ``q_t``
  (Sec. 3.2.1, step 2);
* :func:`supplement` – control-point supplement (Sec. 3.2.3, Eq. 16);
* :func:`fit_bspline`, :func:`clamped_uniform_knots`, :func:`sample_spline`,
  :func:`curvature` – the clamped uniform B-spline (Sec. 3.2.2, Eqs. 13–15);
* :func:`fillet_points` – control points of a curvature-bounded corner;
* :func:`make_drivable` – the guarantee of SPEC §3 item 9: headings at both ends,
  ``|kappa| <= kappa_max`` everywhere and an exactly collision-free body, with a
  bounded repair loop that ends in an honest failure rather than an unsafe path.

All points are rear-axle positions; a segment ``a -> b`` is driven with the
heading along it, which is what ``checker.edge_free(a, b)`` tests.

How the guarantee is checked: the curvature of a degree-2 curve exactly, span by
span (:func:`quadratic_span_max_curvature`; a cusp counts as infinite), of a
degree-3 curve on a parameter grid eight times finer than the output; the body
with ``checker.path_free`` at curve poses at most ``check_spacing`` (0.1 m) apart
(:func:`parameter_grid` bounds the arc length between them); and, as a backstop,
the heading may turn by at most ``kappa_max`` times the arc length between
poses. Corners that break a limit are rounded by fillets of radius
``1 / (0.97 kappa_max cos(5 deg))`` (about 6.2 m for the paper's car), then
widened, moved, merged, dropped or un-pruned, each step edge-checked.

Modules: :mod:`.operations` (the paper's polygon steps), :mod:`.bspline`,
:mod:`.fillet`, :mod:`.config` (tunables and result), :mod:`.checks` (every
access to the collision checker), :mod:`.corners` (the key polygon),
:mod:`.curve` (control points and checks), :mod:`.repair` (the repair
operations) and :mod:`.drivable` (the orchestrating loop).
"""

from __future__ import annotations

from rrtdrive.planning.smoothing.bspline import (
    clamped_uniform_knots,
    curvature,
    fit_bspline,
    parameter_grid,
    quadratic_span_max_curvature,
    sample_spline,
    spline_curvature,
)
from rrtdrive.planning.smoothing.checks import EdgeChecker, PathChecker
from rrtdrive.planning.smoothing.clothoid import ClothoidTurn, clothoid_turn, sample_turn
from rrtdrive.planning.smoothing.config import (
    STEER_RATE_DESIGN_SPEED,
    CurveKind,
    SmoothingConfig,
    SmoothingResult,
    smoothing_with,
)
from rrtdrive.planning.smoothing.drivable import make_drivable
from rrtdrive.planning.smoothing.fillet import Fillet, fillet_points
from rrtdrive.planning.smoothing.operations import (
    is_sharp,
    prune,
    repair_sharp_angles,
    sharp_flags,
    supplement,
)
from rrtdrive.planning.smoothing.sharpness import (
    interval_sharpness,
    max_sharpness,
    steer_rate_speed_limit,
)

__all__ = [
    "EdgeChecker",
    "PathChecker",
    "prune",
    "is_sharp",
    "sharp_flags",
    "repair_sharp_angles",
    "supplement",
    "clamped_uniform_knots",
    "fit_bspline",
    "curvature",
    "spline_curvature",
    "quadratic_span_max_curvature",
    "parameter_grid",
    "sample_spline",
    "Fillet",
    "fillet_points",
    "SmoothingConfig",
    "smoothing_with",
    "SmoothingResult",
    "CurveKind",
    "STEER_RATE_DESIGN_SPEED",
    "ClothoidTurn",
    "clothoid_turn",
    "sample_turn",
    "interval_sharpness",
    "max_sharpness",
    "steer_rate_speed_limit",
    "make_drivable",
]
