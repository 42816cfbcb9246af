"""The time limit an env runs under, as Gymnasium means ``max_episode_steps``.

``gymnasium.make(id, max_episode_steps=n)`` (and ``make_vec``'s ``"sync"`` and ``"async"``
modes, which call it) applies ``n`` in its ``TimeLimit`` wrapper and never passes it to the
env: the env's ``spec`` that ``make`` sets says ``max_episode_steps=None`` whatever the limit
(Gymnasium 1.x). :func:`limit_from_make` reads the limit from ``make`` itself, so an env that
reports the limit in its infos (``ActiveVision-v0``'s "did not happen" value) reports the
one it really runs under, as the native vector env, which ``make_vec`` hands the keyword to.
"""

from __future__ import annotations

import numbers
import sys

#: ``max_episode_steps=-1``: Gymnasium's "no TimeLimit wrapper"
NO_LIMIT = -1


def resolve_limit(value: object, default: int | None) -> int | None:
    """``max_episode_steps`` as ``gymnasium.make`` reads it: a positive int is the limit,
    ``-1`` no limit (``None``), ``None`` the registration's ``default``. Anything else (0,
    -2, a bool, a float, a string) is a ValueError naming ``max_episode_steps``."""
    if value is None:
        return default
    if isinstance(value, numbers.Integral) and not isinstance(value, bool):
        if int(value) == NO_LIMIT:
            return None
        if int(value) >= 1:
            return int(value)
    raise ValueError(
        f"max_episode_steps: expects a positive integer, -1 (no time limit) or None, got {value!r}"
    )


#: how far up the stack :func:`limit_from_make` looks for ``make`` (the env's own
#: ``__init__``, a subclass's, ``make``)
_MAX_DEPTH = 8


def limit_from_make(env_class: type) -> tuple[bool, int | None]:
    """``(True, limit)`` when ``gymnasium.make`` is constructing ``env_class`` right now
    (``limit``: the positive int its ``TimeLimit`` wrapper will apply, or None for none);
    ``(False, None)`` otherwise (the env made directly, or by some other entry point).

    Reads ``make``'s arguments from its frame, applying its rule: ``-1`` no wrapper, an int
    that limit, ``None`` the spec's ``max_episode_steps``. Gymnasium has no public way to
    tell an env its limit; tests pin this against the installed Gymnasium.
    """
    try:
        from gymnasium.envs.registration import make
    except ImportError:  # pragma: no cover - the envs need Gymnasium anyway
        return False, None
    frame = sys._getframe(1)
    for _ in range(_MAX_DEPTH):
        frame = frame.f_back  # type: ignore[assignment]
        if frame is None:
            break
        if frame.f_code is make.__code__:
            local = frame.f_locals
            if local.get("env_creator") is not env_class or "env_spec" not in local:
                return False, None  # make is building another env, which made this one
            limit = local.get("max_episode_steps")
            if limit == NO_LIMIT:
                return True, None
            if limit is None:
                limit = getattr(local["env_spec"], "max_episode_steps", None)
            return True, int(limit) if isinstance(limit, int) and limit >= 1 else None
    return False, None


def never(limit: int | None) -> int:
    """The info's value for "did not happen" (``steps_to_success``, ``ball_lost_step``): the
    time limit, or -1 without one."""
    return NO_LIMIT if limit is None else limit
