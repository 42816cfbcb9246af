"""``max_episode_steps`` as Gymnasium reads it: a positive int is the time limit, ``-1``
none, ``None`` the registration's. The native vector envs take it from ``make_vec`` as the
sync and async modes' ``TimeLimit`` wrappers do.

``gymnasium.make(id, max_episode_steps=n)`` (and ``make_vec``'s ``"sync"`` and ``"async"``
modes, which call it) applies ``n`` in its ``TimeLimit`` wrapper and tells the env nothing
(the env's ``spec`` says ``max_episode_steps=None``; Gymnasium 1.x), so a single env's
"did not happen" value (:func:`never`) is its own constructor's limit, 20 by default.
"""

from __future__ import annotations

import numbers

#: ``max_episode_steps=-1``: Gymnasium's "no TimeLimit wrapper"
NO_LIMIT = -1
#: The longest time limit: the step counters it is compared with are int64 (a larger one,
#: 2**70, was an OverflowError at the first step, not a ValueError naming it)
MAX_LIMIT = 2**63 - 1


def resolve_limit(value: object, default: int | None) -> int | None:
    """``max_episode_steps`` as ``gymnasium.make`` reads it: a positive int is the limit,
    ``-1`` no limit (``None``), ``None`` the registration's ``default``. Anything else (0,
    -2, past ``MAX_LIMIT``, a bool, a float, a string) is a ValueError naming
    ``max_episode_steps``."""
    if value is None:
        return default
    if isinstance(value, numbers.Integral) and not isinstance(value, bool):
        if int(value) == NO_LIMIT:
            return None
        if 1 <= int(value) <= MAX_LIMIT:
            return int(value)
    raise ValueError(
        "max_episode_steps: expects a positive integer (at most 2**63 - 1), -1 (no time"
        f" limit) or None, got {value!r}"
    )


def never(limit: int | None) -> int:
    """The info's value for "did not happen" (``steps_to_success``, ``ball_lost_step``): the
    time limit, or -1 without one."""
    return NO_LIMIT if limit is None else limit
