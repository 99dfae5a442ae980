"""A PGM reads with white at its maxval, 8-bit or 16-bit, whatever that maxval is."""

from __future__ import annotations

import numpy as np
import pytest

from rrtdrive.occupancy import read_image_map


@pytest.mark.parametrize("maxval", [100, 255, 1000, 65535])
def test_black_grey_white_read_occupied_unknown_free(tmp_path, maxval):
    # ROS map_server's trinary reading: p = (white - v) / white; > 0.65 occupied,
    # < 0.196 free, between unknown (occupied unless --unknown-free).
    values = np.array([[0, maxval // 2, maxval]])
    kind = np.dtype(">u2") if maxval > 255 else np.dtype(np.uint8)
    f = tmp_path / f"m{maxval}.pgm"
    f.write_bytes(b"P5\n3 1\n%d\n" % maxval + values.astype(kind).tobytes())
    grid = read_image_map(f, 0.1)
    assert grid.occupied.tolist() == [[True, True, False]]
    assert grid.unknown == 1
    free = read_image_map(f, 0.1, unknown_free=True)
    assert free.occupied.tolist() == [[True, False, False]]
