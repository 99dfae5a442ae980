"""A diagnosis's finding: its kind, its sentence for the user and its numbers."""

from __future__ import annotations

import enum
from dataclasses import dataclass, field

__all__ = ["Diagnosis", "DiagnosisKind"]


class DiagnosisKind(enum.Enum):
    """What makes a query hard or impossible."""

    BODY_COLLIDES = "body_collides"
    NEEDS_REVERSE = "needs_reverse"
    BOXED_IN = "boxed_in"
    TIGHT_CLEARANCE = "tight_clearance"
    NARROW_PASSAGE = "narrow_passage"
    WALLED_OFF = "walled_off"
    U_TURN = "u_turn"


@dataclass(frozen=True)
class Diagnosis:
    """One finding: its kind, a sentence for the user, and the numbers behind it.

    Attributes
    ----------
    kind : DiagnosisKind
        The constraint.
    message : str
        What it means for the user, with the measured numbers.
    numbers : dict
        The measurements (metres, or an obstacle index; -1 is the map's edge).
    """

    kind: DiagnosisKind
    message: str
    numbers: dict[str, float] = field(default_factory=dict)

    def to_json(self) -> dict[str, object]:
        """``{"kind", "message", "numbers"}`` for the plan JSON."""
        return {
            "kind": self.kind.value,
            "message": self.message,
            "numbers": {k: round(float(v), 4) for k, v in self.numbers.items()},
        }

