"""The end-pose fit's step: least-change Gauss-Newton with parameters held at their bounds.

Used by :mod:`rrtdrive.planning.hybrid.ramps` (its lengths must stay >= 0, its steering
angles within the limit).
"""

from __future__ import annotations

import numpy as np

__all__ = ["RIDGE", "bounded_step"]

#: The regularisation of the step's normal matrix.
RIDGE = 1e-12 * np.eye(3)


def bounded_step(
    jac: np.ndarray,
    err: np.ndarray,
    p: np.ndarray,
    weight: np.ndarray,
    lower: np.ndarray,
    upper: np.ndarray,
) -> np.ndarray | None:
    """The least-change Gauss-Newton step, with parameters at a bound held when pushed out.

    ``lower`` and ``upper`` bound ``p`` (lengths >= 0, angles within the steering limit).
    """
    free = weight.copy()
    jt = jac.T
    rhs = -err
    # The bounds test on Python floats (a handful of parameters: numpy's per-call cost is
    # most of the work); p + step, the comparisons and NaN's falsity are the same there.
    p_l, lower_l, upper_l = p.tolist(), lower.tolist(), upper.tolist()
    for _ in range(len(p) + 1):
        jw = jac * free  # free[None, :] broadcast
        try:
            lam = np.linalg.solve(jw @ jt + RIDGE, rhs)
        except np.linalg.LinAlgError:
            return None
        step = free * (jt @ lam)
        moves = zip(p_l, step.tolist(), lower_l, upper_l, free.tolist(), strict=True)
        out = [
            i for i, (x, d, lo, hi, f) in enumerate(moves)
            if f > 0 and ((x + d < lo and d < 0) or (x + d > hi and d > 0))
        ]  # fmt: skip
        if not out:
            return step
        # Hold those that would cross at their bound (moved exactly onto it next round).
        free[out] = 0.0
    return None
