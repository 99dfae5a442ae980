"""Every example in the package's docstrings runs and prints what it says.

Examples are documentation: one that prints another number than its code gives
misleads (two had gone stale: an IDM acceleration and an actuator profile's speed).
"""

from __future__ import annotations

import doctest
import importlib
import pkgutil

import pytest

#: ``python -m rrtdrive`` runs the CLI when imported.
NOT_IMPORTED = {"rrtdrive.__main__"}


#: The top packages: envs/ and controllers/ live outside src/ (an editable install
#: maps them, so a walk of ``rrtdrive.__path__`` alone would miss them).
TOPS = ("rrtdrive", "rrtdrive.envs", "rrtdrive.controllers")


def _modules() -> list[str]:
    names = set(TOPS)
    for top in TOPS:
        package = importlib.import_module(top)
        for info in pkgutil.walk_packages(package.__path__, f"{top}."):
            if info.name not in NOT_IMPORTED:
                names.add(info.name)
    return sorted(names)


MODULES = _modules()


def test_the_walk_finds_the_subpackages():
    # envs/ and controllers/ are installed as rrtdrive.envs and rrtdrive.controllers.
    for name in ("rrtdrive.envs", "rrtdrive.controllers.speed", "rrtdrive.planning.hybrid.turn"):
        assert name in MODULES


@pytest.mark.parametrize("name", MODULES)
def test_docstring_examples(name: str):
    module = importlib.import_module(name)
    result = doctest.testmod(module, verbose=False, report=True)
    assert result.failed == 0, f"{result.failed} of {result.attempted} examples in {name} failed"
