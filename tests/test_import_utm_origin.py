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


def test_a_name_taken_from_the_file_blames_the_file_not_name(tmp_path, capsys):
    img = np.full((100, 200), 254, dtype=np.uint8)
    image = tmp_path / "a\tb.png"
    Image.fromarray(img).save(image)
    args = ["maps", "--import", str(image), "--resolution", "0.1", "--start", "2,3,0",
            "--goal", "15,3,0", "--out", str(tmp_path / "m.json")]  # fmt: skip
    assert main(args) == 2
    err = capsys.readouterr().err
    assert "the image's file name (give --name)" in err and "--name:" not in err
    assert main([*args, "--name", "site"]) == 0
