"""The public API documents its parameters (numpydoc), and every report field its metric.

"Public" is what a package exports in ``__all__``, with the public methods of the
classes among them: what ``help()`` and an IDE show a user.
"""

from __future__ import annotations

import dataclasses
import enum
import importlib
import inspect
import pathlib
import re
from collections.abc import Callable, Iterator
from typing import Protocol

import pytest

from rrtdrive.evaluation import EpisodeReport

#: Packages whose exports are held to it.
PACKAGES = (
    "rrtdrive",
    "rrtdrive.planning",
    "rrtdrive.evaluation",
    "rrtdrive.collision",
    "rrtdrive.bench",
    "rrtdrive.sim.tasks",
    "rrtdrive.planning.spacetime",
    "rrtdrive.planning.hybrid",
    "rrtdrive.planning.smoothing",
    "rrtdrive.planning.improved",
    "rrtdrive.planning.diagnosis",
    "rrtdrive.controllers",
    "rrtdrive.envs",
    "rrtdrive.maps",
    "rrtdrive.vehicle",
    "rrtdrive.speed_profile",
    "rrtdrive.plotting",
    "rrtdrive.verify",
    "rrtdrive.types",
    "rrtdrive.geometry",
    "rrtdrive.stats",
    "rrtdrive.commonroad_judge",
)

DOCS = pathlib.Path(__file__).resolve().parents[1] / "docs"


def _is_protocol(obj: type) -> bool:
    return Protocol in getattr(obj, "__mro__", ()) or bool(getattr(obj, "_is_protocol", False))


def _public_callables(package: str) -> Iterator[tuple[str, Callable[..., object]]]:
    module = importlib.import_module(package)
    for name in module.__all__:
        obj = getattr(module, name)
        if inspect.isfunction(obj):
            yield f"{package}.{name}", obj
        elif inspect.isclass(obj) and not issubclass(obj, enum.Enum):
            if not _is_protocol(obj):
                yield f"{package}.{name}", obj
            for attr, member in vars(obj).items():
                if not attr.startswith("_") and inspect.isfunction(member):
                    yield f"{package}.{name}.{attr}", member


def _parameters(obj: Callable[..., object]) -> list[str]:
    try:
        signature = inspect.signature(obj)
    except (TypeError, ValueError):
        return []
    return [p for p in signature.parameters if p not in ("self", "cls")]


def _undocumented(package: str) -> list[str]:
    missing = []
    for name, obj in _public_callables(package):
        if not _parameters(obj):
            continue
        doc = inspect.getdoc(obj) or ""
        sections = ("Parameters", "Attributes") if inspect.isclass(obj) else ("Parameters",)
        if not any(f"{s}\n{'-' * len(s)}" in doc for s in sections):
            missing.append(name)
    return missing


@pytest.mark.parametrize("package", PACKAGES)
def test_exports_with_parameters_have_a_parameters_section(package: str) -> None:
    assert _undocumented(package) == []


def test_the_check_sees_an_undocumented_method(monkeypatch: pytest.MonkeyPatch) -> None:
    """The check itself: a method of an exported class without the section is listed."""
    from rrtdrive.maps import Map

    def with_query(self: Map, start: object = None) -> Map:
        """A copy with another start."""
        return self

    monkeypatch.setattr(Map, "with_query", with_query)
    assert "rrtdrive.Map.with_query" in _undocumented("rrtdrive")


def test_every_report_field_is_defined_in_the_metrics_page() -> None:
    """``EpisodeReport``'s docstring sends the reader to docs/metrics.md for its fields."""
    page = (DOCS / "metrics.md").read_text(encoding="utf-8")
    # Named in code spans, alone or as a formula's left side (`cte_rms_m = ...`).
    named = set(re.findall(r"`([a-z][a-z0-9_]*)\b", page))
    missing = [f.name for f in dataclasses.fields(EpisodeReport) if f.name not in named]
    assert missing == []
