from __future__ import annotations

import pytest
from hypothesis import HealthCheck, settings

from rrtdrive.maps import builtin_map
from rrtdrive.planning.base import cached_checker

settings.register_profile(
    "ci",
    max_examples=60,
    deadline=None,
    suppress_health_check=[HealthCheck.too_slow],
    derandomize=True,
)
settings.load_profile("ci")


@pytest.fixture(scope="session")
def parking_lot():
    return builtin_map("parking_lot")


@pytest.fixture(scope="session")
def parking_checker(parking_lot):
    return cached_checker(parking_lot)
