"""A Ctrl-C or SIGTERM while a C extension initialises is an interrupt, not a traceback.

Python reports a signal inside an extension module's initialisation as ``ImportError:
initialization failed`` caused by the KeyboardInterrupt (matplotlib's ``_image`` under
load, seen in a full test run: exit 1 and a 40-line traceback instead of 130).
"""

from __future__ import annotations

import pytest

from rrtdrive import cli_maps
from rrtdrive.cli import main
from rrtdrive.cli_signals import Terminated


def _import_failing_with(interrupt: KeyboardInterrupt):
    def run(args):
        try:
            raise interrupt
        except KeyboardInterrupt as exc:
            raise ImportError("initialization failed") from exc

    return run


@pytest.mark.parametrize(
    ("interrupt", "code", "line"),
    [(KeyboardInterrupt(), 130, "rrtdrive: interrupted"),
     (Terminated(), 143, "rrtdrive: terminated")],
)  # fmt: skip
def test_an_interrupted_import_is_the_interrupt(monkeypatch, capsys, interrupt, code, line):
    monkeypatch.setattr(cli_maps, "_cmd_maps", _import_failing_with(interrupt))
    if isinstance(interrupt, Terminated):  # as the SIGTERM handler marks it
        monkeypatch.setattr("rrtdrive.cli.sigterm_received", lambda: True)
    assert main(["maps"]) == code
    err = capsys.readouterr().err
    assert err.strip() == line and "Traceback" not in err


def test_an_import_error_of_its_own_is_not_taken_for_an_interrupt(monkeypatch):
    def run(args):
        raise ImportError("no module named 'foo'")

    monkeypatch.setattr(cli_maps, "_cmd_maps", run)
    with pytest.raises(ImportError, match="foo"):
        main(["maps"])
