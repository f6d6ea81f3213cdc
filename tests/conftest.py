"""Shared pytest fixtures (deliberately minimal: no global numpy/warning state is changed).

The repository root is appended to ``sys.path`` so that tests can import the verification
scripts (``verification.*``), whose test geometries and report code they check.
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parents[1]
if str(ROOT) not in sys.path:
    sys.path.append(str(ROOT))


@pytest.fixture
def rng() -> np.random.Generator:
    """A fresh, seeded generator per test, so every test is reproducible on its own."""
    return np.random.default_rng(12345)
