"""Session 46 audit: headless video export and plots, as a demanding user.

A student making report figures and an engineer exporting the video of a reversing
parking manoeuvre: the files are real (frames decoded and measured with imageio /
numpy, not looked at), reverse legs and cusps are drawn differently, outputs are
deterministic and atomic, and bad output paths are one-line errors naming the flag.
"""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path as FsPath

import imageio.v3 as iio
import imageio_ffmpeg
import numpy as np
import pytest
from scipy import ndimage

from rrtdrive.cli import main
from rrtdrive.sim.render import CUSP_COLOR, PATH_COLOR, REVERSE_COLOR
from rrtdrive.sim.runner import EpisodeConfig, run_episode
from rrtdrive.sim.tasks import make_scenario
from rrtdrive.sim.video import frame_is_blank, render_frames, write_video
from rrtdrive.types import InputError

PNG_MAGIC = b"\x89PNG\r\n\x1a\n"


def _sigint_deliverable() -> None:
    # In the child before exec: a pytest-xdist worker hands SIGINT down ignored, and a
    # worker that ran a bench may hand it down blocked (a mask survives exec); either way
    # the child never saw the Ctrl-C and ran to the end (exit 0 in CI, session 47).
    signal.signal(signal.SIGINT, signal.SIG_DFL)
    signal.pthread_sigmask(signal.SIG_UNBLOCK, {signal.SIGINT})


def _cli(argv: list[str]) -> int:
    try:
        return int(main(argv))
    except SystemExit as exc:  # argparse errors
        return int(exc.code)


def _mask(frame: np.ndarray, colour: tuple[int, int, int], tol: int = 0) -> np.ndarray:
    return np.abs(frame.astype(int) - np.array(colour)).max(axis=2) <= tol


def _leftovers(folder: FsPath) -> list[str]:
    """Hidden temporary files (the atomic writers' ``.<stem>.*``) left in ``folder``."""
    return sorted(p.name for p in folder.iterdir() if p.name.startswith("."))


@pytest.fixture(scope="module")
def reversing_episode():
    """Two seconds of parallel parking: a plan with three gear changes."""
    scen = make_scenario("parallel-parking", 0)
    return run_episode(scen, config=EpisodeConfig(max_time_s=2.0))


# --------------------------------------------------------------------------- video frames


def test_reversing_video_frames_show_reverse_legs_dashed_and_every_cusp(reversing_episode):
    ep = reversing_episode
    cusps = len(ep.path.cusps)
    assert cusps >= 1, "the parallel-parking plan reverses"
    frames = list(render_frames(ep, stride=10))
    assert len(frames) == len(range(0, len(ep.log.states), 10)) + (
        (len(ep.log.states) - 1) % 10 != 0
    )
    for f in frames:
        assert f.dtype == np.uint8 and f.ndim == 3 and f.shape[2] == 3
        h, w = f.shape[:2]
        assert h % 2 == 0 and w % 2 == 0, "H.264 needs even sides"
        assert h % 16 == 0 and w % 16 == 0, "no rescaling by imageio's macro blocks"
        assert not frame_is_blank(f)
    first = frames[0]
    # Forward legs in the path colour, reverse legs in the reverse colour (exact pixels).
    assert _mask(first, PATH_COLOR).sum() > 50
    reverse = _mask(first, REVERSE_COLOR)
    assert reverse.sum() > 20
    # Dashed: the reverse pixels fall apart into several pieces, not one stroke.
    assert ndimage.label(reverse)[1] >= 2
    # Each cusp is its own dot at the start, before the car has moved over them.
    assert ndimage.label(_mask(first, CUSP_COLOR))[1] == cusps


def test_video_frames_are_identical_for_the_same_episode(reversing_episode):
    a = list(render_frames(reversing_episode, stride=20))
    b = list(render_frames(reversing_episode, stride=20))
    assert len(a) == len(b)
    assert all(np.array_equal(x, y) for x, y in zip(a, b, strict=True))
    assert not np.array_equal(a[0], a[-1]), "the car moved"


# --------------------------------------------------------------------------- the CLI


@pytest.fixture(scope="module")
def cli_outputs(tmp_path_factory):
    """``simulate parallel-parking --video --plot --json`` twice with the same seed."""
    runs = []
    for k in range(2):
        d = tmp_path_factory.mktemp(f"run{k}")
        argv = [
            "simulate",
            "parallel-parking",
            "--max-time",
            "2",
            "--seed",
            "0",
            "--video",
            str(d / "drive.mp4"),
            "--plot",
            str(d / "drive.png"),
            "--json",
            str(d / "drive.json"),
        ]
        rc = _cli(argv)
        runs.append((d, rc))
    return runs


def test_cli_video_of_a_reversing_scenario_is_a_real_mp4(cli_outputs, reversing_episode):
    d, rc = cli_outputs[0]
    assert rc in (0, 1)  # a 2 s drive times out: exit 1, and the outputs are still written
    data = json.loads((d / "drive.json").read_text())
    video = d / "drive.mp4"
    assert data["video"] == str(video)
    assert data["video_frames"] == data["steps"] + 1  # the start and every step
    frames = iio.imread(video)
    assert frames.shape[0] == data["video_frames"]
    assert frames.shape[1] % 2 == 0 and frames.shape[2] % 2 == 0
    stds = frames.reshape(len(frames), -1).std(axis=1)
    assert stds.min() > 5.0, "no blank frame"
    n, secs = imageio_ffmpeg.count_frames_and_secs(str(video))
    assert n == data["video_frames"]
    # Real time: the video lasts the simulated drive (one frame per step at 20 Hz).
    assert secs == pytest.approx(data["duration_s"] + 1.0 / data["simulation_frequency"], abs=0.06)
    # The encoded frames are the rendered ones (lossy, but close).
    rendered = next(iter(render_frames(reversing_episode, stride=10_000)))
    assert frames[0].shape == rendered.shape
    assert np.abs(frames[0].astype(int) - rendered.astype(int)).mean() < 6.0
    assert _leftovers(d) == []


def test_cli_outputs_are_byte_identical_for_the_same_seed(cli_outputs):
    (a, rc_a), (b, rc_b) = cli_outputs
    assert rc_a == rc_b
    for name in ("drive.mp4", "drive.png"):
        assert (a / name).read_bytes() == (b / name).read_bytes(), name
    assert (a / "drive.png").read_bytes()[:8] == PNG_MAGIC


def test_plan_plot_png_is_byte_identical_and_draws_reverse_and_cusps(tmp_path, monkeypatch):
    import rrtdrive.plotting as plotting

    seen = []
    real = plotting.plot_plan

    def spy(m, result, *args, **kwargs):
        fig = real(m, result, *args, **kwargs)
        ax = fig.axes[0]
        dashed = [ln.get_label() for ln in ax.get_lines() if ln.get_linestyle() == "--"]
        cusp = [ln for ln in ax.get_lines() if ln.get_label().startswith("cusp")]
        seen.append((dashed, [len(ln.get_xdata()) for ln in cusp], len(result.path.cusps)))
        return fig

    monkeypatch.setattr(plotting, "plot_plan", spy)
    outs = []
    for k in range(2):
        out = tmp_path / f"plan{k}.png"
        assert (
            _cli(
                [
                    "plan",
                    "kerbside",
                    "--reverse",
                    "--plot",
                    str(out),
                    "--json",
                    str(tmp_path / f"plan{k}.json"),
                ]
            )
            == 0
        )
        outs.append(out.read_bytes())
    assert outs[0][:8] == PNG_MAGIC and outs[0] == outs[1]
    result = json.loads((tmp_path / "plan0.json").read_text())
    assert result["cusps"] >= 1
    # The figure itself: a dashed reverse line and one cusp marker per gear change.
    assert len(seen) == 2
    dashed, cusp_markers, cusps = seen[0]
    assert cusps == result["cusps"]
    assert "path, reverse (dashed)" in dashed
    assert cusp_markers == [cusps]


def test_episode_plot_marks_reverse_and_cusps(reversing_episode):
    import matplotlib.pyplot as plt

    from rrtdrive.sim.episode_plot import plot_episode

    fig = plot_episode(reversing_episode)
    ax = fig.axes[0]
    labels = [ln.get_label() for ln in ax.get_lines()]
    assert "planned path, reverse (dashed)" in labels
    cusp = [ln for ln in ax.get_lines() if ln.get_label().startswith("cusp")]
    assert len(cusp) == 1 and len(cusp[0].get_xdata()) == len(reversing_episode.path.cusps)
    plt.close(fig)


@pytest.mark.parametrize(
    ("extra", "flag", "words"),
    [
        (["--video", "{d}/missing/v.mp4"], "--video", "does not exist"),
        (["--video", "{d}/adir.mp4"], "--video", "is a folder"),
        (["--video", "{d}/afile.txt/v.mp4"], "--video", "not a folder"),
        (["--video", "{d}/v.avi"], "--video", ".mp4"),
        (["--video", ""], "--video", "empty"),
        (["--video", "-"], "--video", ".mp4"),
        (["--video", "/proc/v.mp4"], "--video", "/proc"),
        (["--video", "{d}/v.mp4", "--video-stride", "0"], "--video-stride", ">= 1"),
        (["--video", "{d}/v.mp4", "--video-stride", "-3"], "--video-stride", ">= 1"),
        (["--video", "{d}/v.mp4", "--video-stride", "nan"], "--video-stride", ">= 1"),
        (["--video-stride", "4"], "--video-stride", "--video"),
        (["--plot", "{d}/missing/p.png"], "--plot", "does not exist"),
        (["--plot", "{d}/p.jpg"], "--plot", ".png"),
        (["--plot", "{d}/adir.png"], "--plot", "is a folder"),
        (["--plot", "{d}/same.png", "--json", "{d}/same.png"], "--plot", "own name"),
    ],
)
def test_bad_outputs_are_one_line_errors_naming_the_flag(tmp_path, capsys, extra, flag, words):
    (tmp_path / "adir.mp4").mkdir()
    (tmp_path / "adir.png").mkdir()
    (tmp_path / "afile.txt").write_text("x")
    before = sorted(p.name for p in tmp_path.iterdir())
    argv = ["simulate", "parking", "--max-time", "1"] + [a.format(d=tmp_path) for a in extra]
    rc = _cli(argv)
    err = capsys.readouterr().err.strip()
    assert rc == 2
    assert "Traceback" not in err
    lines = err.splitlines()
    assert len(lines) == 1 and lines[0].startswith("rrtdrive simulate: error:"), err
    assert flag in lines[0] and words in lines[0], err
    assert sorted(p.name for p in tmp_path.iterdir()) == before, "nothing written"


@pytest.mark.skipif(not os.path.exists("/dev/full"), reason="needs /dev/full")
@pytest.mark.parametrize("flag", ["--video", "--plot"])
def test_a_full_disk_is_exit_1_naming_the_flag(tmp_path, capsys, flag):
    target = tmp_path / ("full.mp4" if flag == "--video" else "full.png")
    target.symlink_to("/dev/full")
    rc = _cli(["simulate", "parking", "--max-time", "1", flag, str(target)])
    err = capsys.readouterr().err
    assert rc == 1
    assert "Traceback" not in err
    assert f"{flag}: cannot write" in err and "No space left" in err
    assert target.is_symlink() and _leftovers(tmp_path) == []


def test_interrupting_a_video_keeps_the_old_file_and_leaves_no_temp(tmp_path):
    # A previous video at the target must survive a Ctrl-C halfway through the next one.
    target = tmp_path / "bay.mp4"
    old = b"an older video, kept whole"
    target.write_bytes(old)
    errfile = tmp_path / "stderr.txt"
    with open(errfile, "wb") as err:
        proc = subprocess.Popen(
            [
                sys.executable,
                "-m",
                "rrtdrive",
                "simulate",
                "parking",
                "--reverse-in",
                "--video",
                str(target),
            ],
            stdout=subprocess.DEVNULL,
            stderr=err,
            # A pytest-xdist worker hands its children SIGINT ignored, and Python keeps an
            # inherited SIG_IGN: the child would never see the Ctrl-C (as the test_bench one).
            preexec_fn=_sigint_deliverable,  # noqa: PLW1509
        )
        deadline = time.monotonic() + 40
        while time.monotonic() < deadline and b"video " not in errfile.read_bytes():
            if proc.poll() is not None:
                break
            time.sleep(0.05)
        assert proc.poll() is None, "the export ended before it could be interrupted"
        proc.send_signal(signal.SIGINT)
        rc = proc.wait(timeout=30)
    text = errfile.read_text()
    assert rc == 130, text
    assert "Traceback" not in text
    assert target.read_bytes() == old
    assert _leftovers(tmp_path) == []


# --------------------------------------------------------------------------- bugs found


@pytest.mark.parametrize("fps", [np.int64(20), np.float32(20.0)])
def test_write_video_takes_a_numpy_fps(reversing_episode, tmp_path, fps):
    out = tmp_path / "np.mp4"
    n = write_video(reversing_episode, out, fps=fps, stride=20)
    assert out.exists() and n == imageio_ffmpeg.count_frames_and_secs(str(out))[0]


def test_write_video_rejects_a_folder_target_before_rendering(
    reversing_episode, tmp_path, monkeypatch
):
    folder = tmp_path / "clip.mp4"
    folder.mkdir()
    rendered = []
    real = render_frames

    def spy(*args, **kwargs):
        for f in real(*args, **kwargs):
            rendered.append(1)
            yield f

    monkeypatch.setattr("rrtdrive.sim.video.render_frames", spy)
    with pytest.raises(InputError, match="clip.mp4"):
        write_video(reversing_episode, folder, stride=20)
    assert rendered == [], "nothing rendered for a target that cannot be written"


def test_stock_env_video_is_not_silently_black_under_sdl_dummy(tmp_path):
    out = tmp_path / "stock.mp4"
    env = {**os.environ, "SDL_VIDEODRIVER": "dummy"}
    done = subprocess.run(
        [
            sys.executable,
            "-m",
            "rrtdrive",
            "simulate",
            "parking-v0",
            "--max-time",
            "0.5",
            "--video",
            str(out),
        ],
        env=env,
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert "Traceback" not in done.stderr
    if out.exists():
        frames = iio.imread(out)
        assert not all(frame_is_blank(f) for f in frames), "every frame is blank"
    else:
        assert done.returncode != 0 and "SDL_VIDEODRIVER" in done.stderr


@pytest.mark.skipif(not os.path.exists("/dev/full"), reason="needs /dev/full")
def test_a_failed_video_still_leaves_the_metrics_and_trajectory(tmp_path, capsys):
    video = tmp_path / "full.mp4"
    video.symlink_to("/dev/full")
    js, csv = tmp_path / "m.json", tmp_path / "t.csv"
    rc = _cli(
        [
            "simulate",
            "parking",
            "--max-time",
            "1",
            "--video",
            str(video),
            "--json",
            str(js),
            "--trajectory",
            str(csv),
        ]
    )
    err = capsys.readouterr().err
    assert rc == 1 and "--video: cannot write" in err
    assert js.exists() and json.loads(js.read_text())["steps"] == 20
    assert csv.exists() and len(csv.read_text().splitlines()) == 1 + 21


@pytest.mark.parametrize("fps", [-1.0, float("nan"), float("inf"), 0])
def test_write_video_names_a_bad_fps_and_writes_nothing(reversing_episode, tmp_path, fps):
    with pytest.raises(InputError, match="^fps:"):
        write_video(reversing_episode, tmp_path / "v.mp4", fps=fps)
    assert list(tmp_path.iterdir()) == []


def test_no_video_says_an_older_file_at_the_target_is_not_this_runs(tmp_path, capsys):
    # A failed plan writes no video; an older file there could pass for this drive's.
    from rrtdrive.cli import main

    target = tmp_path / "v.mp4"
    target.write_bytes(b"an older video")
    assert main(["simulate", "no_path", "--video", str(target)]) == 1
    err = capsys.readouterr().err
    assert "no video: planning failed" in err
    assert f"{target} is an earlier run's, left as it was" in err
    assert target.read_bytes() == b"an older video"
    target.unlink()
    assert main(["simulate", "no_path", "--video", str(target)]) == 1
    assert "earlier run" not in capsys.readouterr().err and not target.exists()
