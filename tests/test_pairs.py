"""The pair-geometry helper (mlsgalerkin.pairs) agrees with its numpy reference bit for bit."""

import numpy as np
import pytest

from mlsgalerkin.neighbors import find_neighbors
from mlsgalerkin.pairs import pair_offsets, pair_offsets_reference


@pytest.mark.parametrize("dim", [1, 2, 3])
def test_pair_offsets_agree_with_the_reference_bit_for_bit(dim):
    rng = np.random.default_rng(dim)
    x = rng.uniform(-1.0, 1.0, (400, dim)) * 10.0 ** rng.uniform(-3, 3)   # any scale
    nb = find_neighbors(x, x, 0.4 * np.ptp(x))
    d, r2 = pair_offsets(x, nb.indptr, nb.indices)
    d_ref, r2_ref = pair_offsets_reference(x, nb.indptr, nb.indices)
    assert nb.indices.size > 10 * len(x)
    np.testing.assert_array_equal(d, d_ref)
    np.testing.assert_array_equal(r2, r2_ref)
    rows = np.repeat(np.arange(len(x)), np.diff(nb.indptr))
    np.testing.assert_array_equal(d[:, :dim], x[nb.indices] - x[rows])     # x_j − x_i
    assert np.all(d[:, dim:] == 0.0)
    # r² is the loop sum over the dimensions (the kernels it replaced), to the last bit
    loop = np.zeros(len(rows))
    for a in range(dim):
        loop += (x[rows, a] - x[nb.indices, a]) ** 2
    np.testing.assert_array_equal(r2, loop)


def test_self_pairs_have_zero_offset():
    x = np.array([[0.1, 0.2], [0.4, 0.6]])
    d, r2 = pair_offsets(x, np.array([0, 2, 4]), np.array([0, 1, 1, 0], dtype=np.int32))
    assert r2.tolist() == [0.0, 0.25, 0.0, 0.25]
    assert d[0].tolist() == [0.0, 0.0, 0.0]
