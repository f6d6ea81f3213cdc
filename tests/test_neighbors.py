"""Cell-list neighbour search against the O(n m) brute-force reference, edge cases, validation."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from mlsgalerkin.neighbors import NeighborTable, brute_force_neighbors, find_neighbors

DIMS = (1, 2, 3)


def assert_agrees(points, nodes, **radii) -> NeighborTable:
    """find_neighbors == brute_force_neighbors as sets per row; returns the cell-list table."""
    table = find_neighbors(points, nodes, **radii)
    ref = brute_force_neighbors(points, nodes, **radii)
    assert table.indptr.dtype == np.int64 and table.indices.dtype == np.int32
    assert table.n_points == ref.n_points and table.n_nodes == ref.n_nodes
    s = table.sorted()
    np.testing.assert_array_equal(s.indptr, ref.indptr)
    np.testing.assert_array_equal(s.indices, ref.indices)
    # the reference is sorted by construction, so sorting it is a no-op
    np.testing.assert_array_equal(ref.sorted().indices, ref.indices)
    return table


def _cloud(rng, n, dim, lo=0.0, hi=1.0):
    return rng.uniform(lo, hi, size=(n, dim))


# --------------------------------------------------------------------------------------
# agreement with brute force
# --------------------------------------------------------------------------------------


@pytest.mark.parametrize("dim", DIMS)
def test_scalar_radius(rng, dim):
    nodes = _cloud(rng, 400, dim)
    radius = {1: 0.02, 2: 0.1, 3: 0.2}[dim]
    same = assert_agrees(nodes, nodes, radius=radius)  # the very same object: fast path
    copy = assert_agrees(nodes.copy(), nodes, radius=radius)  # equal values, general path
    np.testing.assert_array_equal(same.sorted().indices, copy.sorted().indices)
    assert same.counts.min() >= 1  # every node finds itself
    # evaluation points elsewhere, a third of them outside the nodes' bounding box
    assert_agrees(_cloud(rng, 300, dim, -0.5, 1.5), nodes, radius=radius)


@pytest.mark.parametrize("dim", DIMS)
def test_per_point_radius(rng, dim):
    nodes = _cloud(rng, 300, dim)
    assert_agrees(nodes, nodes, radius=rng.uniform(0.02, 0.4, 300))
    assert_agrees(nodes.copy(), nodes, radius=rng.uniform(0.02, 0.4, 300))
    points = _cloud(rng, 200, dim, -0.3, 1.3)
    assert_agrees(points, nodes, radius=rng.uniform(0.01, 0.5, 200))


@pytest.mark.parametrize("dim", DIMS)
def test_node_radius(rng, dim):
    nodes = _cloud(rng, 300, dim)
    h = rng.uniform(0.02, 0.4, 300)
    assert_agrees(nodes, nodes, node_radius=h)
    assert_agrees(nodes.copy(), nodes, node_radius=h)
    assert_agrees(_cloud(rng, 200, dim, -0.3, 1.3), nodes, node_radius=h)
    assert_agrees(_cloud(rng, 200, dim, -0.3, 1.3), nodes, node_radius=0.15)  # scalar is allowed


@pytest.mark.parametrize("dim", DIMS)
def test_points_far_outside(rng, dim):
    nodes = _cloud(rng, 100, dim)
    far = np.vstack([np.full(dim, 50.0), np.full(dim, -50.0), np.full(dim, 1e30), np.full(dim, -1e30)])
    for radii in ({"radius": 0.3}, {"radius": np.full(4, 0.3)}, {"node_radius": np.full(100, 0.3)}):
        t = assert_agrees(far, nodes, **radii)
        assert t.n_pairs == 0 and np.all(t.counts == 0)


@pytest.mark.parametrize("dim", DIMS)
def test_far_point_with_radius_reaching_back(rng, dim):
    """A far-away point whose own (large) radius reaches the cloud, among small-radius points.

    The cell size follows the median radius, so the far point's search box spans ~1e26 cells;
    the cell range must be clipped before it is converted to an integer.
    """
    nodes = _cloud(rng, 100, dim)
    points = np.vstack([_cloud(rng, 20, dim), np.full((1, dim), 1e25), np.full((1, dim), -1e25)])
    radius = np.concatenate([np.full(20, 0.1), [1e27, 1e27]])
    t = assert_agrees(points, nodes, radius=radius)
    assert np.all(t.counts[-2:] == 100)


@pytest.mark.parametrize("dim", DIMS)
def test_one_huge_radius_among_small(rng, dim):
    nodes = _cloud(rng, 200, dim)
    radius = np.full(200, 0.05)
    radius[7] = 1e30
    t = assert_agrees(nodes, nodes, radius=radius)
    assert t.counts[7] == 200


@given(
    dim=st.integers(1, 3),
    n_nodes=st.integers(1, 60),
    n_points=st.integers(1, 60),
    seed=st.integers(0, 2**32 - 1),
    log_r=st.floats(-2.5, 0.5),
    spread=st.floats(0.0, 2.0),
    quantise=st.booleans(),
    mode=st.sampled_from(["radius", "radius_array", "node_radius", "node_radius_array", "same"]),
)
@settings(max_examples=30, deadline=None, database=None)
def test_property_matches_brute_force(dim, n_nodes, n_points, seed, log_r, spread, quantise, mode):
    rng = np.random.default_rng(seed)
    nodes = rng.uniform(0.0, 1.0, (n_nodes, dim))
    points = rng.uniform(-spread, 1.0 + spread, (n_points, dim))
    r = 10.0**log_r
    if quantise:
        # coordinates and radii on a dyadic grid: exact duplicates and exact ties |x - y| == r,
        # which both searches must decide identically (strict "<")
        nodes, points = np.round(nodes * 8) / 8, np.round(points * 8) / 8
        r = float(2.0 ** np.round(np.log2(r)))
    if mode == "radius":
        assert_agrees(points, nodes, radius=r)
    elif mode == "radius_array":
        assert_agrees(points, nodes, radius=r * rng.uniform(0.1, 10.0, n_points))
    elif mode == "node_radius":
        assert_agrees(points, nodes, node_radius=r)
    elif mode == "node_radius_array":
        assert_agrees(points, nodes, node_radius=r * rng.uniform(0.1, 10.0, n_nodes))
    else:
        assert_agrees(nodes, nodes, radius=r * rng.uniform(0.1, 10.0, n_nodes))
        assert_agrees(nodes, nodes, node_radius=r * rng.uniform(0.1, 10.0, n_nodes))


# --------------------------------------------------------------------------------------
# awkward clouds
# --------------------------------------------------------------------------------------


@pytest.mark.parametrize("dim", DIMS)
def test_duplicate_nodes(rng, dim):
    base = _cloud(rng, 50, dim)
    nodes = np.repeat(base, 3, axis=0)  # every node three times: rows 3k, 3k+1, 3k+2
    for t in (
        assert_agrees(nodes, nodes, radius=0.05),
        assert_agrees(nodes, nodes, node_radius=np.full(150, 0.05)),
        assert_agrees(base, nodes, radius=0.05),
    ):
        for i in range(t.n_points):
            row = set(t.indices[t.indptr[i] : t.indptr[i + 1]].tolist())
            k = i // 3 if t.n_points == 150 else i
            assert {3 * k, 3 * k + 1, 3 * k + 2} <= row  # all copies of the coincident node
            for j in row:  # and duplicates come as whole groups
                assert {3 * (j // 3), 3 * (j // 3) + 1, 3 * (j // 3) + 2} <= row


@pytest.mark.parametrize("dim", DIMS)
def test_all_nodes_coincident(dim):
    nodes = np.ones((20, dim))
    t = assert_agrees(nodes, nodes, radius=0.1)
    assert np.all(t.counts == 20)


@pytest.mark.parametrize("dim", DIMS)
def test_single_node(rng, dim):
    node = _cloud(rng, 1, dim)
    t = assert_agrees(node, node, radius=0.5)
    assert t.counts.tolist() == [1]
    points = _cloud(rng, 50, dim, -1.0, 2.0)
    assert_agrees(points, node, radius=0.8)
    assert_agrees(points, node, node_radius=[0.8])


@pytest.mark.parametrize("dim", DIMS)
def test_two_clusters_1000_to_1(rng, dim):
    """A fine cluster (spacing ~1e-3) far from a coarse one (spacing ~1): the capped grid."""
    n = {1: 200, 2: 400, 3: 500}[dim]
    fine = _cloud(rng, n, dim) * (n ** (1 / dim) * 1e-3)
    coarse = 10.0 + _cloud(rng, n, dim) * n ** (1 / dim)
    nodes = np.vstack([fine, coarse])
    h = np.concatenate([np.full(n, 3e-3), np.full(n, 3.0)])
    t = assert_agrees(nodes, nodes, node_radius=h)
    assert t.counts[:n].min() >= 1 and t.counts[n:].min() >= 1
    assert_agrees(nodes, nodes, radius=h)
    assert_agrees(nodes, nodes, radius=3e-3)
    points = np.vstack([fine + 1e-4, coarse - 0.5])
    assert_agrees(points, nodes, radius=h)
    assert_agrees(points, nodes, node_radius=h)


@pytest.mark.parametrize("dim", DIMS)
def test_huge_radius(rng, dim):
    nodes = _cloud(rng, 150, dim)
    points = _cloud(rng, 40, dim, -3.0, 4.0)
    for radii in ({"radius": 1e6}, {"radius": np.full(40, 1e6)}, {"node_radius": np.full(150, 1e6)}):
        t = assert_agrees(points, nodes, **radii)
        assert np.all(t.counts == 150)
    assert np.all(find_neighbors(nodes, nodes, radius=1e6).counts == 150)


@pytest.mark.parametrize("dim", DIMS)
def test_tiny_radius(rng, dim):
    """A radius far below the cloud's extent: the uncapped cell count overflows int64."""
    nodes = _cloud(rng, 100, dim)
    for r in (1e-12, 1e-25, 1e-100):
        t = assert_agrees(nodes, nodes, radius=r)
        np.testing.assert_array_equal(t.indices, np.arange(100))  # only itself
        assert_agrees(nodes, nodes, node_radius=np.full(100, r))


@pytest.mark.parametrize("dim", DIMS)
def test_offset_coordinates(rng, dim):
    nodes = 1e6 + _cloud(rng, 300, dim)
    radius = {1: 0.02, 2: 0.1, 3: 0.2}[dim]
    assert_agrees(nodes, nodes, radius=radius)
    assert_agrees(1e6 + _cloud(rng, 200, dim, -0.2, 1.2), nodes, radius=radius)
    assert_agrees(nodes, nodes, node_radius=rng.uniform(0.5, 1.5, 300) * radius)
    assert find_neighbors(nodes, nodes, radius=radius).n_pairs > 300  # more than the self-pairs


def test_one_dimensional_input_is_points_on_a_line(rng):
    x = rng.random(100)
    t = assert_agrees(x, x, radius=0.03)
    assert_agrees(x[:, None], x[:, None], radius=0.03)
    np.testing.assert_array_equal(t.indices, find_neighbors(x[:, None], x[:, None], radius=0.03).indices)


def test_lists_are_accepted():
    nodes = [[0.0, 0.0], [1.0, 0.0], [0.0, 0.5]]
    t = assert_agrees(nodes, nodes, radius=0.75)
    assert t.sorted().indices.tolist() == [0, 2, 1, 0, 2]


def test_deterministic(rng):
    nodes = _cloud(rng, 3000, 2)
    points = _cloud(rng, 2000, 2)
    a = find_neighbors(points, nodes, radius=0.03)
    b = find_neighbors(points, nodes, radius=0.03)
    np.testing.assert_array_equal(a.indptr, b.indptr)
    np.testing.assert_array_equal(a.indices, b.indices)
    assert_agrees(points, nodes, radius=0.03)  # several chunks of queries, in parallel


# --------------------------------------------------------------------------------------
# NeighborTable
# --------------------------------------------------------------------------------------


def test_table_consistency(rng):
    nodes = _cloud(rng, 200, 2)
    points = _cloud(rng, 120, 2, -0.2, 1.2)
    t = find_neighbors(points, nodes, radius=0.12)
    assert t.n_points == 120 and t.n_nodes == 200
    assert t.indptr[0] == 0 and t.n_pairs == t.indices.shape[0]
    counts = t.counts
    assert counts.shape == (120,) and counts.sum() == t.n_pairs
    np.testing.assert_array_equal(counts, np.diff(t.indptr))
    assert counts.min() == 0 and counts.max() > 0  # some points outside have no neighbours

    rows = t.rows()
    assert rows.shape == (t.n_pairs,)
    for i in range(t.n_points):
        assert np.all(rows[t.indptr[i] : t.indptr[i + 1]] == i)

    csr = t.to_csr()
    assert csr.shape == (120, 200) and csr.nnz == t.n_pairs
    np.testing.assert_array_equal(csr.sum(axis=1), counts)
    dense = csr.toarray()
    np.testing.assert_array_equal(dense[rows, t.indices], 1.0)
    d = np.linalg.norm(points[:, None, :] - nodes[None, :, :], axis=2)
    np.testing.assert_array_equal(dense != 0, d < 0.12)

    s = t.sorted()
    np.testing.assert_array_equal(s.indptr, t.indptr)
    for i in range(s.n_points):
        row = s.indices[s.indptr[i] : s.indptr[i + 1]]
        assert np.all(np.diff(row) > 0)  # sorted, no pair twice
        assert sorted(t.indices[t.indptr[i] : t.indptr[i + 1]].tolist()) == row.tolist()


# --------------------------------------------------------------------------------------
# validation
# --------------------------------------------------------------------------------------

SEARCHES = [find_neighbors, brute_force_neighbors]


@pytest.fixture(params=SEARCHES, ids=lambda f: f.__name__)
def search(request):
    return request.param


def _nodes():
    return np.random.default_rng(0).random((10, 2))


def _with(row, value, n=10, dim=2):
    a = np.random.default_rng(1).random((n, dim))
    a[row, dim - 1] = value
    return a


@pytest.mark.parametrize(
    "points, nodes, kwargs, match",
    [
        (np.empty((0, 2)), _nodes(), {"radius": 0.1}, r"points is empty"),
        (_nodes(), np.empty((0, 2)), {"radius": 0.1}, r"nodes is empty"),
        ([], _nodes(), {"radius": 0.1}, r"points is empty"),
        (_with(3, np.nan), _nodes(), {"radius": 0.1}, r"points has 1 row\(s\) with NaN or inf .* row 3"),
        (_nodes(), _with(5, np.inf), {"radius": 0.1}, r"nodes has 1 row\(s\) with NaN or inf .* row 5"),
        (_with(7, -np.inf), _nodes(), {"radius": 0.1}, r"points .*NaN or inf.* row 7"),
        (np.zeros((4, 3)), _nodes(), {"radius": 0.1}, r"points has dimension 3 but the nodes have dimension 2"),
        (np.zeros(4), _nodes(), {"radius": 0.1}, r"points has dimension 1 but the nodes have dimension 2"),
        (np.zeros((4, 4)), np.zeros((4, 4)), {"radius": 0.1}, r"nodes must have 1, 2 or 3 columns .* got 4"),
        (np.zeros((4, 4)), _nodes(), {"radius": 0.1}, r"points must have 1, 2 or 3 columns .* got 4"),
        (np.zeros((2, 2, 2)), _nodes(), {"radius": 0.1}, r"points must have shape \(n, dim\)"),
        (_nodes(), _nodes(), {"radius": 0.0}, r"radius must be positive and finite; entry 0 is .*0\.0"),
        (_nodes(), _nodes(), {"radius": -1.0}, r"radius must be positive and finite"),
        (_nodes(), _nodes(), {"radius": np.nan}, r"radius must be positive and finite; entry 0 is .*nan"),
        (_nodes(), _nodes(), {"radius": np.inf}, r"radius must be positive and finite"),
        (_nodes(), _nodes(), {"radius": np.r_[np.ones(4), -1.0, np.ones(5)]}, r"radius .* entry 4 is .*-1\.0"),
        (_nodes(), _nodes(), {"node_radius": np.r_[np.ones(9), 0.0]}, r"node_radius .* entry 9 is .*0\.0"),
        (_nodes(), _nodes(), {"node_radius": np.nan}, r"node_radius must be positive and finite"),
        (_nodes()[:4], _nodes(), {"radius": np.ones(10)}, r"radius must be a scalar or have one value per evaluation point \(4\)"),
        (_nodes()[:4], _nodes(), {"node_radius": np.ones(4)}, r"node_radius must be a scalar or have one value per node \(10\)"),
        (_nodes(), _nodes(), {"radius": np.ones((10, 1))}, r"radius must be a scalar or have one value"),
        (_nodes(), _nodes(), {"radius": 0.1, "node_radius": 0.1}, r"give exactly one of radius= .* or node_radius="),
        (_nodes(), _nodes(), {}, r"give exactly one of radius= .* or node_radius="),
    ],
)
def test_bad_input(search, points, nodes, kwargs, match):
    with pytest.raises(ValueError, match=match):
        search(points, nodes, **kwargs)


def test_bad_input_same_object(search):
    """The points-is-nodes fast path validates too."""
    bad = _with(2, np.nan)
    with pytest.raises(ValueError, match=r"nodes has 1 row\(s\) with NaN or inf .* row 2"):
        search(bad, bad, radius=0.1)
    nodes = _nodes()
    with pytest.raises(ValueError, match=r"radius must be a scalar or have one value per evaluation point \(10\)"):
        search(nodes, nodes, radius=np.ones(3))


def test_query_points_at_extreme_coordinates():
    """Query cells are clamped in floating point: 1e300 must not overflow the cell index."""
    nodes = np.random.default_rng(3).random((50, 2))
    pts = np.array([[1e300, -1e300], [0.5, 0.5], [-1e300, 1e300]])
    a = find_neighbors(pts, nodes, radius=0.3).sorted()
    b = brute_force_neighbors(pts, nodes, radius=0.3).sorted()
    np.testing.assert_array_equal(a.indptr, b.indptr)
    np.testing.assert_array_equal(a.indices, b.indices)
    assert a.counts[0] == 0 and a.counts[2] == 0 and a.counts[1] > 0
