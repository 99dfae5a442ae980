"""Read-only, hashable keyword options for the frozen configs (:class:`FrozenOptions`).

The episode's and the gym environment's configs are frozen dataclasses that hold
keyword options (a controller's gains, a planner's config fields). Kept as dicts they
could be changed in place after validation and made the config unhashable
(``hash(EpisodeConfig())``: TypeError; an audit).
"""

from __future__ import annotations

from collections.abc import Iterator, Mapping
from typing import Any, TypeVar

__all__ = ["FrozenOptions", "config_of"]

T = TypeVar("T")


class FrozenOptions(Mapping[str, Any]):
    """A mapping that cannot be changed, nested mappings included, and can be hashed.

    It reads and compares like the dict it was made from; ``dict(options)`` gives a
    plain copy back. Lists inside stay lists (their contents hash as tuples).

    Parameters
    ----------
    items : mapping, optional
        The options; nested mappings become :class:`FrozenOptions` too.

    Examples
    --------
    >>> gains = FrozenOptions({"k": 1.5, "speed": {"v_max": 5.0}})
    >>> gains["speed"]["v_max"], gains == {"k": 1.5, "speed": {"v_max": 5.0}}
    (5.0, True)
    >>> gains["k"] = 2.0
    Traceback (most recent call last):
    ...
    TypeError: 'FrozenOptions' object does not support item assignment
    >>> hash(gains) == hash(FrozenOptions({"speed": {"v_max": 5.0}, "k": 1.5}))
    True
    """

    __slots__ = ("_items",)

    def __init__(self, items: Mapping[str, Any] | None = None) -> None:
        self._items = {
            k: FrozenOptions(v) if isinstance(v, Mapping) and not isinstance(v, FrozenOptions)
            else v
            for k, v in (items or {}).items()
        }

    def __getitem__(self, key: str) -> Any:
        return self._items[key]

    def __iter__(self) -> Iterator[str]:
        return iter(self._items)

    def __len__(self) -> int:
        return len(self._items)

    def __eq__(self, other: object) -> bool:
        if not isinstance(other, Mapping):
            return NotImplemented
        return self._items == dict(other.items())

    def __hash__(self) -> int:
        return hash(frozenset((k, _hashable(v)) for k, v in self._items.items()))

    def __repr__(self) -> str:
        return repr(self._items)

    def __reduce__(self) -> tuple[type, tuple[dict[str, Any]]]:
        # Pickled and deep-copied as the dict it holds (a vector env's workers, deepcopy).
        return (FrozenOptions, (self._items,))


def _hashable(value: Any) -> Any:
    """``value`` as something hashable: sequences as tuples, others as their repr."""
    if isinstance(value, list | tuple):
        return tuple(_hashable(v) for v in value)
    try:
        hash(value)
    except TypeError:
        return repr(value)
    return value


def config_of(kind: type[T], value: object, field: str) -> T:
    """``value`` as a ``kind`` config: itself, or built from a mapping of its fields.

    gymnasium's ``EnvSpec.to_json`` keeps a dataclass option as its fields' dict;
    ``gym.make`` of that spec gives it back here (a ``Budget`` or ``SafetyConfig``
    did not survive the round trip; an audit).

    Raises
    ------
    InputError
        Naming ``field``: neither a ``kind`` nor a mapping of its fields.

    Examples
    --------
    >>> from rrtdrive.types import Budget
    >>> config_of(Budget, {"max_iterations": 50}, "budget").max_iterations
    50
    """
    from rrtdrive.types import InputError

    if isinstance(value, kind):
        return value
    if isinstance(value, Mapping):
        try:
            return kind(**value)
        except TypeError as exc:  # an unknown or missing field
            raise InputError(f"{field}: {exc}") from None
    raise InputError(f"{field}: expected a {kind.__name__} or its fields, got {value!r}")
