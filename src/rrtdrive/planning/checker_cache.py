"""The checker of each map, built once per process and shared (``cached_checker``)."""

from __future__ import annotations

import threading

from rrtdrive.collision import CheckerConfig, CollisionChecker
from rrtdrive.maps import Map

__all__ = ["cached_checker"]

_CHECKERS: dict[tuple[object, ...], CollisionChecker] = {}
_CHECKERS_LOCK = threading.Lock()
_BUILDING: dict[tuple[object, ...], threading.Lock] = {}


def cached_checker(m: Map, config: CheckerConfig | None = None) -> CollisionChecker:
    """The checker for ``m``'s obstacles, bounds and car, built once and kept.

    The process keeps up to 17; an 18th distinct map clears them all (each holds its
    grids, tens of MB for a 100 m map, and what its queries' set-up builds).
    """
    config = config or CheckerConfig()
    key = (m.bounds, m.obstacles, m.vehicle, config)
    checker = _CHECKERS.get(key)
    if checker is not None:
        return checker
    # One build per map however many threads ask at once (each built its own: twice the
    # set-up time and memory; an audit); different maps still build side by side.
    with _CHECKERS_LOCK:
        building = _BUILDING.setdefault(key, threading.Lock())
    try:
        with building:
            checker = _CHECKERS.get(key)
            if checker is None:
                checker = CollisionChecker.for_map(m, config=config)
                with _CHECKERS_LOCK:
                    if len(_CHECKERS) > 16:
                        _CHECKERS.clear()
                    _CHECKERS[key] = checker
    finally:  # also after a failed build: no lock left behind
        with _CHECKERS_LOCK:
            # Only this build's lock: a later one's (after the cache was cleared) kept
            # its waiters from building the map a second time at once.
            if _BUILDING.get(key) is building:
                del _BUILDING[key]
    return checker
