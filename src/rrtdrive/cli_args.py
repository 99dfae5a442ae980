"""Argument types shared by the subcommands: each turns bad text into one clear argparse error."""

from __future__ import annotations

import argparse
import math
from collections.abc import Callable

__all__ = ["int_at_least", "nonneg_int", "positive_float", "positive_int"]


def int_at_least(low: int, unit: str = "") -> Callable[[str], int]:
    """An argparse type accepting integers ``>= low`` (``unit`` is named in the error)."""
    suffix = f" ({unit})" if unit else ""

    def parse(text: str) -> int:
        try:
            value = int(text)
        except ValueError:
            raise argparse.ArgumentTypeError(
                f"expected an integer >= {low}{suffix}, got {text!r}"
            ) from None
        if value < low:
            raise argparse.ArgumentTypeError(f"expected an integer >= {low}{suffix}, got {text!r}")
        return value

    return parse


nonneg_int = int_at_least(0)
positive_int = int_at_least(1)


def positive_float(text: str) -> float:
    """An argparse type accepting finite numbers ``> 0``."""
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a number > 0, got {text!r}") from None
    if not (math.isfinite(value) and value > 0):
        raise argparse.ArgumentTypeError(f"expected a finite number > 0, got {text!r}")
    return value
