"""Bad input is one clear ValueError naming the key and the value: environment keywords (for
gym.make, the native vector env and make_vec), config dataclasses and vector actions."""

from __future__ import annotations

import dataclasses
import math
from typing import Any, Literal

import gymnasium as gym
import numpy as np
import pytest

import activevision.envs  # noqa: F401  (registers ActiveVision-v0)
from activevision.envs import ActiveVisionEnv, ActiveVisionVectorEnv, EnvConfig
from activevision.geometry import CameraConfig, FieldSpec
from activevision.typecheck import ALLOW_NONFINITE, check_dataclass_fields

NAN, INF = float("nan"), float("inf")

#: (keyword, bad value, what the message shows of it): keywords of every env constructor
BAD_ENV_KWARGS: list[tuple[str, Any, str]] = [
    ("field", 42, "42"),
    ("field", "mars", "'mars'"),
    ("camera", "default", "'default'"),
    # a JSON object of CameraConfig fields is one (EnvSpec.to_json writes configs so)
    ("camera", {"widht": 160}, "'widht'"),
    ("step_deg", "3", "'3'"),
    ("step_deg", 45.0, "45.0"),
    ("step_deg", NAN, "nan"),
    ("action_set", 8, "8"),
    ("action_set", "3way", "'3way'"),
    ("frame_stack", True, "True"),
    ("frame_stack", 2.0, "2.0"),
    ("frame_stack", 0, "0"),
    ("success_mode", "nearby", "'nearby'"),
    ("success_mode", None, "None"),
    ("success_tolerance_deg", -1.0, "-1.0"),
    ("reward_resolution_deg", "1", "'1'"),
    ("ball_lost_reward", NAN, "nan"),
    ("ball_lost_reward", -INF, "-inf"),
    ("localisation_error", -0.5, "-0.5"),
    ("robot_x_range", (1.0,), "(1.0,)"),
    ("robot_x_range", (1.0, 2.0, 3.0), "(1.0, 2.0, 3.0)"),
    ("robot_x_range", (3.0, -3.0), "(3.0, -3.0)"),
    ("robot_y_range", ("a", "b"), "('a', 'b')"),
    ("robot_y_range", (0.0, NAN), "(0.0, nan)"),
    ("start_tilt_range_deg", 5.0, "5.0"),
    ("start_tilt_range_deg", (0.0, 90.0), "(0.0, 90.0)"),
    ("ball_distance_range", None, "None"),
    ("ball_distance_range", (0.0, 3.0), "(0.0, 3.0)"),
    ("max_start_draws", 0, "0"),
    ("max_start_draws", 10.5, "10.5"),
    ("max_start_draws", 10**9, "up to 1,000,000, got 1000000000"),
    ("config", "paper", "'paper'"),
    ("localisation", "ukf", "'ukf'"),
    ("colour", "red", "'red'"),  # unknown keyword
]

#: keywords only the native vector env (and make_vec's vector_entry_point) takes itself;
#: gym.make hands max_episode_steps to its TimeLimit wrapper instead (checked below)
BAD_VECTOR_KWARGS: list[tuple[str, Any, str]] = [
    ("num_envs", 0, "0"),
    ("num_envs", True, "True"),
    ("num_envs", 2.0, "2.0"),
    # a typo of a size: numpy's MemoryError allocating 10**12 sub-environments, no name
    ("num_envs", 10**12, "up to 65536, got 1000000000000"),
    ("max_episode_steps", 0, "0"),
    ("max_episode_steps", True, "True"),
    ("max_episode_steps", 2.5, "2.5"),
    ("max_episode_steps", -2, "-2"),  # -1 is Gymnasium's "no limit" (tests/envs/test_time_limit.py)
    ("max_episode_steps", "20", "'20'"),
    # past the int64 step counters: an OverflowError at the first step, no name
    ("max_episode_steps", 2**70, "at most 2**63 - 1"),
]


def assert_names(error: pytest.ExceptionInfo[ValueError], key: str, shown: str) -> None:
    message = str(error.value)
    assert key in message and shown in message, message


@pytest.mark.parametrize(("key", "value", "shown"), BAD_ENV_KWARGS)
def test_gym_make_rejects_bad_keyword(key: str, value: Any, shown: str) -> None:
    with pytest.raises(ValueError) as error:
        gym.make("ActiveVision-v0", **{key: value})
    assert_names(error, key, shown)


@pytest.mark.parametrize(("key", "value", "shown"), BAD_ENV_KWARGS + BAD_VECTOR_KWARGS)
def test_vector_env_rejects_bad_keyword(key: str, value: Any, shown: str) -> None:
    kwargs = {"num_envs": 2, key: value}
    with pytest.raises(ValueError) as error:
        ActiveVisionVectorEnv(**kwargs)
    assert_names(error, key, shown)
    with pytest.raises(ValueError) as error:
        gym.make_vec("ActiveVision-v0", vectorization_mode="vector_entry_point", **kwargs)
    assert_names(error, key, shown)


@pytest.mark.parametrize(
    ("key", "value", "shown"),
    [case for case in BAD_VECTOR_KWARGS if case[0] == "max_episode_steps"]
    + [
        ("render_mode", "rgb", "'rgb'"),
    ],
)
def test_single_env_rejects_bad_env_argument(key: str, value: Any, shown: str) -> None:
    with pytest.raises(ValueError) as error:
        ActiveVisionEnv(**{key: value})
    assert_names(error, key, shown)


def test_gym_make_time_limit_must_be_positive() -> None:
    # gym.make keeps max_episode_steps for its TimeLimit wrapper, which checks it itself
    with pytest.raises(ValueError, match=r"max_episode_steps.*0"):
        gym.make("ActiveVision-v0", max_episode_steps=0)


@pytest.mark.parametrize(
    ("cls", "key", "value", "shown"),
    [
        (CameraConfig, "width", 160.0, "160.0"),
        (CameraConfig, "height", True, "True"),
        (CameraConfig, "hfov", "1.0", "'1.0'"),
        (CameraConfig, "camera_height", NAN, "nan"),
        (CameraConfig, "tilt_min", None, "None"),
        (FieldSpec, "length", "9", "'9'"),
        (FieldSpec, "ball_radius", INF, "inf"),
        (FieldSpec, "penalty_area_width", "5", "'5'"),
    ],
)
def test_geometry_configs_reject_bad_types(cls: type, key: str, value: Any, shown: str) -> None:
    with pytest.raises(ValueError) as error:
        cls(**{key: value})
    assert_names(error, f"{cls.__name__}.{key}", shown)


def test_configs_normalise_json_values() -> None:
    """JSON has no tuples and writes 3.0 as 3: both still make the same config."""
    cfg = EnvConfig(step_deg=3, robot_x_range=[-3, 3], field="paper2019")
    assert cfg == EnvConfig(step_deg=3.0, robot_x_range=(-3.0, 3.0), field=FieldSpec.paper_2019())
    assert type(cfg.step_deg) is float and type(cfg.robot_x_range) is tuple
    assert CameraConfig(width=np.int64(80)).width == 80
    assert FieldSpec(penalty_area_length=None, penalty_area_width=None).penalty_area_width is None
    assert math.isclose(EnvConfig(camera=CameraConfig(hfov=1)).camera.hfov, 1.0)


#: (actions for N = 3 sub-envs, what the message shows): every one a ValueError
BAD_ACTIONS: list[tuple[Any, str]] = [
    (np.array([1.0, 0.0, 2.0]), "float64"),
    (np.array([0.5, 0, 2]), "float64"),
    (np.array([True, False, True]), "bool"),
    (np.array([np.nan, 0, 1]), "nan"),
    (np.array(["1", "0", "2"]), "<U1"),
    ([0, "a", 1], "'a'"),
    ([0, None, 1], "None"),
    (np.array([0, 9, 1]), "9"),
    (np.array([0, -1, 1]), "-1"),
    (np.array([0, 1]), "shape (2,)"),
    (np.array([[0], [1], [2]]), "shape (3, 1)"),
    (0, "shape ()"),
    ([[0], [1, 2], [3]], "[[0], [1, 2], [3]]"),
]


@pytest.mark.parametrize(("actions", "shown"), BAD_ACTIONS)
def test_vector_env_rejects_bad_actions(actions: Any, shown: str) -> None:
    envs = ActiveVisionVectorEnv(num_envs=3)
    envs.reset(seed=0)
    with pytest.raises(ValueError, match="invalid action") as error:
        envs.step(actions)
    assert shown in str(error.value), str(error.value)
    # nothing moved: the next valid step is the first step of the episodes
    *_, infos = envs.step(np.zeros(3, dtype=np.int64))
    assert (infos["step"] == 1).all()


@pytest.mark.parametrize("action", [9, -1, 1.0, True, np.float32(2), "1", None, np.array([1])])
def test_single_env_rejects_bad_actions(action: Any) -> None:
    env = gym.make("ActiveVision-v0")
    env.reset(seed=0)
    with pytest.raises(ValueError, match="invalid action"):
        env.step(action)


@dataclasses.dataclass(frozen=True)
class _Typed:
    """Every annotation form check_dataclass_fields supports."""

    flag: bool = False
    count: int = 1
    scale: float = 1.0
    limit: float = dataclasses.field(default=math.inf, metadata=ALLOW_NONFINITE)
    name: str = "a"
    mode: Literal["a", "b"] = "a"
    pair: tuple[float, int] = (0.0, 0)
    many: tuple[int, ...] = ()
    maybe: float | None = None
    camera: CameraConfig = dataclasses.field(default_factory=CameraConfig)

    def __post_init__(self) -> None:
        check_dataclass_fields(self)


@pytest.mark.parametrize(
    ("key", "value", "message"),
    [
        ("flag", 1, "_Typed.flag: expects bool, got 1"),
        ("count", np.bool_(True), "_Typed.count: expects int, got np.True_"),
        ("scale", "1", "_Typed.scale: expects float, got '1'"),
        ("scale", INF, "_Typed.scale: expects float with finite values, got inf"),
        ("name", 3, "_Typed.name: expects str, got 3"),
        ("mode", "c", "_Typed.mode: expects one of 'a', 'b', got 'c'"),
        ("pair", (1.0, 2.5), "_Typed.pair: expects tuple[float, int], got (1.0, 2.5)"),
        ("many", (1, "2"), "_Typed.many: expects tuple[int, ...], got (1, '2')"),
        ("maybe", NAN, "_Typed.maybe: expects float | None with finite values, got nan"),
        ("camera", None, "_Typed.camera: expects CameraConfig, got None"),
    ],
)
def test_check_dataclass_fields_messages(key: str, value: Any, message: str) -> None:
    with pytest.raises(ValueError) as error:
        _Typed(**{key: value})
    assert str(error.value) == message


def test_check_dataclass_fields_normalises() -> None:
    typed = _Typed(
        flag=np.bool_(True),
        count=np.int64(3),
        scale=2,
        limit=-INF,
        pair=[1, 2],
        many=[1, 2, 3],
        maybe=1,
    )
    assert typed == _Typed(
        flag=True, count=3, scale=2.0, limit=-INF, pair=(1.0, 2), many=(1, 2, 3), maybe=1.0
    )
    assert [type(v) for v in (typed.flag, typed.count, typed.scale, typed.maybe)] == [
        bool,
        int,
        float,
        float,
    ]
    assert type(typed.pair) is tuple and type(typed.pair[0]) is float
