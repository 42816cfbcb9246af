"""The head-control method registry: one table behind make_policy, the CLI and compare."""

import numpy as np
import pytest

from activevision.cli import build_parser
from activevision.envs import EnvConfig
from activevision.experiments.methods import (
    compare_method_names,
    make_policy,
    method_names,
    register_method,
)
from activevision.experiments.policies import HeadTarget, OnnxPolicy


def test_every_registered_method_builds_and_acts():
    from activevision.envs import ActiveVisionEnv

    for name in method_names():
        if name == "learned":
            continue  # needs a trained run: tests/cli
        policy = make_policy(name, 0.0, EnvConfig())
        # the shipped policy observes more than the image; the others read only info
        config = policy.env_config() if isinstance(policy, OnnxPolicy) else EnvConfig()
        env = ActiveVisionEnv(config)
        obs, info = env.reset(seed=5)
        policy.reset(info, np.random.default_rng(0))
        action = policy.act(obs, info)
        assert isinstance(action, HeadTarget) or 0 <= action < 9


def test_compare_set_is_the_registry_without_shipped():
    assert compare_method_names() == (
        "learned",
        "entropy_jump",
        "entropy_steps",
        "oracle",
        "scan",
        "random",
    )
    assert set(method_names()) == {*compare_method_names(), "shipped"}


def test_cli_choices_come_from_the_registry(capsys):
    assert build_parser().parse_args(["evaluate", "--methods", *method_names()]).methods
    assert build_parser().parse_args(["compare", "--methods", "scan"]).methods == ["scan"]
    with pytest.raises(SystemExit):
        build_parser().parse_args(["compare", "--methods", "shipped"])  # not a compare method


def test_duplicate_registration_is_refused():
    with pytest.raises(ValueError, match="registered already"):
        register_method("scan", help="again")(lambda context: None)


@pytest.mark.parametrize(("action_set", "n_actions"), [("8way", 9), ("4way", 5)])
def test_random_draws_from_the_envs_action_set(action_set, n_actions):
    policy = make_policy("random", 0.0, EnvConfig(action_set=action_set))
    policy.reset({}, np.random.default_rng(0))
    drawn = {policy.act(None, {}) for _ in range(500)}
    assert drawn == set(range(n_actions))
