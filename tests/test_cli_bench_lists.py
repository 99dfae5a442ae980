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
