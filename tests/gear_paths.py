"""Test helpers: exact-bicycle paths with gear changes, and the plant that tracks them."""

from __future__ import annotations

import math

import numpy as np

from rrtdrive.controllers import VehicleState
from rrtdrive.types import Path, VehicleParams
from rrtdrive.vehicle import bicycle_step

L = 2.51


def integrate_pieces(pieces, ds: float = 0.1) -> Path:
    """Rows of the exact bicycle for ``(gear, kappa, length)`` pieces from the origin."""
    blocks, pose = [], (0.0, 0.0, 0.0)
    for gear, kappa, length in pieces:
        pts = [pose]
        for _ in range(int(round(length / ds))):
            pts.append(bicycle_step(pts[-1], gear * ds, math.atan(L * kappa), 1.0, L))
        p = np.array(pts)
        blocks.append(np.column_stack([p, np.full(len(p), kappa), np.full(len(p), gear)]))
        pose = tuple(p[-1])
    return Path(np.vstack(blocks), np.zeros((0, 2)))


DT = 0.05  # the closed loop's 20 Hz


def track_on_bicycle(controller, path: Path, rate: float | None, x0=None, max_time=120.0):
    """Track ``path`` from rest with ``controller``; rows ``t, x, y, yaw, v, steer, segment,
    cte, heading_err`` (the state before each command).

    The plant is the ego's own longitudinal rule (the speed changes linearly and stops at
    zero within a step rather than reversing) with the exact rear-axle arcs, and the
    actuator either instant (``rate`` None) or slewing at ``rate`` rad/s (turning
    linearly within the step, as the ego integrates it).
    """
    car = VehicleParams(max_steer_rate=rate)
    wheelbase = controller.vehicle.wheelbase
    controller.reset(path)
    x, y, yaw = path.samples[0, :3] if x0 is None else x0
    v = steer = 0.0
    rows = []
    for k in range(int(max_time / DT)):
        a, cmd = controller.control(VehicleState(x, y, yaw, v, steer, k * DT))
        rows.append((k * DT, x, y, yaw, v, steer, controller.segment, controller.cte,
                     controller.heading_error))
        if controller.arrived and v == 0.0:
            break
        cmd = max(-car.max_steer, min(car.max_steer, cmd))
        if rate is not None:
            cmd = min(max(cmd, steer - rate * DT), steer + rate * DT)
        v1 = v + a * DT
        if abs(v1) < 1e-9:
            v1 = 0.0
        if v * v1 < 0.0 or (v != 0.0 and v1 == 0.0):
            ds, v1 = 0.5 * v * abs(v / a), 0.0
        else:
            ds = 0.5 * (v + v1) * DT
        if ds != 0.0:
            n = 8 if rate is not None and cmd != steer else 1
            pose = (x, y, yaw)
            for i in range(n):
                d = steer + (cmd - steer) * (i + 0.5) / n if n > 1 else cmd
                pose = bicycle_step(pose, ds / n, d, 1.0, wheelbase)
            x, y, yaw = pose
        v, steer = v1, cmd
    return np.array(rows)
