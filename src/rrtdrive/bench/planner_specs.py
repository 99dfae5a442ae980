"""A bench's planner rows with options: ``NAME@FIELD=VALUE:FIELD=VALUE``.

``improved-rrt-connect@reverse_detour_tree=false`` is the default planner with one field
of its config set, as ``rrtdrive plan --planner-option reverse_detour_tree=false``; a
grid can hold the same planner with and without it (an ablation). Values are read as
JSON (``false``, ``4``, ``0.5``), else as text (``curve=arcs``); a value cannot hold
``:`` or ``,`` (the separators), so a nested config's field is dotted
(``smoothing.max_rounds=8``). Each row is spelled one way, its *label*: fields
sorted, values as JSON, so two spellings of one row are one run key.
"""

from __future__ import annotations

import json
from collections.abc import Mapping
from dataclasses import dataclass, field

from rrtdrive.types import InputError

__all__ = ["PlannerSpec", "parse_planner_spec"]


@dataclass(frozen=True)
class PlannerSpec:
    """One planner row of a bench grid.

    Attributes
    ----------
    name : str
        The registered planner's name.
    options : Mapping
        Its keyword arguments (``{}``: its defaults).
    """

    name: str
    options: Mapping[str, object] = field(default_factory=dict)

    @property
    def label(self) -> str:
        """The row's one spelling: ``name`` alone, or ``name@field=value:...`` sorted.

        Examples
        --------
        >>> PlannerSpec("hybrid-a-star", {"step": 2, "curve": "arcs"}).label
        'hybrid-a-star@curve=arcs:step=2'
        >>> PlannerSpec("rrt").label
        'rrt'
        >>> PlannerSpec("hybrid-a-star", {"smoothing": {"max_rounds": 8}}).label
        'hybrid-a-star@smoothing.max_rounds=8'
        """
        if not self.options:
            return self.name
        parts = (f"{k}={_text(v)}" for k, v in sorted(_dotted(self.options)))
        return f"{self.name}@{':'.join(parts)}"


def _dotted(options: Mapping[str, object], prefix: str = "") -> list[tuple[str, object]]:
    """A nested config's fields as ``FIELD.FIELD`` keys: its JSON would hold ':' and ','."""
    out: list[tuple[str, object]] = []
    for key, value in options.items():
        if isinstance(value, Mapping) and value:
            out += _dotted(value, f"{prefix}{key}.")
        else:
            out.append((f"{prefix}{key}", value))
    return out


def _text(value: object) -> str:
    if isinstance(value, float) and value.is_integer() and abs(value) < 2**53:
        return str(int(value))  # step=4.0 and step=4: one row
    return value if isinstance(value, str) else json.dumps(value, separators=(",", ":"))


def parse_planner_spec(text: str, field_name: str = "planners") -> PlannerSpec:
    """Read a planner row ``NAME`` or ``NAME@FIELD=VALUE:FIELD=VALUE``.

    The name and fields are checked by :func:`check_planner_spec`, not here.

    Raises
    ------
    InputError
        For a malformed option, a field given twice or ``reverse`` (the grid's own
        setting), named with ``field_name`` and the row.

    Examples
    --------
    >>> parse_planner_spec("improved-rrt-connect@reverse_detour_tree=false:step=4")
    PlannerSpec(name='improved-rrt-connect', options={'reverse_detour_tree': False, 'step': 4})
    >>> parse_planner_spec("rrt@step")  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    rrtdrive.types.InputError: planners: 'rrt@step': expected FIELD=VALUE ..., got 'step'; \
fields are separated by ':', so a value cannot hold ':' or ',' ...
    """
    from rrtdrive.cli_args import parse_planner_options

    name, at, tail = text.partition("@")
    where = f"{field_name}: {text!r}"
    if at and not tail.strip():
        raise InputError(f"{where}: nothing after '@'; give FIELD=VALUE or drop the '@'")
    parts = [p.strip() for p in tail.split(":") if p.strip()]
    try:
        options = parse_planner_options(parts, where)
    except InputError as exc:
        if "expected FIELD=VALUE" not in str(exc):
            raise
        raise InputError(
            f"{exc}; fields are separated by ':', so a value cannot hold ':' or ',' (a "
            "nested config's field is FIELD.FIELD=VALUE, e.g. smoothing.max_rounds=8)"
        ) from None
    return PlannerSpec(name.strip(), options)


def check_planner_spec(spec: PlannerSpec, where: str) -> None:
    """Build the row's planner once, so a bad field is one error before any run.

    ``where``: the field and row for the message (``planners: 'rrt@step=-1'``).

    Raises
    ------
    InputError
        For an unknown planner, an OMPL row given options (they take none) or a field
        the planner refuses (its own message, after ``where``).
    """
    import rrtdrive.bench.ompl_planners  # noqa: F401  (registers the OMPL rows)
    from rrtdrive.planning import PLANNERS, make_planner, unknown_planner

    if "=" in spec.name:  # hybrid-a-star@curve=arcs,step=0.5: the comma split the row
        raise InputError(
            f"{where}: {spec.name!r} is not a planner: a row's fields are separated by ':' "
            "(a ',' starts the next planner)"
        )
    if spec.name not in PLANNERS:
        raise unknown_planner(where, spec.name)
    if spec.options and spec.name.startswith("ompl-"):
        raise InputError(f"{where}: the OMPL rows take no options; drop the '@...'")
    if spec.options:
        try:
            make_planner(spec.name, **spec.options)
        except InputError as exc:
            raise InputError(f"{where}: {exc}") from None
