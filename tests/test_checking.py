"""Both checkers implement the written contract, explicitly."""

from __future__ import annotations

import numpy as np

from rrtdrive.checking import Checker, MotionValidator, PoseValidityChecker
from rrtdrive.collision import CollisionChecker
from rrtdrive.maps import Map, Obstacle, builtin_map
from rrtdrive.planning.spacetime import ArrivalTiming, Prediction, SpaceTimeChecker
from rrtdrive.types import Pose


def _members(proto: type) -> set[str]:
    return {
        name
        for klass in proto.__mro__
        if klass.__module__ == "rrtdrive.checking"
        for name in vars(klass)
        if not name.startswith("_")
    }


def _spacetime(static: CollisionChecker) -> SpaceTimeChecker:
    lead = Prediction.constant_velocity(np.array([[18.0, 44.0, 0.0, 2.0]]), [(4.3, 1.8)], 12.0)
    return SpaceTimeChecker(static, lead, ArrivalTiming(0.0, 4.0, 10.0, 1.5, (2.0, 44.0)))


def _road() -> Map:
    return Map(
        "road", (0.0, 42.0, 70.0, 50.0), (Obstacle((40.0, 49.0), (4.0, 1.0), 0.0),),
        Pose(2.0, 44.0, 0.0), Pose(58.0, 44.0, 0.0),
    )


def test_both_checkers_satisfy_the_protocols():
    static = CollisionChecker.for_map(builtin_map("overtake"))
    for checker in (static, _spacetime(static)):
        assert isinstance(checker, PoseValidityChecker)
        assert isinstance(checker, MotionValidator)
        assert isinstance(checker, Checker)


def test_spacetime_checker_defines_every_contract_member_itself():
    assert "__getattr__" not in vars(SpaceTimeChecker)
    assert not hasattr(SpaceTimeChecker, "__getattr__")
    members = _members(Checker)
    assert {"edge_free", "path_free", "pose_free", "poses_free", "obstacle_union"} <= members
    missing = sorted(m for m in members if m not in vars(SpaceTimeChecker))
    assert missing == []


def test_spacetime_data_is_the_static_checkers_and_tests_never_more_permissive():
    static = CollisionChecker.for_map(_road())
    st = _spacetime(static)
    assert st.obstacles == static.obstacles and st.bounds == static.bounds
    assert st.obstacle_union is static.obstacle_union
    assert np.array_equal(st.free_cells((2.0, 44.0)), static.free_cells((2.0, 44.0)))
    assert st.setup_time_s == static.setup_time_s
    rng = np.random.default_rng(0)
    poses = np.column_stack(
        [rng.uniform(0, 70, 200), rng.uniform(42, 50, 200), rng.uniform(-3, 3, 200)]
    )
    assert not np.any(st.poses_free(poses) & ~static.poses_free(poses))
    assert not np.any(st.poses_free_fast(poses) & ~static.poses_free_fast(poses))
    # The lead car (2 m/s from x = 18) is where the ego, 4 m/s from x = 2, gets to.
    assert static.edge_free((5.0, 44.0), (30.0, 44.0))
    assert not st.edge_free((5.0, 44.0), (30.0, 44.0))
