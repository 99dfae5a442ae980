"""Audit of the bench's settings file, ``rrtdrive bench --config FILE.toml`` (session 50).

docs/bench.md, "A TOML file": the keys are the ``BenchConfig`` fields (``max_time_s`` ...),
optionally in a ``[bench]`` table; flags given as well override the file (the on/off pairs
``--no-plots``/``--plots``, ``--no-reverse``, ``--no-deterministic``, ``--no-ray`` too);
unknown keys and bad values are one exit-2 line; relative paths in the file are read from
the folder the command runs in. Checked here:

- every key has the effect of its flag: a bench configured by file and the same bench
  configured by flags store the same rows (apart from the timing and bookkeeping fields)
  and the same resolved config;
- precedence of flags over the file, per key;
- bad files and bad values: one line on stderr naming the file and the key, exit 2;
- the resolved config recorded in ``bench_config.json``, written back as TOML, reproduces
  the run (its run keys: a re-run in the same folder resumes everything);
- relative map files and ``out`` are read from the working folder, not the file's.

Benches are tiny: ``overtake``/``no_path``, one seed, one worker, no plots.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import pytest

from rrtdrive.cli import main

#: docs/bench.md: fields that depend on the machine's clock and bookkeeping.
VOLATILE = {
    "planning_time_s", "setup_time_s", "diagnosis_time_s", "wall_time_s", "worker",
    "finished_at",
}
PNGS = {"box_length.png", "box_time.png", "success.png", "curvature_hist.png"}


def _toml_value(v: Any) -> str:
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, (int, float)):
        return repr(v)
    if isinstance(v, str):
        return json.dumps(v)  # a TOML basic string for these plain names
    if isinstance(v, (list, tuple)):
        return "[" + ", ".join(_toml_value(x) for x in v) + "]"
    raise TypeError(v)


def _toml(mapping: dict[str, Any]) -> str:
    return "".join(f"{k} = {_toml_value(v)}\n" for k, v in mapping.items())


def _bench(argv: list[str], capsys) -> tuple[int, str, str]:
    capsys.readouterr()
    code = main(["bench", "--quiet", *argv])
    out, err = capsys.readouterr()
    return code, out, err


def _rows(out: Path) -> list[dict[str, Any]]:
    rows = [json.loads(line) for line in (out / "runs.jsonl").read_text().splitlines()]
    return sorted(
        ({k: v for k, v in r.items() if k not in VOLATILE} for r in rows),
        key=lambda r: (r["config_hash"], r["seed"]),
    )


def _config(out: Path) -> dict[str, Any]:
    return json.loads((out / "bench_config.json").read_text())["config"]


def _one_error_line(err: str) -> str:
    lines = err.strip().splitlines()
    assert len(lines) == 1, err
    assert "Traceback" not in err
    assert lines[0].startswith("rrtdrive bench: error: "), err
    return lines[0]


# --- every key: file == flags ----------------------------------------------------------

#: (file keys, the same bench as flags). Together they set every documented key.
SAME_BENCH = {
    "plan-rows": (
        {"maps": ["overtake"], "planners": ["rrt-connect"], "seeds": 2, "workers": 1,
         "max_time_s": 2.5, "max_iterations": 3000, "run_timeout_s": 120.0, "retries": 0,
         "plots": False, "ray": False},
        ["--maps", "overtake", "--planners", "rrt-connect", "--seeds", "2", "--workers", "1",
         "--max-time", "2.5", "--max-iterations", "3000", "--run-timeout", "120",
         "--retries", "0", "--no-plots", "--no-ray"],
    ),
    "episode-rows": (
        # A map driven start to goal; no_path's plan fails at once (the run stays short).
        {"scenarios": ["no_path"], "planners": "rrt-connect", "controllers": ["stanley"],
         "seeds": 1, "workers": 1, "max_iterations": 3000, "plots": False},
        ["--scenarios", "no_path", "--planners", "rrt-connect", "--controllers", "stanley",
         "--seeds", "1", "--workers", "1", "--max-iterations", "3000", "--no-plots"],
    ),
    "deterministic-reverse": (
        {"maps": ["no_path"], "seeds": 1, "workers": 1, "max_iterations": 2000,
         "deterministic": True, "reverse": True, "plots": False},
        ["--maps", "no_path", "--seeds", "1", "--workers", "1", "--max-iterations", "2000",
         "--deterministic", "--reverse", "--no-plots"],
    ),
}


@pytest.mark.parametrize(("case", "table"), [
    ("plan-rows", False), ("plan-rows", True), ("episode-rows", False),
    ("deterministic-reverse", True),
])
def test_file_and_flags_give_the_same_bench(tmp_path, monkeypatch, capsys, case, table):
    keys, flags = SAME_BENCH[case]
    monkeypatch.chdir(tmp_path)
    text = _toml({**keys, "out": "by_file"})
    Path("b.toml").write_text(("[bench]\n" if table else "") + text)
    code, _, err = _bench(["--config", "b.toml"], capsys)
    assert code == 0, err
    code, _, err = _bench([*flags, "--out", "by_flags"], capsys)
    assert code == 0, err
    by_file, by_flags = Path("by_file"), Path("by_flags")
    assert _rows(by_file) == _rows(by_flags)
    cf, cg = _config(by_file), _config(by_flags)
    assert cf.pop("out") == "by_file" and cg.pop("out") == "by_flags"
    assert cf == cg
    # The file's values took effect (not the defaults'), in the config and in the rows.
    for k, v in keys.items():
        if k == "ray":
            assert cf[k] is None
        elif isinstance(v, (list, str)) and k in ("maps", "scenarios", "planners",
                                                  "controllers"):
            assert cf[k] == ([v] if isinstance(v, str) else v)
        else:
            assert cf[k] == v, k
    rows = _rows(by_file)
    assert len(rows) == keys["seeds"]
    for r in rows:
        assert r["max_iterations"] == keys["max_iterations"]
        assert r["deterministic"] is keys.get("deterministic", False)
        assert r["reverse"] is keys.get("reverse", False)
        assert r["max_time_s"] == (1e6 if keys.get("deterministic") else
                                   keys.get("max_time_s", 5.0))
    assert not PNGS & {p.name for p in by_file.iterdir()}


def test_plots_true_in_file_writes_the_plots(tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    Path("b.toml").write_text(_toml({"maps": ["overtake"], "planners": ["rrt-connect"],
                                     "seeds": 1, "workers": 1, "plots": True, "out": "o"}))
    code, _, err = _bench(["--config", "b.toml"], capsys)
    assert code == 0, err
    assert PNGS <= {p.name for p in Path("o").iterdir()}


# --- precedence -------------------------------------------------------------------------

BASE = {"maps": ["overtake"], "planners": ["rrt-connect"], "seeds": 1, "workers": 1,
        "plots": False, "max_iterations": 3000, "out": "from_file"}


@pytest.mark.parametrize(("file_keys", "flags", "check"), [
    # seeds = 0 is bad, but the flag's value is the bench's: the file's is not read.
    ({"seeds": 0, "maps": ["no_path"], "max_iterations": 3000, "max_time_s": 3.0,
      "reverse": True, "ray": True, "retries": 3, "run_timeout_s": 9.0, "workers": 2},
     ["--seeds", "1", "--maps", "overtake", "--max-iterations", "500", "--max-time", "2",
      "--no-reverse", "--no-ray", "--retries", "0", "--run-timeout", "50", "--jobs", "1"],
     lambda c, rows: (
         (c["seeds"], c["maps"], c["ray"], c["retries"], c["run_timeout_s"], c["workers"],
          c["reverse"]) == (1, ["overtake"], None, 0, 50.0, 1, False)
         and [(r["map"], r["max_iterations"], r["max_time_s"], r["reverse"]) for r in rows]
         == [("overtake", 500, 2.0, False)])),
    ({"deterministic": True}, ["--no-deterministic"],
     lambda c, rows: {(r["deterministic"], r["max_time_s"]) for r in rows} == {(False, 5.0)}),
    ({"deterministic": False}, ["--deterministic"],
     lambda c, rows: {(r["deterministic"], r["max_time_s"]) for r in rows} == {(True, 1e6)}),
], ids=["every-valued-key", "no-deterministic", "deterministic"])
def test_flags_override_the_file(tmp_path, monkeypatch, capsys, file_keys, flags, check):
    monkeypatch.chdir(tmp_path)
    Path("b.toml").write_text(_toml({**BASE, **file_keys}))
    code, _, err = _bench(["--config", "b.toml", *flags], capsys)
    assert code == 0, err
    out = Path("from_file")
    assert check(_config(out), _rows(out))


def test_out_flag_overrides_the_file_and_plots_flag_too(tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    Path("b.toml").write_text(_toml(BASE))  # plots = false, out = "from_file"
    code, stdout, err = _bench(["--config", "b.toml", "--out", "from_flag", "--plots"], capsys)
    assert code == 0, err
    assert not Path("from_file").exists()
    assert PNGS <= {p.name for p in Path("from_flag").iterdir()}
    assert "from_flag/runs.jsonl" in stdout


def test_deterministic_in_file_with_max_time_flag_is_refused(tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    Path("b.toml").write_text(_toml({**BASE, "deterministic": True}))
    code, _, err = _bench(["--config", "b.toml", "--max-time", "2"], capsys)
    assert code == 2
    line = _one_error_line(err)
    assert "--max-time" in line and "deterministic" in line
    assert not Path("from_file").exists()


def test_max_time_in_file_with_deterministic_flag_is_refused(tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    Path("b.toml").write_text(_toml({**BASE, "max_time_s": 2.0}))
    code, _, err = _bench(["--config", "b.toml", "--deterministic"], capsys)
    assert code == 2
    line = _one_error_line(err)
    assert "max_time_s" in line and "b.toml" in line


# --- bad files and bad values -------------------------------------------------------------

GOOD = 'maps = ["overtake"]\nplanners = ["rrt-connect"]\nseeds = 1\nplots = false\n'


@pytest.mark.parametrize(("text", "key"), [
    (GOOD + "sede = 2\n", "'sede' (did you mean 'seeds'?)"),
    (GOOD + "max-time = 2\n", "'max-time' (the flag --max-time; its key is 'max_time_s')"),
    (GOOD + "run_timeout = 2\n",
     "'run_timeout' (the flag --run-timeout; its key is 'run_timeout_s')"),
    ("[bench]\n" + GOOD + "retrys = 2\n", "'retrys' (did you mean 'retries'?)"),
    (GOOD + "[extra]\nx = 1\n", "'extra'"),
    ("seeds = 1\n[bench]\nmaps = [\"overtake\"]\n", "'seeds'"),
    ('maps = ["overtake"]\nseeds = "1"\n', "seeds"),
    ('maps = ["overtake"]\nseeds = [1]\n', "seeds"),
    ('maps = ["overtake"]\nseeds = 1.0\n', "seeds"),
    ('maps = ["overtake"]\nseeds = true\n', "seeds"),
    ('maps = ["overtake"]\nseeds = 0\n', "seeds"),
    ('maps = ["overtake"]\nseeds = 100001\n', "seeds"),
    ('maps = ["overtake"]\nseeds = 1979-05-27\n', "seeds"),
    ('maps = ["overtake"]\nworkers = 0\n', "workers"),
    ('maps = ["overtake"]\nworkers = true\n', "workers"),
    ('maps = ["overtake"]\nretries = -1\n', "retries"),
    ('maps = ["overtake"]\nmax_iterations = 1e3\n', "max_iterations"),
    ('maps = ["overtake"]\nmax_time_s = "2"\n', "max_time_s"),
    ('maps = ["overtake"]\nmax_time_s = -1\n', "max_time_s"),
    ('maps = ["overtake"]\nmax_time_s = nan\n', "max_time_s"),
    ('maps = ["overtake"]\nmax_time_s = inf\n', "max_time_s"),
    ('maps = ["overtake"]\nmax_time_s = 1e400\n', "max_time_s"),
    ('maps = ["overtake"]\nrun_timeout_s = 0\n', "run_timeout_s"),
    ('maps = ["overtake"]\nplots = 1\n', "plots"),
    ('maps = ["overtake"]\nplots = "false"\n', "plots"),
    ('maps = ["overtake"]\nreverse = "yes"\n', "reverse"),
    ('maps = ["overtake"]\ndeterministic = 0\n', "deterministic"),
    ('maps = ["overtake"]\ndeterministic = true\nmax_time_s = 2.0\n', "max_time_s"),
    ('maps = ["overtake"]\nout = 5\n', "out"),
    ('maps = ["overtake"]\nout = ""\n', "out"),
    ('maps = ["overtake"]\nout = "-"\n', "out"),
    ("maps = 3\n", "maps"),
    ('maps = ["overtake", 3]\n', "maps"),
    ('maps = [["overtake"]]\n', "maps"),
    ('maps = ["overtak"]\n', "'overtak'"),
    ('maps = ["overtake"]\nplanners = ["rrt-conect"]\n', "did you mean 'rrt-connect'"),
    ('maps = ["overtake"]\nplanners = []\n', "planners"),
    ('maps = ["overtake"]\nplanners = ["rrt-connect@bogus=1"]\n', "bogus"),
    ('maps = ["overtake"]\ncontrollers = ["pur-pursuit"]\n', "did you mean 'pure-pursuit'"),
    ('scenarios = ["overtake-traffic"]\nreverse = true\n', "reverse"),
    ('maps = ["overtake"]\nseeds = 1\nseeds = 2\n', "line 3"),
    ('maps = ["overtake"\nseeds = 1\n', "line 2"),
    ('maps = ["overtake"]\nseeds = null\n', "line 2"),
    ('{"maps": ["overtake"], "seeds": 1}\n', "line 1"),  # JSON is not TOML
    ("maps:\n  - overtake\nseeds: 1\n", "line 1"),  # nor is YAML
    ("maps = " + "[" * 5000 + "]" * 5000 + "\n", "nested"),
    ("seeds = " + "9" * 5000 + "\n", "digits"),
])
def test_bad_file_is_one_line_naming_file_and_key(tmp_path, monkeypatch, capsys, text, key):
    monkeypatch.chdir(tmp_path)
    Path("my bench.toml").write_text(text)
    code, _, err = _bench(["--config", "my bench.toml"], capsys)
    assert code == 2, err
    line = _one_error_line(err)
    assert "my bench.toml" in line
    assert key in line
    assert not Path("bench").exists()  # the default out: nothing written


def test_duplicate_key_is_named(tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    Path("b.toml").write_text('maps = ["overtake"]\nseeds = 1\nseeds = 2\n')
    code, _, err = _bench(["--config", "b.toml"], capsys)
    assert code == 2
    line = _one_error_line(err)
    assert "b.toml" in line and "seeds" in line


@pytest.mark.parametrize("value", ["3", "{a = 1}", "[\"auto\"]"])
def test_bad_ray_value_names_the_file(tmp_path, monkeypatch, capsys, value):
    monkeypatch.chdir(tmp_path)
    Path("b.toml").write_text(f'maps = ["overtake"]\nray = {value}\n')
    code, _, err = _bench(["--config", "b.toml"], capsys)
    assert code == 2
    line = _one_error_line(err)
    assert "ray" in line
    assert "b.toml" in line


@pytest.mark.parametrize("kind", ["missing", "folder", "latin-1", "empty-name"])
def test_unreadable_file_is_one_line_naming_it(tmp_path, monkeypatch, capsys, kind):
    monkeypatch.chdir(tmp_path)
    name = {"missing": "nope.toml", "folder": "adir", "latin-1": "latin.toml",
            "empty-name": ""}[kind]
    if kind == "folder":
        Path(name).mkdir()
    if kind == "latin-1":
        Path(name).write_bytes(b'maps = ["overt\xe9ke"]\n')
    code, _, err = _bench(["--config", name], capsys)
    assert code == 2
    line = _one_error_line(err)
    assert "--config" in line
    assert (f"'{name}'" in line) if name else "empty" in line


def test_empty_file_is_no_settings(tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    Path("empty.toml").write_text("")
    code, _, err = _bench(["--config", "empty.toml"], capsys)
    assert code == 2
    assert "maps/scenarios" in _one_error_line(err)
    # ... and the flags alone make the bench.
    code, _, err = _bench(["--config", "empty.toml", "--maps", "overtake", "--planners",
                           "rrt-connect", "--seeds", "1", "--workers", "1", "--no-plots"],
                          capsys)
    assert code == 0, err
    assert len(_rows(Path("bench"))) == 1


def test_byte_order_mark_and_crlf_are_read(tmp_path, monkeypatch, capsys):
    # Read past the BOM and the CRLFs: the bad value of the last line is what is refused.
    monkeypatch.chdir(tmp_path)
    Path("b.toml").write_bytes(b"\xef\xbb\xbf# a Windows editor's file\r\n"
                               + (GOOD + "max_iterations = 0\n").replace("\n", "\r\n").encode())
    code, _, err = _bench(["--config", "b.toml"], capsys)
    assert code == 2
    line = _one_error_line(err)
    assert "max_iterations" in line and "b.toml" in line


def test_huge_file_is_read_or_refused_quickly(tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    padding = "# " + "x" * 78 + "\n"
    body = padding * 250_000  # 20 MB of comments
    Path("huge.toml").write_text(body + GOOD + "seedz = 1\n")
    code, _, err = _bench(["--config", "huge.toml"], capsys)
    assert code == 2
    line = _one_error_line(err)
    assert "huge.toml" in line and "'seedz'" in line
    assert len(line) < 1000


# --- the recorded config, fed back -----------------------------------------------------------

def _as_file_keys(recorded: dict[str, Any]) -> dict[str, Any]:
    """``bench_config.json``'s config as file keys: its bookkeeping and nulls left out."""
    return {k: v for k, v in recorded.items()
            if k not in ("map_digests", "schema") and v is not None}


@pytest.mark.parametrize("deterministic", [
    False,
    True,  # recorded max_time_s 1e6 was refused when fed back (fixed: recorded as null)
], ids=["timed", "deterministic"])
def test_recorded_config_fed_back_reproduces_the_run(
    tmp_path, monkeypatch, capsys, deterministic
):
    monkeypatch.chdir(tmp_path)
    keys = {**BASE, "maps": ["no_path", "overtake"], "seeds": 2, "reverse": deterministic,
            "out": "first"}
    if deterministic:
        keys["deterministic"] = True
    Path("b.toml").write_text(_toml(keys))
    code, _, err = _bench(["--config", "b.toml"], capsys)
    assert code == 0, err
    recorded = _config(Path("first"))
    # bench_config.json itself is no config (JSON, not TOML): one line naming it.
    code, _, err = _bench(["--config", "first/bench_config.json"], capsys)
    assert code == 2
    assert "first/bench_config.json" in _one_error_line(err)
    assert set(recorded) >= set(keys)
    Path("again.toml").write_text(_toml(_as_file_keys(recorded)))
    # The same folder: every run is already stored under the same key.
    code, stdout, err = _bench(["--config", "again.toml"], capsys)
    assert code == 0, err
    assert "(4 resumed, 0 run now" in stdout
    # Another folder: the same rows.
    code, _, err = _bench(["--config", "again.toml", "--out", "second"], capsys)
    assert code == 0, err
    assert _rows(Path("first")) == _rows(Path("second"))


# --- relative paths ------------------------------------------------------------------------------

def test_relative_paths_are_read_from_the_working_folder(tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    assert main(["maps", "--export", "exported"]) == 0
    capsys.readouterr()
    m = json.loads(Path("exported/overtake.json").read_text())
    m["name"] = "mine"
    Path("mine.json").write_text(json.dumps(m))
    sub = Path("conf")
    sub.mkdir()
    (sub / "b.toml").write_text(_toml({**BASE, "maps": ["mine.json"], "out": "rel_out"}))
    code, _, err = _bench(["--config", "conf/b.toml"], capsys)
    assert code == 0, err
    assert Path("rel_out/runs.jsonl").is_file() and not (sub / "rel_out").exists()
    rows = _rows(Path("rel_out"))
    assert [r["map"] for r in rows] == ["mine.json"]
    assert rows[0]["map_name"] == "mine"
    # A map beside the file only: not found, one line naming it, the key and the file.
    (sub / "only_here.json").write_text(json.dumps(m))
    (sub / "c.toml").write_text(_toml({**BASE, "maps": ["only_here.json"]}))
    code, _, err = _bench(["--config", "conf/c.toml"], capsys)
    assert code == 2
    line = _one_error_line(err)
    assert "maps" in line and "only_here.json" in line and "conf/c.toml" in line


def test_tilde_in_file_out_is_not_a_folder_named_tilde(tmp_path, monkeypatch, capsys):
    home = tmp_path / "home"
    home.mkdir()
    monkeypatch.setenv("HOME", str(home))
    work = tmp_path / "work"
    work.mkdir()
    monkeypatch.chdir(work)
    Path("b.toml").write_text(_toml({**BASE, "out": "~/b"}))
    code, _, err = _bench(["--config", "b.toml"], capsys)
    # Either expanded (written under $HOME) or refused; never a folder named '~' here.
    assert not (work / "~").exists()
    assert code == 2 or (home / "b" / "runs.jsonl").is_file(), err


def test_comma_separated_names_in_file_equal_a_list(tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    Path("a.toml").write_text(_toml({**BASE, "maps": "overtake, no_path,overtake", "out": "a"}))
    code, _, err = _bench(["--config", "a.toml"], capsys)
    assert code == 0, err
    assert _config(Path("a"))["maps"] == ["overtake", "no_path"]
    assert sorted(r["map"] for r in _rows(Path("a"))) == ["no_path", "overtake"]
