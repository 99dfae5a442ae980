"""Start-up time of the ``rrtdrive`` command against ``python -c "import numpy"``.

Usage::

    python experiments/bench_cli_startup.py --repeats 15 --out results
    python experiments/bench_cli_startup.py --repeats 15 --out results --doc docs/cli_startup.md

Runs ``rrtdrive --help``, ``rrtdrive --version``, ``rrtdrive maps``, ``rrtdrive plan
--help``, ``rrtdrive bench --help`` and the numpy baseline as fresh processes,
interleaved round-robin (so a load spike hits every command alike), ``--repeats``
times each after one warm-up round (file cache).
Reports the median wall time of each and its ratio to the baseline's median
(ratios are what carries over between machines), and the extra modules each
command imports over the baseline. Writes ``OUT/bench_cli_startup.json`` (every
sample, the command and the machine) and ``OUT/bench_cli_startup.md``; with
``--doc FILE`` the same section replaces the one between this script's markers
in FILE (or is appended).
"""

from __future__ import annotations

import argparse
import os
import platform
import shutil
import statistics
import subprocess
import sys
import time
from pathlib import Path

from rrtdrive.atomic import write_text_atomic
from rrtdrive.cli_args import positive_int

BEGIN, END = "<!-- bench_cli_startup: begin -->", "<!-- bench_cli_startup: end -->"
HEAVY = (
    "highway_env", "control", "matplotlib", "pygame", "scipy.signal", "scipy.stats",
    "scipy.ndimage",
)  # fmt: skip


def commands() -> dict[str, list[str]]:
    exe = shutil.which("rrtdrive")
    cli = [exe] if exe else [sys.executable, "-m", "rrtdrive"]
    return {
        'python -c "import numpy"': [sys.executable, "-c", "import numpy"],
        "rrtdrive --help": [*cli, "--help"],
        "rrtdrive --version": [*cli, "--version"],
        "rrtdrive maps": [*cli, "maps"],
        # These two build parsers that import the planners (scipy.ndimage, interpolate);
        # bench's imports are also what every bench worker process imports.
        "rrtdrive plan --help": [*cli, "plan", "--help"],
        "rrtdrive bench --help": [*cli, "bench", "--help"],
    }


def time_once(argv: list[str]) -> float:
    t0 = time.perf_counter()
    subprocess.run(argv, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, check=True)
    return time.perf_counter() - t0


def heavy_modules(args: list[str]) -> list[str]:
    """Heavy libraries a CLI invocation imports (run in-process in a fresh interpreter)."""
    code = (
        "import sys\nfrom rrtdrive.cli import main\n"
        f"try:\n    main({args!r})\nexcept SystemExit:\n    pass\n"
        f"print('HEAVY:' + ','.join(m for m in {HEAVY!r} if m in sys.modules))\n"
    )
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                          check=True)
    line = next(x for x in proc.stdout.splitlines()[::-1] if x.startswith("HEAVY:"))
    return [m for m in line.removeprefix("HEAVY:").split(",") if m]


def main(argv: list[str] | None = None) -> int:
    from results_io import json_text, out_folder  # the sibling module (run as a script)

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeats", type=positive_int, default=15,
                    help="timed rounds per command, >= 1 (default: %(default)s)")
    ap.add_argument("--out", type=out_folder, default="results",
                    help="directory for bench_cli_startup.json and .md (default: %(default)s)")
    ap.add_argument("--doc", default=None, help="also put the section into this markdown page")
    args = ap.parse_args(argv)
    if args.repeats < 1:
        ap.error("--repeats: must be >= 1")
    cmds = commands()
    for argv_ in cmds.values():  # warm-up: file cache, .pyc files
        time_once(argv_)
    samples: dict[str, list[float]] = {name: [] for name in cmds}
    for _ in range(args.repeats):
        for name, argv_ in cmds.items():
            samples[name].append(time_once(argv_))
    base_name = next(iter(cmds))
    base = statistics.median(samples[base_name])
    rows = {}
    for name, ts in samples.items():
        med = statistics.median(ts)
        rows[name] = {
            "median_s": med,
            "min_s": min(ts),
            "max_s": max(ts),
            "ratio_to_numpy": med / base,
            "heavy_imports": None if name == base_name else heavy_modules(name.split()[1:]),
            "samples_s": ts,
        }
    load = os.getloadavg() if hasattr(os, "getloadavg") else None
    command = " ".join(["python", "experiments/bench_cli_startup.py",
                        *(sys.argv[1:] if argv is None else argv)])
    report = {
        "command": command,
        "repeats": args.repeats,
        "machine": (
            f"{platform.machine()} {os.cpu_count()} CPUs, Python {platform.python_version()}"
        ),
        "load_average_at_end": load,
        "results": rows,
    }
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    write_text_atomic(out / "bench_cli_startup.json", json_text(report))
    lines = [
        "## CLI start-up",
        "",
        f"`{command}`: each command as a fresh process, {args.repeats} "
        f"round{'s' if args.repeats != 1 else ''} interleaved "
        f"after a warm-up, on {report['machine']}"
        + (f" (load average {load[0]:.1f} at the end)" if load else "") + ".",
        "",
        "| command | median [s] | min / max [s] | × `import numpy` | heavy modules imported |",
        "|---|---|---|---|---|",
    ]
    for name, r in rows.items():
        heavy = "–" if r["heavy_imports"] is None else (", ".join(r["heavy_imports"]) or "none")
        lines.append(
            f"| `{name}` | {r['median_s']:.3f} | {r['min_s']:.3f} / {r['max_s']:.3f} | "
            f"{r['ratio_to_numpy']:.2f} | {heavy} |"
        )
    section = "\n".join(lines) + "\n"
    write_text_atomic(out / "bench_cli_startup.md", section)
    if args.doc:  # docs/ changes only when asked
        doc = Path(args.doc)
        block = f"{BEGIN}\n{section}{END}\n"
        old = doc.read_text(encoding="utf-8") if doc.exists() else ""
        if BEGIN in old and END in old:
            head, rest = old.split(BEGIN, 1)
            new = head + block + rest.split(END, 1)[1].lstrip("\n")
        else:
            new = old + ("\n" if old and not old.endswith("\n") else "") + (
                "\n" if old else "") + block
        write_text_atomic(doc, new)
    print(section)
    return 0


if __name__ == "__main__":
    from results_io import run_main

    raise SystemExit(run_main(main))
