"""A run's numbers do not depend on the numba thread count: every point → node sum is a gather
over the table's node columns in ascending point order (``ShapeTable.node_columns``)."""

from __future__ import annotations

import dataclasses

import numba
import numpy as np
import pytest

from mlsgalerkin import assembly, shape_functions
from mlsgalerkin.approximation.build import evaluate_shape_functions
from mlsgalerkin.approximation.table import NodeColumns
from mlsgalerkin.io import latest_checkpoint, load_checkpoint
from mlsgalerkin.neighbors import find_neighbors
from mlsgalerkin.problem import load_problem, prepare_problem
from mlsgalerkin.simulation import Simulation

MANY = numba.config.NUMBA_NUM_THREADS
needs_threads = pytest.mark.skipif(MANY < 2, reason="numba has one thread on this machine")


def _scattered_points(rng, n=300, dim=2):
    x = rng.uniform(0.0, 1.0, (n, dim))
    return x, np.full(n, 0.09)


def test_node_columns_are_a_stable_sort_of_the_pairs_by_node(rng):
    x, h = _scattered_points(rng)
    nb = find_neighbors(x, x, node_radius=2.0 * h)
    cols = NodeColumns.of(nb.indptr, nb.indices, x.shape[0])
    order = np.argsort(nb.indices, kind="stable")        # by node, then by pair (= by row)
    np.testing.assert_array_equal(cols.pairs, order)
    np.testing.assert_array_equal(cols.rows, np.repeat(np.arange(x.shape[0]), np.diff(nb.indptr))[order])
    np.testing.assert_array_equal(cols.indptr, np.concatenate([[0], np.cumsum(np.bincount(nb.indices,
                                                                                          minlength=x.shape[0]))]))


@needs_threads
def test_node_columns_do_not_depend_on_the_thread_count(rng):
    x, h = _scattered_points(rng, n=1000)
    nb = find_neighbors(x, x, node_radius=2.0 * h)
    built = []
    try:
        for threads in range(1, MANY + 1):
            numba.set_num_threads(threads)
            built.append(NodeColumns.of(nb.indptr, nb.indices, x.shape[0]))
    finally:
        numba.set_num_threads(MANY)
    for cols in built[1:]:
        for name in ("indptr", "pairs", "rows"):
            np.testing.assert_array_equal(getattr(cols, name), getattr(built[0], name))


@needs_threads
@pytest.mark.parametrize("dim", [1, 2, 3])
def test_assembled_sums_are_the_same_bits_on_any_thread_count(dim, rng):
    n_side = {1: 60, 2: 14, 3: 6}[dim]
    g = np.stack(np.meshgrid(*[np.linspace(0.0, 1.0, n_side)] * dim, indexing="ij"), -1).reshape(-1, dim)
    g = g + rng.uniform(-0.25, 0.25, g.shape) / (n_side - 1)
    table = shape_functions(g, g, 1.4 / (n_side - 1))
    sig_v = rng.normal(size=(len(g), dim, dim))
    M = rng.uniform(0.5, 1.5, len(g))
    c = rng.uniform(0.0, 1.0, len(g))
    got = []
    try:
        for threads in range(1, MANY + 1):
            numba.set_num_threads(threads)
            fresh = dataclasses.replace(table, meta={})                # columns built on this thread count
            f, m = assembly.internal_force_and_mass(fresh, sig_v, M)
            terms = assembly.integration_terms(fresh, M, sig_v, c)
            got.append([f, m, assembly.lumped_mass(fresh, M), terms.residual, terms.volume, terms.stress_volume,
                        terms.lowest])
    finally:
        numba.set_num_threads(MANY)
    for arrays in got[1:]:
        for a, b in zip(arrays, got[0]):
            assert a.tobytes() == b.tobytes()


def test_a_table_built_on_the_same_neighbour_arrays_keeps_its_node_columns(rng):
    x, h = _scattered_points(rng)
    nb = find_neighbors(x, x, node_radius=2.0 * h)
    first = evaluate_shape_functions(x, x, h, nb, "cubic_spline", "linear")
    cols = first.node_columns()
    moved = x + 1e-4
    second = evaluate_shape_functions(moved, moved, h, nb, "cubic_spline", "linear", out=first)
    assert second.node_columns() is cols                        # same neighbour arrays: no rebuild
    other = find_neighbors(moved, moved, node_radius=2.0 * h)
    third = evaluate_shape_functions(moved, moved, h, other, "cubic_spline", "linear", out=second)
    assert third.node_columns() is not cols                      # a new neighbour list: built again
    np.testing.assert_array_equal(third.node_columns().pairs, np.argsort(other.indices, kind="stable"))


def _run(name: str, tmp_path, threads: int) -> tuple[str, dict[str, np.ndarray]]:
    """The time series and the last checkpoint's arrays of ``name``'s smoke run, 15 steps."""
    mod = load_problem(name)
    overrides = dict(mod.SMOKE)
    if "gif" in {f.name for f in dataclasses.fields(mod.Parameters)}:
        overrides["gif"] = False
    output = {"gif": False, "png": False, "checkpoint_wall_every": 1e-9}
    sim = Simulation(prepare_problem(name, overrides, output=output).scene)
    out = tmp_path / f"threads{threads}"
    numba.set_num_threads(threads)
    try:
        sim.run(out=out, progress=False, max_steps=15)
    finally:
        numba.set_num_threads(MANY)
    arrays = load_checkpoint(latest_checkpoint(out / "checkpoints"))[0]
    return (out / "timeseries.csv").read_text(), arrays


@needs_threads
@pytest.mark.parametrize("name", ["dam_break_impact", "stratified_rest", "beam_on_spring"])
def test_a_run_is_the_same_bits_on_one_thread_and_on_many(name, tmp_path):
    one_series, one = _run(name, tmp_path, 1)
    many_series, many = _run(name, tmp_path, MANY)
    assert many_series == one_series
    assert sorted(many) == sorted(one)
    moved = [k for k in sorted(one) if not k.startswith("__meta") and k != "run__clock"
             and not np.array_equal(one[k], many[k], equal_nan=True)]
    assert not moved, f"{name}: arrays differ between 1 and {MANY} threads: {moved}"
