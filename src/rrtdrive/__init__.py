"""rrtdrive: curvature-bounded car paths (improved RRT-Connect) driven in highway-env."""

from __future__ import annotations

from rrtdrive.collision import CheckerConfig, CollisionChecker

# Importing rrtdrive.envs registers the gymnasium ids (rrtdrive/Parking-v0, ...) with
# entry-point strings: neither highway-env nor pygame is imported here.
from rrtdrive.envs import ENV_IDS
from rrtdrive.maps import BUILTIN_MAPS, Map, Obstacle, builtin_map, load_map, resolve_map, save_map
from rrtdrive.types import (
    Budget,
    InputError,
    Path,
    PlanResult,
    PlanStatus,
    Pose,
    Tree,
    VehicleParams,
)

__version__ = "0.1.0"

__all__ = [
    "BUILTIN_MAPS",
    "Budget",
    "CheckerConfig",
    "CollisionChecker",
    "ENV_IDS",
    "InputError",
    "Map",
    "Obstacle",
    "Path",
    "PlanResult",
    "PlanStatus",
    "Pose",
    "Tree",
    "VehicleParams",
    "builtin_map",
    "load_map",
    "resolve_map",
    "save_map",
]
