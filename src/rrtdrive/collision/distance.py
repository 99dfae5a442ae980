"""The exact Euclidean distance field of an occupancy grid, in less time and memory.

:func:`distance_field` gives what ``scipy.ndimage.distance_transform_edt`` gives, bit for
bit: scipy's feature transform (the nearest occupied cell of each cell), then the
distances to those cells a block of rows at a time. scipy's own last step holds the
cells' indices and a float64 copy of the offsets for the whole grid at once; on a 1 km
map's 44.6 M cells that was 1.1 GB more and about 3.5 s of each of the two transforms a
checker set-up made.
"""

from __future__ import annotations

import numpy as np
from scipy import ndimage

__all__ = ["distance_field"]

#: Rows of the grid whose distances are computed together (bounds the temporaries).
BLOCK_ROWS = 256


def distance_field(free: np.ndarray) -> np.ndarray:
    """Distance in cells from each cell of ``free`` to the nearest cell that is not free.

    Equal to ``ndimage.distance_transform_edt(free)`` (float64, 0 on the occupied cells).

    Examples
    --------
    >>> free = np.ones((3, 4), dtype=bool)
    >>> free[0, 0] = False
    >>> distance_field(free)[2, 3] == np.hypot(2, 3)
    np.True_
    """
    free = np.asarray(free, dtype=bool)
    if free.ndim != 2 or free.all() or free.size == 0:
        # Nothing occupied (scipy's answer, whatever it is) or not a grid: scipy's own.
        return ndimage.distance_transform_edt(free)
    nearest = ndimage.distance_transform_edt(free, return_distances=False, return_indices=True)
    out = np.empty(free.shape, dtype=np.float64)
    cols = np.arange(free.shape[1], dtype=np.int64)
    for r0 in range(0, free.shape[0], BLOCK_ROWS):
        r1 = min(free.shape[0], r0 + BLOCK_ROWS)
        di = nearest[0, r0:r1].astype(np.int64) - np.arange(r0, r1, dtype=np.int64)[:, None]
        dj = nearest[1, r0:r1].astype(np.int64) - cols
        # Integer squares sum exactly (below 2**53), as scipy's float64 sum of them does.
        np.sqrt((di * di + dj * dj).astype(np.float64), out=out[r0:r1])
    return out
