"""Audit s51: a systematic bad-input sweep of every ``rrtdrive`` subcommand.

A demanding user who mistypes: each numeric option gets negative, zero, nan, inf, -inf,
1e400, '', 'abc' and '1,5'; each file argument a missing file, a folder, an empty file,
random bytes, a JSON array, valid JSON of the wrong kind, a UTF-8 BOM and mode 000;
each enumeration a near miss; and options that contradict each other. The standard
(SPEC §5 and the subcommands' --help): exit 2, one error line on stderr naming the option
or field, no traceback, nothing on stdout, no output file created or touched.

The cases run in-process (``rrtdrive.cli.main``: argparse errors raise ``SystemExit(2)``,
the commands' own return 2), which is what ``python -m rrtdrive`` runs; one subprocess
checks the top-level --help. The numeric options swept are checked against each
subcommand's --help, so an option added later must join the sweep.
"""

from __future__ import annotations

import json
import os
import re
import subprocess
import sys
from pathlib import Path

import pytest

from rrtdrive.cli import main

SUBCOMMANDS = ("plan", "maps", "verify", "simulate", "bench")

BAD_VALUES = ("-1", "0", "nan", "inf", "-inf", "1e400", "", "abc", "1,5")

# Metavars the --help pages use for a number (--density D also takes low/default/high).
NUMERIC_METAVARS = ("N", "M", "S", "HZ", "FPS", "RAD_PER_M", "V", "D")

# Every numeric option of every subcommand, with the options where 0 is a valid value.
NUMERIC = {
    "plan": ("--seed", "--step", "--max-iterations", "--max-time", "--resolution"),
    "maps": ("--resolution", "--despeckle"),
    "verify": ("--max-sharpness", "--clearance"),
    "simulate": (
        "--seed", "--frequency", "--max-time", "--resolution", "--plan-time",
        "--max-iterations", "--oncoming", "--density", "--lead-speed", "--replan-rate",
        "--video-fps", "--video-stride",
    ),
    "bench": ("--seeds", "--workers", "--max-time", "--max-iterations", "--run-timeout",
              "--retries"),
}
ZERO_IS_VALID = {
    ("plan", "--seed"), ("simulate", "--seed"), ("simulate", "--oncoming"),
    ("verify", "--clearance"), ("maps", "--despeckle"), ("bench", "--retries"),
}

# Output files every case names; none may exist after bad input.
OUTPUTS = ("o.json", "o.png", "o.csv", "o.mp4", "bout")


def _cli(argv: list[str], capsys: pytest.CaptureFixture[str]) -> tuple[int, str, str]:
    capsys.readouterr()
    try:
        code = main(argv)
    except SystemExit as exc:  # argparse's errors and --help
        code = exc.code if isinstance(exc.code, int) else 1
    out, err = capsys.readouterr()
    return code, out, err


def _assert_bad_input(code: int, out: str, err: str, names: tuple[str, ...], where: Path) -> None:
    assert code == 2, (code, err)
    assert "Traceback" not in err, err
    lines = [line for line in err.splitlines() if line.strip()]
    assert len(lines) == 1 and ": error: " in lines[0], err  # one clear line
    assert any(name in lines[0] for name in names), (names, err)
    assert out == "", out  # stdout is not polluted
    left = [name for name in OUTPUTS if (where / name).exists()]
    assert not left, (left, err)


@pytest.fixture(scope="module")
def files(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Path]:
    """A plan, a map, an occupancy image and a ROS .yaml made by the CLI itself."""
    import numpy as np
    from PIL import Image

    d = tmp_path_factory.mktemp("inputs")
    cwd = os.getcwd()
    os.chdir(d)
    try:
        assert main(["maps", "--export", "maps"]) == 0
        assert main(["plan", "narrow_gap", "--json", "plan.json"]) == 0
    finally:
        os.chdir(cwd)
    pixels = np.full((100, 100), 255, np.uint8)
    pixels[40:60, 40:60] = 0
    Image.fromarray(pixels).save(d / "img.png")
    (d / "m.yaml").write_text(
        "image: img.png\nresolution: 0.5\norigin: [0, 0, 0]\nnegate: 0\n"
        "occupied_thresh: 0.65\nfree_thresh: 0.196\n"
    )
    return {
        "plan": d / "plan.json",
        "map": d / "maps" / "narrow_gap.json",
        "img": d / "img.png",
        "yaml": d / "m.yaml",
    }


# ---------------------------------------------------------------- the --help pages


def test_top_level_help_lists_the_subcommands_swept() -> None:
    run = subprocess.run(
        [sys.executable, "-m", "rrtdrive", "--help"], capture_output=True, text=True, timeout=30
    )
    assert run.returncode == 0, run.stderr
    listed = re.findall(r"^    (\w+)\s{2,}", run.stdout, flags=re.M)
    assert tuple(listed) == SUBCOMMANDS, run.stdout


@pytest.mark.parametrize("sub", SUBCOMMANDS)
def test_the_sweep_covers_every_numeric_option_in_help(sub, capsys) -> None:
    code, out, _ = _cli([sub, "--help"], capsys)
    assert code == 0
    usage = out.split("\n\n", 1)[0]
    metavars = "|".join(NUMERIC_METAVARS)
    in_help = set(re.findall(rf"(--[\w-]+) (?:{metavars})\b", usage))
    assert in_help == set(NUMERIC[sub]), in_help ^ set(NUMERIC[sub])


# ---------------------------------------------------------------- numeric options


def _numeric_base(sub: str, opt: str, files: dict[str, Path]) -> list[str]:
    if sub == "plan":
        return ["plan", "narrow_gap", "--max-iterations", "300", "--json", "o.json",
                "--plot", "o.png"]
    if sub == "verify":
        return ["verify", str(files["plan"]), "--json", "o.json", "--plot", "o.png"]
    if sub == "maps":
        return ["maps", "--import", str(files["img"]), "--resolution", "0.5",
                "--start", "5,5,0", "--goal", "45,45,0", "--out", "o.json"]
    if sub == "bench":
        return ["bench", "--maps", "narrow_gap", "--seeds", "1", "--workers", "1",
                "--no-plots", "--quiet", "--max-iterations", "100", "--out", "bout"]
    scenario = {
        "--oncoming": "overtake", "--density": "overtake-traffic",
        "--lead-speed": "overtake-traffic", "--replan-rate": "overtake-traffic",
    }.get(opt, "parking")
    budget = [] if scenario == "overtake-traffic" else ["--max-iterations", "300"]
    return ["simulate", scenario, *budget, "--json", "o.json",
            "--trajectory", "o.csv", "--plot", "o.png", "--video", "o.mp4"]


NUMERIC_CASES = [
    pytest.param(sub, opt, value, id=f"{sub}{opt}={value or 'empty'}")
    for sub, opts in NUMERIC.items()
    for opt in opts
    for value in BAD_VALUES
    if not (value == "0" and (sub, opt) in ZERO_IS_VALID)
]


@pytest.mark.parametrize(("sub", "opt", "value"), NUMERIC_CASES)
def test_a_bad_number_is_one_error_naming_its_option(
    sub, opt, value, files, tmp_path, monkeypatch, capsys
) -> None:
    monkeypatch.chdir(tmp_path)
    argv = _numeric_base(sub, opt, files)
    if opt in argv:
        i = argv.index(opt)
        del argv[i : i + 2]
    code, out, err = _cli([*argv, opt, value], capsys)
    _assert_bad_input(code, out, err, (opt,), tmp_path)


@pytest.mark.parametrize(
    "argv",
    [
        ["plan", "narrow_gap", "--max-time", "-inf"],
        ["verify", "PLAN", "--clearance", "-inf"],
        ["simulate", "overtake-traffic", "--lead-speed", "-inf"],
    ],
    ids=["plan", "verify", "simulate"],
)
def test_a_negative_infinity_is_named_as_the_value_given(argv, files, capsys) -> None:
    argv = [str(files["plan"]) if a == "PLAN" else a for a in argv]
    code, out, err = _cli(argv, capsys)
    assert code == 2 and "Traceback" not in err and out == ""
    assert "'-inf'" in err and "expected one argument" not in err, err


# ---------------------------------------------------------------- file arguments

# (case, argv with IN for the file, its suffix, names the error may give)
FILE_ARGS = {
    "plan MAP": (["plan", "IN", "--max-iterations", "300", "--json", "o.json",
                  "--plot", "o.png"], ".json", ("map",)),
    "verify PLAN": (["verify", "IN", "narrow_gap", "--json", "o.json", "--plot", "o.png"],
                    ".json", ("plan",)),
    "verify MAP": (["verify", "PLANFILE", "IN", "--json", "o.json"], ".json", ("map",)),
    "simulate SCENARIO": (["simulate", "IN", "--max-iterations", "300", "--json", "o.json",
                           "--trajectory", "o.csv"], ".json", ("map", "scenario")),
    "simulate --path": (["simulate", "narrow_gap", "--path", "IN", "--json", "o.json",
                         "--trajectory", "o.csv"], ".json", ("--path",)),
    "maps --vehicle": (["maps", "--import", "IMG", "--resolution", "0.5", "--start", "5,5,0",
                        "--goal", "45,45,0", "--vehicle", "IN", "--out", "o.json"],
                       ".json", ("--vehicle",)),
    "maps --import image": (["maps", "--import", "IN", "--resolution", "0.5",
                             "--start", "5,5,0", "--goal", "45,45,0", "--out", "o.json"],
                            ".png", ("--import",)),
    "maps --import yaml": (["maps", "--import", "IN", "--start", "5,5,0",
                            "--goal", "45,45,0", "--out", "o.json"], ".yaml",
                           ("--import", "in.yaml")),
    "bench --config": (["bench", "--config", "IN", "--maps", "narrow_gap", "--seeds", "1",
                        "--workers", "1", "--no-plots", "--quiet", "--out", "bout"],
                       ".toml", ("--config",)),
    "bench --maps": (["bench", "--maps", "IN", "--seeds", "1", "--workers", "1",
                      "--no-plots", "--quiet", "--out", "bout"], ".json", ("--maps",)),
    "bench --scenarios": (["bench", "--scenarios", "IN", "--seeds", "1", "--workers", "1",
                           "--no-plots", "--quiet", "--out", "bout"], ".json",
                          ("--scenarios",)),
}

# What "valid JSON of the wrong kind" is for each: a plan where a map is read, a map
# where a plan is read, a map (not an image, not TOML) where those are read.
WRONG_KIND = {
    "plan MAP": "plan", "verify MAP": "plan", "simulate SCENARIO": "plan",
    "bench --maps": "plan", "bench --scenarios": "plan",
    "verify PLAN": "map", "simulate --path": "map",
    "maps --import image": "map", "bench --config": "map", "maps --import yaml": "plan",
    "maps --vehicle": "null",
}

FILE_KINDS = ("missing", "folder", "empty", "binary", "array", "wrong-kind", "mode-000")


def _write(kind: str, case: str, path: Path, files: dict[str, Path]) -> None:
    if kind == "missing":
        return
    if kind == "folder":
        path.mkdir()
        return
    if kind == "empty":
        path.write_bytes(b"")
    elif kind == "binary":
        path.write_bytes(bytes(range(256)) * 4 + os.urandom(64))
    elif kind == "array":
        path.write_text("[1, 2, 3]")
    elif kind == "wrong-kind":
        other = WRONG_KIND[case]
        path.write_text("null" if other == "null" else files[other].read_text())
    elif kind == "mode-000":
        path.write_text("[1, 2, 3]")  # unreadable; were it read, still bad input
        path.chmod(0)


@pytest.mark.parametrize(
    ("case", "kind"),
    # An empty TOML file is a valid --config: every setting its default.
    [(c, k) for c in FILE_ARGS for k in FILE_KINDS if (c, k) != ("bench --config", "empty")],
)
def test_a_bad_input_file_is_one_error_naming_its_argument(
    case, kind, files, tmp_path, monkeypatch, capsys
) -> None:
    monkeypatch.chdir(tmp_path)
    argv, suffix, names = FILE_ARGS[case]
    target = tmp_path / f"in{suffix}"
    _write(kind, case, target, files)
    if kind == "mode-000" and os.access(target, os.R_OK):
        pytest.skip("running as root: a mode 000 file is readable anyway")
    subst = {"IN": str(target), "PLANFILE": str(files["plan"]), "IMG": str(files["img"])}
    code, out, err = _cli([subst.get(a, a) for a in argv], capsys)
    _assert_bad_input(code, out, err, names, tmp_path)


@pytest.mark.parametrize(
    ("argv", "key"),
    [
        (["plan", "IN.json", "--max-iterations", "300"], "map"),
        (["verify", "IN.json"], "plan"),
        (["verify", "PLANFILE", "IN.json"], "map"),
        (["maps", "--import", "IMG", "--resolution", "0.5", "--start", "5,5,0",
          "--goal", "45,45,0", "--vehicle", "IN.json", "--out", "o.json"], "vehicle"),
        (["maps", "--import", "IN.yaml", "--start", "5,5,0", "--goal", "45,45,0",
          "--out", "o.json"], "yaml"),
    ],
    ids=["plan MAP", "verify PLAN", "verify MAP", "maps --vehicle", "maps --import yaml"],
)
def test_a_utf8_bom_is_read_as_the_text_it_precedes(
    argv, key, files, tmp_path, monkeypatch, capsys
) -> None:
    """Editors on Windows save JSON/YAML with a BOM: the file still reads."""
    monkeypatch.chdir(tmp_path)
    text = {
        "map": files["map"].read_text(),
        "plan": files["plan"].read_text(),
        "vehicle": json.dumps({"length": 3.0}),
        "yaml": files["yaml"].read_text().replace("img.png", str(files["img"])),
    }[key]
    for name in ("IN.json", "IN.yaml"):
        (tmp_path / name).write_text(text, encoding="utf-8-sig")
    subst = {"PLANFILE": str(files["plan"]), "IMG": str(files["img"])}
    code, _, err = _cli([subst.get(a, a) for a in argv], capsys)
    assert code == 0, err
    if key == "vehicle":
        assert json.loads((tmp_path / "o.json").read_text())["vehicle"]["length"] == 3.0


def test_a_bench_config_with_a_bom_is_read_as_toml(tmp_path, monkeypatch, capsys) -> None:
    """A BOM'd TOML reaches the value check (seeds = 0), not a 'malformed TOML' error."""
    monkeypatch.chdir(tmp_path)
    (tmp_path / "b.toml").write_text('seeds = 0\nmaps = ["narrow_gap"]\n', encoding="utf-8-sig")
    code, out, err = _cli(["bench", "--config", "b.toml", "--out", "bout", "--quiet"], capsys)
    _assert_bad_input(code, out, err, ("seeds",), tmp_path)
    assert "malformed" not in err, err


@pytest.mark.parametrize("sub", ["plan", "verify", "simulate"])
def test_a_plan_given_as_the_map_is_named_as_a_plan(sub, files, tmp_path, capsys) -> None:
    argv = {
        "plan": ["plan", str(files["plan"])],
        "verify": ["verify", str(files["plan"]), str(files["plan"])],
        "simulate": ["simulate", str(files["plan"])],
    }[sub]
    code, out, err = _cli(argv, capsys)
    assert code == 2 and out == "" and "Traceback" not in err
    said = re.sub(r"\[[^\]]*\]", "", err.split(": error: ", 1)[1])  # without the key lists
    assert "plan.json" in said and re.search(r"\bplan\b", said), said


# ---------------------------------------------------------------- nothing half-written


@pytest.mark.parametrize(
    ("argv", "outputs"),
    [
        (["plan", "narow_gap", "--json", "o.json", "--plot", "o.png"], ("o.json", "o.png")),
        (["plan", "narrow_gap", "--planner-option", "smoothing.max_rounds=-1",
          "--json", "o.json", "--plot", "o.png"], ("o.json", "o.png")),
        (["verify", "BADPLAN", "--json", "o.json", "--plot", "o.png"], ("o.json", "o.png")),
        (["simulate", "narrow_gap", "--path", "BADPLAN", "--json", "o.json", "--plot", "o.png",
          "--trajectory", "o.csv", "--video", "o.mp4"], ("o.json", "o.png", "o.csv", "o.mp4")),
        (["simulate", "parking", "--planner-option", "step=abc", "--json", "o.json",
          "--trajectory", "o.csv", "--video", "o.mp4"], ("o.json", "o.csv", "o.mp4")),
        (["maps", "--import", "IMG", "--resolution", "0.5", "--start", "25,25,0",
          "--goal", "45,45,0", "--out", "o.json"], ("o.json",)),
    ],
    ids=["plan map", "plan option", "verify plan", "simulate path", "simulate option",
         "maps start"],
)
def test_bad_input_leaves_existing_outputs_untouched(
    argv, outputs, files, tmp_path, monkeypatch, capsys
) -> None:
    monkeypatch.chdir(tmp_path)
    plan = json.loads(files["plan"].read_text())
    plan["path"][3][0] = float("nan")
    (tmp_path / "bad.json").write_text(json.dumps(plan))
    for name in outputs:
        (tmp_path / name).write_text("KEEP")
    subst = {"BADPLAN": "bad.json", "IMG": str(files["img"])}
    code, out, err = _cli([subst.get(a, a) for a in argv], capsys)
    assert code == 2 and out == "" and "Traceback" not in err, err
    assert {n: (tmp_path / n).read_text() for n in outputs} == dict.fromkeys(outputs, "KEEP")


def test_an_output_naming_the_input_is_refused_before_work(files, tmp_path, capsys) -> None:
    copy = tmp_path / "map.json"
    copy.write_text(files["map"].read_text())
    before = copy.read_text()
    code, out, err = _cli(["plan", str(copy), "--json", str(copy)], capsys)
    assert code == 2 and out == "" and "--json" in err and "MAP" in err, err
    assert copy.read_text() == before


# ---------------------------------------------------------------- names: near misses


NEAR_MISSES = [
    pytest.param(["plan", "narrow_gap", "--planner", "rrt-conect"], "rrt-connect",
                 id="plan --planner"),
    pytest.param(["simulate", "parking", "--planner", "rrt-start"], "rrt-star",
                 id="simulate --planner"),
    pytest.param(["simulate", "parkng"], "parking", id="simulate scenario"),
    pytest.param(["simulate", "narow_gap"], "narrow_gap", id="simulate map name"),
    pytest.param(["bench", "--planners", "rrt-conect", "--maps", "narrow_gap", "--out", "bout"],
                 "rrt-connect", id="bench --planners"),
    pytest.param(["bench", "--scenarios", "parkng", "--out", "bout"], "parking",
                 id="bench --scenarios"),
    pytest.param(["bench", "--controllers", "stanly", "--scenarios", "parking", "--out", "bout"],
                 "stanley", id="bench --controllers"),
    pytest.param(
        ["plan", "narow_gap"], "narrow_gap", id="plan map name",
    ),
    pytest.param(
        ["verify", "PLANFILE", "narow_gap"], "narrow_gap", id="verify map name",
    ),
    pytest.param(
        ["bench", "--maps", "narow_gap", "--out", "bout"], "narrow_gap", id="bench --maps",
    ),
    pytest.param(
        ["simulate", "parking", "--controller", "stanly"], "stanley",
        id="simulate --controller",
    ),
]


@pytest.mark.parametrize(("argv", "right"), NEAR_MISSES)
def test_a_near_miss_name_is_answered_with_the_right_one(
    argv, right, files, tmp_path, monkeypatch, capsys
) -> None:
    monkeypatch.chdir(tmp_path)
    argv = [str(files["plan"]) if a == "PLANFILE" else a for a in argv]
    code, out, err = _cli(argv, capsys)
    assert code == 2 and out == "" and "Traceback" not in err, err
    assert f"did you mean {right!r}?" in err, err
    assert not (tmp_path / "bout").exists()


def test_an_empty_scenario_is_named_as_the_scenario(capsys) -> None:
    code, out, err = _cli(["simulate", ""], capsys)
    assert code == 2 and out == "" and "Traceback" not in err
    assert "scenario" in err.lower() and "parking" in err, err


# ---------------------------------------------------------------- contradictions


CONFLICTS = [
    (["verify", "PLANFILE", "--max-sharpness", "0.3", "--no-sharpness"], "--no-sharpness"),
    (["bench", "--ray", "--no-ray", "--maps", "narrow_gap", "--out", "bout"], "--no-ray"),
    (["bench", "--deterministic", "--max-time", "3", "--maps", "narrow_gap", "--out", "bout"],
     "--max-time"),
    (["bench", "--seed", "3", "--maps", "narrow_gap", "--out", "bout"], "--seeds"),
    (["simulate", "narrow_gap", "--path", "PLANFILE", "--planner", "rrt"], "--planner"),
    (["simulate", "narrow_gap", "--path", "PLANFILE", "--start", "10,20,0"], "--start"),
    (["simulate", "parking", "--path", "PLANFILE"], "--path"),
    (["simulate", "parking", "--deterministic", "--plan-time", "3"], "--plan-time"),
    (["simulate", "parking", "--json", "o.csv", "--trajectory", "o.csv"], "--trajectory"),
    (["simulate", "parking", "--video-fps", "10"], "--video-fps"),
    (["simulate", "parking", "--oncoming", "2"], "--oncoming"),
    (["simulate", "parking", "--density", "5"], "--density"),
    (["simulate", "overtake", "--reverse-in"], "--reverse-in"),
    (["plan", "narrow_gap", "--planner", "rrt", "--disable", "prune"], "--disable"),
    (["plan", "narrow_gap", "--planner", "hybrid-a-star", "--paper-smoothing"],
     "--paper-smoothing"),
    (["plan", "narrow_gap", "--planner-option", "reverse=true"], "--reverse"),
    (["maps", "--export", "ex", "--import", "IMG"], "--export"),
    (["maps", "--out", "o.json"], "--out"),
    (["maps", "--import", "IMG", "--resolution", "0.5", "--out", "o.json"], "--start"),
]


@pytest.mark.parametrize(("argv", "named"), CONFLICTS, ids=[" ".join(c[0][:4]) for c in CONFLICTS])
def test_contradicting_options_are_one_error_naming_one_of_them(
    argv, named, files, tmp_path, monkeypatch, capsys
) -> None:
    monkeypatch.chdir(tmp_path)
    subst = {"PLANFILE": str(files["plan"]), "IMG": str(files["img"])}
    code, out, err = _cli([subst.get(a, a) for a in argv], capsys)
    _assert_bad_input(code, out, err, (named,), tmp_path)
    assert not (tmp_path / "ex").exists()
