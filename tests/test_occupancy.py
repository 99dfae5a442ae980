"""``rrtdrive maps --import``: maps from occupancy images (ROS map_server or plain images).

References: the rectangles painted back into a grid (numpy), shapely's union of the
obstacles against each cell centre, and the ROS trinary thresholds worked by hand.
"""

from __future__ import annotations

from pathlib import Path

import imageio.v3 as iio
import numpy as np
import pytest
import shapely
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays

from rrtdrive.cli import main
from rrtdrive.maps import load_map
from rrtdrive.occupancy import (
    ImageMap,
    despeckle,
    grid_rectangles,
    image_obstacles,
    read_image_map,
    read_ros_map,
)
from rrtdrive.types import InputError
from rrtdrive.vehicle import VehicleParams, footprint_polygon

grids = st.tuples(st.integers(1, 12), st.integers(1, 15)).flatmap(
    lambda shape: arrays(bool, shape)
)


@settings(max_examples=80, deadline=None)
@given(grids)
def test_rectangles_cover_exactly_the_occupied_cells_once(occupied):
    painted = np.zeros(occupied.shape, dtype=int)
    for r0, c0, r1, c1 in grid_rectangles(occupied):
        assert r0 < r1 and c0 < c1
        painted[r0:r1, c0:c1] += 1
    assert np.array_equal(painted, occupied.astype(int))


@settings(max_examples=40, deadline=None)
@given(grids, st.sampled_from([0.05, 0.25, 1.0]))
def test_obstacles_lie_on_the_occupied_cells_image_rows_from_the_top(occupied, res):
    rows, cols = occupied.shape
    grid = ImageMap(occupied, res, (-3.0, 2.0))
    assert grid.bounds == pytest.approx((-3.0, 2.0, -3.0 + cols * res, 2.0 + rows * res))
    obstacles = image_obstacles(grid)
    union = shapely.union_all([o.polygon() for o in obstacles])
    for r in range(rows):
        for c in range(cols):
            # Row r counts from the top: its cell centre is rows - 1 - r cells up, + 0.5.
            centre = shapely.Point(-3.0 + (c + 0.5) * res, 2.0 + (rows - 1 - r + 0.5) * res)
            assert union.contains(centre) == bool(occupied[r, c])
    assert union.area == pytest.approx(occupied.sum() * res * res)
    assert sum(o.polygon().area for o in obstacles) == pytest.approx(union.area)


def _write(tmp_path, pixels: np.ndarray, name: str = "lot.pgm"):
    f = tmp_path / name
    iio.imwrite(f, pixels)
    return f


def test_ros_trinary_thresholds_and_negate(tmp_path):
    # p = (255 - v) / 255: occupied above 0.65 (v <= 89), free below 0.196 (v >= 206),
    # unknown between (ROS's grey 205 is unknown: p = 0.19608).
    values = np.array([[0, 89, 90, 205, 206, 254]], dtype=np.uint8)
    f = _write(tmp_path, values)
    grid = read_image_map(f, 0.1)
    assert grid.occupied.tolist() == [[True, True, True, True, False, False]]
    assert grid.unknown == 2
    assert read_image_map(f, 0.1, unknown_free=True).occupied.tolist() == [
        [True, True, False, False, False, False]]
    # negate: p = v / 255 = 0, .349, .353, .804, .808, .996: white is occupied, 89 and
    # 90 unknown (read as free here), only 0 free by the threshold.
    flipped = read_image_map(f, 0.1, negate=True, unknown_free=True)
    assert flipped.occupied.tolist() == [[False, False, False, True, True, True]]
    assert flipped.unknown == 2


def test_thresholds_are_strict_as_map_servers(tmp_path):
    # map_server: occupied when p > occupied_thresh, free when p < free_thresh. With
    # thresholds 0.6 and 0.2, v = 102 gives p = 153/255 = 0.6 and v = 204 p = 0.2 exactly:
    # both unknown.
    f = _write(tmp_path, np.array([[101, 102, 204, 205]], dtype=np.uint8))
    grid = read_image_map(f, 0.1, occupied_thresh=0.6, free_thresh=0.2, unknown_free=True)
    assert grid.occupied.tolist() == [[True, False, False, False]] and grid.unknown == 2
    with pytest.raises(InputError, match="^free_thresh: must be below occupied_thresh"):
        read_image_map(f, 0.1, occupied_thresh=0.5, free_thresh=0.5)


def test_colour_and_sixteen_bit_images(tmp_path):
    rgb = np.zeros((1, 3, 3), dtype=np.uint8)
    rgb[0, 1] = (255, 255, 255)
    rgb[0, 2] = (255, 0, 255)  # mean 170: p = 0.333, unknown
    f = _write(tmp_path, rgb, "c.png")
    grid = read_image_map(f, 0.5, unknown_free=True)
    assert grid.occupied.tolist() == [[True, False, False]] and grid.unknown == 1
    # 16 bits: p = (65535 - v) / 65535, whatever the brightest pixel: 200 is p = 0.997,
    # occupied; 30000 is p = 0.54, unknown.
    wide = np.array([[0, 200, 30000, 65535]], dtype=np.uint16)
    grid = read_image_map(_write(tmp_path, wide, "w.png"), 0.5, unknown_free=True)
    assert grid.occupied.tolist() == [[True, True, False, False]] and grid.unknown == 1


def test_alpha_is_averaged_in_as_map_server_does_in_trinary_mode_only(tmp_path):
    """map_server's image_loader: in trinary mode the mean takes every channel, alpha
    too; in scale mode the colour channels only. Worked by hand (thresholds 0.65, 0.196):
    opaque (60, 60, 60, 255): trinary mean 108.75, p = 0.574, unknown; scale mean 60,
    p = 0.765, occupied. Opaque ROS grey (205, 205, 205, 255): trinary mean 217.5,
    p = 0.147, free; scale mean 205, p = 0.196, not below free_thresh: unknown.
    Grey-alpha (60, 255): trinary mean 157.5, p = 0.382, unknown; scale 60: occupied."""
    rgba = np.array([[[60, 60, 60, 255], [205, 205, 205, 255]]], dtype=np.uint8)
    f = _write(tmp_path, rgba, "rgba.png")
    grid = read_image_map(f, 0.1, unknown_free=True)
    assert grid.occupied.tolist() == [[False, False]] and grid.unknown == 1
    grid = read_image_map(f, 0.1, unknown_free=True, mode="scale")
    assert grid.occupied.tolist() == [[True, False]] and grid.unknown == 1
    la = np.array([[[60, 255]]], dtype=np.uint8)
    g = _write(tmp_path, la, "la.png")
    assert read_image_map(g, 0.1, unknown_free=True).unknown == 1
    assert read_image_map(g, 0.1, unknown_free=True, mode="scale").occupied.tolist() == [[True]]
    # A ROS map's mode reaches the reader.
    (tmp_path / "s.yaml").write_text(
        "image: rgba.png\nresolution: 0.1\norigin: [0.0, 0.0, 0.0]\nmode: scale\n")
    assert read_ros_map(tmp_path / "s.yaml", unknown_free=True).occupied.tolist() == [[True, False]]
    with pytest.raises(InputError, match="^mode: only trinary and scale"):
        read_image_map(f, 0.1, mode="raw")


def _garage(tmp_path, origin="[-2.0, -1.0, 0.0]", extra=""):
    img = np.full((140, 300), 254, dtype=np.uint8)
    img[:3, :] = img[-3:, :] = 0
    img[:, :3] = img[:, -3:] = 0
    img[60:80, 130:170] = 0  # a 4 x 2 m block at x 11..15, y 5..7 (origin -2, -1)
    _write(tmp_path, img, "garage.pgm")
    y = tmp_path / "garage.yaml"
    y.write_text(f"image: garage.pgm\nresolution: 0.1\norigin: {origin}\n{extra}")
    return y


def test_a_ros_map_imports_and_plans(tmp_path, capsys):
    y = _garage(tmp_path)
    out = tmp_path / "g.json"
    code = main(["maps", "--import", str(y), "--start", "2,2,0", "--goal", "22,10,0",
                 "--out", str(out)])  # fmt: skip
    assert code == 0
    line = capsys.readouterr().out
    assert "300 x 140 cells at 0.1 m, 30 x 14 m" in line and "as 5 rectangles" in line
    m = load_map(out)
    assert m.name == "garage" and m.bounds == (-2.0, -1.0, 28.0, 13.0)
    block = [o for o in m.obstacles if o.size == (4.0, 2.0)]
    assert len(block) == 1 and block[0].center == pytest.approx((13.0, 6.0))
    assert main(["plan", str(out), "--json", str(tmp_path / "p.json")]) == 0


@pytest.mark.parametrize(
    ("argv", "needle"),
    [
        (["--start", "2,2,0", "--goal", "22,10,0"], "--out: --import needs it"),
        (["--goal", "22,10,0", "--out", "g.json"], "--start: --import needs it"),
        (["--start", "13,6,0", "--goal", "22,10,0", "--out", "g.json"], "--start: "),
        (["--start", "2,2,0", "--goal", "22,10,0", "--out", "g.txt"], "--out: "),
        (["--start", "2,2,0", "--goal", "22,10,0", "--out", "g.json", "--resolution", "0.1"],
         "--resolution: the .yaml gives it"),
        (["--start", "2,2,0", "--goal", "22,10,0", "--out", "g.json", "--export", "d"],
         "--export: writes the built-in maps"),
    ],
)
def test_bad_imports_are_one_line_naming_the_flag(tmp_path, capsys, monkeypatch, argv, needle):
    y = _garage(tmp_path)
    monkeypatch.chdir(tmp_path)
    code = main(["maps", "--import", str(y), *argv])
    err = capsys.readouterr().err
    assert code == 2 and err.count("\n") == 1 and "Traceback" not in err
    assert err.startswith(f"rrtdrive maps: error: {needle}"), err
    assert not (tmp_path / "g.json").exists()


@pytest.mark.parametrize(
    ("origin", "extra", "needle"),
    [
        ("[-2.0, -1.0, 0.3]", "", "origin: the map is rotated (yaw 0.3 rad)"),
        ("[-2.0]", "", "origin: expected [x, y, yaw]"),
        ("[0, 0, 0]", "free_thresh: 0.7\n", "free_thresh: must be below occupied_thresh"),
        ("[0, 0, 0]", "mode: raw\n", "mode: only trinary and scale maps are read"),
        # PyYAML kept the last of two equal keys silently: a 0.05 m map read at 0.1 m.
        ("[0, 0, 0]", "resolution: 0.05\n", "resolution: given twice in"),
        ("[0, 0, 0]", "meta: {a: 1, a: 2}\n", "a: given twice in"),
    ],
)
def test_bad_ros_yaml_fields_are_named(tmp_path, capsys, origin, extra, needle):
    y = _garage(tmp_path, origin, extra)
    code = main(["maps", "--import", str(y), "--start", "2,2,0", "--goal", "22,10,0",
                 "--out", str(tmp_path / "g.json")])  # fmt: skip
    err = capsys.readouterr().err
    assert code == 2 and err.startswith(f"rrtdrive maps: error: {needle}"), err
    if "twice" in needle:  # the lines, as an editor numbers them
        assert err.rstrip().endswith(("(lines 2 and 4); keep one", "(line 4); keep one")), err


def test_plain_images_need_a_resolution_and_bad_files_are_named(tmp_path, capsys):
    img = np.full((50, 80), 254, dtype=np.uint8)
    f = _write(tmp_path, img, "open.png")
    base = ["maps", "--import", str(f), "--start", "3,4.5,0", "--goal", "4,4.5,0",
            "--out", str(tmp_path / "o.json")]  # fmt: skip
    assert main(base) == 2
    assert "--resolution: an image needs its metres per pixel" in capsys.readouterr().err
    assert main([*base, "--resolution", "0.1", "--origin", "1,2"]) == 0
    assert load_map(tmp_path / "o.json").bounds == (1.0, 2.0, 9.0, 7.0)
    capsys.readouterr()
    (tmp_path / "junk.png").write_text("not an image")
    assert main(["maps", "--import", str(tmp_path / "junk.png"), "--resolution", "0.1",
                 "--start", "3,4.5,0", "--goal", "4,4.5,0", "--out", str(tmp_path / "j.json")]) == 2
    err = capsys.readouterr().err
    assert err.startswith("rrtdrive maps: error: --import: cannot read") and err.count("\n") == 1
    assert main(["maps", "--start", "1,1,0"]) == 2
    assert "--start: only with --import" in capsys.readouterr().err
    with pytest.raises(InputError, match="^resolution: expected a number"):
        read_image_map(f, 0.0)


def _groups(occupied: np.ndarray) -> list[set[tuple[int, int]]]:
    """Occupied cells grouped with their eight neighbours, by a plain flood fill."""
    seen: set[tuple[int, int]] = set()
    out = []
    rows, cols = occupied.shape
    for r0 in range(rows):
        for c0 in range(cols):
            if not occupied[r0, c0] or (r0, c0) in seen:
                continue
            group, todo = set(), [(r0, c0)]
            while todo:
                r, c = todo.pop()
                if (r, c) in group:
                    continue
                group.add((r, c))
                for dr in (-1, 0, 1):
                    for dc in (-1, 0, 1):
                        rr, cc = r + dr, c + dc
                        if 0 <= rr < rows and 0 <= cc < cols and occupied[rr, cc]:
                            todo.append((rr, cc))
            seen |= group
            out.append(group)
    return out


@settings(max_examples=80, deadline=None)
@given(grids, st.integers(0, 5))
def test_despeckle_drops_exactly_the_small_groups(occupied, max_cells):
    """Each group of <= max_cells touching cells (corners too) goes, every other cell stays."""
    grid = ImageMap(occupied, 0.1, (1.0, 2.0), unknown=3)
    clean, groups, cells = despeckle(grid, max_cells)
    small = [g for g in _groups(occupied) if len(g) <= max_cells]
    expected = occupied.copy()
    for g in small:
        for r, c in g:
            expected[r, c] = False
    assert np.array_equal(clean.occupied, expected)
    assert (groups, cells) == (len(small), sum(len(g) for g in small))
    assert (clean.resolution, clean.origin, clean.unknown) == (0.1, (1.0, 2.0), 3)


def test_despeckle_refuses_a_bad_size():
    grid = ImageMap(np.ones((2, 2), dtype=bool), 0.1, (0.0, 0.0))
    for bad in (-1, 1.5, True, "2"):
        with pytest.raises(InputError, match="^max_cells: must be an integer >= 0"):
            despeckle(grid, bad)


def test_import_despeckle_clears_a_scan_and_keeps_a_speck_on_the_wall(tmp_path, capsys):
    """A walled yard with noise: --despeckle 2 leaves the walls, the block and the speck
    that touches the block at a corner; without it the noise blocks the start."""
    pixels = np.full((60, 100), 254, dtype=np.uint8)  # 0.5 m cells: 50 x 30 m
    pixels[:2, :] = pixels[-2:, :] = 0
    pixels[:, :2] = pixels[:, -2:] = 0
    pixels[20:40, 60:70] = 0  # a 5 x 10 m block
    noise = [(50, 10), (50, 11), (30, 30), (10, 80)]  # a pair and two single cells
    for r, c in noise:
        pixels[r, c] = 0
    pixels[19, 59] = 0  # touches the block's top left cell at a corner only
    source = _write(tmp_path, pixels, "yard.png")
    out = tmp_path / "yard.json"
    argv = ["maps", "--import", str(source), "--resolution", "0.5", "--start", "4,5.25,0",
            "--goal", "20,15,0", "--out", str(out)]  # fmt: skip
    assert main(argv) == 2  # the pair of noise cells at rows 50, cols 10-11 is on the start
    assert "--start: the car's body" in capsys.readouterr().err
    assert main([*argv, "--despeckle", "2"]) == 0
    said = capsys.readouterr().out
    assert "(3 specks of <= 2 cells dropped: 4 cells)" in said
    union = shapely.union_all([o.polygon() for o in load_map(out).obstacles])
    kept = (pixels < 128)
    for r, c in noise:
        kept[r, c] = False
    assert union.area == pytest.approx(kept.sum() * 0.25)
    assert union.contains(shapely.Point(59.5 * 0.5, (60 - 19 - 0.5) * 0.5))  # the corner speck


def test_a_transparent_background_is_named_when_the_start_lands_in_it(tmp_path, capsys):
    """matplotlib's transparent=True: white with alpha 0 reads as unknown (map_server's
    trinary mean takes in the alpha), the whole image became one obstacle, and the only
    word was "--start: ... overlaps obstacle 0" (a new user's find)."""
    rgba = np.zeros((100, 200, 4), np.uint8)
    rgba[..., :3] = 255  # a white, fully transparent background
    rgba[40:60, 90:110] = (0, 0, 0, 255)  # one opaque black block
    png = tmp_path / "mpl.png"
    iio.imwrite(png, rgba)
    argv = ["maps", "--import", str(png), "--resolution", "0.1", "--start", "3,3,0",
            "--goal", "14,7,0", "--out", str(tmp_path / "m.json")]
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert err.startswith("rrtdrive maps: error: --start: ") and err.count("\n") == 1
    # All but the 20 x 20 block of 100 x 200 cells; under the body, every cell it covers.
    body = footprint_polygon((3.0, 3.0, 0.0), VehicleParams())
    covered = sum(
        shapely.box(c * 0.1, 10 - (r + 1) * 0.1, (c + 1) * 0.1, 10 - r * 0.1)
        .intersection(body).area > 1e-12
        for r in range(100) for c in range(200)
        if not (40 <= r < 60 and 90 <= c < 110)
    )
    assert f"{covered} cells under the car's body and 98% of the image read as unknown" in err
    assert "--unknown-free" in err
    assert main([*argv, "--unknown-free"]) == 0  # the block alone is an obstacle then
    assert len(load_map(str(tmp_path / "m.json")).obstacles) == 1


def test_the_readme_import_example_prints_what_the_readme_says(tmp_path, capsys, monkeypatch):
    root = Path(__file__).resolve().parents[1]
    readme = (root / "README.md").read_text(encoding="utf-8")
    lines = readme.splitlines()
    command = next(ln for ln in lines if ln.startswith("rrtdrive maps --import docs/"))
    printed = readme.split(command + "\n# ", 1)[1].splitlines()[0]
    argv = command.split()[1:]
    argv[argv.index("--out") + 1] = str(tmp_path / "lot.json")
    monkeypatch.chdir(root)
    assert main(argv) == 0
    out = capsys.readouterr().out.strip()
    assert out.split(" -> ")[0] == printed.split(" -> ")[0]
    assert load_map(tmp_path / "lot.json").bounds == (0.0, 0.0, 40.0, 20.0)


def test_the_unknown_hint_only_for_a_body_on_unknown_cells(tmp_path, capsys):
    """A start on a dark speck said "0% of the image's cells read as unknown ...
    --unknown-free" where reading grey as free changes nothing (an audit)."""
    img = np.full((100, 200), 254, np.uint8)
    img[70:75, 20:25] = 0  # a dark speck at x 2..2.5, y 2.5..3
    img[10:30, 150:170] = 205  # a grey patch at x 15..17, y 7..9
    png = tmp_path / "g.png"
    iio.imwrite(png, img)
    base = ["maps", "--import", str(png), "--resolution", "0.1", "--out", str(tmp_path / "m.json")]
    assert main([*base, "--start", "2,2.75,0", "--goal", "8,5,0"]) == 2
    err = capsys.readouterr().err
    assert err.startswith("rrtdrive maps: error: --start: ") and "unknown" not in err
    # The goal's body over the patch's corner: the hint counts the cells it covers.
    goal = (14.0, 7.5, 0.0)
    body = footprint_polygon(goal, VehicleParams())
    patch = [shapely.box(15 + c * 0.1, 7 + r * 0.1, 15 + (c + 1) * 0.1, 7 + (r + 1) * 0.1)
             for r in range(20) for c in range(20)]  # fmt: skip
    covered = sum(cell.intersection(body).area > 1e-12 for cell in patch)
    assert 0 < covered < 400
    assert main([*base, "--start", "5,5,0", "--goal", "14,7.5,0"]) == 2
    err = capsys.readouterr().err
    assert err.startswith("rrtdrive maps: error: --goal: ")
    assert f"({covered} cells under the car's body and 2% of the image read as unknown" in err
    assert main([*base, "--start", "5,5,0", "--goal", "14,7.5,0", "--unknown-free"]) == 0


def test_negate_reads_a_dark_floor_image_and_the_refusal_suggests_it(tmp_path, capsys):
    """A plain image had no way to say "light is occupied" (a .yaml has negate: 1); a
    dark floor made the whole image one obstacle, with no word why."""
    img = np.full((100, 100), 1, np.uint8)  # a black floor
    img[40:60, 40:60] = 255  # one white block: x 20..30, y 20..30 at 0.5 m
    png = _write(tmp_path, img, "neg.png")
    base = ["maps", "--import", str(png), "--resolution", "0.5", "--start", "5,5,0",
            "--goal", "40,40,0", "--out", str(tmp_path / "n.json")]  # fmt: skip
    assert main(base) == 2
    err = capsys.readouterr().err
    assert err.startswith("rrtdrive maps: error: --start: ") and err.count("\n") == 1
    assert "(96% of the image reads as occupied: if its floor is the dark part, --negate" in err
    assert main([*base, "--negate"]) == 0
    got = load_map(tmp_path / "n.json")
    assert got.obstacle_union().symmetric_difference(shapely.box(20, 20, 30, 30)).area < 1e-9
    capsys.readouterr()
    # A .yaml gives its own negate.
    y = _garage(tmp_path)
    assert main(["maps", "--import", str(y), "--negate", "--start", "2,2,0", "--goal",
                 "22,10,0", "--out", str(tmp_path / "g.json")]) == 2  # fmt: skip
    assert "--negate: the .yaml gives it" in capsys.readouterr().err
