"""Read-only numpy data in frozen dataclasses: made so, and kept so through pickling.

A frozen dataclass cannot be re-assigned, but its arrays could be written into; the
results and paths freeze them (:func:`read_only_array`). Unpickling runs no
``__post_init__`` and numpy unpickles (and deep-copies) every array writable, so a
result sent back from a worker process came back writable (an audit):
:class:`ReadOnlyArrays` freezes them again.
"""

from __future__ import annotations

from typing import Any

import numpy as np

__all__ = ["ReadOnlyArrays", "read_only_array"]


def read_only_array(values: Any, dtype: Any = None) -> np.ndarray:
    """A read-only array of ``values`` that shares no memory with a writable caller's array.

    Parameters
    ----------
    values : array_like
        The data; a read-only array is kept as it is.
    dtype : data-type, optional
        The array's type (default: numpy's choice).

    Examples
    --------
    >>> mine = np.zeros(3)
    >>> kept = read_only_array(mine)
    >>> mine[0] = 1.0
    >>> float(kept[0]), kept.flags.writeable
    (0.0, False)
    """
    a = np.asarray(values, dtype=dtype)
    if a.flags.writeable:
        a = a.copy()
        a.setflags(write=False)
    return a


class ReadOnlyArrays:
    """Base of a frozen dataclass whose array fields stay read-only when unpickled or copied.

    Examples
    --------
    >>> import copy, pickle
    >>> from rrtdrive.types import Tree
    >>> tree = Tree(np.zeros((2, 2)), np.array([-1, 0]))
    >>> twins = pickle.loads(pickle.dumps(tree)), copy.deepcopy(tree)
    >>> [t.nodes.flags.writeable for t in twins]
    [False, False]
    """

    __slots__ = ()

    def __setstate__(self, state: dict[str, Any]) -> None:
        for name, value in state.items():
            if isinstance(value, np.ndarray):
                value.flags.writeable = False
            object.__setattr__(self, name, value)
