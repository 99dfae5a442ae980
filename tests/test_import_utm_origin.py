"""A ROS map placed in UTM coordinates (a northing about 5e6 m) imports and plans there."""

from __future__ import annotations

import numpy as np
from PIL import Image

from rrtdrive.cli import main
from rrtdrive.maps import load_map


def test_a_map_at_utm_coordinates_imports(tmp_path, capsys):
    img = np.full((100, 200), 254, dtype=np.uint8)  # 20 x 10 m free, a 2 m block top right
    img[:20, 180:200] = 0
    Image.fromarray(img).save(tmp_path / "site.pgm")
    (tmp_path / "site.yaml").write_text(
        "image: site.pgm\nresolution: 0.1\norigin: [500000.0, 5400000.0, 0.0]\n"
        "negate: 0\noccupied_thresh: 0.65\nfree_thresh: 0.196\n"
    )
    out = tmp_path / "site.json"
    code = main(["maps", "--import", str(tmp_path / "site.yaml"), "--start",
                 "500002,5400003,0", "--goal", "500015,5400003,0", "--out", str(out)])  # fmt: skip
    assert code == 0, capsys.readouterr().err
    m = load_map(out)
    assert m.bounds == (500000.0, 5400000.0, 500020.0, 5400010.0)
    assert "1 rectangle " in capsys.readouterr().out
    assert main(["plan", str(out)]) == 0
