"""``python -m rrtdrive`` runs the CLI."""

from __future__ import annotations

import sys

from rrtdrive.cli import main

sys.exit(main())
