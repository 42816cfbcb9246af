"""Gymnasium's ``VectorEnv`` attribute API (``get_attr``, ``set_attr``, ``call``) on the
native vector envs, against ``SyncVectorEnv`` over the same registered env: a user's code
written for ``SyncVectorEnv`` (reading the render mode, a sub-environment's generator,
calling ``render`` per sub-environment, setting a curriculum attribute) runs unchanged."""

from __future__ import annotations

from typing import Any

import gymnasium as gym
import numpy as np
import pytest

import activevision.envs  # noqa: F401  (registers the envs)

IDS = ["ActiveVision-v0", "ActiveVisionMatch-v0"]
N = 3


def pair(env_id: str, **kwargs: Any) -> dict[str, gym.vector.VectorEnv]:
    """The sync and the native vector env of ``env_id``, both reset with the same seeds."""
    envs = {
        mode: gym.make_vec(env_id, num_envs=N, vectorization_mode=mode, **kwargs)
        for mode in ("sync", "vector_entry_point")
    }
    for env in envs.values():
        env.reset(seed=[11, 3, 8])
    return envs


def same(a: Any, b: Any) -> bool:
    if isinstance(a, np.random.Generator):
        return a.bit_generator.state == b.bit_generator.state
    if isinstance(a, np.ndarray):
        return a.dtype == b.dtype and a.shape == b.shape and a.tobytes() == b.tobytes()
    return type(a) is type(b) and a == b


@pytest.mark.parametrize("env_id", IDS)
def test_get_attr_and_call_report_what_sync_reports(env_id: str) -> None:
    envs = pair(env_id, render_mode="rgb_array")
    sync, native = envs["sync"], envs["vector_entry_point"]
    names = [
        "render_mode",
        "config",
        "np_random",
        "np_random_seed",
        "metadata",
        "observation_space",
        "action_space",
        "spec",
    ]
    for name in names:
        want, got = sync.get_attr(name), native.get_attr(name)
        assert isinstance(got, tuple) and len(got) == N, name
        assert all(same(g, w) for g, w in zip(got, want, strict=True)), (name, got, want)
        # call of an attribute that is no method returns it, as Sync's does
        assert all(same(g, w) for g, w in zip(native.call(name), want, strict=True)), name
    methods = ["render"] + (["entropy_regret"] if env_id == "ActiveVision-v0" else [])
    for step in range(2):
        for method in methods:
            want, got = sync.call(method), native.call(method)
            assert len(got) == N
            for g, w in zip(got, want, strict=True):
                assert np.array_equal(g, w) and type(g) is type(w), (method, step)
        for env in envs.values():
            env.step(np.array([1, 4, 6]))
    for env in envs.values():
        with pytest.raises(AttributeError):
            env.get_attr("no_such_attribute")
        env.close()


@pytest.mark.parametrize("env_id", IDS)
def test_set_attr_takes_one_value_or_one_per_env_as_sync_does(env_id: str) -> None:
    envs = pair(env_id)
    for env in envs.values():
        env.set_attr("difficulty", 0.5)
        assert env.get_attr("difficulty") == (0.5,) * N
        env.set_attr("difficulty", [0.7] * N)
        assert env.get_attr("difficulty") == (0.7,) * N
        with pytest.raises(ValueError, match="Got `2` values for 3 environments"):
            env.set_attr("difficulty", [0.1, 0.2])
    # a generator per sub-environment, as Sync's envs take them: the same next episodes
    for env in envs.values():
        env.set_attr("np_random", [np.random.default_rng(s) for s in (1, 2, 3)])
        assert env.get_attr("np_random_seed") == (-1,) * N
    got, want = envs["vector_entry_point"].reset()[0], envs["sync"].reset()[0]
    assert same(
        np.asarray(got["image"] if isinstance(got, dict) else got),
        np.asarray(want["image"] if isinstance(want, dict) else want),
    )
    with pytest.raises(AttributeError, match="'num_envs' cannot be set"):
        envs["vector_entry_point"].set_attr("num_envs", 5)
    for env in envs.values():
        env.close()


def test_call_refuses_a_method_it_cannot_run_per_sub_environment() -> None:
    """A method of the native env acts on the whole batch: ``call("reset")`` would have
    reset every sub-environment and returned the batch N times."""
    env = gym.make_vec("ActiveVision-v0", num_envs=2, vectorization_mode="vector_entry_point")
    env.reset(seed=0)
    for name in ("reset", "step"):
        with pytest.raises(AttributeError, match=repr(name)):
            env.call(name)
    env.close()


@pytest.mark.parametrize(
    ("env_id", "limit"), [(IDS[0], {"max_episode_steps": 2}), (IDS[1], {"ticks": 2})]
)
def test_rgb_array_list_collects_the_pictures_sync_collects(env_id: str, limit: dict) -> None:
    """``render_mode="rgb_array_list"`` (Gymnasium's ``RenderCollection``, which ``make``
    and so the sync mode apply): the native env refused it ("expects one of ['rgb_array']"),
    so ``make_vec`` with it worked in sync mode only. Each sub-environment's pictures since
    its last reset or render, an autoreset starting the list again, a partial reset too."""
    envs = {
        mode: gym.make_vec(
            env_id, num_envs=2, vectorization_mode=mode, render_mode="rgb_array_list", **limit
        )
        for mode in ("sync", "vector_entry_point")
    }
    got: dict[str, list[Any]] = {mode: [] for mode in envs}
    for mode, env in envs.items():
        env.reset(seed=5)
        for t in range(4):  # the episodes end after 2 steps: the next step autoresets
            env.step(np.array([1, 3]))
            if t == 1:
                got[mode].append(env.render())
        env.reset(options={"reset_mask": np.array([False, True])})
        got[mode].append(env.call("render"))
        got[mode].append(env.render())  # popped: empty lists
        got[mode].append(env.get_attr("render_mode"))
        got[mode].append(env.metadata["render_modes"])
        env.close()
    want = got["sync"]
    assert [[len(frames) for frames in r] for r in want[:3]] == [[3, 3], [2, 1], [0, 0]]
    for g, w in zip(got["vector_entry_point"], want, strict=True):
        assert len(g) == len(w)
        for a, b in zip(g, w, strict=True):
            if isinstance(b, list) and b and isinstance(b[0], np.ndarray):
                assert len(a) == len(b)
                assert all(np.array_equal(x, y) for x, y in zip(a, b, strict=True))
            else:
                assert a == b


def test_get_attr_of_what_only_sync_sub_environments_have_says_why() -> None:
    env = gym.make_vec("ActiveVision-v0", num_envs=2, vectorization_mode="vector_entry_point")
    with pytest.raises(AttributeError, match=r"slots of one batch, with no 'unwrapped'"):
        env.get_attr("unwrapped")
    assert env.unwrapped is env  # the vector env's own, as VectorEnv documents
    env.close()


def same_result(a: Any, b: Any) -> bool:
    """Whether two single-env results (an observation, a step tuple, an info) are one value,
    byte for byte, types included."""
    if isinstance(b, tuple):
        return isinstance(a, tuple) and len(a) == len(b) and all(map(same_result, a, b))
    if isinstance(b, dict):
        return (
            isinstance(a, dict) and a.keys() == b.keys() and all(same_result(a[k], b[k]) for k in b)
        )
    return same(a, b)


@pytest.mark.parametrize(
    "kwargs",
    [
        {},
        {"frame_stack": 2},
        {"observation": "image+head+pose", "action_history": 2},
    ],
)
def test_call_jump_head_jumps_each_sub_environment_as_sync_does(kwargs: dict) -> None:
    """``call("jump_head", pan, tilt)``: ``SyncVectorEnv`` jumps every sub-environment's head
    (the entropy baselines' move); the native env refused it as no attribute of its
    sub-environments. Each sub-environment's result, then every later step (autoresets, and
    truncation by step() calls only, as Sync's ``TimeLimit`` counts them), byte for byte."""
    envs = pair("ActiveVision-v0", **kwargs)
    sync, native = envs["sync"], envs["vector_entry_point"]
    rng = np.random.default_rng(4)
    # mostly "stay", so that episodes last to the time limit
    actions = np.where(rng.random((60, N)) < 0.9, 0, rng.integers(0, 9, (60, N)))
    head, truncated = sync.reset(seed=[11, 3, 8])[1]["head"], 0
    native.reset(seed=[11, 3, 8])
    for t, row in enumerate(actions):
        if t % 25 in (2, 9):  # to sub-environment 0's own head (it goes on), or far away
            pan, tilt = head[0] if t % 25 == 2 else (np.float32(0.4), 0.25)
            want, got = sync.call("jump_head", pan, tilt), native.call("jump_head", pan, tilt)
            assert len(got) == N and same_result(got, want), t
        want, got = sync.step(row), native.step(row)
        assert same_result(got, want), t
        head, truncated = want[4]["head"], truncated + int(got[3][0])
    assert truncated == 2  # sub-environment 0 reached the time limit after a jump twice
    for env in envs.values():
        env.close()


def test_jump_head_is_refused_as_sync_refuses_it() -> None:
    """A bad angle, or a sub-environment never reset, fails as the single env's does."""
    for mode in ("sync", "vector_entry_point"):
        env = gym.make_vec("ActiveVision-v0", num_envs=2, vectorization_mode=mode)
        with pytest.raises(Exception, match="reset"):
            env.call("jump_head", 0.1, 0.1)
        env.reset(seed=1)
        with pytest.raises(ValueError, match="jump_head: pan expects a finite number"):
            env.call("jump_head", float("nan"), 0.1)
        env.close()


def test_call_of_what_it_cannot_run_per_sub_environment_says_what_to_use() -> None:
    """``call("reset")``, ``call("step", a)`` and ``call("close")`` run each of Sync's envs by
    itself, outside its autoreset; the native env's sub-environments are slots of one batch,
    so it refuses them, naming the vector env's own method to use instead."""
    env = gym.make_vec("ActiveVision-v0", num_envs=2, vectorization_mode="vector_entry_point")
    env.reset(seed=0)
    hints = {
        "reset": r"reset\(seed=\.\.\., options=\{'reset_mask': mask\}\)",
        "step": r"step\(actions\)",
        "close": r"close\(\)",
        "get_wrapper_attr": r"get_attr\(name\)",
        "set_wrapper_attr": r"set_attr\(name, values\)",
    }
    for name, hint in hints.items():
        with pytest.raises(AttributeError, match=rf"call\({name!r}\).*use the vector env's {hint}"):
            env.call(name)
    env.close()
    match = gym.make_vec(
        "ActiveVisionMatch-v0", num_envs=2, vectorization_mode="vector_entry_point"
    )
    with pytest.raises(AttributeError, match="no attribute 'jump_head'"):
        match.call("jump_head", 0.1, 0.1)  # as Sync: the match env has no jump_head
    match.close()


@pytest.mark.parametrize("env_id", IDS)
def test_set_attr_keeps_one_value_per_sub_environment_as_sync_does(env_id: str) -> None:
    """An attribute of the user's own (a curriculum level, a tag) takes one value per
    sub-environment, as Sync's env objects do; the native env refused differing values.
    What the env reads (its config, render mode, time limit) is shared by the batch: differing
    values are refused with what to use instead, and the attribute keeps its value."""
    envs = pair(env_id)
    for env in envs.values():
        env.set_attr("level", [0.1, 0.2, 0.3])
        assert env.get_attr("level") == (0.1, 0.2, 0.3)
        assert env.call("level") == (0.1, 0.2, 0.3)
        env.set_attr("level", 0.5)
        assert env.get_attr("level") == (0.5,) * N
        env.set_attr("level", (1, "b", None))
        assert env.get_attr("level") == (1, "b", None)
    native = envs["vector_entry_point"]
    for name, values in (
        ("render_mode", [None, "rgb_array", None]),
        ("max_episode_steps", [3, 4, 5]),
    ):
        before = native.get_attr(name)
        with pytest.raises(ValueError, match=rf"share {name!r}.*make one vector env per value"):
            native.set_attr(name, values)
        assert native.get_attr(name) == before
    for env in envs.values():
        env.close()
