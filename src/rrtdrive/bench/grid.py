"""The bench grid: its configuration (flags or TOML), validation, expansion and run keys.

A bench is the product of

- planning-only runs: ``maps × planners × seeds`` (no controller), and
- closed-loop runs: ``scenarios × planners × controllers × seeds`` (a scenario is a
  built-in one, a stock highway-env one (``parking-v0``, ``parking-parked-v0``) or a map,
  built-in or a ``.json`` file, driven from its start to its goal).

Each run is a :class:`RunSpec`. Its *configuration hash* covers everything that
defines the run except the seed (kind, map content or scenario name, planner,
controller, budget), so ``(config_hash, seed)`` identifies a run across
interrupted and repeated benches.
"""

from __future__ import annotations

import dataclasses
import functools
import hashlib
import importlib.util
import json
import os
from collections.abc import Iterable, Mapping
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

from rrtdrive.types import InputError, brief_repr, is_finite_number, require_int
from rrtdrive.values import did_you_mean

if TYPE_CHECKING:
    from rrtdrive.maps import Map

__all__ = [
    "BenchConfig",
    "RunSpec",
    "CONFIG_KEYS",
    "expand",
    "map_digest",
    "SCHEMA",
    "is_map_scenario",
]

#: Most seeds per cell of a bench grid.
MAX_SEEDS = 100_000

#: Version of the row schema and of the hashed fields; bump to invalidate old rows.
SCHEMA = 1

#: Keys accepted in a TOML bench file (the same names as the ``BenchConfig`` fields).
CONFIG_KEYS = (
    "maps",
    "scenarios",
    "planners",
    "controllers",
    "seeds",
    "workers",
    "out",
    "max_time_s",
    "max_iterations",
    "run_timeout_s",
    "retries",
    "ray",
    "plots",
    "deterministic",
    "reverse",
)

#: The planning time budget of a deterministic bench: never reached (iterations bind).
NO_WALL_LIMIT_S = 1e6
#: The planning time budget of a bench that gives none (and is not deterministic).
DEFAULT_MAX_TIME_S = 5.0


DETERMINISTIC_TIME = "max_time_s: a deterministic bench has no planning time limit; drop it"


def _names(field_name: str, value: object) -> tuple[str, ...]:
    """Normalise a list of names: strings, comma-separated allowed, de-duplicated in order."""
    if isinstance(value, str):
        value = [value]
    if not isinstance(value, (list, tuple)):
        raise InputError(f"{field_name}: expected a list of names, got {value!r}")
    out: list[str] = []
    for item in value:
        if not isinstance(item, str):
            raise InputError(f"{field_name}: expected names (strings), got {item!r}")
        for part in item.split(","):
            part = part.strip()
            if not part:
                continue
            if part not in out:
                out.append(part)
    return tuple(out)


def _positive(field_name: str, value: object) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise InputError(f"{field_name}: expected a number > 0, got {brief_repr(value)}")
    if not (is_finite_number(value) and value > 0):  # an int of 400 digits too
        raise InputError(f"{field_name}: must be a finite number > 0, got {brief_repr(value)}")
    return float(value)


def map_digest(spec: str, m: Map | None = None) -> tuple[str, str | None]:
    """A short digest of the map ``spec`` resolves to (content and car), for run keys.

    ``m``: the map ``spec`` resolved to, when the caller has read it already.

    Returns
    -------
    digest : str
        16 hex digits.
    content : str or None
        The map's JSON text for a map file (runs carry it, so workers on other
        machines need no copy of the file); ``None`` for a built-in map.

    Raises
    ------
    InputError
        When ``spec`` is neither a built-in map nor a readable map file.
    """
    from rrtdrive.maps import BUILTIN_MAPS, resolve_map

    if m is None:
        m = resolve_map(spec)
    payload = {"map": m.to_json(), "vehicle": dataclasses.asdict(m.vehicle)}
    text = json.dumps(payload, sort_keys=True, separators=(",", ":"))
    content = None if spec in BUILTIN_MAPS else json.dumps(m.to_json())
    return hashlib.sha256(text.encode()).hexdigest()[:16], content


def _check_grid(m: Map) -> None:
    """Refuse, once before any run, a map too big for any collision grid bench would use.

    Bench plans on the default grid (it has no ``--resolution``): such a map failed in
    every run, each retried as a crash and kept as an error row.
    """
    from rrtdrive.collision import CheckerConfig
    from rrtdrive.collision.grid import grid_resolution

    grid_resolution(m.bounds, CheckerConfig())


def ompl_available() -> bool:
    """True when the optional ``ompl`` package can be imported."""
    return importlib.util.find_spec("ompl") is not None


@dataclass(frozen=True)
class BenchConfig:
    """A bench: the grid, its budgets and where and how it runs.

    Parameters
    ----------
    maps : tuple of str
        Built-in map names or map ``.json`` files for planning-only runs.
    scenarios : tuple of str
        Closed-loop scenarios: built-in ones (``parking``, ``overtake`` …), stock
        highway-env ones (``parking-v0``, ``parking-parked-v0``: its own draw per seed,
        judged by it too) or maps (built-in names or ``.json`` files), driven from their
        start to their goal.
    planners : tuple of str
        Registered planner names, including the OMPL rows (``ompl-r2-rrtconnect`` …);
        a name may carry fields of the planner's config,
        ``improved-rrt-connect@reverse_detour_tree=false:step=4`` (see
        :mod:`~rrtdrive.bench.planner_specs`; each row is kept in its one spelling).
    controllers : tuple of str
        Controllers for scenario runs (ignored by planning-only runs).
    seeds : int
        Seeds ``0 … seeds-1`` for every cell of the grid (at most :data:`MAX_SEEDS`).
    workers : int, optional
        Local worker processes (default: one per core); with Ray, the largest
        number of runs in flight.
    out : str
        Output folder: ``runs.jsonl``, ``bench_config.json``, the summary and plots.
    max_time_s : float, optional
        Planning wall-clock safety cap of every run in seconds (``None``: the default,
        :data:`DEFAULT_MAX_TIME_S`; a deterministic bench takes none).
    max_iterations : int
        Planning iteration budget of every run.
    run_timeout_s : float
        A run that takes longer is killed and counts as a crashed attempt.
    retries : int
        Extra attempts of a crashed run before it is recorded as an error row.
    ray : str, optional
        ``None`` for local processes; ``""`` for ``ray.init()`` (a local Ray or
        ``RAY_ADDRESS``); otherwise the address given to ``ray.init``.
    plots : bool
        Write the summary plots.
    deterministic : bool
        Wall-clock limits off: the planning budget is ``max_iterations`` alone
        (``max_time_s`` becomes :data:`NO_WALL_LIMIT_S`; giving both is an error, but for
        that value itself, so a copy by ``dataclasses.replace`` stays valid) and
        overtake-traffic's re-planning cycles are not cut at their time budget, so a
        run depends on its seed only, not on the machine's load.
    reverse : bool
        Allow gear changes in every run (``rrtdrive plan --reverse``; scenarios as
        ``rrtdrive simulate --reverse``). A planner that cannot reverse plans forward.

    Examples
    --------
    >>> cfg = BenchConfig(maps=("overtake",), planners=("rrt-connect",), seeds=3)
    >>> len(expand(cfg))
    3
    """

    maps: tuple[str, ...] = ()
    scenarios: tuple[str, ...] = ()
    planners: tuple[str, ...] = ("improved-rrt-connect",)
    controllers: tuple[str, ...] = ("pure-pursuit",)
    seeds: int = 10
    workers: int | None = None
    out: str = "bench"
    max_time_s: float | None = None
    max_iterations: int = 20_000
    run_timeout_s: float = 600.0
    retries: int = 1
    ray: str | None = None
    plots: bool = True
    deterministic: bool = False
    reverse: bool = False
    map_digests: Mapping[str, str] = field(default_factory=dict, compare=False, repr=False)
    map_contents: Mapping[str, str | None] = field(
        default_factory=dict, compare=False, repr=False
    )

    def __post_init__(self) -> None:
        set_ = object.__setattr__
        for name in ("maps", "scenarios", "planners", "controllers"):
            set_(self, name, _names(name, getattr(self, name)))
        # A bound keeps a typo (seeds = 10000000) from a grid that never ends.
        set_(self, "seeds", require_int("seeds", self.seeds, 1, MAX_SEEDS))
        if self.workers is not None:
            set_(self, "workers", require_int("workers", self.workers, 1))
        if not isinstance(self.out, (str, os.PathLike)) or not str(self.out):
            raise InputError(f"out: expected a folder name, got {self.out!r}")
        if str(self.out) == "-":  # the other commands' stdout: a folder named "-" surprised
            raise InputError("out: a bench writes a folder of files, not stdout: name a folder")
        set_(self, "out", str(self.out))
        if not isinstance(self.deterministic, bool):
            raise InputError(
                f"deterministic: expected true or false, got {self.deterministic!r}"
            )
        if self.deterministic:
            # None: not given. Any value given is an error, even the default's 5.0.
            if self.max_time_s not in (None, NO_WALL_LIMIT_S):
                raise InputError(DETERMINISTIC_TIME)
            set_(self, "max_time_s", NO_WALL_LIMIT_S)
        elif self.max_time_s is None:
            set_(self, "max_time_s", DEFAULT_MAX_TIME_S)
        set_(self, "max_time_s", _positive("max_time_s", self.max_time_s))
        set_(self, "max_iterations", require_int("max_iterations", self.max_iterations, 1))
        set_(self, "run_timeout_s", _positive("run_timeout_s", self.run_timeout_s))
        set_(self, "retries", require_int("retries", self.retries, 0))
        if self.ray is not None and not isinstance(self.ray, str):
            raise InputError(f"ray: expected an address string, got {self.ray!r}")
        if not isinstance(self.plots, bool):
            raise InputError(f"plots: expected true or false, got {self.plots!r}")
        if not isinstance(self.reverse, bool):
            raise InputError(f"reverse: expected true or false, got {self.reverse!r}")
        if not self.planners:
            raise InputError("planners: give at least one planner")
        if not self.controllers:  # `--controllers ""` read as none (a garbled note; an audit)
            raise InputError("controllers: give at least one controller")
        # The names first: `--controllers foo` alone was told to give a map (an audit).
        self._check_names()
        if not self.maps and not self.scenarios:
            raise InputError("maps/scenarios: give at least one map or one scenario")

    def _check_names(self) -> None:
        from rrtdrive.bench.planner_specs import check_planner_spec, parse_planner_spec

        labels: list[str] = []
        for text in self.planners:
            # Checked as the workers will read it: its label (step=4.0 is step=4 there).
            spec = parse_planner_spec(parse_planner_spec(text).label)
            check_planner_spec(spec, "planners" if "@" not in text else f"planners: {text!r}")
            if spec.label not in labels:  # two spellings of one row: one row
                labels.append(spec.label)
            p = spec.name
            if p.startswith("ompl-rs-") and not self.reverse:
                # Reeds-Shepp curves reverse whatever the grid says: beside forward-only
                # planners they compared paths with gear changes to paths without.
                raise InputError(
                    f"planners: {p!r} plans Reeds-Shepp paths, which change gear; bench it "
                    "with --reverse (reverse = true), or use an ompl-r2 planner"
                )
            if p.startswith("ompl-") and self.deterministic:
                raise InputError(
                    f"planners: {p!r} has no iteration budget, only a time limit, which a "
                    "deterministic bench does not set (each unsolved run would last the "
                    "run timeout); bench it without --deterministic"
                )
            if p.startswith("ompl-") and not ompl_available():
                raise InputError(
                    f"planners: {p!r} needs OMPL; install it with pip install 'rrtdrive[ompl]'"
                )
        object.__setattr__(self, "planners", tuple(labels))
        digests, contents = dict(self.map_digests), dict(self.map_contents)
        for m in self.maps:
            if m not in digests or m not in contents:
                try:
                    from rrtdrive.maps import resolve_map

                    resolved = resolve_map(m)
                    _check_grid(resolved)
                    digests[m], contents[m] = map_digest(m, resolved)
                except InputError as exc:
                    raise InputError(f"maps: {m!r}: {exc}") from None
        # The scenarios that are maps, driven from their start to their goal.
        for s in self.scenarios:
            if is_map_scenario(s) and (s not in digests or s not in contents):
                from rrtdrive.sim.stock import STOCK_ENVS
                from rrtdrive.sim.tasks import SCENARIO_VARIANTS, CustomTask, scenario_map

                driven = scenario_map("scenarios", s, tuple(STOCK_ENVS), SCENARIO_VARIANTS)
                try:
                    # The task every episode of it builds, checked once here: its bad input
                    # (a goal that is the start) is one exit-2 line, not an error per run.
                    CustomTask.from_map(driven)
                    _check_grid(driven)
                except InputError as exc:
                    raise InputError(f"scenarios: {s!r}: {exc}") from None
                digests[s], contents[s] = map_digest(s, driven)
        object.__setattr__(self, "map_digests", digests)
        object.__setattr__(self, "map_contents", contents)
        for field_, names in (("maps", self.maps),
                              ("scenarios", [s for s in self.scenarios if s in digests])):
            seen: dict[str, str] = {}
            for m in names:
                if digests[m] in seen:
                    # One content, one run key: the second name's runs were "already stored".
                    raise InputError(
                        f"{field_}: {seen[digests[m]]!r} and {m!r} are the same map (the same "
                        "content); give it once"
                    )
                seen[digests[m]] = m
        if self.reverse and self.scenarios:
            from rrtdrive.sim.tasks import REPLANNING_SCENARIOS

            forward_only = [s for s in self.scenarios if s in REPLANNING_SCENARIOS]
            if forward_only:
                # As rrtdrive simulate --reverse: the re-planner drives forward only, so a
                # reverse cell would repeat the forward one under another name.
                raise InputError(
                    f"reverse: {forward_only[0]} re-plans while driving, forward only; "
                    "bench it without reverse"
                )
        if self.scenarios:
            from rrtdrive.sim.tasks import TASKS

            for s in self.scenarios:
                # The task's own planners (overtake-traffic re-plans with its space-time
                # one): checked only when an episode started, each other planner's run
                # became an error row (tried twice) and the bench exited 1.
                own = getattr(TASKS.get(s), "PLANNERS", None)
                others = [p for p in self.planners if own is not None and p not in own]
                if others and others[0].partition("@")[0] in own:
                    raise InputError(
                        f"planners: {others[0]!r}: {s} re-plans with its own planner, which "
                        "takes no options in a bench; drop the '@...'"
                    )
                if others:
                    raise InputError(
                        f"planners: {s} re-plans with its own space-time planner ({own[0]!r} "
                        f"in a grid); {others[0]!r} cannot drive it: bench {s} in a grid of "
                        f"its own with --planners {own[0]}"
                    )
            if not self.controllers:
                raise InputError("controllers: scenario runs need at least one controller")
        from rrtdrive.controllers import CONTROLLERS

        # Named even where no run drives (a bench of maps): a typo is no silent no-op.
        for c in self.controllers:
            if c not in CONTROLLERS:
                raise InputError(
                    f"controllers: unknown controller {c!r}{did_you_mean(c, CONTROLLERS)}; "
                    f"choose from {', '.join(sorted(CONTROLLERS))}"
                )

    @property
    def runs(self) -> int:
        """Number of runs in the grid."""
        per_seed = len(self.maps) * len(self.planners) + len(self.scenarios) * len(
            self.planners
        ) * len(self.controllers)
        return per_seed * self.seeds

    def to_json(self) -> dict[str, Any]:
        """The resolved configuration as a JSON-ready dict."""
        out = {k: getattr(self, k) for k in CONFIG_KEYS}
        for k in ("maps", "scenarios", "planners", "controllers"):
            out[k] = list(out[k])
        if self.deterministic:  # no limit, as a config that is fed back says it (an audit)
            out["max_time_s"] = None
        out["map_digests"] = dict(self.map_digests)
        out["schema"] = SCHEMA
        return out


@dataclass(frozen=True)
class RunSpec:
    """One run of the grid: what to plan (and drive) with which seed.

    Attributes
    ----------
    kind : str
        ``"plan"`` (planning only) or ``"episode"`` (closed loop).
    target : str
        The map spec (kind ``plan``) or the scenario name (kind ``episode``).
    planner : str
        Registered planner name.
    controller : str or None
        Controller name; ``None`` for planning-only runs.
    seed : int
        Run seed.
    max_time_s, max_iterations : float, int
        Planning budget.
    config_hash : str
        Hash of every field above but the seed (and of the map's content).
    map_json : str or None
        The map as JSON text for a map file, planned or driven (``None``: ``target`` is
        a built-in map or scenario).
    deterministic : bool
        Re-planning without wall-time cuts (the planning budget is in ``max_time_s``).
    reverse : bool
        Gear changes allowed.
    """

    kind: str
    target: str
    planner: str
    controller: str | None
    seed: int
    max_time_s: float
    max_iterations: int
    config_hash: str
    map_json: str | None = None
    deterministic: bool = False
    reverse: bool = False

    @property
    def key(self) -> tuple[str, int]:
        """``(config_hash, seed)``: the identity of the run across benches."""
        return (self.config_hash, self.seed)

    def describe(self) -> str:
        """Short human-readable label."""
        parts = [self.target, self.planner] + ([self.controller] if self.controller else [])
        return "/".join(parts) + f" seed {self.seed}"


def config_hash(payload: Mapping[str, Any]) -> str:
    """Stable 16-hex-digit SHA-256 of a JSON-able mapping (sorted keys).

    Examples
    --------
    >>> config_hash({"a": 1, "b": 2}) == config_hash({"b": 2, "a": 1})
    True
    """
    text = json.dumps(payload, sort_keys=True, separators=(",", ":"))
    return hashlib.sha256(text.encode()).hexdigest()[:16]


def expand(cfg: BenchConfig) -> list[RunSpec]:
    """Every run of the grid, seed-major so a partial bench covers every cell.

    Parameters
    ----------
    cfg : BenchConfig
        The bench.

    Returns
    -------
    list of RunSpec
    """
    cells: list[tuple[str, str, str, str | None, str]] = []
    for m in cfg.maps:
        for p in cfg.planners:
            h = config_hash(_hash_payload(cfg, "plan", m, p, None))
            cells.append(("plan", m, p, None, h))
    for s in cfg.scenarios:
        for p in cfg.planners:
            for c in cfg.controllers:
                h = config_hash(_hash_payload(cfg, "episode", s, p, c))
                cells.append(("episode", s, p, c, h))
    max_time_s = cfg.max_time_s
    assert max_time_s is not None  # __post_init__ resolved it
    return [
        RunSpec(
            kind, target, p, c, seed, max_time_s, cfg.max_iterations, h,
            cfg.map_contents.get(target) if kind == "plan" or is_map_scenario(target) else None,
            cfg.deterministic, cfg.reverse,
        )
        for seed in range(cfg.seeds)
        for kind, target, p, c, h in cells
    ]


def _hash_payload(
    cfg: BenchConfig, kind: str, target: str, planner: str, controller: str | None
) -> dict[str, Any]:
    payload: dict[str, Any] = {
        "schema": SCHEMA,
        "kind": kind,
        "planner": planner,
        "controller": controller,
        "max_time_s": cfg.max_time_s,
        "max_iterations": cfg.max_iterations,
    }
    if cfg.deterministic:  # only then: earlier benches' run keys stay valid
        payload["deterministic"] = True
    if cfg.reverse and not (kind == "episode" and always_reverses(target)):
        # Likewise; a scenario that reverses anyway runs the same episodes with or
        # without it (one key: a --reverse grid found them stored).
        payload["reverse"] = True
    if kind == "plan" or is_map_scenario(target):
        # The map's content, not its spelling: a changed file is a new configuration
        # (and a renamed one the same), planned or driven.
        payload["map_digest"] = cfg.map_digests[target]
    else:
        payload["scenario"] = target
    return payload


def is_map_scenario(target: str) -> bool:
    """Whether a closed-loop target is a map (driven start to goal), not a named scenario."""
    from rrtdrive.sim.stock import STOCK_ENVS
    from rrtdrive.sim.tasks import SCENARIO_VARIANTS, SCENARIOS

    return target not in SCENARIOS and target not in SCENARIO_VARIANTS and target not in STOCK_ENVS


@functools.cache
def always_reverses(target: str) -> bool:
    """Whether a named scenario plans with gear changes unasked.

    u-turn, parallel-parking and parking-reverse-in: ``--reverse`` changes nothing in
    their runs.
    """
    from rrtdrive.sim.stock import STOCK_ENVS
    from rrtdrive.sim.tasks import make_variant

    if is_map_scenario(target) or target in STOCK_ENVS:
        return False
    return bool(make_variant(target, 0).reverse)


def grid_keys(specs: Iterable[RunSpec]) -> set[tuple[str, int]]:
    """The run keys of ``specs``."""
    return {s.key for s in specs}
