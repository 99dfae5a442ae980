"""Test helper: a car's body rectangle at a rear-axle pose, written out from SPEC section 1.

An independent reference for the product's footprint (shapely, not rrtdrive.vehicle).
"""

from __future__ import annotations

import math

import shapely


def body(car: dict, x: float, y: float, yaw: float) -> shapely.Polygon:
    """The body at a rear-axle pose: rear overhang (L - wheelbase) / 2, SPEC section 1."""
    back = (car["length"] - car["wheelbase"]) / 2.0
    front = car["length"] - back
    w = car["width"] / 2.0
    c, s = math.cos(yaw), math.sin(yaw)
    return shapely.Polygon([(x + c * a - s * b, y + s * a + c * b)
                            for a, b in ((-back, -w), (front, -w), (front, w), (-back, w))])
