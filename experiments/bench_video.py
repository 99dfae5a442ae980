"""Video export speed: the full export against the encoder alone on the same frames.

Usage::

    python experiments/bench_video.py --repeats 3 --out results [--doc]

Drives one episode (default: ``parking``, seed 0, the default planner and
``pure-pursuit``, as ``rrtdrive simulate parking --video parking.mp4``), renders its
frames once into memory, then times, interleaved ``--repeats`` times:

* ``encode``: the pre-rendered frames through imageio-ffmpeg alone (the settings of
  :func:`rrtdrive.sim.video.write_video`, written from the calling thread): the
  encoder's own frames/s, the ceiling of any export;
* ``export``: :func:`rrtdrive.sim.video.write_video` (render, with the static layer
  drawn once, and encode in a writer thread);
* ``render``: :func:`rrtdrive.sim.video.render_frames` alone.

Once: ``render`` with ``reuse_background=False`` (every frame drawn from scratch, as
before the static layer). Reports medians and the ratio export/encode frames/s
(target >= 0.8). The machine's load is recorded: the ratio is only meaningful
from one run. Writes ``OUT/bench_video.json`` and ``.md``; ``--doc`` also rewrites
the results block of ``docs/video.md``.
"""

from __future__ import annotations

import argparse
import os
import platform
import statistics
import sys
import tempfile
import time
from collections.abc import Callable
from pathlib import Path as FsPath

import imageio.v2 as imageio

from rrtdrive.cli_args import positive_int
from rrtdrive.maps import write_text_atomic
from rrtdrive.sim.runner import run_episode
from rrtdrive.sim.video import frame_is_blank, render_frames, write_video

DOC = FsPath(__file__).resolve().parents[1] / "docs" / "video.md"
BEGIN, END = "<!-- bench_video:begin -->", "<!-- bench_video:end -->"


def _timed(fn: Callable[[], object]) -> float:
    t0 = time.perf_counter()
    fn()
    return time.perf_counter() - t0


def _encode(frames: list, path: FsPath, fps: float) -> None:
    writer = imageio.get_writer(
        path, format="FFMPEG", mode="I", fps=fps, codec="libx264", quality=7,
        macro_block_size=16, ffmpeg_log_level="error",
    )
    try:
        for f in frames:
            writer.append_data(f)
    finally:
        writer.close()


def main(argv: list[str] | None = None) -> int:
    from results_io import json_text, out_folder  # the sibling module (run as a script)

    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--scenario", default="parking",
                    help="scenario of the episode to export (default: %(default)s)")
    ap.add_argument("--seed", type=int, default=0,
                    help="episode seed (default: %(default)s)")
    ap.add_argument("--controller", default="pure-pursuit",
                    help="pure-pursuit, stanley or lqr (default: %(default)s)")
    ap.add_argument("--repeats", type=positive_int, default=3,
                    help="interleaved timing rounds, >= 1; medians reported (default: %(default)s)")
    ap.add_argument("--out", type=out_folder, default="results",
                    help="directory for bench_video.json and .md (default: %(default)s)")
    ap.add_argument("--doc", action="store_true", help=f"rewrite the results block of {DOC}")
    args = ap.parse_args(argv)
    if args.repeats < 1:
        ap.error("--repeats: need >= 1")
    episode = run_episode(args.scenario, controller=args.controller, seed=args.seed)
    fps = 1.0 / episode.log.dt
    frames = list(render_frames(episode))
    n = len(frames)
    h, w = frames[0].shape[:2]
    if any(frame_is_blank(f) for f in frames[:: max(1, n // 10)]):
        print("bench_video: blank frames", file=sys.stderr)
        return 1
    times: dict[str, list[float]] = {"encode": [], "export": [], "render": []}
    load = [os.getloadavg()[0]]
    with tempfile.TemporaryDirectory(prefix="bench-video-") as tmp:
        folder = FsPath(tmp)
        for r in range(args.repeats):
            times["encode"].append(_timed(lambda: _encode(frames, folder / "enc.mp4", fps)))
            times["export"].append(_timed(lambda: write_video(episode, folder / "exp.mp4")))
            times["render"].append(_timed(lambda: sum(1 for _ in render_frames(episode))))
            load.append(os.getloadavg()[0])
            print(f"repeat {r}: " + ", ".join(
                f"{k} {n / v[-1]:.1f} frames/s" for k, v in times.items()), file=sys.stderr)
        scratch = _timed(lambda: sum(1 for _ in render_frames(episode, reuse_background=False)))
    med = {k: statistics.median(v) for k, v in times.items()}
    fps_of = {k: n / v for k, v in med.items()}
    ratio = fps_of["export"] / fps_of["encode"]
    given = sys.argv[1:] if argv is None else argv
    command = "python experiments/bench_video.py " + " ".join(given)
    meta = {
        "command": command, "python": platform.python_version(), "machine": platform.machine(),
        "cpus": os.cpu_count(), "load_1min": load,
    }
    summary = {
        "scenario": args.scenario, "seed": args.seed, "controller": args.controller,
        "frames": n, "frame_size": [w, h], "episode_status": episode.status,
        "repeats": args.repeats, "median_s": med, "frames_per_s": fps_of,
        "render_from_scratch_s": scratch, "render_from_scratch_frames_per_s": n / scratch,
        "export_over_encode": ratio, "target": 0.8, "meets_target": bool(ratio >= 0.8),
    }
    out = FsPath(args.out)
    out.mkdir(parents=True, exist_ok=True)
    write_text_atomic(out / "bench_video.json", json_text(
        {"meta": meta, "summary": summary, "times_s": times}))
    table = [
        f"Command: `{command}`; {args.scenario} seed {args.seed}, {args.controller}: "
        f"{n} frames of {w} x {h}; median of {args.repeats} interleaved repeats; "
        f"{os.cpu_count()} CPUs, 1-min load {min(load):.1f}-{max(load):.1f}.", "",
        "| step | median [s] | frames/s | ms/frame |", "|---|---|---|---|",
    ]
    labels = {
        "encode": "encode pre-rendered frames (imageio-ffmpeg alone)",
        "export": "**full export** (`write_video`)",
        "render": "render alone (static layer reused)",
    }
    for k, label in labels.items():
        table.append(f"| {label} | {med[k]:.2f} | {fps_of[k]:.1f} | {1e3 * med[k] / n:.1f} |")
    table.append(f"| render from scratch (once; every item every frame) | {scratch:.2f} | "
                 f"{n / scratch:.1f} | {1e3 * scratch / n:.1f} |")
    table += ["", f"Export / encode frames/s: **{ratio:.2f}** (target >= 0.8: "
              f"{'met' if ratio >= 0.8 else 'NOT met'})."]
    write_text_atomic(out / "bench_video.md",
                      "# Video export speed\n\n" + "\n".join(table) + "\n")
    print("\n".join(table))
    if args.doc:
        text = DOC.read_text()
        if BEGIN not in text or END not in text:
            print(f"bench_video: {DOC} has no {BEGIN} ... {END} block", file=sys.stderr)
            return 1
        head, rest = text.split(BEGIN, 1)
        tail = rest.split(END, 1)[1]
        write_text_atomic(DOC, head + BEGIN + "\n" + "\n".join(table) + "\n" + END + tail)
    return 0


if __name__ == "__main__":
    from results_io import run_main

    raise SystemExit(run_main(main))
