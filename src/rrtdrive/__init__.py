"""rrtdrive: curvature-bounded car paths (improved RRT-Connect) driven in highway-env."""

from __future__ import annotations

import importlib
import sys
from typing import TYPE_CHECKING

from rrtdrive.cli_signals import quiet_interrupt_while_loading

# The console script imports this package before its main() can catch a Ctrl-C. Its
# path as Python was started (orig_argv): a bench's spawned workers get its sys.argv.
_started = getattr(sys, "orig_argv", [])
quiet_interrupt_while_loading(_started[1] if len(_started) > 1 else "")
del _started

# Importing rrtdrive.envs registers the gymnasium ids (rrtdrive/Parking-v0, ...) with
# entry-point strings: neither highway-env nor pygame is imported here.
from rrtdrive.envs import ENV_IDS  # noqa: E402 - after the handler above

if TYPE_CHECKING:
    from rrtdrive.collision import CheckerConfig, CollisionChecker
    from rrtdrive.maps import (
        BUILTIN_MAPS,
        Map,
        Obstacle,
        builtin_map,
        load_map,
        resolve_map,
        save_map,
    )
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

# The other public names load on first use (PEP 562): the collision checker pulls in
# scipy.ndimage, and `rrtdrive --version` should not pay for it.
_LAZY: dict[str, str] = {
    "CheckerConfig": "rrtdrive.collision",
    "CollisionChecker": "rrtdrive.collision",
    **dict.fromkeys(
        ("BUILTIN_MAPS", "Map", "Obstacle", "builtin_map", "load_map", "resolve_map", "save_map"),
        "rrtdrive.maps",
    ),
    **dict.fromkeys(
        ("Budget", "InputError", "Path", "PlanResult", "PlanStatus", "Pose", "Tree",
         "VehicleParams"),
        "rrtdrive.types",
    ),
}

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


def __getattr__(name: str) -> object:
    module = _LAZY.get(name)
    if module is None:
        raise AttributeError(f"module 'rrtdrive' has no attribute {name!r}")
    value = getattr(importlib.import_module(module), name)
    globals()[name] = value  # later look-ups skip this function
    return value


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(_LAZY))
