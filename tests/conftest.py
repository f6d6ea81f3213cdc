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


@pytest.fixture
def one_numba_thread():
    """numba on one thread for the test (tiny examples: threads only add overhead, and they slow
    down badly on a loaded machine)."""
    import numba

    before = numba.get_num_threads()
    numba.set_num_threads(1)
    try:
        yield
    finally:
        numba.set_num_threads(before)
