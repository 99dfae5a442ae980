"""ROS map .yaml numbers written quoted, and the hint for a noisy scan's many rectangles."""

from __future__ import annotations

import json

import numpy as np
import pytest
from PIL import Image

from rrtdrive.cli import main


def _image(folder, name: str, pixels: np.ndarray) -> None:
    Image.fromarray(pixels).save(folder / name)


def test_quoted_numbers_read_as_map_server_reads_them(tmp_path, capsys):
    pixels = np.full((50, 80), 255, np.uint8)
    pixels[:5, :] = 0
    _image(tmp_path, "m.png", pixels)
    plain = "image: m.png\nresolution: 0.1\norigin: [1, 2, 0]\nnegate: 0\noccupied_thresh: 0.65\n"
    quoted = ('image: m.png\nresolution: "0.1"\norigin: ["1", "2", "0"]\nnegate: "0"\n'
              'occupied_thresh: "0.65"\n')  # fmt: skip
    maps = []
    for name, text in (("plain", plain), ("quoted", quoted)):
        (tmp_path / f"{name}.yaml").write_text(text)
        out = tmp_path / f"{name}.json"
        code = main(["maps", "--import", str(tmp_path / f"{name}.yaml"), "--start", "2.5,3,0",
                     "--goal", "4,3.5,0", "--out", str(out)])  # fmt: skip
        assert code == 0, capsys.readouterr().err
        maps.append(json.loads(out.read_text()))
    assert maps[0]["bounds"] == maps[1]["bounds"] == [1.0, 2.0, 9.0, 7.0]
    assert maps[0]["obstacles"] == maps[1]["obstacles"]


@pytest.mark.parametrize(("field", "value"), [("resolution", '"abc"'), ("negate", '"yes"')])
def test_a_quoted_word_is_still_refused_naming_the_field(tmp_path, capsys, field, value):
    _image(tmp_path, "m.png", np.full((50, 80), 255, np.uint8))
    fields = {"resolution": "0.1", "negate": "0", field: value}
    (tmp_path / "m.yaml").write_text(
        "image: m.png\norigin: [0, 0, 0]\n" + "".join(f"{k}: {v}\n" for k, v in fields.items())
    )
    code = main(["maps", "--import", str(tmp_path / "m.yaml"), "--start", "2,2,0", "--goal",
                 "4,2.5,0", "--out", str(tmp_path / "o.json")])  # fmt: skip
    assert code == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith(f"rrtdrive maps: error: {field}: "), err
    assert err[0].endswith(f"(in {tmp_path / 'm.yaml'})"), err  # which file it is in


def test_thousands_of_rectangles_point_to_despeckle(tmp_path, capsys):
    pixels = np.full((300, 300), 255, np.uint8)
    pixels[100::3, ::3] = 0  # single dark pixels below y = 20 m: a scan's noise, 6700 specks
    _image(tmp_path, "noisy.png", pixels)
    args = ["maps", "--import", str(tmp_path / "noisy.png"), "--resolution", "0.1",
            "--start", "3,25,0", "--goal", "8,25,0", "--out", str(tmp_path / "o.json")]
    assert main(args) == 0
    said = capsys.readouterr().out
    assert "6700 rectangles" in said and "--despeckle N drops them" in said
    assert main([*args, "--despeckle", "1"]) == 0
    said = capsys.readouterr().out
    assert "--despeckle N drops them" not in said and "as 0 rectangles (6700 specks" in said
