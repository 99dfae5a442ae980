"""The ``rrtdrive bench`` subcommand.

Wiring in ``rrtdrive.cli``::

    from rrtdrive.bench import cli_bench
    cli_bench.add_parser(subparsers)   # sets func=cli_bench.run

Exit codes: 0 when every run of the grid has a result row, 1 when some runs
ended as error rows (crashed twice) or the worker processes could not start,
2 on bad input (one line on stderr).
"""

from __future__ import annotations

import argparse
import shlex
import sys
from pathlib import Path
from typing import Any

from rrtdrive.types import InputError

__all__ = ["HELP", "add_parser", "run", "config_from_args"]

EXIT_OK, EXIT_FAILED, EXIT_BAD_INPUT = 0, 1, 2
HELP = "run a grid of maps/scenarios x planners x controllers x seeds in parallel"


def _int_arg(text: str) -> int:
    # Range checks are the config's, so TOML and flags report alike (naming the field).
    try:
        return int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected an integer, got {text!r}") from None


def _float_arg(text: str) -> float:
    try:
        return float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a number, got {text!r}") from None


class _GivenOnce(argparse.Action):
    """An option that may be given once: a second ``--config`` silently replaced the first."""

    def __call__(self, parser: Any, namespace: Any, values: Any, option: Any = None) -> None:
        if getattr(namespace, self.dest, None) is not None:
            parser.error(f"argument {option}: given twice; give one file")
        setattr(namespace, self.dest, values)


def add_parser(subparsers: Any) -> argparse.ArgumentParser:
    """Add ``bench`` to an argparse subparsers object and return its parser."""
    p = subparsers.add_parser(
        "bench",
        help=HELP,
        description="Run every combination of maps (planning only) or scenarios (closed loop), "
        "planners, controllers and seeds on local processes or a Ray cluster. One JSON line "
        "per run goes to OUT/runs.jsonl as it finishes; a re-run resumes without redoing "
        "finished runs. Writes OUT/summary.md, OUT/summary.csv and plots. Lists are "
        "comma-separated or repeated flags; flags override --config. Exit 0 when every run "
        "has a result, 1 when some runs crashed twice (error rows) or the worker processes "
        "could not start, 2 on bad input; 130 on Ctrl-C, 143 on SIGTERM.",
    )
    p.add_argument(
        "--config", metavar="FILE.toml", action=_GivenOnce,
        help="read the bench from a TOML file ('-': stdin)",
    )
    p.add_argument(
        "--maps", action="append", metavar="NAMES",
        help="maps for planning-only runs: built-in names or .json files",
    )
    p.add_argument(
        "--scenarios", action="append", metavar="NAMES",
        help="closed-loop runs: built-in scenarios (parking, overtake, overtake-traffic, "
        "parallel-parking, u-turn, parking-reverse-in), stock highway-env ones (parking-v0, "
        "parking-parked-v0) "
        "or maps, built-in names or .json files, driven from their start to their goal",
    )
    p.add_argument(
        "--planners", action="append", metavar="NAMES",
        help="planners, including OMPL rows such as ompl-r2-rrtconnect, ompl-rs-bitstar "
        "(the Reeds-Shepp ompl-rs rows only with --reverse; default: improved-rrt-connect); "
        "NAME@FIELD=VALUE:FIELD=VALUE sets fields of a planner's config, as plan "
        "--planner-option (improved-rrt-connect@reverse_detour_tree=false)",
    )
    p.add_argument(
        "--controllers", action="append", metavar="NAMES",
        help="controllers for scenario runs: pure-pursuit, stanley, lqr (default: pure-pursuit)",
    )
    p.add_argument("--seeds", type=_int_arg, metavar="N", help="seeds 0..N-1 (default 10)")
    # plan's and simulate's --seed is one seed: argparse read it here as --seeds (a count).
    p.add_argument("--seed", dest="one_seed", metavar="N", help=argparse.SUPPRESS)
    p.add_argument(
        "--workers", "--jobs", type=_int_arg, metavar="N", dest="workers",
        help="local worker processes (default: one per core); with --ray, runs in flight "
        "(--jobs: the same, as the experiment scripts call it)",
    )
    p.add_argument("--out", metavar="DIR", help="output folder (default: bench)")
    ray = p.add_mutually_exclusive_group()
    ray.add_argument(
        "--ray", nargs="?", const="", default=None, metavar="ADDRESS",
        help="run on Ray: no ADDRESS starts a local Ray (or uses RAY_ADDRESS); "
        "'auto' or 'ray://host:10001' connects to a cluster",
    )
    ray.add_argument(
        "--no-ray", action="store_true",
        help="run in local processes although the --config file sets ray",
    )
    p.add_argument(
        "--max-time", dest="max_time_s", type=_float_arg, metavar="S",
        help="planning wall-clock safety cap per run in seconds (default 5); a plan that "
        "reaches it fails as 'timeout' (the iterations decide otherwise); not for "
        "overtake-traffic, which re-plans within its own per-cycle budget",
    )
    p.add_argument(
        "--max-iterations", type=_int_arg, metavar="N",
        help="planning iteration budget per run (default 20000); not for overtake-traffic, "
        "which re-plans within its own per-cycle budget",
    )
    p.add_argument(
        "--run-timeout", dest="run_timeout_s", type=_float_arg, metavar="S",
        help="kill a run after S seconds; it counts as a crash (default 600)",
    )
    p.add_argument(
        "--retries", type=_int_arg, metavar="N",
        help="attempts after a crash before an error row is recorded (default 1)",
    )
    p.add_argument(
        "--retry-errors", action="store_true",
        help="run the grid's stored error rows again (they are replaced)",
    )
    # On/off pairs (--no-reverse ...): a flag turns off what the --config file turns on.
    p.add_argument(
        "--deterministic", action=argparse.BooleanOptionalAction, default=None,
        help="wall-clock limits off: planning stops on --max-iterations only and "
        "overtake-traffic re-plans without cutting cycles at their time budget, so rows "
        "depend on the seed alone (not with --max-time; default: off)",
    )
    p.add_argument(
        "--reverse", action=argparse.BooleanOptionalAction, default=None,
        help="allow gear changes in every run, as plan/simulate --reverse (a planner that "
        "cannot reverse plans forward; default: off)",
    )
    p.add_argument(
        "--plots", action=argparse.BooleanOptionalAction, default=None,
        help="write the PNG plots (default); --no-plots skips them and removes those an "
        "earlier bench left in --out: they would describe other runs",
    )
    p.add_argument("--quiet", action="store_true", help="no progress line")
    p.set_defaults(func=run)
    return p


#: The config field each flag sets, for errors naming the flag (``--seeds: ...``).
FLAG_OF_FIELD = {
    "maps": "--maps", "scenarios": "--scenarios", "planners": "--planners",
    "controllers": "--controllers", "seeds": "--seeds", "workers": "--workers",
    "out": "--out", "ray": "--ray", "max_time_s": "--max-time",
    "max_iterations": "--max-iterations", "run_timeout_s": "--run-timeout",
    "retries": "--retries",
}


def given_flags(args: argparse.Namespace) -> dict[str, str]:
    """The fields set on the command line, each with its flag (a TOML key keeps its name)."""
    return {k: f for k, f in FLAG_OF_FIELD.items() if getattr(args, k, None) is not None}


def config_from_args(args: argparse.Namespace) -> Any:
    """The :class:`~rrtdrive.bench.grid.BenchConfig` of parsed arguments (flags over TOML)."""
    from rrtdrive.bench.config_file import config_from_mapping, load_toml

    if args.config == "":  # an unset shell variable: not "no config"
        raise InputError("--config: needs a file name, got an empty one")
    values: dict[str, Any] = load_toml(args.config) if args.config is not None else {}
    from_file = set(values)
    values.update({k: getattr(args, k) for k in given_flags(args)})  # flags over TOML
    from_file -= set(given_flags(args))
    for key in ("plots", "reverse", "deterministic"):  # on/off flags over the file's too
        if getattr(args, key, None) is not None:
            values[key] = getattr(args, key)
            from_file.discard(key)
    if getattr(args, "no_ray", False):
        values["ray"] = None
    if values.get("deterministic") is True and args.max_time_s is not None:
        flag = getattr(args, "deterministic", None)
        whose = "--deterministic" if flag else "the config's deterministic = true"
        raise InputError(f"--max-time: {whose} turns the planning time limit off")
    try:
        return config_from_mapping(values)
    except InputError as exc:
        # A bad value read from the file names the file, as an unknown key there does.
        field = str(exc).split(":", 1)[0]
        # An empty file or maps = [] leaves no map or scenario: the file is named too.
        if field in from_file or (field == "maps/scenarios" and args.config is not None
                                  and not {"maps", "scenarios"} & set(given_flags(args))):
            where = "stdin" if args.config == "-" else args.config
            raise InputError(f"{exc} (in {where!r})") from None
        raise


def forward_only_notes(planners: tuple[str, ...]) -> list[str]:
    """As ``rrtdrive plan --reverse``: a note for each row whose planner plans forward only.

    Its rows say ``reverse: true`` (gear changes were asked for) while its paths have
    none; the OMPL rows are left out (``ompl-rs`` rows reverse, ``ompl-r2`` rows are
    geometric paths, as the bench docs say).
    """
    from rrtdrive.bench.planner_specs import parse_planner_spec
    from rrtdrive.planning import forward_only_note, make_planner, reverses

    notes = []
    for label in planners:
        spec = parse_planner_spec(label)
        if spec.name.startswith("ompl-"):
            continue
        if not getattr(make_planner(spec.name, **spec.options), "reverses", False):
            # The default reverses only in its escalation, which the row's options end.
            why = f" with {label.partition('@')[2]}" if reverses(spec.name) else ""
            notes.append(forward_only_note(spec.name, why=why))
    return notes


def unused_controllers_note(cfg: Any, given: bool = False) -> str | None:
    """A note when controllers were asked for but no run drives.

    ``--maps`` runs plan only; the controllers apply to ``--scenarios`` runs (a map is
    driven with ``--scenarios MAP``). Without the note they were silently left out.
    """
    from rrtdrive.bench.grid import BenchConfig

    # ``given``: on the command line, even as the default (an audit: --controllers
    # pure-pursuit said nothing).
    if cfg.scenarios or (cfg.controllers == BenchConfig.controllers and not given):
        return None
    return (
        f"note: --controllers {','.join(cfg.controllers)} applies to --scenarios runs; "
        "--maps runs plan only (to drive a map: --scenarios MAP)"
    )


def run(args: argparse.Namespace) -> int:
    """Run the ``bench`` subcommand; return the exit code."""
    from rrtdrive.cli_args import flags_for

    flags = given_flags(args)
    if args.config:  # the file's own errors name the flag ("config: no such file" did not)
        flags["config"] = "--config"
    if "maps" in flags or "scenarios" in flags:  # `--maps ''` read "maps/scenarios: ..."
        given = [flags[k] for k in ("maps", "scenarios") if k in flags]
        flags["maps/scenarios"] = "/".join(given)
    try:
        with flags_for(flags):
            return _run(args)
    except InputError as exc:
        print(f"rrtdrive bench: error: {exc}", file=sys.stderr)
        return EXIT_BAD_INPUT


def _run(args: argparse.Namespace) -> int:
    if args.one_seed is not None:
        raise InputError(
            f"--seed: a bench runs the seeds 0..N-1 of every row; give their count with "
            f"--seeds N (--seed {args.one_seed} is plan's and simulate's one seed)"
        )
    from rrtdrive.bench.backends import WorkerStartupError
    from rrtdrive.bench.core import run_bench
    from rrtdrive.cli_args import writing

    cfg = config_from_args(args)
    note = unused_controllers_note(cfg, given=bool(getattr(args, "controllers", None)))
    if note is not None:
        print(f"rrtdrive bench: {note}", file=sys.stderr)
    if cfg.reverse:
        for note in forward_only_notes(cfg.planners):
            print(f"rrtdrive bench: {note}", file=sys.stderr)
    argv = getattr(args, "argv", None)
    argv = sys.argv[1:] if argv is None else argv
    command = "rrtdrive " + " ".join(shlex.quote(a) for a in argv)
    try:
        # A full disk while storing rows or writing the summary: one line, exit 1 (it was
        # a traceback); the rows stored so far stay, and a re-run resumes from them.
        with writing("--out", cfg.out):
            report = run_bench(
                cfg,
                progress=None if args.quiet else sys.stderr,
                retry_errors=args.retry_errors,
                command=command,
            )
    except WorkerStartupError as exc:
        print(f"rrtdrive bench: error: {exc}", file=sys.stderr)
        return EXIT_FAILED
    print(
        f"bench: {report.total} runs ({report.skipped} resumed, {report.executed} run now, "
        f"{report.errors} errors)" + (f" on {report.backend}" if report.executed else "")
        + (f"; {report.throughput:.2f} runs/s" if report.executed else "")
    )
    from rrtdrive.bench.summary import PLOT_FILES

    plots = [name for name in PLOT_FILES if cfg.plots and (Path(cfg.out) / name).is_file()]
    print(
        f"results: {cfg.out}/runs.jsonl; summary: {cfg.out}/summary.md, {cfg.out}/summary.csv"
        + (f"; plots: {', '.join(plots)} in {cfg.out}" if plots else "")
    )
    return EXIT_FAILED if report.errors else EXIT_OK
