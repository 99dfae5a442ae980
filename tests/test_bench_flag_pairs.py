"""Each on/off key of a bench's TOML file can be turned back off on the command line.

``reverse = true`` or ``deterministic = true`` in a ``--config`` file used to be
permanent for that file: the flags could only turn them on (an audit).
"""

from __future__ import annotations

import pytest

from rrtdrive.bench.cli_bench import config_from_args
from rrtdrive.cli import build_parser, main

TOML = """\
maps = ["parking_lot"]
reverse = true
deterministic = true
plots = false
ray = "auto"
"""


def _config(tmp_path, *flags):
    f = tmp_path / "bench.toml"
    f.write_text(TOML)
    args = build_parser().parse_args(["bench", "--config", str(f), *flags])
    return config_from_args(args)


def test_the_file_alone_sets_its_keys(tmp_path):
    cfg = _config(tmp_path)
    assert (cfg.reverse, cfg.deterministic, cfg.plots, cfg.ray) == (True, True, False, "auto")


@pytest.mark.parametrize(
    ("flag", "field", "value"),
    [
        ("--no-reverse", "reverse", False),
        ("--no-deterministic", "deterministic", False),
        ("--plots", "plots", True),
        ("--no-ray", "ray", None),
    ],
)
def test_a_flag_overrides_the_files_switch(tmp_path, flag, field, value):
    cfg = _config(tmp_path, flag)
    assert getattr(cfg, field) == value
    # ... and only that one.
    others = {"reverse": True, "deterministic": True, "plots": False, "ray": "auto"}
    del others[field]
    assert {k: getattr(cfg, k) for k in others} == others


def test_no_deterministic_lets_max_time_in(tmp_path):
    # deterministic = true refuses --max-time; turning it off on the command line takes it.
    cfg = _config(tmp_path, "--no-deterministic", "--max-time", "2.5")
    assert (cfg.deterministic, cfg.max_time_s) == (False, 2.5)


def test_deterministic_from_the_file_still_refuses_max_time(tmp_path, capsys):
    f = tmp_path / "bench.toml"
    f.write_text(TOML)
    assert main(["bench", "--config", str(f), "--max-time", "2"]) == 2
    assert "--max-time" in capsys.readouterr().err


def test_ray_and_no_ray_are_one_or_the_other(capsys):
    with pytest.raises(SystemExit) as exc:
        build_parser().parse_args(["bench", "--ray", "auto", "--no-ray"])
    assert exc.value.code == 2
    assert "--no-ray" in capsys.readouterr().err


def test_without_a_file_the_defaults_hold():
    cfg = config_from_args(build_parser().parse_args(["bench", "--maps", "parking_lot"]))
    assert (cfg.reverse, cfg.deterministic, cfg.plots, cfg.ray) == (False, False, True, None)
