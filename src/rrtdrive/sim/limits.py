"""The simulator's frequency range, for :class:`~rrtdrive.sim.scenes.SimConfig` and the CLI.

A light module (no highway-env): the command line's argument types read it at start-up.
"""

from __future__ import annotations

__all__ = ["MAX_SIM_FREQUENCY", "MIN_SIM_FREQUENCY"]

#: Lowest simulation frequency, Hz (the controllers' gain limits are set for it).
MIN_SIM_FREQUENCY = 15
#: Highest simulation frequency, Hz: an episode's step count is time x frequency, and
#: 1e11 Hz for half a second ran for hours without a word.
MAX_SIM_FREQUENCY = 1000
