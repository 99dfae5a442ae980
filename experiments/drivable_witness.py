"""Is there a drivable forward path where OMPL's instant-steering Dubins car gets through?

Usage (needs OMPL for the first guesses: ``pip install "ompl>=2.0.1"``)::

    python experiments/drivable_witness.py --query start:81 --out results/drivable_witness

For a forward-only random query of ``experiments/coverage.py`` (``parking_lot``, the set
of ``--seed``) it looks, by local optimisation, for the start of a path the car could
drive: curvature kappa(s) piecewise linear on knots ``--knot`` m apart over the first
``--window`` metres from the start pose, ``|kappa| <= kappa_max`` and, by the rule of
the row, ``|d delta / ds| <= --sharpness`` rad/m (``delta = atan(L kappa)``). It
maximises the least separating-axis gap between the body and every obstacle and the
map's edge along it (scipy's SLSQP): where that gap is negative it is exactly the
depth of the worst overlap; where positive, a lower bound on the clearance, which
shapely then measures exactly (``CollisionChecker.body_clearance``). The window's end
must lie within ``--end-tol`` m of the first guess's position at ``--window`` m, so that
the way on is the first guess's.

First guesses: OMPL's Dubins RRT paths for the query (as ``coverage.py`` plans them, our
exact body test as validity checker, no clearance kept), OMPL seeds ``index + 1000 k``
for ``k < --ompl-tries``. The rows:

- ``straight wheels``: the wheels straight at the start, the sharpness bound after (what
  our planners' paths guarantee), from every first guess;
- ``wheels set at the start``: the wheels turned to any angle before the car moves
  (steering at standstill), the bound after; from the first guess;
- ``instant steering``: no sharpness bound (OMPL's car), from the first guess: a check
  that the optimisation finds a clear path where one is known to exist.

A local optimum is no proof: a negative gap from several first guesses is evidence, not
a proof, that no such path exists. Writes ``OUT/drivable_witness.{json,md}``.
"""

from __future__ import annotations

import argparse
import math
import sys
import time
from pathlib import Path as FsPath
from typing import Any

import numpy as np

sys.path.insert(0, str(FsPath(__file__).resolve().parent))
import coverage as cov  # noqa: E402  (the sibling script)
from forward_misses import _item  # noqa: E402
from results_io import command, machine, out_folder, run_main, write_results  # noqa: E402

from rrtdrive.cli_args import positive_float, positive_int  # noqa: E402
from rrtdrive.vehicle import footprint_corners  # noqa: E402

#: Integration substeps per knot interval (0.05 m at the default knot spacing).
SUB = 5
#: The rows' steering rules: (the first knot's curvature free?, sharpness bound on?).
RULES = {
    "straight wheels": (False, True),
    "wheels set at the start": (True, True),
    "instant steering": (True, False),
}


def rectangles(m: Any, box: tuple[float, float, float, float]) -> np.ndarray:
    """Corners ``(K, 4, 2)`` of the obstacles whose centre lies in ``box``."""
    x0, y0, x1, y1 = box
    keep = [o.corners() for o in m.obstacles if x0 <= o.center[0] <= x1 and y0 <= o.center[1] <= y1]
    return np.asarray(keep, dtype=float).reshape(-1, 4, 2)


def _normals(corners: np.ndarray) -> np.ndarray:
    """The two edge normals of each rectangle ``(..., 4, 2)``: ``(..., 2, 2)``, unit."""
    e = corners[..., 1:3, :] - corners[..., 0:2, :]
    n = np.stack([-e[..., 1], e[..., 0]], axis=-1)
    return n / np.linalg.norm(n, axis=-1, keepdims=True)


def gaps(poses: np.ndarray, obstacles: np.ndarray, bounds: tuple[float, ...], vehicle: Any
         ) -> np.ndarray:  # fmt: skip
    """The least separating-axis gap of each pose's body to the obstacles and the bounds."""
    body = footprint_corners(poses, vehicle)  # (M, 4, 2)
    xmin, ymin, xmax, ymax = bounds
    edge = np.minimum.reduce([
        body[..., 0].min(1) - xmin, xmax - body[..., 0].max(1),
        body[..., 1].min(1) - ymin, ymax - body[..., 1].max(1),
    ])  # fmt: skip
    if not len(obstacles):
        return edge
    m, k = len(body), len(obstacles)
    best = np.full((m, k), -np.inf)
    for axes in (np.broadcast_to(_normals(obstacles)[None], (m, k, 2, 2)),
                 np.broadcast_to(_normals(body)[:, None], (m, k, 2, 2))):  # fmt: skip
        for a in range(2):
            n = axes[:, :, a, :]
            pb = np.einsum("mkd,mcd->mkc", n, body)
            po = np.einsum("mkd,kcd->mkc", n, obstacles)
            best = np.maximum(best, np.maximum(po.min(-1) - pb.max(-1), pb.min(-1) - po.max(-1)))
    return np.minimum(best.min(1), edge)


def integrate(kappa: np.ndarray, start: tuple[float, float, float], knot: float) -> np.ndarray:
    """Poses ``(SUB * (len(kappa) - 1) + 1, 3)`` along curvature linear between the knots."""
    frac = (np.arange(SUB) + 0.5) / SUB
    ks = (kappa[:-1, None] * (1.0 - frac) + kappa[1:, None] * frac).ravel()
    ds = knot / SUB
    yaw = start[2] + np.concatenate([[0.0], np.cumsum(ks * ds)])
    mid = 0.5 * (yaw[:-1] + yaw[1:])
    x = start[0] + np.concatenate([[0.0], np.cumsum(np.cos(mid) * ds)])
    y = start[1] + np.concatenate([[0.0], np.cumsum(np.sin(mid) * ds)])
    return np.stack([x, y, yaw], axis=1)


def guess_kappa(path: np.ndarray, count: int, knot: float) -> tuple[np.ndarray, np.ndarray]:
    """The first guess's curvature at ``count`` knots and its position at the window's end."""
    ds = np.hypot(*np.diff(path[:, :2], axis=0).T)
    s = np.concatenate([[0.0], np.cumsum(ds)])
    kappa = np.gradient(np.unwrap(path[:, 2]), s)
    knots = np.arange(count) * knot
    end = np.array([np.interp(knots[-1], s, path[:, 0]), np.interp(knots[-1], s, path[:, 1])])
    return np.interp(knots, s, kappa), end


def optimise(problem: Any, m: Any, guess: np.ndarray, rule: str, args: argparse.Namespace
             ) -> dict[str, Any]:  # fmt: skip
    """The best least gap found under ``rule`` from the first guess ``guess`` (path rows)."""
    from scipy.optimize import minimize

    v = m.vehicle
    kmax, wheelbase = 1.0 / v.min_turning_radius, v.wheelbase
    free_first, bounded = RULES[rule]
    count = int(round(args.window / args.knot)) + 1
    k0, end = guess_kappa(guess, count, args.knot)
    start = problem.start.as_tuple()
    # The obstacles near the window's part of the guess (all of them made it 5x slower).
    along = np.concatenate([[0.0], np.cumsum(np.hypot(*np.diff(guess[:, :2], axis=0).T))])
    pts = guess[along <= args.window + args.end_tol]
    box = (pts[:, 0].min() - 8, pts[:, 1].min() - 8, pts[:, 0].max() + 8, pts[:, 1].max() + 8)
    obstacles = rectangles(m, box)
    step = args.sharpness * args.knot  # the steering angle's change per knot interval

    # The guess made to keep the rule (the curvature walked toward it within the bound).
    k = np.clip(k0, -kmax, kmax)
    if not free_first:
        k[0] = 0.0
    if bounded:
        for i in range(1, count):
            lo, hi = math.tan(math.atan(wheelbase * k[i - 1]) - step), math.tan(
                math.atan(wheelbase * k[i - 1]) + step)
            k[i] = np.clip(k[i], lo / wheelbase, hi / wheelbase)
    least = lambda z: gaps(integrate(z[:-1], start, args.knot), obstacles, m.bounds, v)  # noqa: E731
    z0 = np.append(k, min(float(least(np.append(k, 0.0)).min()), 0.0) - 0.01)
    cons = [{"type": "ineq", "fun": lambda z: least(z) - z[-1]},
            {"type": "ineq", "fun": lambda z: args.end_tol**2 - np.sum(
                (integrate(z[:-1], start, args.knot)[-1, :2] - end) ** 2, keepdims=True)}]
    if bounded:
        cons.append({"type": "ineq",
                     "fun": lambda z: step - np.abs(np.diff(np.arctan(wheelbase * z[:-1])))})
    limits = [(-kmax, kmax)] * count + [(-5.0, 5.0)]
    if not free_first:
        limits[0] = (0.0, 0.0)
    t0 = time.perf_counter()
    res = minimize(lambda z: -z[-1], z0, jac=lambda z: np.append(np.zeros(count), -1.0),
                   bounds=limits, constraints=cons, method="SLSQP",
                   options={"maxiter": args.iterations, "ftol": 1e-10})  # fmt: skip
    z = res.x
    poses = integrate(z[:-1], start, args.knot)
    g = least(z)
    worst = int(np.argmin(g))
    exact = min(problem.checker.body_clearance(p) for p in poses)
    delta = np.arctan(wheelbase * z[:-1])
    return {
        "rule": rule, "optimiser": str(res.message), "iterations": int(res.nit),
        "time_s": time.perf_counter() - t0,
        "least_gap_m": float(g[worst]), "at": [round(float(c), 3) for c in poses[worst]],
        "at_s_m": worst * args.knot / SUB,
        "exact_clearance_m": float(exact),
        "max_kappa": float(np.abs(z[:-1]).max()),
        "first_kappa": float(z[0]),
        "max_sharpness": float(np.abs(np.diff(delta)).max() / args.knot),
        "end_off_m": float(np.hypot(*(poses[-1, :2] - end))),
    }  # fmt: skip


def report(payload: dict[str, Any]) -> str:
    """The markdown page."""
    lines = [
        f"# A drivable forward path for `{payload['query']}`?",
        "",
        f"Command: `{payload['command']}`  ",
        f"{payload['machine']}; wall time {payload['wall_time_s']:.0f} s. Window "
        f"{payload['window_m']:g} m, knots {payload['knot_m']:g} m apart, sharpness bound "
        f"{payload['sharpness']:g} rad/m, kappa_max {payload['kappa_max']:.4f} 1/m.",
        "",
        "| first guess (OMPL Dubins RRT) | rule | least gap [m] | at s [m] | exact "
        "clearance [m] | first kappa [1/m] | max sharpness [rad/m] | end off [m] | optimiser |",
        "|---|---|---|---|---|---|---|---|---|",
    ]
    for r in payload["rows"]:
        lines.append(
            f"| seed {r['ompl_seed_index']}, {r['guess_length_m']:.1f} m | {r['rule']} | "
            f"{r['least_gap_m']:.4f} | {r['at_s_m']:.2f} | {r['exact_clearance_m']:.4f} | "
            f"{r['first_kappa']:.4f} | {r['max_sharpness']:.3f} | {r['end_off_m']:.2f} | "
            f"{r['optimiser']} |"
        )
    lines += [
        "",
        "A negative least gap is the depth of the worst overlap at the optimiser's answer "
        "(a local optimum: evidence, not a proof). The exact clearance is shapely's, 0 "
        "where the body touches or overlaps. End off: how far the window's end lies from "
        "the first guess's (at most --end-tol).",
        "",
    ]
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--query", default="start:81", help="goal:N or start:N (default start:81)")
    ap.add_argument("--seed", type=int, default=1, help="the random set's seed (default 1)")
    ap.add_argument("--count", type=positive_int, default=100, help="poses per set (default 100)")
    ap.add_argument("--window", type=positive_float, default=36.0,
                    help="metres of path optimised from the start (default: %(default)s)")
    ap.add_argument("--knot", type=positive_float, default=0.25,
                    help="knot spacing of the curvature, metres (default: %(default)s)")
    ap.add_argument("--sharpness", type=positive_float, default=0.2,
                    help="bound on |d delta/ds|, rad/m (default: %(default)s, "
                    "0.4 rad/s at 2 m/s)")
    ap.add_argument("--end-tol", type=positive_float, default=1.0,
                    help="how far the window's end may lie from the first guess's, metres "
                    "(default: %(default)s)")
    ap.add_argument("--iterations", type=positive_int, default=300,
                    help="SLSQP iterations per row (default: %(default)s)")
    ap.add_argument("--ompl-tries", type=positive_int, default=4,
                    help="OMPL seeds tried for first guesses (default: %(default)s)")
    ap.add_argument("--out", type=out_folder, default="results/drivable_witness",
                    help="directory for drivable_witness.json and .md (default: %(default)s)")
    args = ap.parse_args(argv)
    if cov.availability("ompl-dubins-rrt") is not None:
        print("drivable_witness: needs OMPL: pip install \"ompl>=2.0.1\"", file=sys.stderr)
        return 2
    try:
        item = _item(args.query, args.seed, args.count)
    except ValueError as err:
        ap.error(str(err))
    m, problem = cov._problem(item)
    t0 = time.perf_counter()
    rows: list[dict[str, Any]] = []
    first = True
    for k in range(args.ompl_tries):
        index = item["index"] + 1000 * k
        _, _, length, path = cov.solve_ompl(problem, index, "ompl-dubins-rrt", 10.0)
        if path is None:
            print(f"OMPL seed {index}: no path in 10 s", file=sys.stderr)
            continue
        for rule in RULES if first else ("straight wheels",):
            print(f"OMPL seed {index} ({length:.1f} m): {rule} ...", file=sys.stderr, flush=True)
            row = optimise(problem, m, path.samples[:, :3], rule, args)
            rows.append({"ompl_seed_index": index, "guess_length_m": length, **row})
            print(f"  least gap {row['least_gap_m']:.4f} m", file=sys.stderr)
        first = False
    payload = {
        "command": command("drivable_witness.py", argv), "machine": machine(),
        "query": args.query, "pose": item["pose"], "window_m": args.window,
        "knot_m": args.knot, "sharpness": args.sharpness,
        "kappa_max": 1.0 / m.vehicle.min_turning_radius,
        "wall_time_s": time.perf_counter() - t0, "rows": rows,
    }  # fmt: skip
    print(write_results(args.out, "drivable_witness", payload, report))
    return 0


if __name__ == "__main__":
    raise SystemExit(run_main(main))
