"""Every subcommand's --help states its exit codes, Ctrl-C's and SIGTERM's too."""

from __future__ import annotations

import re

import pytest

from rrtdrive.cli import main


@pytest.mark.parametrize("command", ["plan", "simulate", "maps", "verify", "bench"])
def test_help_states_the_exit_codes(capsys, command):
    with pytest.raises(SystemExit) as done:
        main([command, "--help"])
    assert done.value.code == 0
    text = " ".join(capsys.readouterr().out.split())
    assert re.search(r"Exit 0 when [^.]*, 1 when [^.]*, 2 on bad input; 130 on Ctrl-C, "
                     r"143 on SIGTERM\.", text), text[:600]  # fmt: skip
