"""Every way to vectorise ActiveVision-v0 gives the same batches: Gymnasium's SyncVectorEnv
and AsyncVectorEnv over single envs, the native vector env, and N single envs stepped by
hand with Gymnasium's NEXT_STEP autoreset. Byte for byte: observations, rewards,
terminated, truncated and every info array, dtypes included."""

from __future__ import annotations

import subprocess
import sys
import textwrap
from typing import Any

import gymnasium as gym
import numpy as np
import pytest

import activevision.envs  # noqa: F401  (registers ActiveVision-v0)
from activevision.envs import ActiveVisionEnv, ActiveVisionVectorEnv
from activevision.envs.actions import action_table

N, SEED, STEPS = 3, 5, 200

#: (observations, rewards, terminated, truncated, infos) of one reset or step of N envs
Batch = tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, dict[str, Any]]
Step = tuple[np.ndarray, float, bool, bool, dict[str, Any]]


def random_actions(steps: int = STEPS, n: int = N, seed: int = 0) -> np.ndarray:
    return np.random.default_rng(seed).integers(0, 9, (steps, n))


def vector_rollout(envs: gym.vector.VectorEnv, seed: int, actions: np.ndarray) -> list[Batch]:
    """Reset with ``seed`` (sub-env i gets seed + i), then one batch per row of ``actions``."""
    obs, infos = envs.reset(seed=seed)
    n = actions.shape[1]
    out = [(obs, np.zeros(n), np.zeros(n, bool), np.zeros(n, bool), infos)]
    return out + [envs.step(a) for a in actions]


def singles_rollout(seed: int, actions: np.ndarray) -> list[Batch]:
    """``gym.make`` envs stepped one by one (env i reset with seed + i), batched as
    Gymnasium's vectorizers batch them."""
    envs = [gym.make("ActiveVision-v0") for _ in range(actions.shape[1])]
    first = [env.reset(seed=seed + i) for i, env in enumerate(envs)]
    steps: list[Step] = [(obs, 0.0, False, False, info) for obs, info in first]
    out = [stack(steps)]
    for row in actions:
        steps = [next_step(env, int(a), s) for env, a, s in zip(envs, row, steps, strict=True)]
        out.append(stack(steps))
    return out


def next_step(env: gym.Env, action: int, last: Step) -> Step:
    """Gymnasium's NEXT_STEP autoreset: the step after an episode ends resets the env
    (reward 0, neither terminated nor truncated) and ignores the action."""
    if last[2] or last[3]:
        obs, info = env.reset()
        return obs, 0.0, False, False, info
    return env.step(action)


def stack(steps: list[Step]) -> Batch:
    obs, reward, terminated, truncated, infos = zip(*steps, strict=True)
    batch: dict[str, Any] = {key: np.array([info[key] for info in infos]) for key in infos[0]}
    batch.update({f"_{key}": np.ones(len(infos), bool) for key in infos[0]})  # "has key" masks
    return np.stack(obs), np.array(reward), np.array(terminated), np.array(truncated), batch


def assert_same_batches(got: list[Batch], want: list[Batch]) -> None:
    assert len(got) == len(want)
    names = ("observations", "rewards", "terminated", "truncated")
    for t, (g, w) in enumerate(zip(got, want, strict=True)):
        for name, a, b in zip(names, g[:4], w[:4], strict=True):
            assert_same_bytes(a, b, f"step {t}: {name}")
        assert g[4].keys() == w[4].keys(), f"step {t}: info keys"
        for key in w[4]:
            assert_same_bytes(g[4][key], w[4][key], f"step {t}: info[{key!r}]")


def assert_same_bytes(a: Any, b: Any, where: str) -> None:
    a, b = np.asarray(a), np.asarray(b)
    assert (a.dtype, a.shape) == (b.dtype, b.shape), where
    if a.tobytes() != b.tobytes():
        at = np.argwhere(a != b)
        pytest.fail(f"{where}: {len(at)} elements differ, first at {tuple(at[0])}")


@pytest.fixture(scope="module")
def reference() -> list[Batch]:
    return singles_rollout(SEED, random_actions())


@pytest.mark.parametrize("mode", ["sync", "async", "vector_entry_point"])
def test_make_vec_modes_equal_single_envs(mode: str, reference: list[Batch]) -> None:
    envs = gym.make_vec("ActiveVision-v0", num_envs=N, vectorization_mode=mode)
    try:
        got = vector_rollout(envs, SEED, random_actions())
    finally:
        envs.close()
    assert_same_batches(got, reference)
    # 200 steps cross the 20-step limit: both kinds of episode end (and autoresets) happen
    assert np.any([b[2] for b in got]) and np.any([b[3] for b in got])


def test_async_close_returns() -> None:
    """The issue's hang: a fresh process makes an async vector env, steps it and closes it
    (a parent that failed to merge the workers' infos left close() waiting forever)."""
    code = textwrap.dedent("""
        import gymnasium as gym, numpy as np, activevision.envs
        envs = gym.make_vec("ActiveVision-v0", num_envs=2, vectorization_mode="async")
        envs.reset(seed=0)
        for a in np.random.default_rng(0).integers(0, 9, (25, 2)):
            envs.step(a)
        envs.close()
        print("closed")
    """)
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=300)
    assert out.returncode == 0, out.stderr
    assert out.stdout.split() == ["closed"]


def test_info_values_keep_shape_and_type() -> None:
    """What lets every vectorizer stack the infos: per key, one type, shape and dtype at
    every step, episode ends and resets included."""
    env = gym.make("ActiveVision-v0")
    _, info = env.reset(seed=3)
    signature = {key: _signature(value) for key, value in info.items()}
    for a in random_actions(60, 1)[:, 0]:
        _, _, terminated, truncated, info = env.step(int(a))
        assert {key: _signature(value) for key, value in info.items()} == signature
        if terminated or truncated:
            _, info = env.reset()
            assert {key: _signature(value) for key, value in info.items()} == signature
    k = len(env.unwrapped.sim.landmarks)
    assert signature["desired_mask"] == signature["observed_mask"] == (np.ndarray, (k,), "bool")
    assert signature["steps_to_success"] == (int, (), None)


def _signature(value: Any) -> tuple[type, tuple[int, ...], str | None]:
    dtype = value.dtype.name if isinstance(value, np.ndarray) else None
    return type(value), np.shape(value), dtype


def greedy_episode(seed: int) -> list[int]:
    """The actions of a greedy walk to the goal viewpoint, up to its success."""
    env = ActiveVisionEnv()
    table = np.degrees(action_table(3.0))
    _, info = env.reset(seed=seed)
    actions = []
    for _ in range(20):
        delta = np.degrees(info["goal_viewpoint"] - info["head"])
        actions.append(int(np.argmin(np.linalg.norm(delta - table, axis=1))))
        _, _, terminated, _, info = env.step(actions[-1])
        if terminated:
            return actions if info["success"] else []
    return []


def test_success_on_the_last_step_is_also_truncated_everywhere() -> None:
    """TimeLimit's rule: a step that reaches max_episode_steps is truncated even when it also
    terminates; the native vector env follows it, so all vectorizers agree."""
    seed, actions = next((s, a) for s in range(20) if (a := greedy_episode(s)))
    limit = len(actions)  # the episode succeeds on its last allowed step
    single = gym.make("ActiveVision-v0", max_episode_steps=limit)
    single.reset(seed=seed)
    vector = ActiveVisionVectorEnv(num_envs=1, max_episode_steps=limit)
    vector.reset(seed=seed)
    for a in actions:
        _, _, s_term, s_trunc, _ = single.step(a)
        _, _, v_term, v_trunc, _ = vector.step(np.array([a]))
        assert (s_term, s_trunc) == (v_term[0], v_trunc[0])
    assert s_term and s_trunc


DICT_KWARGS = {
    "observation": "image+head+pose+proposal",
    "action_history": 2,
    "prior_error_range": (0.0, 1.0),
    "prior_exact_share": 0.5,
}


def test_dict_observations_agree_in_every_mode() -> None:
    # sync and async stack the single envs' Dict observations; the native env builds them
    actions = random_actions(60)
    got = {}
    for mode in ("sync", "async", "vector_entry_point"):
        envs = gym.make_vec("ActiveVision-v0", num_envs=N, vectorization_mode=mode, **DICT_KWARGS)
        try:
            got[mode] = vector_rollout(envs, SEED, actions)
        finally:
            envs.close()
    for mode in ("async", "vector_entry_point"):
        for t, (a, b) in enumerate(zip(got["sync"], got[mode], strict=True)):
            assert a[0].keys() == b[0].keys()
            for key in a[0]:
                assert_same_bytes(a[0][key], b[0][key], f"{mode} step {t}: obs[{key!r}]")
            for name, x, y in zip(
                ("rewards", "terminated", "truncated"), a[1:4], b[1:4], strict=True
            ):
                assert_same_bytes(x, y, f"{mode} step {t}: {name}")
            for key in a[4]:
                assert_same_bytes(a[4][key], b[4][key], f"{mode} step {t}: info[{key!r}]")


MAKERS = {
    "make": lambda env_id: gym.make(env_id),
    "unwrapped": lambda env_id: gym.make(env_id).unwrapped,
    "native vector": lambda env_id: gym.make_vec(
        env_id, num_envs=2, vectorization_mode="vector_entry_point"
    ),
    "sync": lambda env_id: gym.make_vec(env_id, num_envs=2, vectorization_mode="sync"),
}


@pytest.mark.parametrize("maker", list(MAKERS))
@pytest.mark.parametrize("env_id", ["ActiveVision-v0", "ActiveVisionMatch-v0"])
def test_a_step_before_reset_is_refused_on_every_path(env_id: str, maker: str) -> None:
    """Gymnasium's ResetNeeded from the env, its unwrapped self, and every vectorizer (the
    native vector envs and ``.unwrapped`` used to play from the zeros the state starts as;
    the match's filter failed on them with a numerical error)."""
    from gymnasium.error import ResetNeeded

    env = MAKERS[maker](env_id)
    action: Any = 0 if env.action_space.shape == () else np.zeros(2, dtype=np.int64)
    with pytest.raises(ResetNeeded, match="reset"):
        env.step(action)
    env.reset(seed=1)
    env.step(action)  # and a reset is all it takes
    env.close()


@pytest.mark.parametrize("maker", ["unwrapped", "native vector", "sync"])
@pytest.mark.parametrize("env_id", ["ActiveVision-v0", "ActiveVisionMatch-v0"])
def test_a_render_before_reset_is_refused_on_every_path(env_id: str, maker: str) -> None:
    """``render_mode="rgb_array"``: ``render()`` before the first reset is Gymnasium's
    ResetNeeded, as ``SyncVectorEnv`` (through each env's order check) gives it (the native
    vector envs and ``.unwrapped`` drew a picture of the zeros the state starts as)."""
    from gymnasium.error import ResetNeeded

    if maker == "unwrapped":
        env: Any = gym.make(env_id, render_mode="rgb_array").unwrapped
    else:
        mode = "sync" if maker == "sync" else "vector_entry_point"
        env = gym.make_vec(env_id, num_envs=2, vectorization_mode=mode, render_mode="rgb_array")
    with pytest.raises(ResetNeeded, match="reset"):
        env.render()
    env.reset(seed=1)
    assert env.render() is not None  # and a reset is all it takes
    env.close()


def resets_rollout(envs: gym.vector.VectorEnv, actions: np.ndarray) -> list[Any]:
    """Steps between every kind of reset a vector env takes: seeded, unseeded (each
    sub-environment goes on drawing from its seeded generator), and partial ones through
    ``options={"reset_mask": ...}`` (with a seed for the masked sub-environment only, then
    none, one of them at an episode's end). Each reset's and step's full output."""
    n = actions.shape[1]
    out: list[Any] = [envs.reset(seed=SEED)]
    out += [envs.step(a) for a in actions[:25]]  # past the first episodes' ends
    out.append(envs.reset())
    out += [envs.step(a) for a in actions[25:30]]
    first = np.zeros(n, dtype=bool)
    first[0] = True
    out.append(envs.reset(seed=[11] + [None] * (n - 1), options={"reset_mask": first}))
    # 20 steps: the first sub-environment's match ends on the last, and the partial reset
    # after leaves it to be autoreset on the next step
    out += [envs.step(a) for a in actions[30:50]]
    out.append(envs.reset(options={"reset_mask": ~first}))
    out += [envs.step(a) for a in actions[50:]]
    return out


@pytest.mark.parametrize(
    ("env_id", "kwargs"),
    [
        ("ActiveVision-v0", {}),
        ("ActiveVision-v0", {"frame_stack": 3}),
        ("ActiveVisionMatch-v0", {"ticks": 20}),
    ],
    ids=["episodic", "episodic-stack3", "match"],
)
def test_unseeded_and_partial_resets_agree_in_every_mode(env_id: str, kwargs: dict) -> None:
    """``reset()`` after ``reset(seed=s)`` goes on from the seeded generators, and
    ``reset_mask`` resets just its sub-environments, in every vectorizer alike (the native
    envs drew fresh entropy for an unseeded reset and reset every sub-environment)."""
    actions = random_actions(70)
    got = {}
    for mode in ("sync", "async", "vector_entry_point"):
        envs = gym.make_vec(env_id, num_envs=N, vectorization_mode=mode, **kwargs)
        try:
            got[mode] = resets_rollout(envs, actions)
        finally:
            envs.close()
    for mode in ("async", "vector_entry_point"):
        for t, (a, b) in enumerate(zip(got["sync"], got[mode], strict=True)):
            assert len(a) == len(b)
            names = ("observations", "rewards", "terminated", "truncated")[: len(a) - 1]
            for name, x, y in zip(names, a[:-1], b[:-1], strict=True):
                assert_same_bytes(x, y, f"{mode} output {t}: {name}")
            assert a[-1].keys() == b[-1].keys(), f"{mode} output {t}: info keys"
            for key in a[-1]:
                assert_same_bytes(a[-1][key], b[-1][key], f"{mode} output {t}: info[{key!r}]")
    # the unseeded reset drew from the seeded generators: a second sync run repeats it
    envs = gym.make_vec(env_id, num_envs=N, vectorization_mode="sync", **kwargs)
    again = resets_rollout(envs, actions)
    assert_same_bytes(again[26][0], got["sync"][26][0], "sync again: unseeded reset")
    if env_id == "ActiveVisionMatch-v0":  # 20 ticks a match: its end is known
        before_partial = got["sync"][52]  # the step before the second partial reset
        assert before_partial[3][0]  # the first sub-environment's match ended there


@pytest.mark.parametrize("env_id", ["ActiveVision-v0", "ActiveVisionMatch-v0"])
def test_reset_options_the_env_does_not_take_are_refused(env_id: str) -> None:
    single = gym.make(env_id)
    with pytest.raises(ValueError, match=r"reset takes no options, got \['start'\]"):
        single.reset(seed=0, options={"start": 1})
    single.reset(seed=0, options={})  # SyncVectorEnv passes {} after taking its reset_mask
    native = gym.make_vec(env_id, num_envs=2, vectorization_mode="vector_entry_point")
    with pytest.raises(ValueError, match=r"only the option 'reset_mask', got \['start'\]"):
        native.reset(options={"start": 1})
    with pytest.raises(TypeError, match="numpy array"):
        native.reset(options={"reset_mask": [True, False]})
    with pytest.raises(ValueError, match=r"shape \(2,\)"):
        native.reset(options={"reset_mask": np.ones(3, dtype=bool)})
    with pytest.raises(TypeError, match="dtype bool"):
        native.reset(options={"reset_mask": np.ones(2, dtype=int)})
    with pytest.raises(ValueError, match="at least one True"):
        native.reset(options={"reset_mask": np.zeros(2, dtype=bool)})


@pytest.mark.parametrize(
    ("seed", "error"),
    [
        (1.5, TypeError),
        ("12", TypeError),
        ({"a": 1, "b": 2}, TypeError),
        (object(), TypeError),
        (np.array([[1, 2]]), TypeError),
        ([1], ValueError),
        ((1, 2, 3), ValueError),
    ],
)
@pytest.mark.parametrize("env_id", ["ActiveVision-v0", "ActiveVisionMatch-v0"])
def test_a_bad_seed_is_one_clear_error(env_id: str, seed: Any, error: type) -> None:
    """The native vector envs' ``reset(seed=...)`` names the seed it cannot take (a float
    failed with "'float' object is not iterable", a string or a dict was read as a list of
    its characters or keys) and leaves the env as it was."""
    native = gym.make_vec(env_id, num_envs=2, vectorization_mode="vector_entry_point")
    with pytest.raises(error, match="seed") as raised:
        native.reset(seed=seed)
    assert "not iterable" not in str(raised.value)
    obs, _ = native.reset(seed=[SEED, None])  # a list with None for one, as Sync takes it
    want, _ = gym.make(env_id).reset(seed=SEED)
    assert_same_bytes(obs[0], want, "observation")
    native.close()


@pytest.mark.parametrize("env_id", ["ActiveVision-v0", "ActiveVisionMatch-v0"])
def test_a_first_reset_that_raises_leaves_the_env_usable(env_id: str) -> None:
    """Gymnasium's passive checker failed every later step of an env whose first reset had
    raised; the envs are registered without it (the tests run the full check_env)."""
    env = gym.make(env_id)
    for bad in ({"seed": -1}, {"options": {"start": 1}}):
        with pytest.raises(Exception, match=r"[Ss]eed|options"):
            env.reset(**bad)
    env.reset(seed=0)
    for _ in range(3):
        env.step(env.action_space.sample())


@pytest.mark.parametrize("maker", ["make", "native vector"])
@pytest.mark.parametrize("env_id", ["ActiveVision-v0", "ActiveVisionMatch-v0"])
def test_a_copied_or_pickled_env_goes_on_as_the_original(env_id: str, maker: str) -> None:
    """``copy.deepcopy`` and a pickle round trip (planning by simulation, checkpointing a
    rollout) give an env that continues exactly as the original. (The episodic env's head
    angles were views of one array, which a copy turned into separate arrays: its head
    then moved without the image following.)"""
    import copy
    import pickle

    env = MAKERS[maker](env_id)
    env.reset(seed=1)
    rng = np.random.default_rng(0)
    batch = maker == "native vector"
    actions = rng.integers(0, 9, (12, 2) if batch else 12)
    for a in actions[:4]:
        env.step(a if batch else int(a))
    copies = [copy.deepcopy(env), pickle.loads(pickle.dumps(env))]
    for a in actions[4:]:
        want = env.step(a if batch else int(a))
        for twin in copies:
            got = twin.step(a if batch else int(a))
            for name, x, y in zip(
                ("obs", "reward", "terminated", "truncated"), got, want, strict=False
            ):
                assert_same_bytes(x, y, f"{name} at a step after the copy")
            for key in want[4]:
                assert_same_bytes(got[4][key], want[4][key], f"info[{key!r}]")


@pytest.mark.parametrize("env_id", ["ActiveVision-v0", "ActiveVisionMatch-v0"])
def test_the_native_vector_env_renders_as_sync_does(env_id: str) -> None:
    """``render_mode="rgb_array"``: a tuple of each sub-environment's picture, the very
    pictures of ``SyncVectorEnv`` (the native envs took no render_mode)."""
    pictures = {}
    for mode in ("sync", "vector_entry_point"):
        envs = gym.make_vec(env_id, num_envs=2, vectorization_mode=mode, render_mode="rgb_array")
        envs.reset(seed=4)
        envs.step(np.array([1, 7]))
        pictures[mode] = envs.render()
        envs.close()
    assert len(pictures["sync"]) == len(pictures["vector_entry_point"]) == 2
    for a, b in zip(pictures["sync"], pictures["vector_entry_point"], strict=True):
        assert a.shape == (340, 900, 3)
        assert_same_bytes(b, a, "picture")
    assert not np.array_equal(*pictures["sync"])  # two sub-environments, two pictures
    plain = gym.make_vec(env_id, num_envs=2, vectorization_mode="vector_entry_point")
    plain.reset(seed=4)
    assert plain.render() is None
    with pytest.raises(ValueError, match="render_mode"):
        gym.make_vec(
            env_id, num_envs=2, vectorization_mode="vector_entry_point", render_mode="human"
        )


@pytest.mark.parametrize("ticks", [20, 4], ids=["limit-first", "ticks-first"])
def test_a_match_time_limit_is_taken_by_every_vectorizer(ticks: int) -> None:
    """``make_vec("ActiveVisionMatch-v0", max_episode_steps=n)``: sync and async wrap each
    match in Gymnasium's ``TimeLimit``; the native env refused the keyword as an unknown
    ``MatchConfig`` field. It now ends matches after ``min(n, ticks)`` ticks, as they do."""
    actions = random_actions(16)
    got = {}
    for mode in ("sync", "async", "vector_entry_point"):
        envs = gym.make_vec(
            "ActiveVisionMatch-v0",
            num_envs=N,
            vectorization_mode=mode,
            max_episode_steps=6,
            ticks=ticks,
        )
        try:
            got[mode] = vector_rollout(envs, SEED, actions)
        finally:
            envs.close()
    truncated = np.array([batch[3][0] for batch in got["sync"]])
    ends = min(6, ticks)
    # truncated every ``ends`` ticks, each followed by the autoreset step
    assert np.flatnonzero(truncated).tolist() == list(range(ends, len(actions) + 1, ends + 1))
    for mode in ("async", "vector_entry_point"):
        assert_same_batches(got[mode], got["sync"])


@pytest.mark.parametrize("env_id", ["ActiveVision-v0", "ActiveVisionMatch-v0"])
def test_a_first_partial_reset_leaves_the_others_awaiting_their_first(env_id: str) -> None:
    """A first ``reset`` with a ``reset_mask`` resets those sub-environments as a single env
    with their seeds; the others report nothing and a step asks for their reset. (The
    native match env failed in that reset with the entropy of a belief never started.)"""
    from gymnasium.error import ResetNeeded

    envs = gym.make_vec(env_id, num_envs=2, vectorization_mode="vector_entry_point")
    obs, info = envs.reset(seed=SEED, options={"reset_mask": np.array([True, False])})
    want, want_info = gym.make(env_id).reset(seed=SEED)
    for key in want_info:
        assert_same_bytes(info[key][0], np.asarray(want_info[key]), f"info[{key!r}]")
        assert info[f"_{key}"].tolist() == [True, False], key
    if isinstance(want, dict):
        for key in want:
            assert_same_bytes(obs[key][0], want[key], f"obs[{key!r}]")
    else:
        assert_same_bytes(obs[0], want, "obs")
    with pytest.raises(ResetNeeded, match=r"never reset: \[1\]"):
        envs.step(np.zeros(2, dtype=np.int64))
    envs.reset(seed=SEED)  # a reset of both is all it takes
    envs.step(np.zeros(2, dtype=np.int64))


@pytest.mark.parametrize("env_id", ["ActiveVision-v0", "ActiveVisionMatch-v0"])
def test_the_native_vector_env_names_the_autoreset_modes_it_runs(env_id: str) -> None:
    """``make_vec(..., autoreset_mode=...)`` in ``vector_entry_point`` mode reached the config
    and was refused as "unknown keyword autoreset_mode" of EnvConfig; NEXT_STEP (the mode
    the native envs run), as the enum or its value, is taken, and any other is one line
    that says which vectorizers run it."""
    for mode in (gym.vector.AutoresetMode.NEXT_STEP, "NextStep"):
        envs = gym.make_vec(
            env_id, num_envs=2, vectorization_mode="vector_entry_point", autoreset_mode=mode
        )
        assert envs.metadata["autoreset_mode"] == gym.vector.AutoresetMode.NEXT_STEP
        envs.close()
    for mode in (gym.vector.AutoresetMode.SAME_STEP, gym.vector.AutoresetMode.DISABLED, "x"):
        with pytest.raises(ValueError, match=r"^autoreset_mode: .*'sync' or 'async'") as error:
            gym.make_vec(
                env_id, num_envs=2, vectorization_mode="vector_entry_point", autoreset_mode=mode
            )
        assert "unknown keyword" not in str(error.value) and repr(mode) in str(error.value)


@pytest.mark.parametrize("env_id", ["ActiveVision-v0", "ActiveVisionMatch-v0"])
def test_the_native_vector_env_reports_the_seeds_sync_does(env_id: str) -> None:
    """``np_random_seed`` of the native vector env was ``VectorEnv``'s own: a random 128-bit
    seed whatever the reset was given; it is each sub-environment's, as ``SyncVectorEnv``
    reports them, through seeded, unseeded and partial resets, and ``np_random`` the
    sub-environments' generators."""
    made = {
        mode: gym.make_vec(env_id, num_envs=2, vectorization_mode=mode)
        for mode in ("sync", "vector_entry_point")
    }
    resets: list[dict[str, Any]] = [
        {"seed": 7},
        {},
        {"seed": [None, 11]},
        {"seed": 20, "options": {"reset_mask": np.array([True, False])}},
    ]
    for kwargs in resets:
        for envs in made.values():  # a copy each: SyncVectorEnv pops the reset mask
            envs.reset(**{key: dict(v) if key == "options" else v for key, v in kwargs.items()})
        want = made["sync"].np_random_seed
        assert made["vector_entry_point"].np_random_seed == want, kwargs
    assert made["vector_entry_point"].np_random_seed == (20, 11)
    draws = [[g.integers(1 << 30) for g in envs.np_random] for envs in made.values()]
    assert draws[0] == draws[1]
    for envs in made.values():
        envs.close()


@pytest.mark.parametrize(
    ("env_id", "observation"),
    [
        ("ActiveVision-v0", "image+head+pose+proposal"),
        ("ActiveVisionMatch-v0", "image+head+belief"),
    ],
)
def test_dict_observations_keep_their_space_order_in_every_mode(env_id: str, observation: str):
    """A Dict observation's keys come in its space's (sorted) order, the order Sync and
    Async batch them in: the single and native envs gave them in the order they were built
    ("image" first), so ``obs.values()`` differed between vectorizers and from the space."""
    single = gym.make(env_id, observation=observation)
    obs, _ = single.reset(seed=SEED)
    assert list(obs) == list(single.observation_space.spaces)
    assert list(single.step(single.action_space.sample())[0]) == list(obs)
    for mode in ("sync", "async", "vector_entry_point"):
        envs = gym.make_vec(env_id, num_envs=2, vectorization_mode=mode, observation=observation)
        batch, _ = envs.reset(seed=SEED)
        assert list(batch) == list(obs), mode
        assert list(envs.step(envs.action_space.sample())[0]) == list(obs), mode
        envs.close()


@pytest.mark.parametrize("env_id", ["ActiveVision-v0", "ActiveVisionMatch-v0"])
def test_a_single_env_takes_a_numpy_integer_seed_as_the_vector_envs_do(env_id: str) -> None:
    """``reset(seed=np.int64(s))`` is ``reset(seed=s)`` in a single env too (Gymnasium
    refused it, "must be a python integer", where the native vector envs take it), and
    other seeds are still Gymnasium's to refuse."""
    env = gym.make(env_id)
    obs, _ = env.reset(seed=np.int64(SEED))
    want, _ = gym.make(env_id).reset(seed=SEED)
    assert_same_bytes(obs, want, "observation")
    assert env.unwrapped.np_random_seed == SEED and type(env.unwrapped.np_random_seed) is int
    for bad in (1.5, "12", np.float64(3.0)):
        with pytest.raises(gym.error.Error, match=r"[Ss]eed"):
            env.reset(seed=bad)
