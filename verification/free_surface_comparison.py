"""Free-surface detectors compared on 2D test geometries: errors against the exact surface and cost.

Both detectors of :mod:`mlsgalerkin.fluid.free_surface` (the circle-coverage test of Koh et
al. 2012 and the neighbour-deficit screen) on a square lattice block, a disc of concentric
rings, a jittered block, a block with a cavity and a hexagonal block (spacing ``r0 = 1``)::

    python verification/free_surface_comparison.py                 # the table of docs/theory/galerkin_fluid.md
    python verification/free_surface_comparison.py --jitter 0.25 --seed 3

The test geometries (with their exact surfaces) are also used by ``tests/test_fluid_free_surface.py``.
"""

from __future__ import annotations

import argparse
import sys
import time

import numpy as np

from mlsgalerkin.fluid.free_surface import detect_free_surface
from mlsgalerkin.neighbors import find_neighbors

BoolArray = np.ndarray
FloatArray = np.ndarray


def lattice_block(n_side: int, hole: int = 0) -> tuple[FloatArray, BoolArray]:
    """Square lattice ``n_side``² (spacing 1) with an optional centred ``hole``² cavity.

    Returns positions and the exact surface: a particle is on the surface iff one of its four
    lattice (axis) neighbours is missing (the block's outer ring and the cavity's edge rows;
    the particles diagonal to the cavity corners are interior).
    """
    ij = np.stack(np.meshgrid(np.arange(n_side), np.arange(n_side), indexing="ij"), axis=-1)
    ij = ij.reshape(-1, 2)
    present = np.ones((n_side + 2, n_side + 2), dtype=bool)
    present[0, :] = present[-1, :] = present[:, 0] = present[:, -1] = False
    if hole:
        lo = (n_side - hole) // 2
        present[lo + 1 : lo + 1 + hole, lo + 1 : lo + 1 + hole] = False
    keep = present[ij[:, 0] + 1, ij[:, 1] + 1]
    ij = ij[keep]
    a, b = ij[:, 0] + 1, ij[:, 1] + 1
    exact = ~(present[a - 1, b] & present[a + 1, b] & present[a, b - 1] & present[a, b + 1])
    return ij.astype(np.float64), exact


def ring_disc(n_rings: int) -> tuple[FloatArray, BoolArray]:
    """Disc of concentric rings at radii 0, 1, …, n_rings (spacing ≈ 1); surface = last ring."""
    pts = [np.zeros((1, 2))]
    ring = [np.zeros(1, dtype=int)]
    for k in range(1, n_rings + 1):
        m = int(round(2 * np.pi * k))
        t = 2 * np.pi * (np.arange(m) + 0.5 * (k % 2)) / m
        pts.append(k * np.stack([np.cos(t), np.sin(t)], axis=1))
        ring.append(np.full(m, k))
    ring_all = np.concatenate(ring)
    return np.concatenate(pts), ring_all == n_rings


def hexagonal_block(n_side: int) -> tuple[FloatArray, BoolArray]:
    """Hexagonal lattice, ``n_side`` rows of ``n_side`` (nearest distance 1), odd rows shifted by
    1/2; exact surface = first and last rows and the first and last particle of every row (on the
    zigzag sides this includes the recessed particles, which the circle test calls interior)."""
    k, i = np.meshgrid(np.arange(n_side), np.arange(n_side), indexing="ij")
    x = np.stack([i + 0.5 * (k % 2), k * np.sqrt(3.0) / 2.0], axis=-1).reshape(-1, 2)
    k, i = k.ravel(), i.ravel()
    exact = (k == 0) | (k == n_side - 1) | (i == 0) | (i == n_side - 1)
    return x, exact


def free_surface_method_comparison(
    n_side: int = 40, jitter: float = 0.1, seed: int = 0, repeats: int = 5
) -> list[dict]:
    """Compare the circle and cheap detectors on four 2D geometries (spacing ``r0 = 1``).

    Cases: a square lattice block ``n_side``²; a disc of concentric rings (``n_side // 2``
    rings); the block with each particle jittered by ``U(-jitter, jitter) r0`` per coordinate;
    the block with a square cavity of ``n_side // 4``² particles removed; a hexagonal block.
    The exact surface is the outer layer (plus the cavity's edge rows). Each row has ``case``,
    ``n``, ``n_exact``, ``n_circle``, ``n_cheap``, ``circle_errors`` and ``cheap_errors``
    (misclassified particles against the exact answer), ``agree`` (particles on which the
    methods agree) and ``circle_us`` / ``cheap_us`` (best-of-``repeats`` wall time per
    particle in µs, neighbour search excluded; the first call compiles and is not timed).
    """
    rng = np.random.default_rng(seed)
    block, block_exact = lattice_block(n_side)
    disc, disc_exact = ring_disc(n_side // 2)
    jittered = block + rng.uniform(-jitter, jitter, block.shape)
    cavity, cavity_exact = lattice_block(n_side, hole=max(2, n_side // 4))
    hexagonal, hexagonal_exact = hexagonal_block(n_side)
    cases = [
        ("lattice block", block, block_exact),
        ("disc (rings)", disc, disc_exact),
        (f"jittered block ±{jitter:g} r0", jittered, block_exact),
        ("block with cavity", cavity, cavity_exact),
        ("hexagonal block (zigzag sides)", hexagonal, hexagonal_exact),
    ]
    rows = []
    for name, x, exact in cases:
        table = find_neighbors(x, x, radius=2.2)
        timings = {}
        flags = {}
        for method in ("circle", "cheap"):
            flags[method] = detect_free_surface(x, table, 1.0, method=method)
            best = np.inf
            for _ in range(repeats):
                t0 = time.perf_counter()
                detect_free_surface(x, table, 1.0, method=method)
                best = min(best, time.perf_counter() - t0)
            timings[method] = best / x.shape[0] * 1e6
        rows.append(
            {
                "case": name,
                "n": int(x.shape[0]),
                "n_exact": int(exact.sum()),
                "n_circle": int(flags["circle"].sum()),
                "n_cheap": int(flags["cheap"].sum()),
                "circle_errors": int((flags["circle"] != exact).sum()),
                "cheap_errors": int((flags["cheap"] != exact).sum()),
                "agree": int((flags["circle"] == flags["cheap"]).sum()),
                "circle_us": round(float(timings["circle"]), 3),
                "cheap_us": round(float(timings["cheap"]), 3),
            }
        )
    return rows


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--n-side", type=int, default=40, help="particles per side of the blocks")
    parser.add_argument("--jitter", type=float, default=0.1, help="jitter of the jittered block (units of r0)")
    parser.add_argument("--seed", type=int, default=0, help="seed of the jitter")
    args = parser.parse_args(argv)
    rows = free_surface_method_comparison(n_side=args.n_side, jitter=args.jitter, seed=args.seed)
    cols = list(rows[0])
    print("| " + " | ".join(cols) + " |")
    print("|" + "---|" * len(cols))
    for r in rows:
        print("| " + " | ".join(str(r[c]) for c in cols) + " |")
    return 0


if __name__ == "__main__":
    sys.exit(main())
