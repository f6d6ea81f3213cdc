"""``verification/volume_attribution.py``: each class's contribution to a frame's volume error,
on a block whose top row is stretched (a loose surface) and on a plain lattice block."""

from __future__ import annotations

import numpy as np
import pytest

from mlsgalerkin.fluid import lattice
from mlsgalerkin.fluid.distribution import cell_volumes, neighbourhood_excess
from verification.volume_attribution import CLASSES, FLOOR, frame_attribution

DX = 0.01


def _classes(row: dict) -> float:
    return sum(row[f"{name}: contribution"] for name, _, _ in CLASSES)


def test_a_lattice_block_has_no_error_in_any_class():
    x = lattice((0.0, 0.0), (0.3, 0.1), DX) + 0.00037
    row = frame_attribution(x, np.full(len(x), DX**2), DX)
    assert row["volume_error"] == pytest.approx(0.0, abs=1e-12)
    for name, _, _ in CLASSES:
        assert row[f"{name}: contribution"] == pytest.approx(0.0, abs=1e-12)
    assert row["surface rows and bulk: particles"] > 0.95   # only the four corners have fewer than 5


def test_a_stretched_top_row_carries_the_error():
    """A lattice block with a top row at 1.3 spacings: the closing fills the 0.3-spacing gaps of
    that row, so the error is positive, the classes add up to it, and the loose row's particles
    (most with four neighbours within 1.5 spacings, the rest five) carry it."""
    block = lattice((0.0, 0.0), (0.4, 0.1), DX) + 0.00037
    xs = np.arange(0.005, 0.4, 1.3 * DX)
    top = np.c_[xs, np.full(len(xs), block[:, 1].max() + DX)] + [0.00037, 0.0]
    x = np.vstack([block, top])
    row = frame_attribution(x, np.full(len(x), DX**2), DX)
    assert row["volume_error"] > 0.005
    assert _classes(row) == pytest.approx(row["volume_error"], abs=1e-12)
    shares = cell_volumes(x, DX)
    total = len(x) * DX**2
    top_excess = (shares[len(block):] - DX**2).sum() / total
    under = np.flatnonzero(np.isclose(block[:, 1], block[:, 1].max()))
    assert top_excess > 0.8 * row["volume_error"]          # the loose row carries it, the row under it the rest
    assert top_excess + (shares[under] - DX**2).sum() / total == pytest.approx(row["volume_error"], rel=1e-9)
    assert row["sheets and ragged surface: contribution"] > 0.5 * row["volume_error"]  # ... most of it 3-4 neighbours
    floor = np.arange(len(x)) >= len(block)                 # the loose row at the cavitation floor
    split = frame_attribution(x, np.full(len(x), DX**2), DX, shares, floor)
    assert split[f"{FLOOR}: contribution"] == pytest.approx(top_excess, rel=1e-12)
    assert split[f"{FLOOR}: particles"] == pytest.approx(len(top) / len(x))
    excess = neighbourhood_excess(x, shares, np.full(len(x), DX**2), DX)
    deep = x[:, 1] < 0.05
    assert excess[len(block):].mean() > 0.05 and np.abs(excess[deep]).max() < 1e-12
