"""Test helper: exact-bicycle paths with gear changes, shared by the reversing tests."""

from __future__ import annotations

import math

import numpy as np

from rrtdrive.types import Path
from rrtdrive.vehicle import bicycle_step

L = 2.51


def integrate_pieces(pieces, ds: float = 0.1) -> Path:
    """Rows of the exact bicycle for ``(gear, kappa, length)`` pieces from the origin."""
    blocks, pose = [], (0.0, 0.0, 0.0)
    for gear, kappa, length in pieces:
        pts = [pose]
        for _ in range(int(round(length / ds))):
            pts.append(bicycle_step(pts[-1], gear * ds, math.atan(L * kappa), 1.0, L))
        p = np.array(pts)
        blocks.append(np.column_stack([p, np.full(len(p), kappa), np.full(len(p), gear)]))
        pose = tuple(p[-1])
    return Path(np.vstack(blocks), np.zeros((0, 2)))
