from __future__ import annotations

import os

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
# A hunt for thin properties, not for CI: a fresh seed per run, 600 examples where a
# test sets no count of its own
# (``HYPOTHESIS_PROFILE=stress python -m pytest -n auto tests``). CI's examples are fixed
# per test, but not quite per run: Hypothesis also draws constants found in the modules
# loaded so far, which depends on the test order.
settings.register_profile(
    "stress",
    max_examples=600,
    deadline=None,
    suppress_health_check=[HealthCheck.too_slow],
)
settings.load_profile(os.environ.get("HYPOTHESIS_PROFILE", "ci"))


@pytest.fixture(scope="session")
def parking_lot():
    return builtin_map("parking_lot")


@pytest.fixture(scope="session")
def parking_checker(parking_lot):
    return cached_checker(parking_lot)
