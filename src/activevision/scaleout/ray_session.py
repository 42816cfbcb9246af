"""Lazy Ray import and a context manager that starts (or joins) a Ray instance."""

from __future__ import annotations

import contextlib
import signal
import socket
import threading
from collections.abc import Iterator
from types import ModuleType
from typing import Any

RAY_INSTALL_HINT = "pip install activevision[ray]"


def require_ray() -> ModuleType:
    """Import and return :mod:`ray`, or raise ImportError saying how to install it."""
    try:
        import ray
        import ray.tune  # the sweep needs Tune: fail here, not mid-run
    except ImportError as error:
        raise ImportError(
            f"activevision.scaleout needs Ray with Tune: {RAY_INSTALL_HINT}"
            f" (or pip install 'ray[tune]'); import failed: {error}"
        ) from error
    return ray


@contextlib.contextmanager
def ray_session(
    address: str | None = None, num_cpus: int | None = None, **init_kwargs: Any
) -> Iterator[ModuleType]:
    """Yield :mod:`ray`, initialised.

    If Ray is already initialised in this process it is used as is and left running.
    Otherwise ``address=None`` starts a local instance (``num_cpus`` CPUs, default all,
    no dashboard) and ``address="auto"`` or ``"ray://host:10001"`` connects to an existing
    cluster; whatever this call started or connected is shut down on exit. The caller's
    SIGTERM handler is kept: ``ray.init`` sets its own, which exits with status 1.
    """
    ray = require_ray()
    if ray.is_initialized():
        yield ray
        return
    if address is not None:
        check_reachable(address)
    init_kwargs.setdefault("include_dashboard", False)
    if address is not None and num_cpus is not None:
        raise ValueError("num_cpus applies to a local Ray instance, not to --address")
    main_thread = threading.current_thread() is threading.main_thread()
    sigterm = signal.getsignal(signal.SIGTERM) if main_thread else None
    try:
        if address is None:
            ray.init(num_cpus=num_cpus, **init_kwargs)
        else:
            init_kwargs.pop("include_dashboard")  # the cluster's dashboard is its own business
            ray.init(address=address, **init_kwargs)
    finally:  # also where ray.init fails after it set its handler (a cluster it cannot join)
        if main_thread:
            signal.signal(signal.SIGTERM, signal.SIG_DFL if sigterm is None else sigterm)
    try:
        yield ray
    finally:
        ray.shutdown()


def check_reachable(address: str, timeout_s: float = 5.0) -> None:
    """ValueError, naming ``address``, when a ``HOST:PORT`` or ``ray://HOST:PORT`` address
    takes no connection within ``timeout_s``: Ray itself retries one for minutes (a GCS
    address) or half a minute (a client address), printing its own log lines. Other forms
    (``auto``, which finds a local cluster or fails at once) go to Ray as they are."""
    host, sep, port = address.removeprefix("ray://").rpartition(":")
    if not sep or not host or not port.isdigit():
        return
    try:
        with socket.create_connection((host.strip("[]"), int(port)), timeout=timeout_s):
            pass
    except OSError as error:
        raise ValueError(
            f"no Ray cluster answers at --address {address} ({error or type(error).__name__}):"
            " start one there (ray start --head), or check the host and port"
        ) from None
