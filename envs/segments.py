"""When an agent driving alone moves on to the next gear segment of its path.

With ``residual=True`` the controller changes segment at each cusp; an agent driving
alone has no such stop, so :class:`~rrtdrive.envs.drive_env.DriveEnv` asks
:func:`starts_next_segment` after every step.
"""

from __future__ import annotations

__all__ = ["CUSP_REACH_M", "starts_next_segment"]

#: How near the cusp (metres along the segment, or past it) an agent driving alone must
#: be for moving in the next segment's gear to start that segment (at most half the
#: segment's length).
CUSP_REACH_M = 1.0


def starts_next_segment(
    speed: float,
    next_gear: int,
    to_cusp: float,
    segment_length: float,
    goal_tol: float,
    stop_speed: float,
) -> bool:
    """Whether the car has left its gear segment for the next one.

    It has when it stands still (``|speed| <= stop_speed``) within ``goal_tol`` of the
    cusp, or when it moves in the next segment's gear within ``CUSP_REACH_M`` of the
    cusp (or past it), and within half the segment's length: just after a switch
    into a 1 m segment the car still rolls on a little in the last gear, which is the
    next segment's, and that must not skip the metre.

    Parameters
    ----------
    speed : float
        Signed speed, m/s (negative in reverse).
    next_gear : int
        +1 or -1, the next segment's gear.
    to_cusp : float
        Length along the segment left to its cusp, metres (negative past it).
    segment_length : float
        The current segment's length, metres.
    goal_tol, stop_speed : float
        The evaluator's goal tolerance (m) and stop speed (m/s).

    Examples
    --------
    >>> starts_next_segment(-0.08, -1, 0.96, 1.0, 0.5, 0.1)  # rolling back, just in
    False
    >>> starts_next_segment(-0.08, -1, 0.4, 1.0, 0.5, 0.1)  # turned near its cusp
    True
    >>> starts_next_segment(0.0, 1, 0.3, 20.0, 0.5, 0.1)  # stopped at the cusp
    True
    """
    at_cusp = abs(speed) <= stop_speed and abs(to_cusp) <= goal_tol
    reach = min(CUSP_REACH_M, segment_length / 2.0)
    turned = speed != 0.0 and (speed > 0.0) == (next_gear > 0) and to_cusp <= reach
    return at_cusp or turned
