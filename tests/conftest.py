"""Shared pytest fixtures (deliberately minimal: no global numpy/warning state is changed).

Tests import the verification scripts (``verification.*``: test geometries, report code)
through pytest's ``pythonpath = ["."]`` (pyproject.toml).
"""

from __future__ import annotations

import numpy as np
import pytest


@pytest.fixture
def rng() -> np.random.Generator:
    """A fresh, seeded generator per test, so every test is reproducible on its own."""
    return np.random.default_rng(12345)
