"""Shared fixtures: the presets, and reproducible random joint vectors and poses."""

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
