"""Audit (session 45): a user's own maps — the JSON format, ``maps``, ``--export``, ``--import``.

Imported obstacles are compared with an independent reading of the image (ROS
``map_server`` trinary rules, row 0 at the top) as shapely unions of cell squares.
"""

from __future__ import annotations

import json
import math

import imageio.v3 as iio
import numpy as np
import pytest
import shapely
from shapely import affinity
from shapely.geometry import box

from rrtdrive.cli import main
from rrtdrive.maps import BUILTIN_MAPS, builtin_map, load_map
from rrtdrive.occupancy import read_image_map, read_ros_map

# ----------------------------------------------------------------------------- helpers


def expected_occupied(values, negate=False, occ=0.65, free=0.196, unknown_free=False, white=255.0):
    """ROS map_server trinary reading, written out independently."""
    v = np.asarray(values, dtype=float)
    p = v / white if negate else (white - v) / white
    occupied = p > occ
    unknown = (~occupied) & (p >= free)
    return occupied | (unknown & (not unknown_free))


def cells_union(mask, res, x0, y0):
    rows = mask.shape[0]
    return shapely.union_all([
        box(x0 + c * res, y0 + (rows - 1 - r) * res, x0 + (c + 1) * res, y0 + (rows - r) * res)
        for r, c in zip(*np.nonzero(mask), strict=True)
    ])


def run(capsys, *argv):
    try:
        code = main([str(a) for a in argv])
    except SystemExit as exc:  # argparse's own errors
        code = exc.code
    out, err = capsys.readouterr()
    return code, out, err


def one_error_line(err):
    lines = [ln for ln in err.splitlines() if ln.strip()]
    assert len(lines) == 1, err
    return lines[0]


def lot_image():
    """60 x 100 pixels: a 2-pixel border, a block, a grey patch, one speck."""
    img = np.full((60, 100), 254, np.uint8)
    img[0:2, :] = 0
    img[-2:, :] = 0
    img[:, 0:2] = 0
    img[:, -2:] = 0
    img[20:40, 45:55] = 0
    img[5:8, 70:72] = 205  # ROS's unknown grey
    img[50, 80] = 0  # a speck
    img[3, 10] = 120  # unknown, p = 0.53
    return img


def write_yaml(path, image, origin="[0.0, 0.0, 0.0]", res="0.5", **extra):
    text = f"image: {image}\nresolution: {res}\norigin: {origin}\n"
    text += "".join(f"{k}: {v}\n" for k, v in extra.items())
    path.write_text(text)
    return path


@pytest.fixture
def lot(tmp_path):
    img = lot_image()
    iio.imwrite(tmp_path / "lot.png", img)
    write_yaml(tmp_path / "lot.yaml", "lot.png", origin="[-10.0, 5.0, 0.0]")
    return tmp_path, img


# ----------------------------------------------------------------------------- --import


@pytest.mark.parametrize("unknown_free", [False, True])
def test_import_yaml_cells_match_independent_reading(lot, capsys, unknown_free):
    d, img = lot
    out_json = d / "lot.json"
    argv = ["maps", "--import", d / "lot.yaml", "--start", "-4,10,0", "--goal", "30,27,0",
            "--out", out_json] + (["--unknown-free"] if unknown_free else [])
    code, out, err = run(capsys, *argv)
    assert code == 0, err
    mask = expected_occupied(img, unknown_free=unknown_free)
    assert f"{int(mask.sum())} occupied cells" in out
    m = load_map(out_json)
    assert m.bounds == (-10.0, 5.0, 40.0, 35.0)
    assert m.name == "lot"
    got = m.obstacle_union()
    want = cells_union(mask, 0.5, -10.0, 5.0)
    assert got.symmetric_difference(want).area == pytest.approx(0.0, abs=1e-9)
    assert got.area == pytest.approx(mask.sum() * 0.25)
    # The rectangles are disjoint and axis-aligned.
    assert sum(o.polygon().area for o in m.obstacles) == pytest.approx(got.area)
    assert all(o.yaw == 0.0 for o in m.obstacles)


def test_import_row_zero_is_the_top(tmp_path, capsys):
    img = np.full((40, 60), 255, np.uint8)
    img[0, 0] = 0  # top left pixel
    img[39, 59] = 0  # bottom right pixel
    iio.imwrite(tmp_path / "o.pgm", img)
    code, _, err = run(capsys, "maps", "--import", tmp_path / "o.pgm", "--resolution", "0.25",
                       "--origin", "3,-2", "--start", "5,1,0", "--goal", "10,5,0",
                       "--out", tmp_path / "o.json")
    assert code == 0, err
    m = load_map(tmp_path / "o.json")
    assert m.bounds == (3.0, -2.0, 18.0, 8.0)
    centres = sorted(o.center for o in m.obstacles)
    assert centres == [(3.125, 7.875), (17.875, -1.875)]
    assert all(o.size == (0.25, 0.25) for o in m.obstacles)


GRADIENT = np.arange(256, dtype=np.uint8).reshape(16, 16)


@pytest.mark.parametrize("extra", [
    {},
    {"negate": 1},
    {"occupied_thresh": 0.9, "free_thresh": 0.1},
    {"negate": 1, "occupied_thresh": 0.5, "free_thresh": 0.25},
    {"mode": "scale"},
    {"mode": "trinary", "negate": 0},
])
@pytest.mark.parametrize("unknown_free", [False, True])
def test_ros_thresholds_and_negate(tmp_path, extra, unknown_free):
    iio.imwrite(tmp_path / "g.pgm", GRADIENT)
    write_yaml(tmp_path / "g.yaml", "g.pgm", res="0.1", **extra)
    grid = read_ros_map(tmp_path / "g.yaml", unknown_free)
    want = expected_occupied(GRADIENT, bool(extra.get("negate")),
                             extra.get("occupied_thresh", 0.65), extra.get("free_thresh", 0.196),
                             unknown_free)
    np.testing.assert_array_equal(grid.occupied, want)
    # ROS's grey 205 is unknown with the default thresholds.
    if not extra and not unknown_free:
        assert grid.occupied[205 // 16, 205 % 16]


def test_rgba_alpha_in_trinary_not_in_scale(tmp_path):
    rgba = np.zeros((16, 16, 4), np.uint8)
    rgba[..., :3] = GRADIENT[..., None]
    rgba[..., 3] = 255
    rgba[0, :, 3] = 0  # a transparent row
    iio.imwrite(tmp_path / "c.png", rgba)
    tri = read_image_map(tmp_path / "c.png", 0.1, mode="trinary")
    sca = read_image_map(tmp_path / "c.png", 0.1, mode="scale")
    np.testing.assert_array_equal(tri.occupied, expected_occupied(rgba.astype(float).mean(axis=2)))
    np.testing.assert_array_equal(sca.occupied, expected_occupied(GRADIENT))


def test_16bit_png_uses_65535_as_white(tmp_path):
    v16 = GRADIENT.astype(np.uint16) * 257
    iio.imwrite(tmp_path / "g16.png", v16)
    grid = read_image_map(tmp_path / "g16.png", 0.1)
    np.testing.assert_array_equal(grid.occupied, expected_occupied(GRADIENT))


def test_16bit_pgm_uses_65535_as_white(tmp_path):
    v16 = GRADIENT.astype(">u2") * 257
    (tmp_path / "g16.pgm").write_bytes(b"P5\n16 16\n65535\n" + v16.tobytes())
    grid = read_image_map(tmp_path / "g16.pgm", 0.1)
    np.testing.assert_array_equal(grid.occupied, expected_occupied(GRADIENT))


def gif_or_tiff_block():
    img = np.full((30, 50), 254, np.uint8)
    img[5:10, 20:30] = 0
    return img


@pytest.mark.parametrize("suffix", ["tif", "bmp", "webp", "pgm"])
def test_other_single_image_formats(tmp_path, suffix):
    from PIL import Image

    img = gif_or_tiff_block()
    Image.fromarray(img).save(tmp_path / f"one.{suffix}", **({"lossless": True}
                                                           if suffix == "webp" else {}))
    grid = read_image_map(tmp_path / f"one.{suffix}", 0.1)
    np.testing.assert_array_equal(grid.occupied, expected_occupied(img))


def test_single_frame_gif(tmp_path):
    from PIL import Image

    img = gif_or_tiff_block()
    Image.fromarray(img).save(tmp_path / "one.gif")
    grid = read_image_map(tmp_path / "one.gif", 0.1)
    np.testing.assert_array_equal(grid.occupied, expected_occupied(img))


def test_multi_page_tiff_not_misread(tmp_path):
    from PIL import Image

    from rrtdrive.types import InputError

    img = gif_or_tiff_block()
    Image.fromarray(img).save(tmp_path / "multi.tif", save_all=True,
                              append_images=[Image.fromarray(255 - img)])
    try:
        grid = read_image_map(tmp_path / "multi.tif", 0.1)
    except InputError as exc:
        assert "tif" in str(exc).lower() or "page" in str(exc) or "frame" in str(exc)
        return
    np.testing.assert_array_equal(grid.occupied, expected_occupied(img))


def test_yaml_resolution_in_scientific_notation(tmp_path):
    iio.imwrite(tmp_path / "g.pgm", GRADIENT)
    write_yaml(tmp_path / "g.yaml", "g.pgm", res="5e-2")
    assert read_ros_map(tmp_path / "g.yaml").resolution == 0.05


def test_rotated_origin_refused_full_turn_accepted(lot, capsys):
    d, _ = lot
    common = ["--start", "-4,10,0", "--goal", "30,27,0", "--out", d / "r.json"]
    write_yaml(d / "rot.yaml", "lot.png", origin="[-10.0, 5.0, 0.3]")
    code, _, err = run(capsys, "maps", "--import", d / "rot.yaml", *common)
    assert code == 2
    line = one_error_line(err)
    assert "origin" in line and "rotated" in line
    assert not (d / "r.json").exists()
    write_yaml(d / "turn.yaml", "lot.png", origin=f"[-10.0, 5.0, {2 * math.pi!r}]")
    code, _, err = run(capsys, "maps", "--import", d / "turn.yaml", *common)
    assert code == 0, err


@pytest.mark.parametrize("field, yaml_text", [
    ("resolution", "image: lot.png\nresolution: 0\norigin: [0, 0, 0]\n"),
    ("resolution", "image: lot.png\nresolution: .nan\norigin: [0, 0, 0]\n"),
    ("resolution", "image: lot.png\nresolution: 'fine'\norigin: [0, 0, 0]\n"),
    ("origin", "image: lot.png\nresolution: 0.5\norigin: [.inf, 0, 0]\n"),
    ("origin", "image: lot.png\nresolution: 0.5\norigin: ['x', 0, 0]\n"),
    ("origin", "image: lot.png\nresolution: 0.5\norigin: 5\n"),
    ("origin", "image: lot.png\nresolution: 0.5\n"),
    ("image", "resolution: 0.5\norigin: [0, 0, 0]\n"),
    ("image", "image: nope.png\nresolution: 0.5\norigin: [0, 0, 0]\n"),
    ("negate", "image: lot.png\nresolution: 0.5\norigin: [0, 0, 0]\nnegate: 2\n"),
    ("mode", "image: lot.png\nresolution: 0.5\norigin: [0, 0, 0]\nmode: raw\n"),
    ("occupied_thresh", "image: lot.png\nresolution: 0.5\norigin: [0, 0, 0]\n"
                        "occupied_thresh: .nan\n"),
    ("free_thresh", "image: lot.png\nresolution: 0.5\norigin: [0, 0, 0]\n"
                    "occupied_thresh: 0.2\nfree_thresh: 0.5\n"),
])
def test_bad_yaml_field_one_error_naming_it(lot, capsys, field, yaml_text):
    d, _ = lot
    (d / "bad.yaml").write_text(yaml_text)
    code, _, err = run(capsys, "maps", "--import", d / "bad.yaml", "--start", "-4,10,0",
                       "--goal", "30,27,0", "--out", d / "bad.json")
    assert code == 2
    assert one_error_line(err).startswith(f"rrtdrive maps: error: {field}:")
    assert not (d / "bad.json").exists()


@pytest.mark.parametrize("flags, field", [
    ([], "--resolution"),
    (["--resolution", "0"], "--resolution"),
    (["--resolution", "0.5", "--origin", "nan,0"], "--origin"),
    (["--resolution", "0.5", "--origin", "1,2,3"], "--origin"),
    (["--resolution", "0.5", "--despeckle", "-1"], "--despeckle"),
    (["--resolution", "0.5", "--name", ""], "--name"),
    (["--resolution", "0.5", "--start", "1,1"], "--start"),
])
def test_bad_image_flags_one_error(lot, capsys, flags, field):
    d, _ = lot
    base = {"--start": "4,5,0", "--goal": "40,20,0", "--out": str(d / "x.json")}
    argv = ["maps", "--import", d / "lot.png"] + flags
    for flag, value in base.items():
        if flag not in flags:
            argv += [flag, value]
    code, _, err = run(capsys, *argv)
    assert code == 2
    assert field in one_error_line(err)


def own_components(occ):
    rows, cols = occ.shape
    seen = np.zeros_like(occ)
    groups = []
    for r0, c0 in zip(*np.nonzero(occ), strict=True):
        if seen[r0, c0]:
            continue
        stack, cells = [(r0, c0)], []
        seen[r0, c0] = True
        while stack:
            r, c = stack.pop()
            cells.append((r, c))
            for dr in (-1, 0, 1):
                for dc in (-1, 0, 1):
                    rr, cc = r + dr, c + dc
                    if 0 <= rr < rows and 0 <= cc < cols and occ[rr, cc] and not seen[rr, cc]:
                        seen[rr, cc] = True
                        stack.append((rr, cc))
        groups.append(cells)
    return groups


def test_despeckle_matches_own_connected_components(tmp_path, capsys):
    rng = np.random.default_rng(7)
    img = np.full((50, 80), 255, np.uint8)
    noise = rng.random(img.shape) < 0.06
    noise[10:40, 0:30] = False  # room for the car
    img[noise] = 0
    img[45:47, 50:70] = 0  # a wall, kept
    iio.imwrite(tmp_path / "n.png", img)
    n = 2
    code, out, err = run(capsys, "maps", "--import", tmp_path / "n.png", "--resolution", "0.5",
                         "--despeckle", n, "--start", "3,12,0", "--goal", "8,14,0",
                         "--out", tmp_path / "n.json")
    assert code == 0, err
    mask = img < 128
    groups = [g for g in own_components(mask) if len(g) <= n]
    for g in groups:
        for r, c in g:
            mask[r, c] = False
    assert f"({len(groups)} specks of <= {n} cells dropped: {sum(map(len, groups))} cells)" in out
    got = load_map(tmp_path / "n.json").obstacle_union()
    assert got.symmetric_difference(cells_union(mask, 0.5, 0.0, 0.0)).area < 1e-9


def test_unknown_hint_when_pose_lands_on_grey(lot, capsys):
    d, _ = lot
    # The goal sits on the 205 (unknown) patch at x 25..26, y 31..32.5.
    code, _, err = run(capsys, "maps", "--import", d / "lot.yaml", "--start", "-4,10,0",
                       "--goal", "24,31,0", "--out", d / "h.json")
    assert code == 2
    line = one_error_line(err)
    assert "--goal" in line and "--unknown-free" in line


def test_every_imported_map_plans_verifies_and_simulates(lot, capsys):
    d, _ = lot
    out_json = d / "lot.json"
    code, _, err = run(capsys, "maps", "--import", d / "lot.yaml", "--start", "-4,10,0",
                       "--goal", "30,27,0", "--out", out_json, "--despeckle", "1")
    assert code == 0, err
    plan = d / "plan.json"
    code, _, err = run(capsys, "plan", out_json, "--json", plan)
    assert code == 0, err
    code, out, err = run(capsys, "verify", plan, out_json)
    assert code == 0, out + err
    sim = d / "sim.json"
    code, _, err = run(capsys, "simulate", out_json, "--json", sim)
    assert code == 0, err
    result = json.loads(sim.read_text())
    assert result["success"] and not result["collision_footprint"]


@pytest.mark.parametrize("origin", [(0.0, 0.0), (500000.0, 400000.0), (-999000.0, 999000.0)])
def test_imported_map_far_from_origin_plans_the_translated_path(lot, capsys, origin):
    d, _ = lot
    ox, oy = origin
    out_json = d / "far.json"
    code, _, err = run(capsys, "maps", "--import", d / "lot.png", "--resolution", "0.5",
                       f"--origin={ox!r},{oy!r}", "--start", f"{ox + 6!r},{oy + 5!r},0",
                       "--goal", f"{ox + 40!r},{oy + 22!r},0", "--out", out_json,
                       "--despeckle", "1")
    assert code == 0, err
    plan = d / "far_plan.json"
    code, _, err = run(capsys, "plan", out_json, "--json", plan)
    assert code == 0, err
    path = np.array(json.loads(plan.read_text())["path"], dtype=float)[:, :3]
    path[:, 0] -= ox
    path[:, 1] -= oy
    code, out, _ = run(capsys, "verify", plan, out_json)
    assert code == 0, out
    # Same image, same relative query: the same path up to rounding.
    code, _, err = run(capsys, "maps", "--import", d / "lot.png", "--resolution", "0.5",
                       "--start", "6,5,0", "--goal", "40,22,0", "--out", d / "near.json",
                       "--despeckle", "1")
    assert code == 0, err
    code, _, err = run(capsys, "plan", d / "near.json", "--json", d / "near_plan.json")
    assert code == 0, err
    near = np.array(json.loads((d / "near_plan.json").read_text())["path"], dtype=float)[:, :3]
    assert path.shape == near.shape
    np.testing.assert_allclose(path, near, atol=1e-6)


# ----------------------------------------------------------------------------- maps / --export


def test_maps_lists_every_builtin(capsys):
    code, out, _ = run(capsys, "maps")
    assert code == 0
    for name in BUILTIN_MAPS:
        m = builtin_map(name)
        line = next(ln for ln in out.splitlines() if ln.split()[0] == name)
        assert f"{len(m.obstacles)} obstacles" in line


def test_export_round_trip_equal_maps(tmp_path, capsys):
    code, _, err = run(capsys, "maps", "--export", tmp_path / "ex")
    assert code == 0, err
    for name in BUILTIN_MAPS:
        m, back = builtin_map(name), load_map(tmp_path / "ex" / f"{name}.json")
        assert (back.name, back.bounds, back.start, back.goal) == (m.name, m.bounds, m.start,
                                                                  m.goal)
        assert back.obstacles == m.obstacles


@pytest.mark.parametrize("name, flags", [("narrow_gap", []), ("garage", []),
                                         ("kerbside", ["--reverse"])])
def test_export_then_plan_gives_same_plan(tmp_path, capsys, name, flags):
    assert run(capsys, "maps", "--export", tmp_path)[0] == 0
    plans = []
    for spec, out in ((name, "b.json"), (tmp_path / f"{name}.json", "f.json")):
        code, _, err = run(capsys, "plan", spec, *flags, "--json", tmp_path / out)
        assert code == 0, err
        plans.append(json.loads((tmp_path / out).read_text()))
    assert plans[0]["path"] == plans[1]["path"]
    assert plans[0]["length_m"] == plans[1]["length_m"]


def test_export_into_a_file_refused(tmp_path, capsys):
    (tmp_path / "f").write_text("x")
    code, _, err = run(capsys, "maps", "--export", tmp_path / "f")
    assert code == 2
    assert "--export" in one_error_line(err)


# ----------------------------------------------------------------------------- JSON map format

BASE = {"name": "t", "bounds": [0, 0, 50, 30],
        "obstacles": [{"center": [25, 15], "size": [4, 12], "yaw": 0.3}],
        "start": [5, 5, 0], "goal": [40, 25, 0]}


def mutated(path, literal):
    data = json.loads(json.dumps(BASE))
    node = data
    for key in path[:-1]:
        node = node[key]
    node[path[-1]] = "@@"
    return json.dumps(data).replace('"@@"', literal)


FIELDS = [(("bounds", 0), "bounds"), (("bounds", 3), "bounds"),
          (("obstacles", 0, "center", 1), "obstacles[0].center"),
          (("obstacles", 0, "size", 0), "obstacles[0].size"),
          (("obstacles", 0, "yaw"), "obstacles[0].yaw"),
          (("start", 0), "start"), (("start", 2), "start"), (("goal", 2), "goal"),
          (("name",), "name")]


LITERALS = ["NaN", "Infinity", "-Infinity", '"5"', "null", "1e400"]


@pytest.mark.parametrize("path, field, literal", [
    (p, f, lit) for p, f in FIELDS for lit in LITERALS if not (p == ("name",) and lit == '"5"')
])
def test_bad_number_one_error_naming_field(tmp_path, capsys, path, field, literal):
    (tmp_path / "m.json").write_text(mutated(path, literal))
    code, _, err = run(capsys, "plan", tmp_path / "m.json")
    assert code == 2
    assert one_error_line(err).startswith(f"rrtdrive plan: error: {field}:")


@pytest.mark.parametrize("text", [
    json.dumps(BASE)[:-1] + ', "name": "u"}',
    json.dumps(BASE).replace('"yaw": 0.3', '"yaw": 0.3, "yaw": 0.1'),
])
def test_duplicate_keys_refused(tmp_path, capsys, text):
    (tmp_path / "m.json").write_text(text)
    code, _, err = run(capsys, "plan", tmp_path / "m.json")
    assert code == 2
    assert "twice" in one_error_line(err)


def test_unicode_name_and_path_round_trip(tmp_path, capsys):
    data = dict(BASE, name="Parkplatz Ü 駐車場 🚗")
    f = tmp_path / "地図.json"
    f.write_text(json.dumps(data, ensure_ascii=False), encoding="utf-8")
    code, out, err = run(capsys, "plan", f, "--json", tmp_path / "p.json")
    assert code == 0, err
    assert out.startswith("Parkplatz Ü 駐車場 🚗:")
    assert json.loads((tmp_path / "p.json").read_text())["map"] == data["name"]
    code, out, _ = run(capsys, "verify", tmp_path / "p.json", f)
    assert code == 0, out


def rectangle(center, size, yaw):
    return affinity.translate(
        affinity.rotate(box(-size[0] / 2, -size[1] / 2, size[0] / 2, size[1] / 2), yaw,
                        origin=(0, 0), use_radians=True), *center)


def test_rotated_obstacles_match_shapely():
    rng = np.random.default_rng(11)
    obstacles = [{"center": [float(x), float(y)], "size": [float(a), float(b)], "yaw": float(t)}
                 for x, y, a, b, t in zip(rng.uniform(10, 40, 12), rng.uniform(10, 20, 12),
                                          rng.uniform(0.1, 6, 12), rng.uniform(0.1, 3, 12),
                                          rng.uniform(-4, 4, 12), strict=True)]
    from rrtdrive.maps import map_from_json

    m = map_from_json(dict(BASE, obstacles=obstacles, start=[5, 3, 0], goal=[44, 27, 0]))
    for o, spec in zip(m.obstacles, obstacles, strict=True):
        want = rectangle(spec["center"], spec["size"], spec["yaw"])
        assert o.polygon().symmetric_difference(want).area < 1e-9
    union = shapely.union_all([rectangle(s["center"], s["size"], s["yaw"]) for s in obstacles])
    assert m.obstacle_union().symmetric_difference(union).area < 1e-9


@pytest.mark.parametrize("gap, ok", [(0.03, True), (-0.03, False)])
def test_verify_against_rotated_obstacle_is_exact(tmp_path, capsys, gap, ok):
    """A straight drive at y = 10 past a yawed rectangle 3 cm clear of / into the body."""
    yaw, size = 0.7, (6.0, 2.0)
    lowest = rectangle((0, 0), size, yaw).bounds[1]
    centre = (22.0, 10.9 + gap - lowest)  # body's top edge is y = 10 + 0.9
    body = box(5 - 0.895, 9.1, 40 + 3.405, 10.9)
    assert (body.distance(rectangle(centre, size, yaw)) > 0.02) is ok  # the set-up itself
    m = dict(BASE, obstacles=[{"center": list(centre), "size": list(size), "yaw": yaw}],
             start=[5, 10, 0], goal=[40, 10, 0])
    (tmp_path / "m.json").write_text(json.dumps(m))
    rows = [[float(x), 10.0, 0.0] for x in np.linspace(5, 40, 351)]
    (tmp_path / "p.json").write_text(json.dumps({"path": rows}))
    code, out, _ = run(capsys, "verify", tmp_path / "p.json", tmp_path / "m.json")
    assert (code == 0) is ok, out
    if not ok:
        assert "obstacle 0" in out


def test_obstacles_touching_overlapping_and_outside_bounds(tmp_path, capsys):
    m = dict(BASE, obstacles=[
        {"center": [25, 0], "size": [10, 4]},  # straddles the lower edge
        {"center": [50, 15], "size": [2, 40]},  # straddles the right edge, beyond both ends
        {"center": [-10, -10], "size": [1, 1]},  # wholly outside
        {"center": [25, 30.5], "size": [60, 1]},  # touches the top edge from outside
        {"center": [30, 20], "size": [1e-6, 1e-6]},  # tiny
    ], start=[5, 10, 0], goal=[40, 20, 0])
    (tmp_path / "m.json").write_text(json.dumps(m))
    code, _, err = run(capsys, "plan", tmp_path / "m.json", "--json", tmp_path / "p.json")
    assert code == 0, err
    assert "obstacles[2]" in err and "obstacles[3]" in err and "obstacles[0]" not in err
    code, out, _ = run(capsys, "verify", tmp_path / "p.json", tmp_path / "m.json")
    assert code == 0, out


@pytest.mark.parametrize("offset", [1e5, 1e8, -1e8])
def test_huge_coordinates_plan_the_translated_path(tmp_path, capsys, offset):
    def shifted(off):
        return {"name": "off", "bounds": [off, off, off + 50, off + 30],
                "obstacles": [{"center": [off + 25, off + 15], "size": [4, 12], "yaw": 0.3}],
                "start": [off + 5, off + 5, 0], "goal": [off + 40, off + 25, 0]}

    lengths = []
    for off, name in ((0.0, "a"), (offset, "b")):
        (tmp_path / f"{name}.json").write_text(json.dumps(shifted(off)))
        code, _, err = run(capsys, "plan", tmp_path / f"{name}.json", "--json",
                           tmp_path / f"{name}p.json")
        assert code == 0, err
        lengths.append(json.loads((tmp_path / f"{name}p.json").read_text())["length_m"])
        code, out, _ = run(capsys, "verify", tmp_path / f"{name}p.json", tmp_path / f"{name}.json")
        assert code == 0, out
    assert lengths[1] == pytest.approx(lengths[0], abs=1e-3)


def test_bounds_beyond_max_coordinate_refused(tmp_path, capsys):
    m = {"name": "far", "bounds": [2e9, 2e9, 2e9 + 50, 2e9 + 30], "obstacles": [],
         "start": [2e9 + 5, 2e9 + 5, 0], "goal": [2e9 + 40, 2e9 + 25, 0]}
    (tmp_path / "m.json").write_text(json.dumps(m))
    code, _, err = run(capsys, "plan", tmp_path / "m.json")
    assert code == 2
    assert one_error_line(err).startswith("rrtdrive plan: error: bounds:")


def test_verify_survives_obstacle_far_outside(tmp_path, capsys):
    m = dict(BASE, obstacles=[{"center": [1e200, 1e200], "size": [1, 1]}])
    (tmp_path / "m.json").write_text(json.dumps(m))
    code, _, err = run(capsys, "plan", tmp_path / "m.json", "--json", tmp_path / "p.json")
    assert code == 0, err
    assert "obstacles[0]" in err  # warned about: wholly outside
    code, out, err = run(capsys, "verify", tmp_path / "p.json", tmp_path / "m.json")
    assert code == 0, out + err
