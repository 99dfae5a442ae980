"""`rrtdrive bench` names its comma-separated lists when a second value stands alone."""

from __future__ import annotations

import pytest

from rrtdrive.cli import main


def test_bench_names_its_comma_separated_lists_for_a_stray_argument(capsys):
    with pytest.raises(SystemExit) as stop:
        main(["bench", "--scenarios", "a.json", "b.json"])
    assert stop.value.code == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "b.json" in err[0] and "comma-separated" in err[0]


def test_jobs_is_workers_as_the_experiment_scripts_call_it(tmp_path, capsys):
    out = tmp_path / "bench"
    code = main(["bench", "--maps", "parking_lot", "--jobs", "1", "--seeds", "1",
                 "--out", str(out), "--no-plots"])  # fmt: skip
    assert code == 0
    assert "on 1 local worker process" in capsys.readouterr().out


def test_an_unknown_controller_is_named_before_the_missing_maps(capsys):
    assert main(["bench", "--controllers", "foo"]) == 2
    assert "--controllers: unknown controller 'foo'" in capsys.readouterr().err


def test_an_empty_controller_list_is_refused(capsys):
    assert main(["bench", "--maps", "overtake", "--controllers", "", "--seeds", "1"]) == 2
    assert "controllers: give at least one controller" in capsys.readouterr().err


def test_a_misspelt_controller_gets_a_suggestion_and_a_plain_list(capsys):
    assert main(["bench", "--maps", "parking_lot", "--controllers", "pure_pursuit"]) == 2
    err = capsys.readouterr().err
    assert "unknown controller 'pure_pursuit' (did you mean 'pure-pursuit'?)" in err
    assert "choose from lqr, pure-pursuit, stanley" in err


@pytest.mark.parametrize("given", [["--controllers", "pure-pursuit"], []])
def test_controllers_given_to_a_maps_bench_get_the_note_even_the_default(
    given, tmp_path, capsys
):
    code = main(["bench", "--maps", "parking_lot", *given, "--seeds", "1",
                 "--max-iterations", "200", "--out", str(tmp_path / "b"), "--no-plots",
                 "--quiet"])  # fmt: skip
    assert code in (0, 1)
    noted = "applies to --scenarios runs; --maps runs plan only" in capsys.readouterr().err
    assert noted == bool(given)


def test_a_bad_value_in_the_config_file_names_the_file(tmp_path, capsys, monkeypatch):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "b.toml").write_text('[bench]\nseeds = "2"\nmaps = ["parking_lot"]\n')
    assert main(["bench", "--config", "b.toml"]) == 2
    assert "seeds: must be an integer in 1..100000, got '2' (in 'b.toml')" in (
        capsys.readouterr().err
    )
    # The same field given as a flag is the flag's error, not the file's.
    assert main(["bench", "--config", "b.toml", "--seeds", "0"]) == 2
    err = capsys.readouterr().err
    assert "--seeds: must be an integer" in err and "b.toml" not in err


@pytest.mark.parametrize(
    ("args", "flag"),
    [(["--maps", ""], "--maps"), (["--scenarios", ""], "--scenarios"),
     (["--maps", "", "--scenarios", ""], "--maps/--scenarios")],
)
def test_an_empty_map_list_names_the_flag_given(tmp_path, capsys, args, flag):
    assert main(["bench", *args, "--out", str(tmp_path / "b")]) == 2
    err = capsys.readouterr().err
    assert f"error: {flag}: give at least one map or one scenario" in err
    assert not (tmp_path / "b").exists()
