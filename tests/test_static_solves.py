"""Static Galerkin solves: forms vs sparse algebra, patch tests per rule/BC, MMS convergence.

Measured values (unit square, cubic spline, linear MLS, h = 1.5 Δx, 9 x 9 nodes, perturbed =
interior nodes jittered by ±0.3 Δx, boundary nodes on the boundary; relative L2 errors on a
16 x 16 x 4² Gauss background grid):

=========================  ==========  ==========  ==========  ==========
Poisson u = 1 + 2x - 3y     SCNI reg.   SCNI pert.  DNI reg.    DNI pert.
=========================  ==========  ==========  ==========  ==========
Nitsche (β = 100)           1.2e-13     1.8e-13     1.1e-2      3.3e-2
penalty (β = 1e4)           1.7e-5      2.2e-5      9.3e-3      2.3e-2
Nitsche, node segments      9.2e-5      3.2e-4      1.1e-2      3.3e-2
=========================  ==========  ==========  ==========  ==========

Plane-strain elasticity (linear field, E = 1000, ν = 0.3), L2 (regular / perturbed):
SCNI + Nitsche 7.8e-14 / 4.1e-14 (energy 3.1e-12 / 1.3e-12), SCNI + penalty 7.1e-6 / 9.2e-6,
DNI + Nitsche 2.9e-3 / 1.0e-2, DNI + penalty 2.8e-3 / 7.3e-3. Nitsche with the SCNI smoothed
boundary gradients (``gradients="rule"``) is equally exact (Poisson 1.9e-13 / 7.9e-14).
"""

from __future__ import annotations

import logging

import numpy as np
import pytest
from scipy.sparse import csr_array, diags_array
from scipy.sparse.linalg import spsolve

from mlsgalerkin.analysis import ErrorNorms, rectangle_quadrature
from mlsgalerkin.basis import MeshfreeBasis
from mlsgalerkin.forms import BilinearForm, Functional, LinearForm
from mlsgalerkin.helpers import div, dot, grad
from mlsgalerkin.integration import (
    boundary_basis,
    direct_nodal_integration,
    meshfree_basis,
    rectangle,
    voronoi_volumes,
)
from mlsgalerkin.models import (
    elasticity,
    neumann_load,
    nitsche,
    nitsche_inverse_constant,
    penalty,
    poisson,
)

DOMAIN = rectangle((0, 0), (1, 1))
QUAD = rectangle_quadrature((0, 0), (1, 1), n_cells=16, n_gauss=4)
E_MOD, NU = 1000.0, 0.3
LAM, MU = elasticity.lame_parameters(E_MOD, NU)


def grid(n: int, jitter: float = 0.0, seed: int = 1):
    """``n x n`` nodes on the unit square; interior nodes jittered by ``±jitter Δx``."""
    dx = 1.0 / (n - 1)
    x = np.linspace(0, 1, n)
    g = np.stack(np.meshgrid(x, x, indexing="ij"), -1).reshape(-1, 2)
    inner = (g > 1e-9).all(axis=1) & (g < 1 - 1e-9).all(axis=1)
    g[inner] += np.random.default_rng(seed).uniform(-jitter, jitter, (inner.sum(), 2)) * dx
    return g, dx


def make_basis(rule: str, jitter: float = 0.3, n: int = 9, n_components: int = 1,
               h_factor: float = 1.5):
    g, dx = grid(n, jitter)
    return meshfree_basis(g, h_factor * dx, rule=rule, domain=DOMAIN, n_components=n_components)


def rel_diff(A, B) -> float:
    return float(abs(A - B).max() / abs(B).max())


# ---- linear exact solutions ------------------------------------------------------------

def u_lin(x):
    return 1.0 + 2.0 * x[0] - 3.0 * x[1]


def grad_u_lin(x):
    return np.stack([np.full(x.shape[1], 2.0), np.full(x.shape[1], -3.0)])


A_DISP = np.array([[0.01, 0.02], [-0.015, 0.005]])
C_DISP = np.array([0.003, -0.002])


def disp_lin(x):
    return C_DISP[:, None] + A_DISP @ x


def grad_disp_lin(x):
    return np.repeat(A_DISP[:, :, None], x.shape[1], axis=2)


SIGMA_LIN = 2 * MU * 0.5 * (A_DISP + A_DISP.T) + LAM * np.trace(A_DISP) * np.eye(2)


# ======================================================================================
# (a) forms against sparse algebra
# ======================================================================================


@pytest.mark.parametrize("rule", ["scni", "dni"])
def test_laplace_equals_sparse_gradient_product(rule):
    b = make_basis(rule)
    K = poisson.laplace.assemble(b)
    W = diags_array(b.weights)
    ref = sum(G.T @ W @ G for G in b.table.gradient_matrices())
    assert isinstance(K, csr_array) and K.shape == (b.n_dofs, b.n_dofs)
    assert rel_diff(K, ref) < 1e-14
    assert rel_diff(K, K.T) < 1e-15
    assert abs(K @ np.ones(b.n_dofs)).max() < 1e-12 * abs(K).max()  # constants: zero energy


def test_mass_load_and_point_data_match_sparse_algebra():
    b = make_basis("scni")
    N, W = b.table.value_matrix(), diags_array(b.weights)
    assert rel_diff(poisson.mass.assemble(b), N.T @ W @ N) < 1e-14
    kappa = 1.0 + b.points[:, 0] ** 2  # per-point coefficient, shape (n_points,)

    @LinearForm
    def weighted_load(v, w):
        return w.kappa * w.x[1] * v

    f = weighted_load.assemble(b, kappa=kappa)
    np.testing.assert_allclose(f, N.T @ (b.weights * kappa * b.points[:, 1]), rtol=1e-13)
    assert poisson.unit_load.assemble(b).sum() == pytest.approx(1.0, rel=1e-13)  # Σ_I N_I = 1
    assert Functional(lambda w: w.x[0] * 0 + 1.0).assemble(b) == pytest.approx(1.0, rel=1e-13)


def test_body_force_matches_sparse_algebra():
    b = make_basis("scni", n_components=2)
    N, wts = b.table.value_matrix(), b.weights
    f = elasticity.body_force([0.0, -9.81e3]).assemble(b).reshape(-1, 2)  # node-major
    np.testing.assert_allclose(f[:, 1], N.T @ (wts * -9.81e3), rtol=1e-13)
    assert abs(f[:, 0]).max() == 0.0
    fx = elasticity.body_force(lambda x: np.stack([x[0], x[1] ** 2])).assemble(b).reshape(-1, 2)
    np.testing.assert_allclose(fx, np.column_stack([N.T @ (wts * b.points[:, 0]),
                                                    N.T @ (wts * b.points[:, 1] ** 2)]), rtol=1e-13)


def test_interpolated_field_keyword():
    b = make_basis("scni")
    u = np.random.default_rng(3).normal(size=b.n_dofs)
    a = b.interpolate(u)
    K, M = poisson.laplace.assemble(b), poisson.mass.assemble(b)

    @LinearForm
    def from_field(v, w):
        return dot(grad(w.a), grad(v)) + w.a * v

    np.testing.assert_allclose(from_field.assemble(b, a=a), K @ u + M @ u, rtol=1e-12, atol=1e-12)


def _strain_matrix(b: MeshfreeBasis):
    """Voigt strain-displacement matrix (3 n_points, 2 n_nodes), node-major DOFs."""
    from scipy.sparse import vstack

    G0, G1 = b.table.gradient_matrices()
    n = b.n_nodes

    def place(A, comp):  # columns of component `comp`
        A = A.tocoo()
        return csr_array((A.data, (A.row, 2 * A.col + comp)), shape=(A.shape[0], 2 * n))

    return vstack([place(G0, 0), place(G1, 1), place(G1, 0) + place(G0, 1)]).tocsr()


@pytest.mark.parametrize("rule", ["scni", "dni"])
def test_elasticity_equals_voigt_product(rule):
    b = make_basis(rule, n_components=2)
    K = elasticity.linear_elasticity(LAM, MU).assemble(b)
    B = _strain_matrix(b)
    D = np.array([[LAM + 2 * MU, LAM, 0.0], [LAM, LAM + 2 * MU, 0.0], [0.0, 0.0, MU]])
    from scipy.sparse import kron

    ref = B.T @ kron(csr_array(D), diags_array(b.weights)) @ B
    assert rel_diff(K, ref) < 1e-14
    assert rel_diff(K, K.T) < 1e-15


@pytest.mark.parametrize("rule", ["scni", "dni"])
def test_rigid_body_null_space(rule):
    b = make_basis(rule, n=6, n_components=2)
    K = elasticity.linear_elasticity(LAM, MU).assemble(b).toarray()
    ev = np.linalg.eigvalsh(K)
    assert np.count_nonzero(np.abs(ev) < 1e-12 * ev[-1]) == 3
    assert ev[3] > 1e-7 * ev[-1]  # no further (spurious) zero-energy mode at this size
    x, y = b.nodes.T
    for mode in (np.ones_like(x), np.zeros_like(x)), (np.zeros_like(x), np.ones_like(x)), (-y, x):
        r = np.column_stack(mode).ravel()  # node-major
        assert abs(K @ r).max() < 1e-12 * abs(K).max()


def test_petrov_galerkin_square_and_mixed():
    g, dx = grid(9, 0.3)
    vol = voronoi_volumes(g, DOMAIN)
    trial = MeshfreeBasis(g, direct_nodal_integration(g, 1.5 * dx, vol), h=1.5 * dx)
    test = MeshfreeBasis(g, direct_nodal_integration(g, 2.2 * dx, vol), h=2.2 * dx)
    W = diags_array(vol)
    Gu, Gv = trial.table.gradient_matrices(), test.table.gradient_matrices()
    K = poisson.laplace.assemble(trial, test)
    assert rel_diff(K, sum(Gv[d].T @ W @ Gu[d] for d in range(2))) < 1e-14
    assert rel_diff(K, K.T) > 1e-3  # genuinely unsymmetric

    # vector trial (displacement), scalar test (pressure): ∫ q div u, node-major columns
    trial_v = MeshfreeBasis(g, direct_nodal_integration(g, 1.5 * dx, vol), n_components=2)
    Bdiv = BilinearForm(lambda u, q, w: div(u) * q).assemble(trial_v, test)
    assert Bdiv.shape == (81, 162)
    Nq = test.table.value_matrix()
    for d in range(2):
        assert rel_diff(Bdiv[:, d::2], Nq.T @ W @ Gu[d]) < 1e-14

    other = MeshfreeBasis(g, direct_nodal_integration(g, 1.5 * dx, 1.01 * vol))
    with pytest.raises(ValueError, match="different integration weights"):
        poisson.laplace.assemble(other, trial)
    with pytest.raises(ValueError, match="share the integration points"):
        poisson.laplace.assemble(make_basis("scni", n=8), trial)


def test_chunked_assembly_is_identical():
    b = make_basis("scni", n_components=2)
    form = elasticity.linear_elasticity(LAM, MU)
    chunked = BilinearForm(chunk_size=997)(form.form)  # decorator-with-arguments style
    assert chunked.chunk_size == 997 and chunked.name == "linear_elasticity"
    assert abs(chunked.assemble(b) - form.assemble(b)).max() < 1e-13 * abs(form.assemble(b)).max()
    load = elasticity.body_force([1.0, 2.0])
    np.testing.assert_allclose(LinearForm(load.form, chunk_size=101).assemble(b), load.assemble(b),
                               rtol=1e-13, atol=1e-15)


def test_pattern_is_cached_per_basis_pair():
    b = make_basis("scni")
    poisson.laplace.assemble(b)
    pat = b._triples[id(b)][1]
    poisson.mass.assemble(b)
    assert b._triples[id(b)][1] is pat


def test_helpers_mirror_skfem():
    from skfem import helpers as sk

    from mlsgalerkin import helpers as mh

    rng = np.random.default_rng(0)
    A, B, x = rng.normal(size=(2, 2, 7)), rng.normal(size=(2, 2, 7)), rng.normal(size=(2, 7))
    np.testing.assert_allclose(mh.ddot(A, B), sk.ddot(A, B))
    np.testing.assert_allclose(mh.dot(x, x), sk.dot(x, x))
    np.testing.assert_allclose(mh.mul(A, x), sk.mul(A, x))
    np.testing.assert_allclose(mh.trace(A), sk.trace(A))
    np.testing.assert_allclose(mh.transpose(A), sk.transpose(A))
    np.testing.assert_allclose(mh.eye(x[0], 2), sk.eye(x[0], 2))


def test_bad_input_is_rejected_before_work():
    b = make_basis("scni")
    with pytest.raises(ValueError, match="unknown integration rule"):
        meshfree_basis(b.nodes, 0.2, rule="fem", domain=DOMAIN)
    with pytest.raises(ValueError, match="n_components"):
        MeshfreeBasis(b.nodes, b, n_components=3)
    with pytest.raises(ValueError, match="keyword 'k'"):
        poisson.laplace.assemble(b, k=np.ones(5))
    with pytest.raises(ValueError, match="interpolate"):
        poisson.laplace.assemble(b, k=np.ones((2, 3)))
    with pytest.raises(ValueError, match="one scalar per entry"):
        BilinearForm(lambda u, v, w: grad(u)).assemble(b)
    with pytest.raises(ValueError, match="DOF vector"):
        b.interpolate(np.ones(b.n_dofs + 1))
    with pytest.raises(ValueError, match="edges"):
        boundary_basis(b, DOMAIN, edges=[4])
    with pytest.raises(ValueError, match="segments"):
        boundary_basis(b, DOMAIN, segments="facets")
    bb = boundary_basis(b, DOMAIN)
    with pytest.raises(ValueError, match="g must be"):
        nitsche(bb, np.ones(3))
    with pytest.raises(ValueError, match="beta"):
        nitsche(bb, 0.0, beta=-1.0)
    with pytest.raises(ValueError, match="components"):
        penalty(bb, 0.0, components=[0])
    bv = boundary_basis(make_basis("scni", n_components=2), DOMAIN)
    with pytest.raises(ValueError, match="flux="):
        nitsche(bv, 0.0)


# ======================================================================================
# boundary quadrature
# ======================================================================================


def test_boundary_quadrature_geometry():
    b = make_basis("scni")
    bb = boundary_basis(b, DOMAIN)
    assert bb.length == pytest.approx(4.0, rel=1e-14)
    for k, normal in enumerate([(0, -1), (1, 0), (0, 1), (-1, 0)]):
        on = bb.edge == k
        assert bb.weights[on].sum() == pytest.approx(1.0, rel=1e-14)
        np.testing.assert_allclose(bb.normals[on], np.tile(normal, (on.sum(), 1)), atol=1e-15)
    # Σ_I N_I(x) n = n: ∫_Γ n dΓ = 0 over the closed boundary, per node the SCNI constraint
    lhs = np.column_stack([G.T @ b.weights for G in b.table.gradient_matrices()])
    N = bb.table.value_matrix()
    rhs = np.column_stack([N.T @ (bb.weights * bb.normals[:, d]) for d in range(2)])
    np.testing.assert_allclose(lhs, rhs, atol=1e-14)  # integration constraint, these very points
    assert bb.n_points == 2 * 4 * 9  # one cell edge per boundary node, 2 Gauss points each


def test_nodes_segmentation_warns_for_scni(caplog):
    b = make_basis("scni")
    with caplog.at_level(logging.WARNING, logger="mlsgalerkin.integration.boundary"):
        boundary_basis(b, DOMAIN, segments="nodes")
    assert "will not cancel exactly" in caplog.text


# ======================================================================================
# (b) linear patch tests
# ======================================================================================


def poisson_patch(rule, jitter, method="nitsche", **bkw):
    b = make_basis(rule, jitter)
    beta = bkw.pop("beta", None)
    bb = boundary_basis(b, DOMAIN, **bkw)
    kw = {} if beta is None else {"beta": beta}
    Kb, fb = (nitsche if method == "nitsche" else penalty)(bb, u_lin, **kw)
    u = spsolve((poisson.laplace.assemble(b) + Kb).tocsc(), fb)
    return ErrorNorms(b, QUAD).l2(u, u_lin, relative=True)


def elastic_patch(rule, jitter, method="nitsche", **bkw):
    b = make_basis(rule, jitter, n_components=2)
    bb = boundary_basis(b, DOMAIN, **bkw)
    if method == "nitsche":
        Kb, fb = nitsche(bb, disp_lin, flux=elasticity.stress(LAM, MU), modulus=E_MOD)
    else:
        Kb, fb = penalty(bb, disp_lin, modulus=E_MOD)
    u = spsolve((elasticity.linear_elasticity(LAM, MU).assemble(b) + Kb).tocsc(), fb)
    norms = ErrorNorms(b, QUAD)
    return (norms.l2(u, disp_lin, relative=True),
            norms.energy(u, grad_disp_lin, LAM, MU, relative=True))


@pytest.mark.parametrize("gradients", ["direct", "rule"])
@pytest.mark.parametrize("jitter", [0.0, 0.3], ids=["regular", "perturbed"])
def test_scni_nitsche_poisson_patch_is_exact(jitter, gradients):
    assert poisson_patch("scni", jitter, gradients=gradients) < 1e-11  # measured 1e-13


@pytest.mark.parametrize("gradients", ["direct", "rule"])
@pytest.mark.parametrize("jitter", [0.0, 0.3], ids=["regular", "perturbed"])
def test_scni_nitsche_elasticity_patch_is_exact(jitter, gradients):
    l2, energy = elastic_patch("scni", jitter, gradients=gradients)
    assert l2 < 1e-11 and energy < 1e-10  # measured ~1e-13 and ~1e-12


def test_scni_patch_needs_boundary_points_on_the_cell_edges():
    """Same rule, boundary Gauss points between boundary nodes instead: quadrature residual."""
    err = poisson_patch("scni", 0.3, segments="nodes")
    assert err > 1e-6  # measured 3.2e-4


def test_penalty_is_not_variationally_consistent():
    """Error ∝ 1/β (1.25e-3, 1.4e-4, 2.2e-5 for β = 1e2, 1e3, 1e4), then it stalls near 1e-6
    (5.8e-6, 2.2e-6, 1.1e-6 for β = 1e5..1e7) as the conditioning (∝ β) takes over."""
    errs = [poisson_patch("scni", 0.3, method="penalty", beta=beta) for beta in (1e2, 1e3, 1e4)]
    assert 5 < errs[0] / errs[1] < 20  # ∝ 1/β
    assert errs[2] > 1e-6  # default β = 1e4: measured 2.2e-5
    l2, _ = elastic_patch("scni", 0.3, method="penalty")
    assert l2 > 1e-7  # measured 9.2e-6


@pytest.mark.parametrize("jitter", [0.0, 0.3], ids=["regular", "perturbed"])
def test_dni_fails_the_patch_test(jitter):
    """DNI violates the integration constraint (also at the half cells of a regular grid)."""
    err = poisson_patch("dni", jitter)
    assert err > 1e-3  # measured 1.1e-2 regular, 3.3e-2 perturbed
    assert err > 1e6 * poisson_patch("scni", jitter)
    l2, _ = elastic_patch("dni", jitter)
    assert l2 > 1e-3  # measured 2.9e-3, 1.0e-2


def test_scni_mixed_nitsche_and_traction_patch():
    """Nitsche on left/bottom, exact traction σn on right/top: still exact."""
    b = make_basis("scni", 0.3, n_components=2)
    bd = boundary_basis(b, DOMAIN, edges=[0, 3])
    bn = boundary_basis(b, DOMAIN, edges=[1, 2])
    Kb, fb = nitsche(bd, disp_lin, flux=elasticity.stress(LAM, MU), modulus=E_MOD)
    f = fb + neumann_load(bn, SIGMA_LIN @ bn.normals.T)
    u = spsolve((elasticity.linear_elasticity(LAM, MU).assemble(b) + Kb).tocsc(), f)
    assert ErrorNorms(b, QUAD).l2(u, disp_lin, relative=True) < 1e-11


def test_scni_poisson_mixed_dirichlet_flux_patch():
    """Nitsche on bottom/left, prescribed flux ∇u·n on right/top."""
    b = make_basis("scni", 0.3)
    Kb, fb = nitsche(boundary_basis(b, DOMAIN, edges=[0, 3]), u_lin)
    bn = boundary_basis(b, DOMAIN, edges=[1, 2])
    q = np.einsum("dn,nd->n", grad_u_lin(bn.points.T), bn.normals)
    u = spsolve((poisson.laplace.assemble(b) + Kb).tocsc(), fb + neumann_load(bn, q))
    assert ErrorNorms(b, QUAD).l2(u, u_lin, relative=True) < 1e-11


def test_scni_roller_components_patch():
    """u_x prescribed on the left, u_y on the bottom (components=), other components natural."""
    b = make_basis("scni", 0.3, n_components=2)
    flux = elasticity.stress(LAM, MU)
    K = elasticity.linear_elasticity(LAM, MU).assemble(b)
    f = np.zeros(b.n_dofs)
    for edge, comp in ((3, 0), (0, 1)):
        be = boundary_basis(b, DOMAIN, edges=[edge])
        Kb, fb = nitsche(be, disp_lin, flux=flux, modulus=E_MOD, components=[comp])
        K, f = K + Kb, f + fb
        t = SIGMA_LIN @ be.normals.T
        t[comp] = 0.0  # the constrained component's reaction is unknown
        f += neumann_load(be, t)
    bn = boundary_basis(b, DOMAIN, edges=[1, 2])
    f += neumann_load(bn, SIGMA_LIN @ bn.normals.T)
    u = spsolve(K.tocsc(), f)
    assert ErrorNorms(b, QUAD).l2(u, disp_lin, relative=True) < 1e-11


def test_nitsche_inverse_constant_and_default_beta():
    """β = 100 must exceed 2 C_I. Rule (smoothed) boundary gradients keep C_I O(1) for any dilation."""
    c = {}
    for hf in (1.5, 2.5):
        b = make_basis("scni", 0.3, n=7, h_factor=hf)
        K = poisson.laplace.assemble(b)
        for gr in ("direct", "rule"):
            c[hf, gr] = nitsche_inverse_constant(boundary_basis(b, DOMAIN, gradients=gr), K)
    assert 2 * c[1.5, "direct"] < 100  # measured 9.1: the patch-test settings are coercive
    assert c[2.5, "direct"] > 4 * c[1.5, "direct"]  # direct grows with the dilation: 48 at 2.5 Δx
    assert c[1.5, "rule"] < 3 and c[2.5, "rule"] < 3  # measured 1.5


# ======================================================================================
# (c) manufactured solution convergence
# ======================================================================================


def u_sin(x):
    return np.sin(np.pi * x[0]) * np.sin(np.pi * x[1])


def grad_u_sin(x):
    return np.pi * np.stack([np.cos(np.pi * x[0]) * np.sin(np.pi * x[1]),
                             np.sin(np.pi * x[0]) * np.cos(np.pi * x[1])])


def test_poisson_mms_scni_converges():
    hs, l2, h1 = [], [], []
    for n in (11, 21, 41):
        g, dx = grid(n)
        b = meshfree_basis(g, 1.5 * dx, rule="scni", domain=DOMAIN)
        K = poisson.laplace.assemble(b)
        f = poisson.source(lambda x: 2 * np.pi**2 * u_sin(x)).assemble(b)
        Kb, fb = nitsche(boundary_basis(b, DOMAIN), 0.0)
        u = spsolve((K + Kb).tocsc(), f + fb)
        norms = ErrorNorms(b, rectangle_quadrature((0, 0), (1, 1), n - 1, 4))
        hs.append(dx)
        l2.append(norms.l2(u, u_sin, relative=True))
        h1.append(norms.h1_seminorm(u, grad_u_sin, relative=True))
    rate_l2 = np.polyfit(np.log(hs), np.log(l2), 1)[0]
    rate_h1 = np.polyfit(np.log(hs), np.log(h1), 1)[0]
    # measured: L2 1.46e-2, 3.77e-3, 9.60e-4 (rate 1.96); H1 1.69e-2, 4.46e-3, 1.31e-3 (1.85)
    assert rate_l2 > 1.5
    assert rate_h1 > 0.9
    assert l2[-1] < 2e-3
