"""Audit (session 49): ``rrtdrive maps --import`` against ROS ``map_server``'s conventions.

References, computed here independently of ``rrtdrive.occupancy``:
- geometry: ROS puts the image's bottom-left pixel at ``origin`` and counts pixel rows
  top-down, so row ``r``, column ``c`` of an ``H``-row image is the square
  ``[x0 + c*res, x0 + (c+1)*res] x [y0 + (H-1-r)*res, y0 + (H-r)*res]``; the written
  map's obstacles (read back from the JSON, boxes built here with shapely) must cover
  exactly the occupied pixels;
- thresholds: map_server's ``p = (255 - v) / 255`` (``v / 255`` with ``negate``),
  occupied when ``p > occupied_thresh``, free when ``p < free_thresh``, unknown otherwise
  (wiki.ros.org/map_server; nav2's ``map_io.cpp``: in ``scale`` mode a pixel that is not
  opaque is unknown);
- planning: ``rrtdrive plan`` and ``rrtdrive verify`` on the written file.
"""

from __future__ import annotations

import json
import math
import struct
import zlib
from pathlib import Path

import numpy as np
import pytest
import shapely
from PIL import Image

from rrtdrive.cli import main
from rrtdrive.maps import load_map, save_map

RES = 0.1


# ----------------------------------------------------------------------------- helpers
def _pgm(path: Path, img: np.ndarray, maxval: int) -> Path:
    """A binary PGM written by hand (8-bit, or big-endian 16-bit when maxval > 255)."""
    h, w = img.shape
    dtype = ">u2" if maxval > 255 else "u1"
    path.write_bytes(f"P5\n{w} {h}\n{maxval}\n".encode() + img.astype(dtype).tobytes())
    return path


def _yaml(path: Path, image: str, origin: str = "[0.0, 0.0, 0.0]", res: float = RES,
          **extra: object) -> Path:
    lines = [f"image: {image}", f"resolution: {res}", f"origin: {origin}"]
    lines += [f"{k}: {v}" for k, v in extra.items()]
    path.write_text("\n".join(lines) + "\n")
    return path


def _main(argv: list[str]) -> int:
    """``rrtdrive`` in process; argparse's own refusals exit by SystemExit."""
    try:
        return main(argv)
    except SystemExit as exc:
        return int(exc.code or 0)


def _import(capsys, source: Path, out: Path, start: str, goal: str, *flags: str):
    code = _main(["maps", "--import", str(source), "--start", start, "--goal", goal,
                 "--out", str(out), *flags])  # fmt: skip
    cap = capsys.readouterr()
    return code, cap.out, cap.err


def _obstacle_union(json_file: Path) -> shapely.Geometry:
    """The map file's obstacles as shapely boxes, built from the JSON alone."""
    data = json.loads(json_file.read_text())
    boxes = []
    for o in data["obstacles"]:
        (cx, cy), (length, width), yaw = o["center"], o["size"], o.get("yaw", 0.0)
        b = shapely.box(-length / 2, -width / 2, length / 2, width / 2)
        b = shapely.affinity.rotate(b, yaw, origin=(0, 0), use_radians=True)
        boxes.append(shapely.affinity.translate(b, cx, cy))
    return shapely.union_all(boxes) if boxes else shapely.Polygon()


def _cell(r: int, c: int, rows: int, x0: float, y0: float, res: float) -> shapely.Polygon:
    """ROS: the bottom-left pixel at the origin, pixel rows top-down."""
    return shapely.box(x0 + c * res, y0 + (rows - 1 - r) * res,
                       x0 + (c + 1) * res, y0 + (rows - r) * res)  # fmt: skip


def _covered(union: shapely.Geometry, rows: int, cols: int, x0: float, y0: float,
             res: float) -> np.ndarray:
    """Which pixels' centres lie inside the obstacles (top row first)."""
    r, c = np.mgrid[0:rows, 0:cols]
    xs = x0 + (c + 0.5) * res
    ys = y0 + (rows - 1 - r + 0.5) * res
    return shapely.contains_xy(union, xs.ravel(), ys.ravel()).reshape(rows, cols)


def _ros_class(p: np.ndarray, occ: float, free: float) -> np.ndarray:
    """map_server trinary: 100 occupied, 0 free, -1 unknown."""
    return np.where(p > occ, 100, np.where(p < free, 0, -1))


# ----------------------------------------------------------------------------- geometry
def test_occupied_blocks_cover_exactly_the_ros_rectangles(tmp_path, capsys):
    rows, cols, res, x0, y0 = 160, 240, 0.05, -3.2, 1.5
    img = np.full((rows, cols), 254, np.uint8)
    img[5:17, 70:103] = 0          # a block near the top right
    img[0, 0] = 0                  # the top-left pixel: the top of the map, not its bottom
    img[rows - 1, cols - 1] = 10   # the bottom-right pixel, dark enough
    img[60:66, 2:9] = 205          # ROS's grey: unknown
    img[30:33, 40:41] = 95         # p = 0.627: between the thresholds, unknown too
    _pgm(tmp_path / "g.pgm", img, 255)
    y = _yaml(tmp_path / "g.yaml", "g.pgm", f"[{x0}, {y0}, 0.0]", res)
    out = tmp_path / "g.json"
    code, line, err = _import(capsys, y, out, "-1.5,3,0", "4,3,0")
    assert code == 0, err
    m = load_map(out)
    assert m.bounds == pytest.approx((x0, y0, x0 + cols * res, y0 + rows * res), abs=1e-9)
    union = _obstacle_union(out)

    # The block is exactly ROS's rectangle (area of the symmetric difference ~ 0).
    block = shapely.box(x0 + 70 * res, y0 + (rows - 17) * res, x0 + 103 * res,
                        y0 + (rows - 5) * res)  # fmt: skip
    assert block.area == pytest.approx(33 * 12 * res * res)
    near = union.intersection(shapely.box(x0 + 60 * res, y0 + 50 * res, x0 + cols * res,
                                          y0 + rows * res))  # fmt: skip
    assert near.symmetric_difference(block).area < 1e-9
    # The single pixels, placed with the y flip.
    for r, c in ((0, 0), (rows - 1, cols - 1)):
        cell = _cell(r, c, rows, x0, y0, res)
        assert union.intersection(cell).area == pytest.approx(res * res, rel=1e-6)
    # Every pixel: covered exactly when ROS calls it occupied or unknown (the default).
    p = (255 - img.astype(float)) / 255
    ros = _ros_class(p, 0.65, 0.196)
    assert np.array_equal(_covered(union, rows, cols, x0, y0, res), ros != 0)
    # The total area is the occupied-or-unknown pixels', no more (no overlap, no spill).
    assert union.area == pytest.approx(np.count_nonzero(ros != 0) * res * res, rel=1e-9)
    assert f"{np.count_nonzero(ros == -1)} unknown, read as occupied" in line

    # --unknown-free: the unknown pixels are floor, the rest as before.
    code, line, err = _import(capsys, y, out, "-1.5,3,0", "4,3,0", "--unknown-free")
    assert code == 0, err
    union = _obstacle_union(out)
    assert np.array_equal(_covered(union, rows, cols, x0, y0, res), ros == 100)
    assert "read as free" in line


# ----------------------------------------------------------------------------- thresholds
def _sweep_image(values: np.ndarray, background: int, dtype: type) -> np.ndarray:
    """Row 0: the values under test; below: 50 rows of floor for the car (>= 20 m wide)."""
    img = np.full((51, max(values.size, 200)), background, dtype)
    img[0, : values.size] = values
    return img


START, GOAL = "4,2.5,0", "14,2.5,0"


@pytest.mark.parametrize("negate", [0, 1])
@pytest.mark.parametrize("mode", ["trinary", "scale"])
@pytest.mark.parametrize(("occ", "free"), [(0.65, 0.196), (0.6, 0.3)])
def test_eight_bit_thresholds_negate_and_mode_as_map_server(tmp_path, capsys, negate, mode,
                                                            occ, free):
    values = np.arange(256)
    img = _sweep_image(values, 0 if negate else 255, np.uint8)
    _pgm(tmp_path / "s.pgm", img, 255)
    y = _yaml(tmp_path / "s.yaml", "s.pgm", negate=negate, mode=mode, occupied_thresh=occ,
              free_thresh=free)  # fmt: skip
    out = tmp_path / "s.json"
    p = values / 255.0 if negate else (255 - values) / 255.0
    ros = _ros_class(p, occ, free)
    # The cells next to each threshold are both in the sweep.
    assert {100, 0, -1} <= set(ros.tolist())
    for flags, blocked in (((), ros != 0), (("--unknown-free",), ros == 100)):
        code, _, err = _import(capsys, y, out, START, GOAL, *flags)
        assert code == 0, err
        cov = _covered(_obstacle_union(out), img.shape[0], img.shape[1], 0.0, 0.0, RES)
        assert np.array_equal(cov[0], blocked), np.flatnonzero(cov[0] != blocked)
        assert not cov[1:].any()  # the floor stays free


def test_sixteen_bit_pgm_and_png_use_the_full_range(tmp_path, capsys):
    # Values around the thresholds on the 16-bit scale: 0.35 * 65535 = 22937.25 and
    # 0.804 * 65535 = 52690.14; an 8-bit reading (v / 255) would call all of these white.
    probe = np.array([0, 22937, 22938, 40000, 52690, 52691, 65535])
    values = np.repeat(probe, 20)
    p = (65535 - values) / 65535.0
    ros = _ros_class(p, 0.65, 0.196)
    assert ros[:20].tolist() == [100] * 20 and ros[-20:].tolist() == [0] * 20
    img = _sweep_image(values, 65535, np.uint16)
    _pgm(tmp_path / "s16.pgm", img, 65535)
    Image.fromarray(img).save(tmp_path / "s16.png")
    for name in ("s16.pgm", "s16.png"):
        out = tmp_path / f"{name}.json"
        code, line, err = _import(capsys, tmp_path / name, out, START, GOAL, "--resolution",
                                  str(RES))  # fmt: skip
        assert code == 0, (name, err)
        cov = _covered(_obstacle_union(out), img.shape[0], img.shape[1], 0.0, 0.0, RES)
        assert np.array_equal(cov[0, : values.size], ros != 0), name
        assert not cov[0, values.size :].any() and not cov[1:].any()
        assert f"{np.count_nonzero(ros == -1)} unknown" in line


def test_a_pgm_maxval_below_the_type_maximum_is_scaled_by_it(tmp_path, capsys):
    # maxval 1000: 350 is p = 0.65 (unknown, not above), 349 occupied, 805 free (p 0.195).
    values = np.repeat(np.array([0, 349, 350, 804, 805, 1000]), 20)
    img = _sweep_image(values, 1000, np.uint16)
    _pgm(tmp_path / "m.pgm", img, 1000)
    ros = _ros_class((1000 - values) / 1000.0, 0.65, 0.196)
    out = tmp_path / "m.json"
    code, _, err = _import(capsys, tmp_path / "m.pgm", out, START, GOAL, "--resolution",
                           str(RES))  # fmt: skip
    assert code == 0, err
    cov = _covered(_obstacle_union(out), img.shape[0], img.shape[1], 0.0, 0.0, RES)
    # Occupied and unknown both block by default, so 350 (p == 0.65 exactly, which Pillow's
    # rescaling to 16 bits may tip either way) is blocked whichever side it lands on.
    assert np.array_equal(cov[0, : values.size], ros != 0)


def test_colour_and_alpha_pixels_average_as_map_server_trinary(tmp_path, capsys):
    pixels = [  # RGBA, and map_server's mean over all four channels in trinary mode
        (0, 0, 0, 255), (255, 255, 255, 255), (255, 0, 0, 255), (200, 210, 220, 255),
        (255, 255, 255, 0), (255, 255, 255, 128), (0, 0, 0, 0), (60, 60, 60, 255),
    ]
    values = np.repeat(np.array(pixels, dtype=np.uint8), 20, axis=0)
    img = np.full((51, 200, 4), 255, np.uint8)
    img[0, : values.shape[0]] = values
    Image.fromarray(img, "RGBA").save(tmp_path / "c.png")
    Image.fromarray(img[..., :3].copy(), "RGB").save(tmp_path / "c3.png")
    mean4 = values.astype(float).mean(axis=1)
    mean3 = values[:, :3].astype(float).mean(axis=1)
    for name, mean in (("c.png", mean4), ("c3.png", mean3)):
        ros = _ros_class((255 - mean) / 255, 0.65, 0.196)
        out = tmp_path / f"{name}.json"
        code, _, err = _import(capsys, tmp_path / name, out, START, GOAL, "--resolution",
                               str(RES))  # fmt: skip
        assert code == 0, err
        cov = _covered(_obstacle_union(out), img.shape[0], img.shape[1], 0.0, 0.0, RES)
        assert np.array_equal(cov[0, : values.shape[0]], ros != 0), name
        assert not cov[0, values.shape[0] :].any()


def test_scale_mode_transparent_pixels_are_unknown(tmp_path, capsys):
    img = np.full((51, 200, 4), 255, np.uint8)
    img[0, :100, 3] = 0     # transparent white: unknown in a scale map
    img[0, 100:, 3] = 255   # opaque white: free
    Image.fromarray(img, "RGBA").save(tmp_path / "t.png")
    y = _yaml(tmp_path / "t.yaml", "t.png", mode="scale")
    out = tmp_path / "t.json"
    code, _, err = _import(capsys, y, out, START, GOAL)
    assert code == 0, err
    cov = _covered(_obstacle_union(out), 51, 200, 0.0, 0.0, RES)
    assert cov[0, :100].all() and not cov[0, 100:].any() and not cov[1:].any()


def test_palette_png_transparency_reads_as_the_rgba_picture_does(tmp_path, capsys):
    idx = np.zeros((51, 200), np.uint8)  # palette 0: white; 1: transparent white
    idx[0, :100] = 1
    pal = Image.fromarray(idx, "P")
    pal.putpalette([255, 255, 255, 255, 255, 255] + [0, 0, 0] * 254)
    pal.save(tmp_path / "p.png", transparency=1)
    rgba = np.full((51, 200, 4), 255, np.uint8)
    rgba[0, :100, 3] = 0
    Image.fromarray(rgba, "RGBA").save(tmp_path / "r.png")
    cov = {}
    for name in ("p.png", "r.png"):
        out = tmp_path / f"{name}.json"
        code, _, err = _import(capsys, tmp_path / name, out, START, GOAL, "--resolution",
                               str(RES))  # fmt: skip
        assert code == 0, err
        cov[name] = _covered(_obstacle_union(out), 51, 200, 0.0, 0.0, RES)
    assert cov["r.png"][0, :100].all()  # the RGBA picture: unknown, an obstacle
    assert np.array_equal(cov["p.png"], cov["r.png"])


# ----------------------------------------------------------------------------- planning
def _corridor(tmp_path: Path, closed: bool) -> Path:
    img = np.zeros((200, 400), np.uint8)          # 40 x 20 m, dark: occupied
    img[30:170, 10:390] = 254                     # the corridor's floor: x 1..39, y 3..17
    img[(30 if closed else 80):170, 195:205] = 0  # a wall up from its floor, or right across
    Image.fromarray(img).save(tmp_path / "c.png")
    return _yaml(tmp_path / "c.yaml", "c.png", "[0, 0, 0]", RES)


def test_a_corridor_image_plans_and_the_path_verifies(tmp_path, capsys):
    out, plan = tmp_path / "c.json", tmp_path / "plan.json"
    code, _, err = _import(capsys, _corridor(tmp_path, closed=False), out, "3,5,0", "33,5,0")
    assert code == 0, err
    assert main(["plan", str(out), "--json", str(plan)]) == 0
    result = json.loads(plan.read_text())
    assert result["success"] is True and result["length_m"] > 30.0
    capsys.readouterr()
    assert main(["verify", str(plan), str(out)]) == 0, capsys.readouterr()


def test_a_wall_image_is_proven_unreachable(tmp_path, capsys):
    out, plan = tmp_path / "c.json", tmp_path / "plan.json"
    code, _, err = _import(capsys, _corridor(tmp_path, closed=True), out, "3,5,0", "33,5,0")
    assert code == 0, err
    assert main(["plan", str(out), "--json", str(plan)]) == 1
    assert json.loads(plan.read_text())["status"] == "proven_unreachable"


# ----------------------------------------------------------------------------- round trip
def test_the_written_map_reloads_with_the_same_obstacles(tmp_path, capsys):
    y = _corridor(tmp_path, closed=False)
    out = tmp_path / "c.json"
    assert _import(capsys, y, out, "3,5,0", "33,5,0")[0] == 0
    m = load_map(out)
    again = tmp_path / "again.json"
    save_map(m, again)
    assert load_map(again).obstacles == m.obstacles
    assert _obstacle_union(again).symmetric_difference(_obstacle_union(out)).area < 1e-12
    # plan reads the same map: its JSON names it and it solves from the file's poses.
    plan = tmp_path / "p.json"
    assert main(["plan", str(out), "--json", str(plan), "--max-iterations", "4000"]) == 0
    assert json.loads(plan.read_text())["map"] == "c"
    # The image's own occupied pixels, independently: dark (0) pixels only.
    img = np.asarray(Image.open(tmp_path / "c.png"))
    cov = _covered(_obstacle_union(again), *img.shape, 0.0, 0.0, RES)
    assert np.array_equal(cov, img < 100)


# ----------------------------------------------------------------------------- bad inputs
def _floor(tmp_path: Path) -> Path:
    img = np.full((100, 200), 254, np.uint8)
    img[40:60, 90:110] = 0  # a 2 x 2 m block at x 9..11, y 4..6
    Image.fromarray(img).save(tmp_path / "f.png")
    return tmp_path / "f.png"


@pytest.mark.parametrize(
    ("yaml_text", "needle"),
    [
        ("resolution: 0.1\norigin: [0, 0, 0]\n", "image: missing"),
        ("image: f.png\norigin: [0, 0, 0]\n", "resolution: missing"),
        ("image: f.png\nresolution: 0.1\n", "origin: missing"),
        ("image: f.png\nresolution: 0\norigin: [0, 0, 0]\n", "resolution: expected a number"),
        ("image: f.png\nresolution: -0.1\norigin: [0, 0, 0]\n", "resolution: expected a number"),
        ("image: f.png\nresolution: .nan\norigin: [0, 0, 0]\n", "resolution: expected a number"),
        ("image: f.png\nresolution: [0.1]\norigin: [0, 0, 0]\n", "resolution: expected a number"),
        ("image: f.png\nresolution: 0.1\norigin: [0, 0, 0.5]\n", "origin: the map is rotated"),
        ("image: f.png\nresolution: 0.1\norigin: [0, 0, 3.14159]\n", "origin: the map is rotated"),
        ("image: f.png\nresolution: 0.1\norigin: 0\n", "origin: expected [x, y, yaw]"),
        ("image: f.png\nresolution: 0.1\norigin: [a, 0, 0]\n", "origin: x: expected a number"),
        ("image: 7\nresolution: 0.1\norigin: [0, 0, 0]\n", "image: expected the image's"),
        ("image: no.png\nresolution: 0.1\norigin: [0, 0, 0]\n", "image: "),
        ("image: f.png\nresolution: 0.1\norigin: [0, 0, 0]\nnegate: 2\n",
         "negate: expected 0 or 1"),
        ("image: f.png\nresolution: 0.1\norigin: [0, 0, 0]\noccupied_thresh: 1.5\n",
         "occupied_thresh: expected a number"),
        ("image: f.png\nresolution: 0.1\norigin: [0, 0, 0]\nfree_thresh: x\n",
         "free_thresh: expected a number"),
        ("image: f.png\nresolution: 0.1\norigin: [0, 0, 0]\nmode: raw\n", "mode: only trinary"),
        ("[1, 2]\n", "--import: "),
        ("image: [f.png\n", "--import: "),
    ],
)
def test_bad_yaml_is_one_line_naming_the_field(tmp_path, capsys, yaml_text, needle):
    _floor(tmp_path)
    (tmp_path / "b.yaml").write_text(yaml_text)
    out = tmp_path / "b.json"
    code, _, err = _import(capsys, tmp_path / "b.yaml", out, "3,2,0", "15,2,0")
    assert code == 2 and err.count("\n") == 1 and "Traceback" not in err, err
    assert err.startswith(f"rrtdrive maps: error: {needle}"), err
    assert not out.exists()


def test_a_full_turn_of_yaw_is_no_rotation(tmp_path, capsys):
    _floor(tmp_path)
    y = _yaml(tmp_path / "t.yaml", "f.png", f"[0, 0, {2 * math.pi:.6f}]")
    code, _, err = _import(capsys, y, tmp_path / "t.json", "3,2,0", "15,2,0")
    assert code == 0, err


@pytest.mark.parametrize(
    ("flags", "needle"),
    [
        (["--start", "10,5,0", "--goal", "15,2,0"], "--start: "),     # on the block
        (["--start", "3,2,0", "--goal", "10,5,0"], "--goal: "),       # on the block
        (["--start", "30,2,0", "--goal", "15,2,0"], "--start: "),     # outside the image
        (["--start", "3,2,0", "--goal", "15,-4,0"], "--goal: "),      # below the image
        (["--start", "3,2,0", "--goal", "15,2,0", "--resolution", "0"], "argument --resolution"),
        (["--start", "3,2,0", "--goal", "15,2,0", "--resolution", "nan"], "argument --resolution"),
        (["--start", "3,2,0", "--goal", "15,2,0", "--resolution", "-0.1"], "argument --resolution"),
        (["--start", "3,2,0", "--goal", "15,2,0"], "--resolution: an image needs"),
        (["--start", "3,2,0", "--goal", "15,2,0", "--resolution", "0.1", "--origin", "nan,0"],
         "--origin: "),
        (["--start", "3,2,0", "--goal", "15,2,0", "--resolution", "0.1", "--origin", "1"],
         "--origin: "),
    ],
)
def test_bad_flags_and_poses_are_one_line_naming_the_flag(tmp_path, capsys, flags, needle):
    f = _floor(tmp_path)
    out = tmp_path / "o.json"
    if "--resolution" not in flags and needle != "--resolution: an image needs":
        flags = [*flags, "--resolution", "0.1"]
    code = _main(["maps", "--import", str(f), "--out", str(out), *flags])
    err = capsys.readouterr().err
    assert code == 2 and err.count("\n") == 1 and "Traceback" not in err, err
    assert err.startswith(f"rrtdrive maps: error: {needle}"), err
    assert not out.exists()


def test_a_file_that_is_no_image_is_named(tmp_path, capsys):
    (tmp_path / "n.png").write_text("P5 this is not an image\n")
    (tmp_path / "n.yaml").write_text("image: n.png\nresolution: 0.1\norigin: [0, 0, 0]\n")
    for source, needle in ((tmp_path / "n.png", "--import: cannot read"),
                           (tmp_path / "n.yaml", "image: cannot read")):  # fmt: skip
        code, _, err = _import(capsys, source, tmp_path / "o.json", "3,2,0", "15,2,0",
                               *(["--resolution", "0.1"] if source.suffix == ".png" else []))
        assert code == 2 and err.count("\n") == 1, err
        assert err.startswith(f"rrtdrive maps: error: {needle}"), err


def _huge_png(path: Path, width: int, height: int) -> None:
    """A white 8-bit grayscale PNG of the given size, a few hundred kB (rows compress)."""
    def chunk(kind: bytes, data: bytes) -> bytes:
        return (struct.pack(">I", len(data)) + kind + data
                + struct.pack(">I", zlib.crc32(kind + data) & 0xFFFFFFFF))  # fmt: skip

    z = zlib.compressobj(6)
    row = b"\x00" + b"\xff" * width
    data = b"".join(z.compress(row) for _ in range(height)) + z.flush()
    ihdr = struct.pack(">IIBBBBB", width, height, 8, 0, 0, 0, 0)
    path.write_bytes(b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", ihdr) + chunk(b"IDAT", data)
                     + chunk(b"IEND", b""))  # fmt: skip


def test_a_huge_image_is_refused_in_one_line(tmp_path, capsys):
    _huge_png(tmp_path / "huge.png", 20000, 10000)  # 2e8 pixels: Pillow's bomb limit
    code, _, err = _import(capsys, tmp_path / "huge.png", tmp_path / "o.json", "3,2,0",
                           "15,2,0", "--resolution", "0.05")  # fmt: skip
    assert code == 2 and err.count("\n") == 1 and "Traceback" not in err, err
    assert err.startswith("rrtdrive maps: error: --import: "), err


def test_a_huge_image_refusal_says_it_is_too_large(tmp_path, capsys):
    _huge_png(tmp_path / "huge.png", 20000, 10000)
    _, _, err = _import(capsys, tmp_path / "huge.png", tmp_path / "o.json", "3,2,0",
                        "15,2,0", "--resolution", "0.05")  # fmt: skip
    why = err.replace(str(tmp_path), "")
    assert "pixel" in why or "large" in why or "size" in why, err


def test_a_cmyk_image_reads_as_its_grey_picture(tmp_path, capsys):
    grey = np.full((60, 200), 255, np.uint8)
    grey[:10, 90:110] = 0  # a black block at the top
    Image.fromarray(grey).save(tmp_path / "g.png")
    Image.fromarray(grey).convert("CMYK").save(tmp_path / "k.tif")
    unions = {}
    for name in ("g.png", "k.tif"):
        out = tmp_path / f"{name}.json"
        code, _, err = _import(capsys, tmp_path / name, out, START, GOAL, "--resolution",
                               str(RES))  # fmt: skip
        assert code == 0, (name, err)
        unions[name] = _obstacle_union(out)
    assert unions["g.png"].area == pytest.approx(20 * 10 * RES * RES)
    assert unions["k.tif"].symmetric_difference(unions["g.png"]).area < 1e-9


@pytest.mark.parametrize("dtype", [np.int32, np.float32])
def test_a_32_bit_tiff_is_refused_not_misread(tmp_path, capsys, dtype):
    """Its values have no white to be read against (0..255 read against 65535 made
    every cell occupied); map_server's libtiff refuses such samples too."""
    grey = np.full((60, 200), 255, dtype)
    grey[:10, 90:110] = 0
    Image.fromarray(grey).save(tmp_path / "w.tif")
    code, _, err = _import(capsys, tmp_path / "w.tif", tmp_path / "o.json", START, GOAL,
                           "--resolution", str(RES))  # fmt: skip
    assert code == 2 and err.count("\n") == 1 and "Traceback" not in err, err
    assert "samples" in err and "8-bit" in err and err.startswith(
        "rrtdrive maps: error: --import: "), err
    assert not (tmp_path / "o.json").exists()
    # The same picture in 16 bits still reads as the 8-bit one.
    Image.fromarray(grey.astype(np.uint16) * 257).save(tmp_path / "w16.png")
    Image.fromarray(grey.astype(np.uint8)).save(tmp_path / "w8.png")
    unions = []
    for name in ("w16.png", "w8.png"):
        out = tmp_path / f"{name}.json"
        code, _, err = _import(capsys, tmp_path / name, out, START, GOAL, "--resolution",
                               str(RES))  # fmt: skip
        assert code == 0, err
        unions.append(_obstacle_union(out))
    assert unions[0].symmetric_difference(unions[1]).area < 1e-9
    assert unions[1].area == pytest.approx(20 * 10 * RES * RES)


def test_the_image_path_is_relative_to_the_yaml_folder_not_the_cwd(tmp_path, capsys,
                                                                   monkeypatch):
    sub = tmp_path / "maps" / "site"
    sub.mkdir(parents=True)
    _floor(sub)
    _yaml(sub / "f.yml", "f.png")
    (tmp_path / "elsewhere").mkdir()
    monkeypatch.chdir(tmp_path / "elsewhere")
    code, line, err = _import(capsys, Path("../maps/site/f.yml"), Path("o.json"), "3,2,0",
                              "15,2,0")  # fmt: skip
    assert code == 0, err
    assert "200 x 100 cells at 0.1 m" in line and "as 1 rectangle " in line
    assert load_map("o.json").name == "f"
