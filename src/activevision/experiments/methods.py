"""The registry of head-control methods: a name maps to a factory of a fresh policy.

``activevision evaluate`` / ``compare`` / ``episode`` take their choices, their order and
their help from it, so a method added here is everywhere at once::

    @register_method("my_scan", help="my team's scan")
    def _my_scan(context: MethodContext) -> HeadPolicy:
        return MyScan(context.config)

A method of your own plays without editing the package: ``activevision evaluate`` /
``compare --strategy FILE.py:NAME`` calls ``NAME(context)`` (a :class:`MethodContext`) for
each policy it needs (:func:`user_method`).
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from activevision.envs.config import EnvConfig
from activevision.envs.observations import Observation
from activevision.experiments.match_methods import built_by_user, load_strategy, user_errors
from activevision.experiments.policies import (
    EntropyPolicy,
    HeadPolicy,
    HeadTarget,
    LearnedPolicy,
    OnnxPolicy,
    OraclePolicy,
    RandomPolicy,
    ScanPolicy,
)


@dataclass(frozen=True)
class MethodContext:
    """What a factory may use to build its policy."""

    config: EnvConfig  #: the env the policy plays
    error: float = 0.0  #: localisation error the entropy methods plan with (m and rad)
    run_dir: Path | None = None  #: training run of the learned policy
    weights: str = "final"  #: which of its weights: "final" or "best"


MethodFactory = Callable[[MethodContext], HeadPolicy]


@dataclass(frozen=True)
class Method:
    name: str
    factory: MethodFactory
    help: str
    in_compare: bool  #: part of ``activevision compare``'s default set
    needs_run: bool  #: needs ``--run``


_REGISTRY: dict[str, Method] = {}


def register_method(
    name: str, *, help: str, in_compare: bool = True, needs_run: bool = False
) -> Callable[[MethodFactory], MethodFactory]:
    """Register ``factory`` under ``name`` (in registration order: the compare order)."""

    def add(factory: MethodFactory) -> MethodFactory:
        if name in _REGISTRY:
            raise ValueError(f"method {name!r} is registered already")
        _REGISTRY[name] = Method(name, factory, help, in_compare, needs_run)
        return factory

    return add


def method_names() -> tuple[str, ...]:
    """Every registered method, in registration order."""
    return tuple(_REGISTRY)


def compare_method_names() -> tuple[str, ...]:
    """The methods of ``activevision compare`` and the default of ``evaluate``, in order."""
    return tuple(n for n, m in _REGISTRY.items() if m.in_compare)


def method(name: str) -> Method:
    if name not in _REGISTRY:
        raise ValueError(f"unknown method {name!r}; choose from {', '.join(_REGISTRY)}")
    return _REGISTRY[name]


def runnable_methods(names: Sequence[str], run_dir: str | Path | None) -> list[str]:
    """``names`` without the methods that need a run when there is none (the defaults)."""
    return [n for n in names if run_dir is not None or not method(n).needs_run]


def check_runs(names: Sequence[str], run_dir: str | Path | None) -> None:
    """ValueError for a method in ``names`` that needs a run directory when there is none."""
    for name in names:
        if method(name).needs_run and run_dir is None:
            raise ValueError(f"the {name} policy needs a run directory (--run runs/NAME)")


def make_policy(
    name: str,
    error: float,
    config: EnvConfig,
    run_dir: str | Path | None = None,
    weights: str = "final",
) -> HeadPolicy:
    """A fresh policy of method ``name`` (see :class:`MethodContext` for the arguments)."""
    check_runs([name], run_dir)
    entry = method(name)
    run = Path(run_dir) if run_dir is not None else None
    return entry.factory(MethodContext(config or EnvConfig(), error, run, weights))


@register_method("learned", help="a trained run's Q-network (--run)", needs_run=True)
def _learned(context: MethodContext) -> HeadPolicy:
    assert context.run_dir is not None
    return LearnedPolicy.from_run(context.run_dir, weights=context.weights)


@register_method("entropy_jump", help="Algorithm 1 on the believed pose, jump there")
def _entropy_jump(context: MethodContext) -> HeadPolicy:
    return EntropyPolicy(context.error, jump=True, config=context.config)


@register_method("entropy_steps", help="Algorithm 1 on the believed pose, 3-degree moves")
def _entropy_steps(context: MethodContext) -> HeadPolicy:
    return EntropyPolicy(context.error, jump=False, config=context.config)


@register_method("oracle", help="greedy moves to the true goal (the ceiling)")
def _oracle(context: MethodContext) -> HeadPolicy:
    return OraclePolicy(context.config)


@register_method("scan", help="pan sweep around the ball, tilt on the ball")
def _scan(context: MethodContext) -> HeadPolicy:
    return ScanPolicy(config=context.config)


@register_method("random", help="uniformly random moves")
def _random(context: MethodContext) -> HeadPolicy:
    return RandomPolicy(context.config)


@register_method("shipped", help="the policy shipped in the package (ONNX)", in_compare=False)
def _shipped(context: MethodContext) -> HeadPolicy:
    from activevision.runtime import pretrained_policy_path

    policy = OnnxPolicy(pretrained_policy_path())
    policy.name = "shipped"  # the episode figure's row (the class's "onnx" said whose neither)
    return policy


def user_method(spec: str) -> tuple[str, MethodFactory]:
    """A user's method from ``"path/to/file.py:NAME"`` or ``"package.module:NAME"``
    (``--strategy``): ``NAME`` is a factory like the registry's, a class or function that
    takes a :class:`MethodContext` and returns a :class:`HeadPolicy` (``reset(info, rng)``,
    ``act(obs, info)``). Returns its label (its ``name`` attribute, else ``NAME``) and the
    factory, checked as it builds; ValueError names what is wrong, in one line, and so does
    the policy it builds for an exception in its ``reset`` or ``act``, wherever it plays."""

    label, factory = load_strategy(spec)
    if label in _REGISTRY:
        raise ValueError(
            f"--strategy {spec}: its label {label!r} is a built-in method's; give NAME a"
            " name attribute of its own"
        )

    def make(context: MethodContext) -> HeadPolicy:
        contract = "a policy has reset(info, rng) and act(obs, info): see HeadPolicy"
        return _UsersPolicy(built_by_user(factory, context, label, "context", contract), label)

    return label, make


class _UsersPolicy:
    """A user's policy, under its label: an exception its ``reset`` or ``act`` raises is one
    ValueError line naming it, the method and the line of their file (in every episode of
    ``evaluate`` and every level of ``compare``, not a traceback)."""

    def __init__(self, policy: HeadPolicy, label: str) -> None:
        self.policy = policy
        self.name = label

    def reset(self, info: dict, rng: np.random.Generator) -> None:
        with user_errors(f"--strategy {self.name}: reset"):
            self.policy.reset(info, rng)

    def act(self, obs: Observation, info: dict) -> int | HeadTarget:
        with user_errors(f"--strategy {self.name}: act"):
            return self.policy.act(obs, info)
