"""Particle and node layouts of part 2: jittered 1D particles, their volumes, 2D node sets."""

from __future__ import annotations

import numpy as np

from mlsgalerkin.studies.kernels.config import DOMAIN_1D

__all__ = ["jittered_particles_1d", "local_spacing", "nodes_2d"]


def jittered_particles_1d(n: int, jitter: float, seed: int) -> np.ndarray:
    """``n`` particles on ``[0, 2]``, interior ones moved by ``U(-jitter, jitter) Δx`` (seeded)."""
    lo, hi = DOMAIN_1D
    x = np.linspace(lo, hi, n)
    dx = (hi - lo) / (n - 1)
    rng = np.random.default_rng([seed, n, 1])
    x[1:-1] += rng.uniform(-jitter, jitter, n - 2) * dx
    return np.sort(x)


def local_spacing(x: np.ndarray) -> np.ndarray:
    """Tributary length of sorted 1D particles (half-cells at the ends; sums to the length)."""
    x = np.asarray(x, float)
    v = np.empty_like(x)
    v[1:-1] = 0.5 * (x[2:] - x[:-2])
    v[0] = 0.5 * (x[1] - x[0])
    v[-1] = 0.5 * (x[-1] - x[-2])
    return v


def nodes_2d(layout: str, n: int, jitter: float, seed: int) -> np.ndarray:
    """``n * n`` nodes in the unit square.

    ``"jittered"``: lattice moved by ``U(-jitter, jitter) Δx`` per coordinate (clipped to the
    square); ``"random"``: uniformly random. Seeded by ``(seed, n, layout)``.
    """
    rng = np.random.default_rng([seed, n, 2 if layout == "jittered" else 3])
    if layout == "jittered":
        g = np.linspace(0.0, 1.0, n)
        p = np.stack(np.meshgrid(g, g, indexing="ij"), axis=-1).reshape(-1, 2)
        p = p + rng.uniform(-jitter, jitter, p.shape) / (n - 1)
        return np.clip(p, 0.0, 1.0)
    if layout == "random":
        return rng.random((n * n, 2))
    raise ValueError(f"unknown 2D layout {layout!r}")
