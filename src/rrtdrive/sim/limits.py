"""The simulator's frequency range and the ego's speed limits, for the CLI and the configs.

A light module (no highway-env): the command line's argument types read it at start-up.
"""

from __future__ import annotations

__all__ = [
    "MAX_REVERSE_SPEED", "MAX_SIM_FREQUENCY", "MAX_SPEED", "MAX_VIDEO_FPS", "MIN_SIM_FREQUENCY",
]

#: Lowest simulation frequency, Hz (the controllers' gain limits are set for it).
MIN_SIM_FREQUENCY = 15
#: Highest simulation frequency, Hz: an episode's step count is time x frequency, and
#: 1e11 Hz for half a second ran for hours without a word.
MAX_SIM_FREQUENCY = 1000
#: The ego's top speed forward and in reverse, m/s (:class:`~rrtdrive.sim.ego.EgoVehicle`
#: clips its speed to them, as highway-env's vehicles do).
MAX_SPEED = 40.0
MAX_REVERSE_SPEED = 10.0
#: Highest frame rate ``simulate --video`` writes by default (players and imageio read a
#: 1000 fps MP4's rate as 0); a higher ``--frequency`` keeps every n-th step.
MAX_VIDEO_FPS = 60
