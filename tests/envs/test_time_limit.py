"""``max_episode_steps`` as Gymnasium means it, in ``gymnasium.make`` and in every
``make_vec`` mode: a positive int is the time limit, ``-1`` none, ``None`` the
registration's (20 for ``ActiveVision-v0``, none for the match). ``steps_to_success`` and
``ball_lost_step`` report the limit the episode really runs under for "did not happen" (-1
without one), whichever way the env was made; ``gymnasium.make`` never passes the limit to
the env (its ``TimeLimit`` wrapper applies it), which made them say 20 in the single env and
the sync and async modes while the native env said ``n``."""

from __future__ import annotations

from typing import Any

import gymnasium as gym
import numpy as np
import pytest

import activevision.envs  # noqa: F401  (registers the envs)
from activevision.envs import ActiveVisionEnv, ActiveVisionVectorEnv

from .test_vectorizers import assert_same_batches, greedy_episode, vector_rollout

MODES = ("sync", "async", "vector_entry_point")
STAY = 0  # the (0, 0) head move: the ball stays in view and the goal is never reached


def rollouts(env_id: str, actions: np.ndarray, seed: int = 11, **kwargs: Any) -> dict[str, list]:
    got = {}
    for mode in MODES:
        envs = gym.make_vec(env_id, num_envs=actions.shape[1], vectorization_mode=mode, **kwargs)
        try:
            got[mode] = vector_rollout(envs, seed, actions)
        finally:
            envs.close()
    return got


@pytest.mark.parametrize(
    ("kwargs", "never", "truncated_at"),
    [
        ({"max_episode_steps": 3}, 3, [3, 7, 11]),
        ({}, 20, []),
        ({"max_episode_steps": None}, 20, []),  # None: the registration's 20, as make reads it
        ({"max_episode_steps": -1}, -1, []),  # -1: no limit, not even the registration's
    ],
    ids=["3", "default", "None", "-1"],
)
def test_every_mode_runs_under_the_limit_and_reports_it(
    kwargs: dict, never: int, truncated_at: list[int]
) -> None:
    """Same seed, same bytes in sync, async and native mode, and each reports ``never`` for an
    episode that neither succeeds nor loses the ball (the head stays put; 13 steps, or 24
    past the registration's 20 steps without a limit)."""
    steps = 24 if never == -1 else 13
    got = rollouts("ActiveVision-v0", np.full((steps, 2), STAY), **kwargs)
    for mode in ("async", "vector_entry_point"):
        assert_same_batches(got[mode], got["sync"])
    batches = got["vector_entry_point"]
    truncated = [t for t, batch in enumerate(batches) if batch[3].any()]
    assert truncated == truncated_at
    for batch in batches:
        info = batch[4]
        assert not info["success"].any() and not info["ball_lost"].any()
        assert info["steps_to_success"].tolist() == [never, never]
        assert info["ball_lost_step"].tolist() == [never, never]
    if never == -1:
        assert batches[-1][4]["step"].tolist() == [24, 24]  # past 20, not truncated


@pytest.mark.parametrize(("limit", "never"), [(4, 4), (-1, -1), (None, 20)])
def test_gym_make_reports_its_own_limit(limit: int | None, never: int) -> None:
    env = gym.make("ActiveVision-v0", max_episode_steps=limit)
    _, info = env.reset(seed=2)
    assert (info["steps_to_success"], info["ball_lost_step"]) == (never, never)
    assert env.unwrapped.max_episode_steps == (None if never == -1 else never)
    _, _, _, truncated, info = env.step(STAY)
    assert info["steps_to_success"] == never and not truncated


def test_a_success_or_a_lost_ball_still_reports_its_step() -> None:
    """Only "did not happen" follows the limit: an episode that succeeds (a greedy walk to
    the goal) or loses the ball (random moves) reports the step it ended at."""
    seed, walk = next((s, a) for s in range(20) if (a := greedy_episode(s)))
    random = np.random.default_rng(0).integers(0, 9, (30, 2))
    seen = {"success": 0, "ball_lost": 0}
    for start, actions in ((seed, np.array(walk)[:, None]), (11, random)):
        got = rollouts("ActiveVision-v0", actions, seed=start, max_episode_steps=30)
        for mode in ("async", "vector_entry_point"):
            assert_same_batches(got[mode], got["sync"])
        for batch in got["sync"]:
            info = batch[4]
            for key, when in (("success", "steps_to_success"), ("ball_lost", "ball_lost_step")):
                happened = info[key]
                assert (info[when][happened] == info["step"][happened]).all()
                assert (info[when][~happened] == 30).all()
                seen[key] += int(happened.sum())
    assert seen["success"] and seen["ball_lost"], seen


def test_direct_construction_reads_the_limit_as_make_does() -> None:
    assert ActiveVisionEnv().max_episode_steps == 20
    assert ActiveVisionEnv(max_episode_steps=None).max_episode_steps == 20
    assert ActiveVisionEnv(max_episode_steps=-1).max_episode_steps is None
    assert ActiveVisionVectorEnv(num_envs=1, max_episode_steps=-1).max_episode_steps is None
    _, info = ActiveVisionEnv(max_episode_steps=7).reset(seed=0)
    assert info["steps_to_success"] == 7


def test_an_env_made_by_another_entry_point_keeps_its_own_limit() -> None:
    """Only ``make`` building ``ActiveVisionEnv`` itself decides its limit, not a ``make``
    of some other env that builds one inside."""
    gym.register("ActiveVisionWrapped-v0", entry_point=lambda: ActiveVisionEnv(max_episode_steps=7))
    try:
        env = gym.make("ActiveVisionWrapped-v0", max_episode_steps=3)
        assert env.unwrapped.max_episode_steps == 7
    finally:
        del gym.registry["ActiveVisionWrapped-v0"]


@pytest.mark.parametrize("mode", MODES)
@pytest.mark.parametrize("limit", [0, -2])
def test_a_limit_below_one_is_refused_in_every_mode(mode: str, limit: int) -> None:
    with pytest.raises(ValueError, match=rf"max_episode_steps.*{limit}") as error:
        gym.make_vec(
            "ActiveVision-v0", num_envs=2, vectorization_mode=mode, max_episode_steps=limit
        )
    assert "\n" not in str(error.value)


def test_a_match_without_a_limit_runs_its_ticks_in_every_mode() -> None:
    """``max_episode_steps=-1`` on the match: no ``TimeLimit`` in sync and async, and the
    native env, which refused -1, ends matches after ``ticks`` as they do."""
    actions = np.random.default_rng(1).integers(0, 9, (11, 2))
    got = rollouts("ActiveVisionMatch-v0", actions, max_episode_steps=-1, ticks=5)
    truncated = [t for t, batch in enumerate(got["sync"]) if batch[3].any()]
    assert truncated == [5, 11]
    assert_same_batches(got["async"], got["sync"])
    assert_same_batches(got["vector_entry_point"], got["sync"])
