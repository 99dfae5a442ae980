"""Audit (session 50) of every output file the CLI and the public writers produce.

For each writer (plan --json/--plot, verify --json/--plot, simulate
--json/--plot/--trajectory/--video, maps --export and --import --out, bench --out, the
Python writers save_map / save_figure / write_text_atomic): names with spaces and
non-ASCII letters, a folder that does not exist, one that cannot be written, a target
that is a folder, overwriting, '-' for stdout, one file named for two outputs, and that
a failure (a full device, a failed rename, SIGTERM) leaves no half-written file and no
temporary file behind. Runs are tiny: the ``overtake`` map (3 obstacles), a fraction of
a second of driving, one seed.
"""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import pytest

from rrtdrive.cli import main
from rrtdrive.maps import builtin_map, load_map, save_map

MAP = "overtake"  # the smallest built-in map: 3 obstacles, plans in milliseconds
DRIVE = ["simulate", MAP, "--max-time", "0.3"]  # six control steps
BENCH = ["bench", "--maps", MAP, "--seeds", "1", "--workers", "1", "--quiet"]
NAME = "out dir é ü 名"  # spaces, accents and a CJK letter


def run(capsys, *argv: str) -> tuple[int, str, str]:
    try:
        code = int(main(list(argv)))
    except SystemExit as exc:  # argparse's own errors
        code = int(exc.code)
    out, err = capsys.readouterr()
    return code, out, err


def one_error_line(code: int, err: str, command: str, *needles: str, expected: int = 2) -> None:
    """One ``rrtdrive COMMAND: error: ...`` line naming ``needles``, no traceback."""
    assert code == expected, err
    assert "Traceback" not in err
    lines = [x for x in err.splitlines() if x.strip() and " video " not in x]  # progress
    assert len(lines) == 1, err
    assert lines[0].startswith(f"rrtdrive {command}: error: "), err
    for needle in needles:
        assert needle in lines[0], err


def temporaries(folder: Path) -> list[str]:
    """Hidden files an atomic writer may leave (``.<stem>.XXXX<suffix>``); bench's lock aside."""
    return sorted(p.name for p in folder.iterdir() if p.name.startswith(".") and p.name != ".lock")


def tree(folder: Path) -> list[str]:
    return sorted(str(p.relative_to(folder)) for p in folder.rglob("*"))


@pytest.fixture(scope="module")
def plan_file(tmp_path_factory) -> Path:
    """A solved plan of the overtake map, for verify."""
    path = tmp_path_factory.mktemp("plan") / "plan.json"
    assert main(["plan", MAP, "--json", str(path)]) == 0
    return path


@pytest.fixture(scope="module")
def image(tmp_path_factory) -> Path:
    """A 30 x 30 m occupancy image (0.1 m a pixel) with one dark square in the middle."""
    import numpy as np
    from PIL import Image

    pixels = np.full((300, 300), 255, np.uint8)
    pixels[140:160, 140:160] = 0
    path = tmp_path_factory.mktemp("img") / "occ é.png"
    Image.fromarray(pixels).save(path)
    return path


def import_argv(image: Path, out: str) -> list[str]:
    return ["maps", "--import", str(image), "--resolution", "0.1", "--start", "5,5,0",
            "--goal", "25,25,0", "--out", out]


@pytest.fixture
def unwritable(tmp_path):
    """A folder this process cannot create files in.

    chmod 555 for a normal user; root ignores mode bits, so then a folder of a read-only
    pseudo file system (/sys refuses new files even to root), or a skip.
    """
    if os.geteuid() != 0:
        folder = tmp_path / "read only"
        folder.mkdir()
        folder.chmod(0o555)
        yield folder
        folder.chmod(0o755)
        return
    for candidate in ("/sys", "/proc/sys"):
        try:
            fd, probe = tempfile.mkstemp(dir=candidate)
        except OSError:
            yield Path(candidate)
            return
        os.close(fd)
        os.unlink(probe)
    pytest.skip("root, and no folder that refuses root's files")


# --------------------------------------------------------------------- names with spaces


def test_plan_and_verify_write_names_with_spaces_and_unicode(capsys, tmp_path):
    folder = tmp_path / NAME
    folder.mkdir()
    plan, fig = folder / "plan é.json", folder / "fig ü.svg"
    code, _, err = run(capsys, "plan", MAP, "--json", str(plan), "--plot", str(fig))
    assert code == 0, err
    assert json.loads(plan.read_text("utf-8"))["status"] == "solved"
    assert fig.read_text("utf-8").lstrip().startswith("<?xml")
    check, cfig = folder / "check 名.json", folder / "check ü.png"
    code, _, err = run(capsys, "verify", str(plan), "--json", str(check), "--plot", str(cfig))
    assert code == 0, err
    assert json.loads(check.read_text("utf-8"))["ok"] is True
    assert cfig.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert temporaries(folder) == []


def test_simulate_writes_all_four_outputs_with_spaces_and_unicode(capsys, tmp_path):
    folder = tmp_path / NAME
    folder.mkdir()
    outs = {"--json": "m é.json", "--plot": "p ü.png", "--trajectory": "t 名.csv",
            "--video": "v ö.mp4"}
    argv = [a for flag, name in outs.items() for a in (flag, str(folder / name))]
    code, _, err = run(capsys, *DRIVE, *argv)
    assert code in (0, 1), err  # 0.3 s does not reach the goal: exit 1, not a write error
    assert "error" not in err, err
    data = json.loads((folder / outs["--json"]).read_text("utf-8"))
    assert data["video"] == str(folder / outs["--video"]) and data["steps"] == 6
    assert data["plot"] == str(folder / outs["--plot"])
    assert len((folder / outs["--trajectory"]).read_text("utf-8").splitlines()) == 1 + 7
    assert (folder / outs["--video"]).read_bytes()[4:8] == b"ftyp"
    assert sorted(p.name for p in folder.iterdir()) == sorted(outs.values())


def test_maps_export_and_import_write_names_with_spaces_and_unicode(capsys, tmp_path, image):
    folder = tmp_path / NAME / "new é"  # two levels that do not exist yet: created
    code, out, err = run(capsys, "maps", "--export", str(folder))
    assert code == 0, err
    assert f"-> {folder / (MAP + '.json')}" in out
    assert load_map(folder / f"{MAP}.json").obstacles == builtin_map(MAP).obstacles
    target = tmp_path / NAME / "imported 名.json"
    code, out, err = run(capsys, *import_argv(image, str(target)))
    assert code == 0, err
    assert load_map(target).name == "occ é"
    assert temporaries(folder) == [] and temporaries(tmp_path / NAME) == []


def test_bench_writes_into_a_new_folder_with_spaces_and_unicode(capsys, tmp_path):
    out = tmp_path / NAME / "bench ü"  # missing, two levels: created (bench.md)
    code, stdout, err = run(capsys, *BENCH, "--out", str(out))
    assert code == 0, err
    names = {p.name for p in out.iterdir()}
    assert {"runs.jsonl", "bench_config.json", "summary.md", "summary.csv",
            "success.png"} <= names
    assert len((out / "runs.jsonl").read_text("utf-8").splitlines()) == 1
    assert f"results: {out}/runs.jsonl" in stdout
    assert temporaries(out) == []


# --------------------------------------------------------------------- a missing folder


SINGLE_FILE_OUTPUTS = [
    # (argv before the flag, the flag, the file name the flag takes)
    (["plan", MAP], "--json", "x.json"),
    (["plan", MAP], "--plot", "x.png"),
    (["verify", "{plan}"], "--json", "x.json"),
    (["verify", "{plan}"], "--plot", "x.pdf"),
    (DRIVE, "--json", "x.json"),
    (DRIVE, "--plot", "x.svg"),
    (DRIVE, "--trajectory", "x.csv"),
    (DRIVE, "--video", "x.mp4"),
]
IDS = [f"{argv[0]} {flag}" for argv, flag, _ in SINGLE_FILE_OUTPUTS]


def _argv(argv: list[str], plan_file: Path) -> list[str]:
    return [a.format(plan=plan_file) for a in argv]


@pytest.mark.parametrize("argv, flag, name", SINGLE_FILE_OUTPUTS, ids=IDS)
def test_a_file_in_a_missing_folder_is_refused_before_any_work(capsys, tmp_path, plan_file,
                                                               argv, flag, name):
    # Consistent across commands: a file's folder is not created (only maps --export's
    # and bench --out's folders are); one line naming the flag and the folder, exit 2.
    target = tmp_path / "missing" / name
    code, out, err = run(capsys, *_argv(argv, plan_file), flag, str(target))
    one_error_line(code, err, argv[0], f"{flag}: folder", "does not exist")
    assert out == "" and tree(tmp_path) == []


def test_maps_import_out_in_a_missing_folder(capsys, tmp_path, image):
    code, _, err = run(capsys, *import_argv(image, str(tmp_path / "missing" / "m.json")))
    one_error_line(code, err, "maps", "--out: folder", "does not exist")
    assert tree(tmp_path) == []


# --------------------------------------------------------------------- an unwritable folder


@pytest.mark.parametrize("argv, flag, name", SINGLE_FILE_OUTPUTS, ids=IDS)
def test_a_file_in_an_unwritable_folder_is_one_line_exit_2(capsys, unwritable, plan_file,
                                                           argv, flag, name):
    code, out, err = run(capsys, *_argv(argv, plan_file), flag, str(unwritable / name))
    one_error_line(code, err, argv[0], f"{flag}: cannot write into folder", str(unwritable))
    assert out == ""


@pytest.mark.parametrize("where", ["the folder", "a new folder in it"])
def test_maps_export_and_bench_into_an_unwritable_folder(capsys, unwritable, where):
    out = unwritable if where == "the folder" else unwritable / "new"
    code, _, err = run(capsys, "maps", "--export", str(out))
    one_error_line(code, err, "maps", "--export: cannot", str(unwritable))
    code, _, err = run(capsys, *BENCH, "--out", str(out))
    one_error_line(code, err, "bench", "--out: cannot", str(unwritable))


def test_maps_import_into_an_unwritable_folder(capsys, unwritable, image):
    code, _, err = run(capsys, *import_argv(image, str(unwritable / "m.json")))
    one_error_line(code, err, "maps", "--out: cannot write into folder")


# --------------------------------------------------------------------- a folder as target


@pytest.mark.parametrize("argv, flag, name", SINGLE_FILE_OUTPUTS, ids=IDS)
def test_a_target_that_is_a_folder_is_refused(capsys, tmp_path, plan_file, argv, flag, name):
    (tmp_path / name).mkdir()
    (tmp_path / name / "keep").write_text("mine")
    code, _, err = run(capsys, *_argv(argv, plan_file), flag, str(tmp_path / name))
    one_error_line(code, err, argv[0], flag, "is a folder")
    assert tree(tmp_path) == [name, f"{name}/keep"]


def test_folder_outputs_given_a_file_are_refused(capsys, tmp_path, image):
    file = tmp_path / "afile"
    file.write_text("mine")
    code, _, err = run(capsys, "maps", "--export", str(file))
    one_error_line(code, err, "maps", "--export:", "is a file")
    code, _, err = run(capsys, *BENCH, "--out", str(file))
    one_error_line(code, err, "bench", "--out:", "not a folder")
    (tmp_path / "d.json").mkdir()
    code, _, err = run(capsys, *import_argv(image, str(tmp_path / "d.json")))
    one_error_line(code, err, "maps", "--out:", "is a folder")
    assert file.read_text() == "mine" and tree(tmp_path) == ["afile", "d.json"]


# --------------------------------------------------------------------- overwriting


def test_overwriting_replaces_the_whole_file_and_keeps_its_mode(capsys, tmp_path, image):
    # A longer old file: an in-place write without truncation would leave its tail.
    plan = tmp_path / "plan.json"
    plan.write_text("x" * 200_000)
    plan.chmod(0o640)
    code, _, err = run(capsys, "plan", MAP, "--json", str(plan))
    assert code == 0, err
    assert json.loads(plan.read_text())["status"] == "solved"
    assert plan.stat().st_mode & 0o777 == 0o640
    exported = tmp_path / "maps"
    exported.mkdir()
    (exported / f"{MAP}.json").write_text("old " * 50_000)
    assert run(capsys, "maps", "--export", str(exported))[0] == 0
    assert load_map(exported / f"{MAP}.json").name == MAP
    target = tmp_path / "imported.json"
    target.write_text("old " * 50_000)
    assert run(capsys, *import_argv(image, str(target)))[0] == 0
    assert load_map(target).name == "occ é"
    assert temporaries(tmp_path) == [] and temporaries(exported) == []


# --------------------------------------------------------------------- '-' for stdout


@pytest.mark.parametrize("argv", [["plan", MAP], ["verify", "{plan}"], DRIVE],
                         ids=["plan", "verify", "simulate"])
def test_json_dash_is_the_json_alone_on_stdout(capsys, tmp_path, plan_file, argv):
    code, out, err = run(capsys, *_argv(argv, plan_file), "--json", "-")
    assert code in (0, 1), err
    assert isinstance(json.loads(out), dict)  # nothing but the JSON on stdout
    assert err.strip()  # the human summary went to stderr
    assert tree(tmp_path) == []  # no file called '-'


@pytest.mark.parametrize(
    "argv",
    [["plan", MAP, "--plot", "-"], ["verify", "{plan}", "--plot", "-"],
     [*DRIVE, "--plot", "-"], [*DRIVE, "--trajectory", "-"], [*DRIVE, "--video", "-"]],
    ids=["plan --plot", "verify --plot", "simulate --plot", "simulate --trajectory",
         "simulate --video"],
)
def test_dash_is_refused_where_it_is_not_stdout(capsys, tmp_path, plan_file, argv,
                                                monkeypatch):
    monkeypatch.chdir(tmp_path)
    code, _, err = run(capsys, *_argv(argv, plan_file))
    one_error_line(code, err, argv[0], argv[-2])
    assert tree(tmp_path) == []


def test_maps_import_refuses_dash(capsys, tmp_path, image, monkeypatch):
    monkeypatch.chdir(tmp_path)
    code, _, err = run(capsys, *import_argv(image, "-"))
    one_error_line(code, err, "maps", "--out: needs a file name")
    assert tree(tmp_path) == []


# --------------------------------------------------------------------- one file, two outputs


@pytest.mark.parametrize(
    "argv, first, second",
    [
        (["plan", MAP], "--json", "--plot"),
        (["verify", "{plan}"], "--json", "--plot"),
        (DRIVE, "--json", "--trajectory"),
        (DRIVE, "--json", "--video"),
        (DRIVE, "--json", "--plot"),
    ],
    ids=["plan", "verify", "simulate csv", "simulate mp4", "simulate png"],
)
def test_one_file_for_two_outputs_is_refused_by_any_spelling(capsys, tmp_path, plan_file,
                                                             argv, first, second):
    suffix = {"--plot": ".png", "--trajectory": ".csv", "--video": ".mp4"}[second]
    name = f"same{suffix}"
    (tmp_path / "sub").mkdir()
    spelt = str(tmp_path / "sub" / ".." / name)  # the same file, another spelling
    code, _, err = run(capsys, *_argv(argv, plan_file), first, str(tmp_path / name),
                       second, spelt)
    one_error_line(code, err, argv[0], first, second, "is also the")
    assert tree(tmp_path) == ["sub"]


# --------------------------------------------------------------------- failures mid-write


def _failing_publish(tmp, target):
    raise OSError(18, "Invalid cross-device link")  # the rename fails (EXDEV)


@pytest.mark.parametrize(
    "argv, flag, name",
    [(["plan", MAP], "--json", "p.json"), (["plan", MAP], "--plot", "p.png"),
     (["verify", "{plan}"], "--json", "v.json"), (DRIVE, "--json", "m.json"),
     (DRIVE, "--trajectory", "t.csv")],
    ids=["plan --json", "plan --plot", "verify --json", "simulate --json",
         "simulate --trajectory"],
)
def test_a_failed_rename_keeps_the_old_file_and_no_temporary(capsys, tmp_path, plan_file,
                                                             monkeypatch, argv, flag, name):
    import rrtdrive.atomic

    target = tmp_path / name
    target.write_bytes(b"old contents\n")
    monkeypatch.setattr(rrtdrive.atomic, "publish", _failing_publish)
    code, _, err = run(capsys, *_argv(argv, plan_file), flag, str(target))
    one_error_line(code, err, argv[0], f"{flag}: cannot write {target}",
                   "Invalid cross-device link", expected=1)
    assert target.read_bytes() == b"old contents\n"
    assert tree(tmp_path) == [name]  # no temporary file beside it


def test_a_failed_rename_in_maps_export_and_import(capsys, tmp_path, image, monkeypatch):
    import rrtdrive.atomic

    folder = tmp_path / "maps"
    folder.mkdir()
    (folder / f"{MAP}.json").write_text("old\n")
    target = tmp_path / "imported.json"
    target.write_text("old\n")
    monkeypatch.setattr(rrtdrive.atomic, "publish", _failing_publish)
    code, _, err = run(capsys, "maps", "--export", str(folder))
    one_error_line(code, err, "maps", "--export: cannot write", expected=1)
    assert tree(folder) == [f"{MAP}.json"] and (folder / f"{MAP}.json").read_text() == "old\n"
    code, _, err = run(capsys, *import_argv(image, str(target)))
    one_error_line(code, err, "maps", f"--out: cannot write {target}", expected=1)
    assert target.read_text() == "old\n" and temporaries(tmp_path) == []


def _rrtdrive(*argv: str) -> subprocess.Popen:
    return subprocess.Popen([sys.executable, "-m", "rrtdrive", *argv], stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True)


def test_sigterm_while_the_video_is_written_keeps_every_old_output(tmp_path):
    old = {"m.json": b"{}\n", "p.png": b"old png", "t.csv": b"old,csv\n", "v.mp4": b"old mp4"}
    for name, data in old.items():
        (tmp_path / name).write_bytes(data)
    # A 20 s drive: its video takes long enough to encode that the signal, sent when the
    # encoding starts, lands in it on a loaded machine too (3 s was done first, once).
    proc = _rrtdrive("simulate", MAP, "--max-time", "20", "--video-stride", "1",
                     *[a for flag, name in (("--json", "m.json"), ("--plot", "p.png"),
                                            ("--trajectory", "t.csv"), ("--video", "v.mp4"))
                       for a in (flag, str(tmp_path / name))])
    assert proc.stderr is not None
    deadline = time.monotonic() + 120
    for line in proc.stderr:  # the first progress line: the video is being encoded
        if " video " in line or time.monotonic() > deadline:
            break
    proc.send_signal(signal.SIGTERM)
    _, err = proc.communicate(timeout=60)
    assert proc.returncode == 143, err
    assert "Traceback" not in err
    assert {p.name: p.read_bytes() for p in tmp_path.iterdir()} == old  # nothing replaced


def test_sigterm_during_a_bench_leaves_whole_files_only(tmp_path):
    out = tmp_path / "b"
    proc = _rrtdrive(*BENCH[:3], "--seeds", "3", *BENCH[5:], "--out", str(out))
    deadline = time.monotonic() + 120
    runs = out / "runs.jsonl"
    while time.monotonic() < deadline:  # the first row stored: runs are under way
        if runs.exists() and runs.read_text().strip():
            break
        time.sleep(0.05)
    proc.send_signal(signal.SIGTERM)
    _, err = proc.communicate(timeout=60)
    assert proc.returncode in (0, 143), err  # 0 if it finished just before the signal
    assert "Traceback" not in err
    assert temporaries(out) == []
    for line in runs.read_text().splitlines():
        json.loads(line)  # every stored row whole
    json.loads((out / "bench_config.json").read_text())


# --------------------------------------------------------------------- the Python writers


def test_python_writers_handle_unicode_names_and_leave_no_temporary(tmp_path):
    import matplotlib

    matplotlib.use("Agg")
    from matplotlib.figure import Figure

    from rrtdrive.atomic import write_text_atomic
    from rrtdrive.plotting import save_figure

    folder = tmp_path / NAME
    folder.mkdir()
    save_map(builtin_map(MAP), folder / "m é.json")
    assert load_map(folder / "m é.json").name == MAP
    save_figure(Figure(), folder / "f ü.pdf")
    assert (folder / "f ü.pdf").read_bytes()[:5] == b"%PDF-"
    write_text_atomic(folder / "t 名.txt", "ünïcode\n")
    assert (folder / "t 名.txt").read_text("utf-8") == "ünïcode\n"
    with pytest.raises(IsADirectoryError):
        save_map(builtin_map(MAP), tmp_path)  # a folder: refused, nothing left
    with pytest.raises(ValueError, match="not supported"):
        save_figure(Figure(), folder / "f.txt")  # matplotlib's own refusal
    assert sorted(p.name for p in folder.iterdir()) == ["f ü.pdf", "m é.json", "t 名.txt"]
    assert temporaries(tmp_path) == []


# --------------------------------------------------------------------- bugs


def _long_name(folder: Path, suffix: str) -> str:
    """A file name of 250 bytes with ``suffix``: legal wherever names may have 255."""
    try:
        limit = os.pathconf(folder, "PC_NAME_MAX")
    except (OSError, ValueError):
        limit = 255
    if limit < 250:
        pytest.skip(f"names here may have only {limit} bytes")
    return "a" * (250 - len(suffix)) + suffix


@pytest.mark.parametrize("flag, suffix", [("--json", ".json"), ("--plot", ".png")])
def test_a_long_but_legal_output_name_is_written(capsys, tmp_path, flag, suffix):
    target = tmp_path / _long_name(tmp_path, suffix)
    target.write_text("")  # the file system takes the name
    target.unlink()
    code, _, err = run(capsys, "plan", MAP, flag, str(target))
    assert code == 0, err
    assert target.stat().st_size > 0 and temporaries(tmp_path) == []


def test_save_map_writes_a_long_but_legal_name(tmp_path):
    target = tmp_path / _long_name(tmp_path, ".json")
    save_map(builtin_map(MAP), target)
    assert load_map(target).name == MAP


@pytest.mark.parametrize("where", ["missing", "unwritable"])
def test_python_writer_errors_name_the_callers_path(tmp_path, unwritable, where):
    folder = tmp_path / "missing" if where == "missing" else unwritable
    target = folder / "x.json"
    with pytest.raises(OSError) as exc:
        save_map(builtin_map(MAP), target)
    assert str(target) in str(exc.value), str(exc.value)
    assert ".x." not in str(exc.value), str(exc.value)


@pytest.mark.skipif(not os.path.exists("/dev/full"), reason="needs /dev/full")
def test_a_failed_trajectory_still_leaves_the_json_and_the_summary(capsys, tmp_path):
    csv = tmp_path / "t.csv"
    csv.symlink_to("/dev/full")  # every write: No space left on device
    js = tmp_path / "m.json"
    code, out, err = run(capsys, *DRIVE, "--trajectory", str(csv), "--json", str(js))
    assert code == 1 and f"--trajectory: cannot write {csv}" in err, err
    assert f"{MAP} seed 0" in out  # the summary
    assert js.exists() and json.loads(js.read_text())["steps"] == 6


@pytest.mark.skipif(not os.path.exists("/dev/full"), reason="needs /dev/full")
def test_every_output_that_failed_is_named(capsys, tmp_path, monkeypatch):
    import rrtdrive.plotting

    def full_disk(fig, path, dpi=110):
        raise OSError(28, "No space left on device")

    monkeypatch.setattr(rrtdrive.plotting, "save_figure", full_disk)
    csv = tmp_path / "t.csv"
    csv.symlink_to("/dev/full")
    png = tmp_path / "p.png"
    code, _, err = run(capsys, *DRIVE, "--trajectory", str(csv), "--plot", str(png))
    assert code == 1
    assert f"--trajectory: cannot write {csv}" in err, err
    assert f"--plot: cannot write {png}" in err, err  # the plot is missing too: say so


def test_a_failed_plot_keeps_the_json_and_says_so(capsys, tmp_path, monkeypatch):
    # The documented half (docs/video.md): --plot fails, --json and the summary stay.
    import rrtdrive.plotting

    def full_disk(fig, path, dpi=110):
        raise OSError(28, "No space left on device")

    monkeypatch.setattr(rrtdrive.plotting, "save_figure", full_disk)
    png, js = tmp_path / "p.png", tmp_path / "m.json"
    code, out, err = run(capsys, *DRIVE, "--plot", str(png), "--json", str(js))
    one_error_line(code, err, "simulate", f"--plot: cannot write {png}", expected=1)
    assert json.loads(js.read_text())["plot"] is None and f"{MAP} seed 0" in out
    assert tree(tmp_path) == ["m.json"]


@pytest.mark.parametrize("name", ["summary.md", "success.png", "bench_config.json"])
def test_bench_names_the_file_it_cannot_write(capsys, tmp_path, name):
    out = tmp_path / "b"
    (out / name).mkdir(parents=True)  # a folder in the way of one of bench's files
    code, _, err = run(capsys, *BENCH, "--out", str(out))
    # Exit 1 (found while writing) or 2 (checked before the runs): either is fine.
    assert code in (1, 2) and "Traceback" not in err, err
    assert err.startswith("rrtdrive bench: error: --out: ") and err.count("\n") == 1, err
    assert temporaries(out) == []
    assert str(out / name) in err, err


def test_bench_out_dash_is_refused_not_a_folder_named_dash(capsys, tmp_path, monkeypatch):
    """Every other command reads '-' as stdout or refuses it; bench made a folder '-'."""
    monkeypatch.chdir(tmp_path)
    code = main(["bench", "--maps", MAP, "--seeds", "1", "--workers", "1", "--out", "-"])
    err = capsys.readouterr().err
    assert code == 2 and err.count("\n") == 1 and "--out: " in err, err
    assert not (tmp_path / "-").exists()


def test_maps_export_dash_is_refused_not_a_folder_named_dash(capsys, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    code = main(["maps", "--export", "-"])
    err = capsys.readouterr().err
    assert code == 2 and err.count("\n") == 1 and "--export: " in err, err
    assert not (tmp_path / "-").exists()
