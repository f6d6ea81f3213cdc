"""The cavitation floor with a void memory (``TaitPressure(negative_pressure="cavitate",
void_memory=ε_max)``): the kernel against its numpy reference, the bookkeeping of one particle
opened and closed again, and bad input refused."""

from __future__ import annotations

import math

import numpy as np
import pytest

from mlsgalerkin.fluid.eos import TaitPressure, remember_void, remember_void_reference


def test_the_kernel_agrees_with_its_numpy_reference(rng):
    n = 500
    rho0 = np.where(rng.random(n) < 0.5, 1000.0, 1100.0)
    rho = rho0 * rng.uniform(0.7, 1.3, n)
    eps = np.where(rng.random(n) < 0.5, rng.uniform(0.0, 0.3, n), 0.0)
    a = (rho.copy(), eps.copy())
    b = (rho.copy(), eps.copy())
    na = remember_void(a[0], rho0, a[1], 0.2)
    nb = remember_void_reference(b[0], rho0, b[1], 0.2)
    assert na == nb == int(np.count_nonzero(rho < rho0))
    np.testing.assert_allclose(a[0], b[0], rtol=1e-14)
    np.testing.assert_allclose(a[1], b[1], rtol=1e-14, atol=1e-15)
    untouched = (rho >= rho0) & ((eps == 0.0) | (rho == rho0))
    np.testing.assert_array_equal(a[0][untouched], rho[untouched])   # bit for bit where nothing happens


def test_an_opened_particle_carries_no_pressure_until_it_has_closed_its_void():
    rho0 = np.array([1000.0])
    rho, eps = np.array([1000.0 / math.exp(0.05)]), np.zeros(1)     # opened by a strain of 0.05
    assert remember_void(rho, rho0, eps, 0.2) == 1
    assert rho[0] == 1000.0 and eps[0] == pytest.approx(0.05)
    rho[0] = 1000.0 * math.exp(0.03)                                  # compressed by 0.03: still open
    remember_void(rho, rho0, eps, 0.2)
    assert rho[0] == pytest.approx(1000.0) and eps[0] == pytest.approx(0.02)
    rho[0] = 1000.0 * math.exp(0.05)                                  # by 0.05 more: 0.03 past closed
    remember_void(rho, rho0, eps, 0.2)
    assert eps[0] == 0.0 and rho[0] == pytest.approx(1000.0 * math.exp(0.03))
    rho[0] = 1000.0 * math.exp(-1.0)                                  # a wide opening is capped
    remember_void(rho, rho0, eps, 0.2)
    assert eps[0] == pytest.approx(0.2) and rho[0] == 1000.0


@pytest.mark.parametrize("kw, match", [({"void_memory": -0.1}, "finite number >= 0"),
                                       ({"void_memory": math.inf}, "finite number >= 0"),
                                       ({"void_memory": 0.2, "negative_pressure": "allow"}, "cavitate' only")])
def test_bad_void_memory_is_refused(kw, match):
    kw.setdefault("negative_pressure", "cavitate")
    problems = TaitPressure(20.0, **kw).check(_Context())
    assert any(match in p for p in problems), problems


class _Context:
    def provides(self, name: str) -> bool:
        return False
