"""numba's ``cache=True`` for every kernel of the package, where numba can keep a cache.

numba keeps compiled kernels on disk beside the package, in ``~/.cache`` or in
``NUMBA_CACHE_DIR``. A read-only install run by a user without a writable home (a robot's
service account) has none of these, and ``@njit(cache=True)`` then refuses the import itself
("cannot cache function ...: no locator available"). These decorators cache where numba can
and compile afresh at each start where it cannot. (The robot runtime has its own, in
``runtime/preprocess.py``: it imports nothing else of activevision.)
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any, TypeVar, cast

from numba import njit, vectorize

#: a kernel's own type, kept by the decorators (numba's dispatchers are called as it is)
F = TypeVar("F", bound=Callable[..., Any])


def cached_njit(**options: Any) -> Callable[[F], F]:
    """``@njit(cache=True, **options)``, or without the cache where numba has nowhere to
    write it."""

    def compile_(function: F) -> F:
        try:
            return cast("F", njit(cache=True, **options)(function))
        except RuntimeError:  # no cache locator: a read-only install, no writable home
            return cast("F", njit(**options)(function))

    return compile_


def cached_vectorize(signatures: list[str], **options: Any) -> Callable[[Callable[..., Any]], Any]:
    """``@vectorize(signatures, cache=True, **options)``, or without the cache where numba
    has nowhere to write it."""

    def compile_(function: Callable[..., Any]) -> Any:  # a ufunc: takes arrays as well
        try:
            return vectorize(signatures, cache=True, **options)(function)
        except RuntimeError:
            return vectorize(signatures, **options)(function)

    return compile_
