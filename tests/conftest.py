"""Shared fixtures: the presets, reproducible random joint vectors and poses, and servers."""

from __future__ import annotations

import numpy as np
import pytest

from ur10core import Arm


@pytest.fixture(scope="session")
def course() -> Arm:
    return Arm.preset("course")


@pytest.fixture(scope="session", params=Arm.PRESETS)
def any_arm(request) -> Arm:
    return Arm.preset(request.param)


def random_joints(n: int, seed: int = 0) -> np.ndarray:
    """n joint vectors uniform in (-π, π]^6."""
    return -np.random.default_rng(seed).uniform(-np.pi, np.pi, (n, 6))


def wrapped_difference(a, b) -> np.ndarray:
    """|a − b| modulo 2π, in [0, π]."""
    return np.abs(np.remainder(np.asarray(a) - np.asarray(b) + np.pi, 2 * np.pi) - np.pi)


@pytest.fixture
def app():
    """A server in independent mode on a free port, in this process."""
    from app.server import TeachingServer

    server = TeachingServer(port=0)
    yield server
    server.stop()


@pytest.fixture
def classroom():
    """A server in shared demo mode (``--shared``) on a free port, in this process."""
    from app.server import TeachingServer

    server = TeachingServer(port=0, shared=True)
    yield server
    server.stop()


@pytest.fixture(autouse=True)
def collect_garbage_after_server_tests(request):
    """Finalise what a test's servers left behind (asyncio tasks whose errors nobody read) now.

    On CPython 3.11 a collection that runs inside ``ast.parse`` (pytest rewriting an
    import) and finalises such a task, which formats a traceback and so parses too,
    corrupts the parser's recursion counter: https://github.com/python/cpython/issues/106905.
    Only tests that run servers leave such tasks.
    """
    yield
    if any(request.node.get_closest_marker(name) for name in ("server", "browser")):
        import gc

        gc.collect()
