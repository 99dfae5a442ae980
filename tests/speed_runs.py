"""A point mass driven by the speed loop alone (no steering, no highway-env)."""

from __future__ import annotations

from rrtdrive.controllers import SpeedController


def point_mass_run(
    ctrl: SpeedController,
    pos: float,
    speed: float,
    dt: float = 0.05,
    steps: int = 2000,
    until_arrived: bool = True,
    trace: list[tuple[float, float, float, float]] | None = None,
) -> tuple[float, float, float]:
    """Step ``ctrl`` on a point mass from ``pos`` at ``speed``: ``(pos, speed, time)`` at the end.

    The speed never goes below 0; the run ends at rest (with ``until_arrived``: at rest
    and arrived) or after ``steps`` steps. ``trace`` (a list) gets ``(t, pos, speed, a)``
    of every step.
    """
    k = 0
    for k in range(steps):
        a = ctrl.control(pos, speed, k * dt)
        if trace is not None:
            trace.append((k * dt, pos, speed, a))
        v1 = max(0.0, speed + a * dt)
        pos += 0.5 * (speed + v1) * dt
        speed = v1
        if speed == 0.0 and (ctrl.arrived or not until_arrived):
            break
    return pos, speed, k * dt
