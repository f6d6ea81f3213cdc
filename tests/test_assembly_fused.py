"""The fused solver entry points of the assembler agree with its numpy references."""

import numpy as np
import pytest

from mlsgalerkin import shape_functions
import numba

from mlsgalerkin.assembly import (
    internal_force_and_mass,
    internal_force_reference,
    lumped_mass_reference,
    velocity_gradient_divergence,
    velocity_gradient_reference,
)


@pytest.mark.parametrize("dim", [2, 3])
def test_fused_kernels_match_references(dim):
    rng = np.random.default_rng(dim)
    n_side = 12 if dim == 2 else 6
    g = np.arange(n_side) * 0.1
    x = np.stack(np.meshgrid(*[g] * dim, indexing="ij"), axis=-1).reshape(-1, dim)
    x += rng.uniform(-0.02, 0.02, x.shape)
    table = shape_functions(x, x, h=0.13, basis="linear")
    v = rng.standard_normal(x.shape)
    L, div = velocity_gradient_divergence(table, v)
    L_ref = velocity_gradient_reference(table, v)
    np.testing.assert_allclose(L, L_ref, rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(div, np.trace(L_ref, axis1=1, axis2=2), rtol=1e-12, atol=1e-12)

    sig = rng.standard_normal((x.shape[0], dim, dim))
    V = rng.uniform(0.5, 1.5, x.shape[0]) * 0.1**dim
    M = rng.uniform(0.5, 1.5, x.shape[0])
    for threads in range(1, numba.config.NUMBA_NUM_THREADS + 1):
        numba.set_num_threads(threads)
        f, m = internal_force_and_mass(table, sig * V[:, None, None], M)
        np.testing.assert_allclose(f, internal_force_reference(table, sig, V), rtol=1e-11, atol=1e-12)
        np.testing.assert_allclose(m, lumped_mass_reference(table, M), rtol=1e-12, atol=1e-14)
    numba.set_num_threads(numba.config.NUMBA_NUM_THREADS)
    assert abs(f.sum(axis=0)).max() < 1e-10 * abs(f).max()  # Σ f_int = 0
