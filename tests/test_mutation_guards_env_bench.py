"""Mutation guards: the gym env (rrtdrive.envs) and the bench's statistics, grid and store.

Each test pins a documented behaviour that a small mutation of the code changed without
any other test failing (the audit that found them names the mutant in each docstring).
References are independent where possible: scipy.stats for intervals, closed-form values
derived in comments, gymnasium's semantics of ``terminated`` and ``truncated``.
"""

from __future__ import annotations

import json
import math
from pathlib import Path as FsPath
from types import SimpleNamespace
from typing import Any

import numpy as np
import pytest
import scipy.stats
from hypothesis import given, settings
from hypothesis import strategies as st

from rrtdrive.bench.grid import BenchConfig, expand
from rrtdrive.bench.store import ResultStore, row_key
from rrtdrive.bench.summary import summarise_rows, to_markdown
from rrtdrive.controllers import PathProjector, SpeedConfig
from rrtdrive.envs.action import RESIDUAL_FADE_M, CommandLimits, ResidualMixer, action_command
from rrtdrive.envs.config import DriveEnvConfig
from rrtdrive.envs.drive_env import DriveEnv
from rrtdrive.envs.observation import OBS_CLIP, ObservationLayout
from rrtdrive.envs.reference_speed import Relaunch, stop_line_speed
from rrtdrive.envs.reward import RewardWeights, state_terms
from rrtdrive.envs.seed_draw import start_drawn_episode
from rrtdrive.envs.segments import starts_next_segment
from rrtdrive.stats import BOOTSTRAP_SEED, Interval, describe, wilson_interval
from rrtdrive.types import InputError, Path

# ----------------------------------------------------------------------------- stats


def _scipy_wilson(k: int, n: int) -> tuple[float, float]:
    ci = scipy.stats.binomtest(k, n).proportion_ci(confidence_level=0.95, method="wilson")
    return (ci.low, ci.high)


@pytest.mark.parametrize(("k", "n"), [(1, 4), (3, 10), (0, 5), (9, 9)])
def test_a_rate_gets_the_wilson_interval_of_its_successes(k: int, n: int) -> None:
    """describe(rate=True) is Wilson's interval of k successes (mutant: n - k)."""
    s = describe([1.0] * k + [0.0] * (n - k), rate=True)
    assert s.mean == k / n
    assert (s.ci_low, s.ci_high) == pytest.approx(_scipy_wilson(k, n), abs=1e-12)


def test_wilson_refuses_more_successes_than_trials() -> None:
    """Successes must lie in [0, n] (mutant: the upper bound dropped)."""
    with pytest.raises(InputError, match="successes"):
        wilson_interval(11, 10)


@settings(max_examples=15, deadline=None)
@given(st.lists(st.floats(0.0, 1e3, allow_nan=False), min_size=2, max_size=12))
def test_the_bootstrap_interval_is_scipys_percentile_bootstrap_of_the_mean(
    values: list[float],
) -> None:
    """The documented bootstrap: percentile, of the mean, 1999 resamples, fixed seed, 95 %.

    Mutants: BCa or median or another resample count or confidence level.
    """
    s = describe(values, nonnegative=True)
    x = np.asarray(values)
    if np.all(x == x[0]):
        assert (s.ci_low, s.ci_high) == (x[0], x[0])  # every resample's mean is x[0]
        return
    res = scipy.stats.bootstrap(
        (x,),
        np.mean,
        n_resamples=1999,
        confidence_level=0.95,
        method="percentile",
        rng=np.random.default_rng(BOOTSTRAP_SEED),
    )
    assert s.interval is Interval.BOOTSTRAP
    assert (s.ci_low, s.ci_high) == pytest.approx(
        (res.confidence_interval.low, res.confidence_interval.high), rel=1e-12
    )


def test_a_constant_signed_sample_has_a_point_interval() -> None:
    """Std 0: Student's t half-width t * 0 / sqrt(n) = 0 (mutant: scipy's NaN for scale 0)."""
    s = describe([-2.0, -2.0, -2.0])
    assert s.interval is Interval.T and (s.ci_low, s.ci_high) == (-2.0, -2.0)


# ----------------------------------------------------------------------------- summary


def _plan_rows(metric: str, values: list[Any]) -> list[dict[str, Any]]:
    return [
        {
            "kind": "plan",
            "map": "m",
            "planner": "p",
            "controller": None,
            "seed": i,
            "config_hash": "h",
            "status": "solved",
            "success": True,
            metric: v,
        }
        for i, v in enumerate(values)
    ]


def test_a_signed_metric_gets_students_t_and_a_nonnegative_one_the_bootstrap() -> None:
    """progress_m is signed (t interval, may go below 0); nodes a bootstrap one.

    Mutant: every metric bootstrapped, so a signed metric's interval never left its range.
    """
    vals = [-3.0, 1.0, 2.0, 8.0]
    (g,) = summarise_rows(_plan_rows("progress_m", vals))
    s = g.stats["progress_m"]
    x = np.asarray(vals)
    lo, hi = scipy.stats.t.interval(0.95, len(x) - 1, loc=x.mean(), scale=scipy.stats.sem(x))
    assert s.interval is Interval.T
    assert (s.ci_low, s.ci_high) == pytest.approx((lo, hi), rel=1e-12)
    (g2,) = summarise_rows(_plan_rows("nodes", [3, 1, 2, 8]))
    assert g2.stats["nodes"].interval is Interval.BOOTSTRAP


def test_a_nan_metric_value_is_skipped_like_none() -> None:
    """A non-finite value is not summarised (mutant: a NaN made the mean NaN)."""
    (g,) = summarise_rows(_plan_rows("length_m", [10.0, float("nan"), 12.0]))
    s = g.stats["length_m"]
    assert s.n == 2 and s.mean == 11.0


def test_a_metric_that_is_a_number_in_some_rows_is_not_a_rate() -> None:
    """A metric is a rate only if every value is a boolean (mutant: any boolean made it one).

    Mean of [2.5, 1, 0] = 7 / 6, a number's interval, not Wilson's (which refused 3.5 of 3).
    """
    (g,) = summarise_rows(_plan_rows("x", [2.5, True, False]))
    s = g.stats["x"]
    assert not s.rate and s.mean == pytest.approx(7.0 / 6.0)


def test_markdown_shows_the_interval_of_two_runs_and_of_a_rate() -> None:
    """Two runs have a std and an interval; a rate shows its Wilson interval.

    Mutants: the ``±`` cell only from three runs; the rate cell without its interval.
    """
    rows = _plan_rows("length_m", [10.0, 12.0])
    rows[1]["success"] = True
    (g,) = summarise_rows(rows)
    md = to_markdown([g])
    assert "11.00 ± 1.41 [" in md  # std of [10, 12] = sqrt(2)
    rate_rows = [{**r, "success": i == 0} for i, r in enumerate(_plan_rows("x", [1, 2, 3, 4]))]
    (gr,) = summarise_rows(rate_rows)
    lo, hi = _scipy_wilson(1, 4)
    assert f"25% [{lo:.0%}, {hi:.0%}]" in to_markdown([gr])


# ----------------------------------------------------------------------------- grid


def test_every_budget_and_controller_is_in_the_run_key() -> None:
    """Run keys differ with max_iterations and with the controller (resumption).

    Mutants: either dropped from the hashed payload, so a changed budget or another
    controller found its runs "already stored".
    """
    base = BenchConfig(maps=("overtake",), planners=("rrt",), seeds=2)
    other = BenchConfig(maps=("overtake",), planners=("rrt",), seeds=2, max_iterations=999)
    assert not {s.key for s in expand(base)} & {s.key for s in expand(other)}
    two = BenchConfig(
        scenarios=("overtake",), planners=("rrt",), controllers=("pure-pursuit", "stanley"), seeds=2
    )
    specs = expand(two)
    assert len({s.key for s in specs}) == len(specs) == two.runs == 4


def test_the_map_digest_covers_the_car() -> None:
    """One map with another car is another configuration (mutant: geometry only)."""
    import dataclasses

    from rrtdrive.bench.grid import map_digest
    from rrtdrive.maps import builtin_map

    m = builtin_map("overtake")
    car = dataclasses.replace(m.vehicle, wheelbase=m.vehicle.wheelbase * 1.1)
    other = dataclasses.replace(m, vehicle=car)
    assert map_digest("overtake", m)[0] != map_digest("overtake", other)[0]


def test_repeated_names_are_one_row_and_seeds_start_at_zero() -> None:
    """A scenario or controller named twice is one row; seeds are 0 .. seeds-1.

    Mutants: names not de-duplicated (two runs with one key: the second "already
    stored"); seeds 1 .. seeds (the BenchConfig docs: ``0 ... seeds-1``).
    """
    cfg = BenchConfig(
        scenarios=("overtake", "overtake"),
        planners=("rrt",),
        controllers=("stanley", "stanley,stanley"),
        seeds=3,
    )
    specs = expand(cfg)
    assert (cfg.scenarios, cfg.controllers) == (("overtake",), ("stanley",))
    assert len({s.key for s in specs}) == len(specs) == cfg.runs == 3
    assert sorted(s.seed for s in specs) == [0, 1, 2]


def test_one_map_content_under_two_names_is_refused(tmp_path: FsPath) -> None:
    """Two names of one map would share run keys (mutant: the check dropped)."""
    from rrtdrive.maps import builtin_map, save_map

    a, b = tmp_path / "a.json", tmp_path / "b.json"
    save_map(builtin_map("overtake"), a)
    save_map(builtin_map("overtake"), b)
    with pytest.raises(InputError, match="same map"):
        BenchConfig(maps=(str(a), str(b)), planners=("rrt",), seeds=1)


# ----------------------------------------------------------------------------- store


def test_a_file_of_only_a_partial_line_is_cut_and_the_next_row_is_kept(
    tmp_path: FsPath,
) -> None:
    """A killed first write leaves no newline at all: all of it is cut.

    Mutant: kept, so the next row was glued onto it and lost as a malformed line.
    """
    (tmp_path / "runs.jsonl").write_text('{"config_hash": "h", "se')
    with ResultStore(tmp_path) as s:
        s.append({"config_hash": "h", "seed": 0})
    with ResultStore(tmp_path) as s:
        assert s.done_keys() == {("h", 0)}
        assert [r["seed"] for r in s.rows()] == [0]


def test_a_malformed_line_in_the_middle_loses_no_later_run(tmp_path: FsPath) -> None:
    """Rows after a malformed line are still read (mutant: reading stopped there)."""
    lines = [
        json.dumps({"config_hash": "h", "seed": 0}),
        "{not json",
        json.dumps({"config_hash": "h", "seed": 1}),
    ]
    (tmp_path / "runs.jsonl").write_text("\n".join(lines) + "\n")
    with ResultStore(tmp_path) as s:
        assert s.done_keys() == {("h", 0), ("h", 1)}


def test_a_boolean_seed_is_not_a_run_key() -> None:
    """``True`` is an int in Python but not a seed (mutant: (h, True) was a key)."""
    assert row_key({"config_hash": "h", "seed": True}) is None
    assert row_key({"config_hash": "h", "seed": 1}) == ("h", 1)


# ----------------------------------------------------------------------------- action

LIM = CommandLimits(a_min=-4.0, a_max=2.0, steer_limit=0.4)


@pytest.mark.parametrize(
    ("action", "expected"),
    [([5.0, -5.0], (2.0, -0.4)), ([-5.0, 5.0], (-4.0, 0.4)), ([-1.0, -1.0], (-4.0, -0.4))],
)
def test_an_action_outside_the_box_is_clipped_to_it(
    action: list[float], expected: tuple[float, float]
) -> None:
    """Each entry is clipped to [-1, 1] first: a_max, |a_min|, steer_limit at most.

    Mutants: an end of either clip dropped.
    """
    assert action_command(action, LIM) == pytest.approx(expected)


def _ctrl(remaining: float, at_stop: bool = False) -> SimpleNamespace:
    return SimpleNamespace(
        remaining=remaining, at_stop=at_stop, steer_window=None, steer_wanted=0.0
    )


def _mixer() -> ResidualMixer:
    # jerk limits wide enough not to bind: the acceleration is the plain sum.
    return ResidualMixer(LIM, SpeedConfig(jerk_max=1e6, jerk_brake_max=1e6), 0.05)


def test_the_residual_fades_out_over_the_last_metre() -> None:
    """At ``remaining`` < RESIDUAL_FADE_M the residual is scaled by remaining / fade.

    0.25 m left of 1 m: a steering residual of 0.2 rad adds 0.05 rad (mutant: no fade).
    """
    rem = 0.25 * RESIDUAL_FADE_M
    _, steer = _mixer().command(_ctrl(rem), 0.0, 0.1, 0.0, 0.2)
    assert steer == pytest.approx(0.1 + 0.25 * 0.2)
    _, steer = _mixer().command(_ctrl(5.0), 0.0, 0.1, 0.0, 0.2)
    assert steer == pytest.approx(0.3)


def test_the_steering_sum_is_clipped_to_the_steering_limit() -> None:
    """Controller 0.35 rad plus residual 0.2 rad: 0.4, the limit (mutant: 0.55)."""
    _, steer = _mixer().command(_ctrl(5.0), 0.0, 0.35, 0.0, 0.2)
    assert steer == pytest.approx(LIM.steer_limit)
    _, steer = _mixer().command(_ctrl(5.0), 0.0, -0.35, 0.0, -0.2)
    assert steer == pytest.approx(-LIM.steer_limit)


def test_past_the_end_of_the_path_the_controller_acts_alone() -> None:
    """Remaining <= 0 (braking past the stop): the controller's command exactly.

    Mutant: only ``at_stop`` handed over, so a residual still pushed past the goal.
    """
    assert _mixer().command(_ctrl(-0.3), -1.0, 0.1, 2.0, 0.4) == (-1.0, 0.1)


# ----------------------------------------------------------------------------- observation


def _straight(length: float = 50.0) -> PathProjector:
    xs = np.linspace(0.0, length, 201)
    return PathProjector(Path(np.column_stack([xs, 0 * xs, 0 * xs, 0 * xs]), np.zeros((0, 2))))


def _ego(x: float, y: float, yaw: float, speed: float = 0.0, steer: float = 0.0) -> Any:
    return SimpleNamespace(rear=(x, y, yaw), speed=speed, steer=steer, heading=yaw)


def _observe(ego: Any, lay: ObservationLayout | None = None, **kw: Any) -> np.ndarray:
    lay = lay or ObservationLayout(3, 2.0, 0, 50.0, 0.5)
    obs, _ = lay.observe(ego, _straight(), lambda s: 3.0, [], **kw)
    return obs


def test_reference_points_are_in_the_ego_frame_ahead_of_the_projection() -> None:
    """Path along +x; ego at (10, 1) facing +x: points at x = 2, 4, 6 and y = -1.

    The first point is one spacing ahead (mutant: at the projection); the ego frame's
    y axis points left, so the path 1 m to the right is at y = -1 (mutant: sign).
    """
    obs = _observe(_ego(10.0, 1.0, 0.0))
    assert obs[2] == pytest.approx(1.0)  # left of the path: cte > 0
    ref = obs[6:12].reshape(3, 2)
    assert ref[:, 0] == pytest.approx([2.0, 4.0, 6.0])
    assert ref[:, 1] == pytest.approx([-1.0, -1.0, -1.0])


def test_reference_points_turn_with_the_car() -> None:
    """Ego at (10, 0) facing +y (left of the path's +x): the path ahead is on its right.

    A point dx = 2 m along +x is 0 m ahead and 2 m to the right: (0, -2) in the ego
    frame (x forward, y left). Mutant: the lateral rotation's sign, (0, +2).
    """
    obs = _observe(_ego(10.0, 0.0, math.pi / 2))
    assert obs[6:12] == pytest.approx([0.0, -2.0, 0.0, -4.0, 0.0, -6.0], abs=1e-9)


def test_a_reverse_segments_curvature_is_that_of_the_steering() -> None:
    """In reverse the projector is the mirror, whose curvature is the negated one.

    Mirror of a left arc of radius 10 (kappa +0.1): the path asks for kappa -0.1 in
    reverse (tan(delta) / L, the steering); forward the same arc gives +0.1.
    Mutant: the mirror's kappa observed as is in reverse.
    """
    th = np.linspace(0.0, 2.0, 201)
    r = 10.0
    arc = np.column_stack([r * np.sin(th), r * (1 - np.cos(th)), th, 0 * th + 1 / r])
    proj = PathProjector(Path(arc, np.zeros((0, 2))))
    lay = ObservationLayout(3, 2.0, 0, 50.0, 0.5)
    ego = _ego(0.0, 0.0, 0.0)
    fwd, _ = lay.observe(ego, proj, lambda s: 1.0, [], gear=1)
    rev, _ = lay.observe(
        _ego(0.0, 0.0, math.pi),
        PathProjector(Path(arc, np.zeros((0, 2)))),
        lambda s: 1.0,
        [],
        gear=-1,
    )
    assert fwd[12:15] == pytest.approx([0.1] * 3)
    assert rev[12:15] == pytest.approx([-0.1] * 3)


def test_behind_the_start_the_points_start_at_the_path_start() -> None:
    """Ego 4 m before the start: points at s = 2, 4, 6, i.e. 6, 8, 10 m ahead.

    Mutant: the projection's negative s used, so the points started behind the path.
    """
    obs = _observe(_ego(-4.0, 0.0, 0.0))
    assert obs[6:12].reshape(3, 2)[:, 0] == pytest.approx([6.0, 8.0, 10.0])


def test_heading_error_spans_minus_pi_to_pi() -> None:
    """A car facing against the path: heading error 3 rad observed as 3 rad.

    Mutant: a tighter Box bound clipped it (the docs: in [-pi, pi]).
    """
    obs = _observe(_ego(10.0, 0.0, 3.0))
    assert obs[3] == pytest.approx(3.0)
    obs = _observe(_ego(10.0, 0.0, -3.0))
    assert obs[3] == pytest.approx(-3.0)


def test_steering_and_reverse_speed_are_observed_with_their_sign() -> None:
    """Right steering (< 0) and a reverse segment's v_ref (< 0) keep their sign.

    Mutants: a Box bound at 0 that clipped them.
    """
    lay = ObservationLayout(3, 2.0, 0, 50.0, 0.5)
    obs = _observe(_ego(10.0, 0.0, math.pi, steer=-0.3), lay, gear=-1)
    assert obs[1] == pytest.approx(-0.3)
    assert obs[4] == pytest.approx(-3.0)
    assert lay.low[1] == -lay.high[1] == pytest.approx(-0.5)


def test_distances_beyond_the_box_are_clipped_into_it() -> None:
    """A car 5 km off the path: cte clipped to -OBS_CLIP, the vector inside the Box.

    Mutant: no clip, an observation outside observation_space.
    """
    lay = ObservationLayout(3, 2.0, 0, 50.0, 0.5)
    obs = _observe(_ego(10.0, -5000.0, 0.0), lay)
    assert obs[2] == -OBS_CLIP
    assert np.all(obs >= lay.low) and np.all(obs <= lay.high)


def test_distance_to_goal_adds_the_segments_after_this_one() -> None:
    """dist_to_goal = rest of this segment + to_goal; dist_to_cusp = rest of this one.

    Ego at s = 10 on a 50 m segment with 30 m after it: 70 m and 40 m.
    Mutants: to_goal dropped from the first, added to the second.
    """
    obs = _observe(_ego(10.0, 0.0, 0.0), to_goal=30.0)
    assert obs[5] == pytest.approx(70.0)
    assert obs[-1] == pytest.approx(40.0)


# ----------------------------------------------------------------------------- reward


def test_reward_terms_follow_the_documented_formulas() -> None:
    """Collision = -w, heading = -w psi^2 T, progress = w (s_after - s_before), signed.

    Mutants: collision rewarded, |psi| instead of psi^2, |progress|.
    """
    w = RewardWeights(progress=2.0, heading=3.0, collision=5.0)
    t = state_terms(
        w, progress_m=-0.5, cte=0.0, heading_err=0.5, speed=1.0, v_ref=1.0, span_s=0.1, crashed=True
    )
    assert t["collision"] == -5.0
    assert t["heading"] == pytest.approx(-3.0 * 0.25 * 0.1)
    assert t["progress"] == pytest.approx(-1.0)


def test_a_zero_weight_turns_a_term_off() -> None:
    """Weights are >= 0 (mutant: > 0, so a term could not be switched off)."""
    assert RewardWeights(cte=0.0).cte == 0.0
    with pytest.raises(InputError, match="reward.cte"):
        RewardWeights(cte=-1.0)


# ----------------------------------------------------------------------------- episode end


def test_a_timeout_is_truncated_not_terminated() -> None:
    """gymnasium: the time limit truncates; terminated stays False (status timeout).

    An agent that never moves on overtake with max_time_s = 0.5 s at 20 Hz: 10 steps,
    the last truncated. Mutants: terminated set too; truncated never set.
    """
    env = DriveEnv("overtake", max_time_s=0.5)
    try:
        env.reset(options={"episode_seed": 0})
        for k in range(1, 11):
            _, _, terminated, truncated, info = env.step(np.zeros(2, np.float32))
            if k < 10:
                assert not (terminated or truncated)
        assert info["status"] == "timeout"
        assert truncated and not terminated
    finally:
        env.close()


def test_leaving_the_path_is_terminated_with_the_off_path_penalty() -> None:
    """Off the path: terminated, not truncated, reward term -w_off_path.

    Mutants: the penalty's sign flipped (a reward for leaving the path); the success
    bonus paid on every episode end.
    """
    env = DriveEnv("overtake", max_cte=0.3, reward={"off_path": 9.0})
    try:
        env.reset(options={"episode_seed": 0})
        for _ in range(400):
            _, _, terminated, truncated, info = env.step(np.array([1.0, 1.0], np.float32))
            if terminated or truncated:
                break
        assert info["status"] == "off_path" and terminated and not truncated
        assert info["reward_terms"]["off_path"] == -9.0
        assert info["reward_terms"]["success"] == 0.0 and not info["is_success"]
    finally:
        env.close()


def test_backing_off_the_start_of_the_path_earns_no_negative_progress() -> None:
    """Progress is along the path clipped to it: behind its start, s stays 0.

    Reversing from rest at the start, the rear axle's projection goes below s = 0 and
    every progress term stays 0 (mutant: the clip at 0 dropped, progress < 0).
    """
    env = DriveEnv("overtake")
    try:
        env.reset(options={"episode_seed": 0})
        for _ in range(8):
            _, _, terminated, truncated, info = env.step(np.array([-1.0, 0.0], np.float32))
            assert not (terminated or truncated)
            assert info["reward_terms"]["progress"] == 0.0
        assert info["speed"] < -1.0  # it did back off
    finally:
        env.close()


def test_the_last_step_of_a_cut_repeat_pays_for_its_own_time_only() -> None:
    """action_repeat 3, a 0.5 s limit at 20 Hz: 10 simulation steps, 3 + 3 + 3 + 1.

    Its heading penalty is -w psi^2 T with T = 0.05 s, the simulated time (mutant:
    T = 3 dt whatever was simulated). Full throttle, steering off the path: psi grows.
    """
    env = DriveEnv("overtake", max_time_s=0.5, action_repeat=3, reward={"heading": 2.0})
    try:
        env.reset(options={"episode_seed": 0})
        t_prev = 0.0
        while True:
            _, _, terminated, truncated, info = env.step(np.array([1.0, 0.6], np.float32))
            span = info["time_s"] - t_prev
            t_prev = info["time_s"]
            want = -2.0 * info["heading_err_rad"] ** 2 * span
            assert info["reward_terms"]["heading"] == pytest.approx(want, rel=1e-9, abs=1e-15)
            if terminated or truncated:
                break
        assert span == pytest.approx(0.05)
        assert info["reward_terms"]["heading"] < -1e-6
    finally:
        env.close()


# ----------------------------------------------------------------------------- segments


def test_moving_in_the_next_gear_past_the_cusp_starts_the_next_segment() -> None:
    """to_cusp < 0 is past the cusp: it counts however far (mutant: |to_cusp| <= reach)."""
    assert starts_next_segment(-0.5, -1, -3.0, 20.0, 0.5, 0.1)


def test_stopped_far_past_the_cusp_in_the_wrong_gear_is_not_at_the_cusp() -> None:
    """Standing still counts within goal_tol of the cusp only (mutant: any way past it)."""
    assert not starts_next_segment(0.0, -1, -3.0, 20.0, 0.5, 0.1)


def test_standing_still_short_of_the_cusp_is_not_moving_in_the_next_gear() -> None:
    """Speed 0, 0.8 m before the cusp (tolerance 0.5): not turned (mutant: speed 0 counts)."""
    assert not starts_next_segment(0.0, -1, 0.8, 20.0, 0.5, 0.1)


# ----------------------------------------------------------------------------- seeds, config


def test_episode_seeds_are_drawn_from_the_half_open_range() -> None:
    """seed_range (5, 6) is [5, 6): only 5 (mutant: hi included)."""
    cfg = DriveEnvConfig.from_options("overtake", seed_range=(5, 6))
    rng = np.random.default_rng(0)
    ok = SimpleNamespace(failure=None)
    seeds = {start_drawn_episode(cfg, rng, lambda seed, task: ok) for _ in range(40)}
    assert seeds == {5}


def test_an_empty_seed_range_is_refused() -> None:
    """Lo < hi (mutant: lo == hi accepted, and every reset failed in numpy)."""
    with pytest.raises(InputError, match="seed_range"):
        DriveEnvConfig.from_options("overtake", seed_range=(5, 5))


def test_a_top_speed_above_the_simulated_cars_is_refused() -> None:
    """v_max above MAX_SPEED would be silently not driven (mutant: 1 m/s of slack)."""
    from rrtdrive.sim.limits import MAX_SPEED

    with pytest.raises(InputError, match="speed_options.v_max"):
        DriveEnvConfig.from_options("overtake", speed_options={"v_max": MAX_SPEED + 0.5})


# ----------------------------------------------------------------------------- reference speed


def test_the_relaunch_cap_applies_only_after_a_stop_line_lets_go() -> None:
    """No stop line ever: no cap (mutant: any step without a line started a rise)."""
    r = Relaunch(1.0)
    for s in (0.0, 1.0, 2.0):
        r.update(None, s, 0.0)
    assert r.cap(10.0) == math.inf
    # Held, then released at s = 2 at rest: sqrt(0 + 2 * 1 * (s - 2)); before s0 it is v0.
    r.update(5.0, 2.0, 0.0)
    r.update(None, 2.0, 0.0)
    assert r.cap(4.0) == pytest.approx(2.0)
    assert r.cap(0.0) == 0.0


def test_within_the_stop_distance_the_reference_speed_is_zero() -> None:
    """D <= stop_distance: 0 (mutant: only at or past the line)."""
    cfg = SpeedConfig(v_max=5.0, decel=1.0)
    assert stop_line_speed(5.0, 12.0 - cfg.stop_distance / 2, 12.0, cfg) == 0.0
