"""``max_episode_steps`` as Gymnasium means it, in ``gymnasium.make`` and in every
``make_vec`` mode: a positive int is the time limit, ``-1`` none, ``None`` the
registration's (20 for ``ActiveVision-v0``, none for the match). Every mode plays the same
episodes and truncates them at the same step; the native envs refused ``-1``.

``steps_to_success`` and ``ball_lost_step`` report the env's own limit for "did not happen":
``gymnasium.make`` applies its limit in a ``TimeLimit`` wrapper and tells the env nothing, so
under ``make`` (and the sync and async modes) they say 20 whatever the limit, while the
native env, which ``make_vec`` hands the limit to, says it (the README's known limitation)."""

from __future__ import annotations

from typing import Any

import gymnasium as gym
import numpy as np
import pytest

import activevision.envs  # noqa: F401  (registers the envs)
from activevision.envs import ActiveVisionEnv, ActiveVisionVectorEnv

from .test_vectorizers import Batch, assert_same_batches, greedy_episode, vector_rollout

MODES = ("sync", "async", "vector_entry_point")
STAY = 0  # the (0, 0) head move: the ball stays in view and the goal is never reached


NEVER_KEYS = ("steps_to_success", "ball_lost_step")


def without_never(batches: list[Batch]) -> list[Batch]:
    """The batches without the two keys whose "did not happen" value the modes differ in."""
    return [(*b[:4], {k: v for k, v in b[4].items() if k not in NEVER_KEYS}) for b in batches]


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
    ("kwargs", "native_never", "truncated_at"),
    [
        ({"max_episode_steps": 3}, 3, [3, 7, 11]),
        ({}, 20, []),
        ({"max_episode_steps": None}, 20, []),  # None: the registration's 20, as make reads it
        ({"max_episode_steps": -1}, -1, []),  # -1: no limit, not even the registration's
    ],
    ids=["3", "default", "None", "-1"],
)
def test_every_mode_runs_under_the_limit(
    kwargs: dict, native_never: int, truncated_at: list[int]
) -> None:
    """Same seed, same bytes in sync, async and native mode, truncated at the same steps, for
    an episode that neither succeeds nor loses the ball (the head stays put; 13 steps, or 24
    past the registration's 20 steps without a limit). "Never" is the native env's limit,
    and 20 in the sync and async modes, whose envs ``make`` does not tell."""
    steps = 24 if native_never == -1 else 13
    got = rollouts("ActiveVision-v0", np.full((steps, 2), STAY), **kwargs)
    assert_same_batches(got["async"], got["sync"])
    assert_same_batches(without_never(got["vector_entry_point"]), without_never(got["sync"]))
    for mode, never in (("sync", 20), ("vector_entry_point", native_never)):
        batches = got[mode]
        truncated = [t for t, batch in enumerate(batches) if batch[3].any()]
        assert truncated == truncated_at, mode
        for batch in batches:
            info = batch[4]
            assert not info["success"].any() and not info["ball_lost"].any()
            assert [info[key].tolist() for key in NEVER_KEYS] == [[never, never]] * 2, mode
    if native_never == -1:
        assert got["sync"][-1][4]["step"].tolist() == [24, 24]  # past 20, not truncated


@pytest.mark.parametrize("limit", [4, -1, None])
def test_gym_make_truncates_at_its_limit_and_the_env_at_its_own(limit: int | None) -> None:
    """``make``'s limit truncates (none with -1) but does not reach the env's infos (20);
    ``TimeLimit(ActiveVisionEnv(max_episode_steps=n), n)`` agrees with itself."""
    env = gym.make("ActiveVision-v0", max_episode_steps=limit)
    env.reset(seed=2)
    steps = [env.step(STAY) for _ in range(4)]
    assert [truncated for *_, truncated, _ in steps] == [False, False, False, limit == 4]
    assert steps[0][-1]["steps_to_success"] == 20  # the README's known limitation
    own = gym.wrappers.TimeLimit(ActiveVisionEnv(max_episode_steps=4), 4)
    _, info = own.reset(seed=2)
    assert (info["steps_to_success"], info["ball_lost_step"]) == (4, 4)


def test_a_success_or_a_lost_ball_still_reports_its_step() -> None:
    """Only "did not happen" follows the limit: an episode that succeeds (a greedy walk to
    the goal) or loses the ball (random moves) reports the step it ended at."""
    seed, walk = next((s, a) for s in range(20) if (a := greedy_episode(s)))
    random = np.random.default_rng(0).integers(0, 9, (30, 2))
    seen = {"success": 0, "ball_lost": 0}
    for start, actions in ((seed, np.array(walk)[:, None]), (11, random)):
        got = rollouts("ActiveVision-v0", actions, seed=start, max_episode_steps=30)
        assert_same_batches(got["async"], got["sync"])
        assert_same_batches(without_never(got["vector_entry_point"]), without_never(got["sync"]))
        for batch in got["vector_entry_point"]:
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
