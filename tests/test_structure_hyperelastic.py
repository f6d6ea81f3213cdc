"""Total-Lagrangian hyperelastic internal force (:mod:`mlsgalerkin.structure.hyperelastic`): the
numba kernel against the scikit-fem ``LinearForm`` reference on Q1, 9-node Q2 and P1 meshes, the
small-displacement limit against ``linear_elasticity``, objectivity under a rigid rotation,
``f = dW/du`` and the tangent against finite differences, and the refused inputs (plane stress,
inverted elements)."""

from __future__ import annotations

import numpy as np
import pytest
from skfem import (
    Basis,
    ElementQuad1,
    ElementQuad2,
    ElementTriP1,
    ElementVector,
    MeshQuad,
    MeshTri,
    asm,
)
from skfem.models.elasticity import lame_parameters, linear_elasticity

from mlsgalerkin.structure.elastic import ElasticMaterial
from mlsgalerkin.structure.hyperelastic import (
    MODELS,
    InvertedElementError,
    QuadratureData,
    internal_force,
    internal_force_reference,
    plane_strain_lame,
    strain_energy,
    strain_energy_reference,
    tangent_stiffness_reference,
)

pytestmark = pytest.mark.usefixtures("one_numba_thread")

LAM, MU = lame_parameters(1.0e7, 0.3)      # Pa
ELEMENTS = ["Q1", "Q2", "P1"]


def make_basis(element: str, nx: int = 4, ny: int = 3) -> Basis:
    x, y = np.linspace(0.0, 1.0, nx + 1), np.linspace(0.0, 0.6, ny + 1)
    if element == "P1":
        return Basis(MeshTri.init_tensor(x, y), ElementVector(ElementTriP1()))
    scalar = {"Q1": ElementQuad1, "Q2": ElementQuad2}[element]()
    return Basis(MeshQuad.init_tensor(x, y), ElementVector(scalar))


def rotation(angle_deg: float) -> np.ndarray:
    a = np.deg2rad(angle_deg)
    return np.array([[np.cos(a), -np.sin(a)], [np.sin(a), np.cos(a)]])


def nodal(basis: Basis, phi) -> np.ndarray:
    """The displacement ``u (N,)`` of the map ``X -> phi(X)`` at the degrees of freedom."""
    X = basis.doflocs                                   # (2, N): location of each dof
    disp = phi(X) - X
    return np.where(np.arange(basis.N) % 2 == 0, disp[0], disp[1])


def moderate(basis: Basis, rng: np.random.Generator) -> np.ndarray:
    """5–10 % strains, a bending-like quadratic term, a 30° rotation and nodal noise."""
    G = np.array([[0.08, 0.05], [-0.03, -0.06]])
    R = rotation(30.0)

    def phi(X):
        stretched = X + G @ X + 0.05 * np.array([X[1] ** 2, X[0] ** 2])
        return R @ stretched

    return nodal(basis, phi) + 2e-3 * rng.standard_normal(basis.N)


def test_quadrature_data_layout():
    """Shapes and dtypes as documented; the weights add up to the area, the gradients of the
    shape functions add up to zero (partition of unity), and the nodes are the vector dofs / 2."""
    basis = make_basis("Q2")
    d = QuadratureData.from_basis(basis)
    ne, nq = basis.dx.shape
    assert d.dofs.dtype == np.int64 and d.dofs.shape == (ne, 9)
    assert d.grads.dtype == np.float64 and d.grads.shape == (ne, nq, 9, 2) and d.grads.flags.c_contiguous
    assert d.weights.shape == (ne, nq) and d.n_dofs == basis.N
    assert d.weights.sum() == pytest.approx(0.6, rel=1e-13)
    assert np.abs(d.grads.sum(axis=2)).max() < 1e-10
    assert np.array_equal(2 * d.dofs.T, basis.element_dofs[0::2])
    with pytest.raises(ValueError, match="ElementVector"):
        QuadratureData.from_basis(Basis(basis.mesh, ElementQuad2()))


@pytest.mark.parametrize("model", MODELS)
@pytest.mark.parametrize("element", ELEMENTS)
def test_numba_force_matches_the_scikit_fem_linear_form(element, model, rng):
    basis = make_basis(element)
    u = moderate(basis, rng)
    d = QuadratureData.from_basis(basis)
    f = internal_force(d, u, LAM, MU, model)
    ref = internal_force_reference(basis, u, LAM, MU, model)
    assert np.linalg.norm(ref) > 1e3                   # a real load, not a trivial zero
    assert np.linalg.norm(f - ref) <= 1e-10 * np.linalg.norm(ref)
    W = strain_energy(d, u, LAM, MU, model)
    assert W > 0 and W == pytest.approx(strain_energy_reference(basis, u, LAM, MU, model), rel=1e-11)


@pytest.mark.parametrize("model", MODELS)
@pytest.mark.parametrize("element", ELEMENTS)
def test_small_displacements_give_linear_elasticity(element, model, rng):
    basis = make_basis(element)
    K = asm(linear_elasticity(LAM, MU), basis)
    ubar = rng.uniform(-1.0, 1.0, basis.N)
    eps = 1e-7
    f = internal_force(QuadratureData.from_basis(basis), eps * ubar, LAM, MU, model) / eps
    Ku = K @ ubar
    assert np.linalg.norm(f - Ku) <= 1e-5 * np.linalg.norm(Ku)


@pytest.mark.parametrize("model", MODELS)
@pytest.mark.parametrize("element", ELEMENTS)
def test_a_rigid_rotation_is_stress_free(element, model, rng):
    """u = (R − I) X with R a 60° rotation: no force, no energy (a small-strain model would give
    forces of order λ·0.5 here); compared with a 1e-3 strain of the same body."""
    basis = make_basis(element)
    d = QuadratureData.from_basis(basis)
    R = rotation(60.0)
    u_rot = nodal(basis, lambda X: R @ X)
    u_strain = nodal(basis, lambda X: X + 1e-3 * np.array([X[0], -0.5 * X[1] + X[0]]))
    f_strain = internal_force(d, u_strain, LAM, MU, model)
    W_strain = strain_energy(d, u_strain, LAM, MU, model)
    assert np.linalg.norm(internal_force(d, u_rot, LAM, MU, model)) <= 1e-9 * np.linalg.norm(f_strain)
    assert abs(strain_energy(d, u_rot, LAM, MU, model)) <= 1e-8 * W_strain


@pytest.mark.parametrize("model", MODELS)
@pytest.mark.parametrize("element", ["Q2", "P1"])
def test_force_is_the_gradient_of_the_strain_energy(element, model, rng):
    basis = make_basis(element)
    d = QuadratureData.from_basis(basis)
    u = moderate(basis, rng)
    f = internal_force(d, u, LAM, MU, model)
    h = 1e-6
    for i in rng.choice(basis.N, size=6, replace=False):
        e = np.zeros(basis.N)
        e[i] = h
        fd = (strain_energy(d, u + e, LAM, MU, model) - strain_energy(d, u - e, LAM, MU, model)) / (2 * h)
        assert abs(fd - f[i]) <= 1e-6 * np.abs(f).max(), (i, fd, f[i])


@pytest.mark.parametrize("model", MODELS)
def test_tangent_stiffness_is_the_derivative_of_the_force(model, rng):
    """K(u) du against central differences of the force; symmetric; linear elasticity at u = 0."""
    basis = make_basis("Q2", 3, 2)
    d = QuadratureData.from_basis(basis)
    u = moderate(basis, rng)
    K = tangent_stiffness_reference(basis, u, LAM, MU, model)
    du = rng.standard_normal(basis.N)
    h = 1e-6
    fd = (internal_force(d, u + h * du, LAM, MU, model) - internal_force(d, u - h * du, LAM, MU, model)) / (2 * h)
    assert np.linalg.norm(K @ du - fd) <= 1e-6 * np.linalg.norm(fd)
    assert abs(K - K.T).max() <= 1e-10 * abs(K).max()
    K0 = tangent_stiffness_reference(basis, np.zeros(basis.N), LAM, MU, model)
    assert abs(K0 - asm(linear_elasticity(LAM, MU), basis)).max() <= 1e-10 * abs(K0).max()


def test_plane_stress_is_refused_with_the_reason():
    with pytest.raises(ValueError, match="plane strain only.*S33 = 0.*plane='strain'"):
        plane_strain_lame(ElasticMaterial(1e7, 0.3, 1000.0, plane="stress"))
    strain = ElasticMaterial(1e7, 0.3, 1000.0, plane="strain")
    assert plane_strain_lame(strain) == pytest.approx(lame_parameters(1e7, 0.3))


@pytest.mark.parametrize("model", MODELS)
def test_an_inverted_element_is_named(model):
    """Pull the corner node (0, 0) of a Q1 mesh past the opposite corner of its only element:
    that element, and no other, is reported by the kernel and by the reference."""
    basis = make_basis("Q1")
    mesh = basis.mesh
    corner = int(np.flatnonzero((mesh.p[0] == 0.0) & (mesh.p[1] == 0.0))[0])
    element = int(np.flatnonzero(np.any(mesh.t == corner, axis=0))[0])
    u = np.zeros(basis.N)
    u[basis.nodal_dofs[:, corner]] = [0.6, 0.45]      # element size 0.25 x 0.2
    d = QuadratureData.from_basis(basis)
    for call in (lambda: internal_force(d, u, LAM, MU, model), lambda: strain_energy(d, u, LAM, MU, model),
                 lambda: internal_force_reference(basis, u, LAM, MU, model)):
        with pytest.raises(InvertedElementError, match=rf"mesh element {element} \(mesh.t\[:, {element}\]\)") as err:
            call()
        assert err.value.elements.tolist() == [element] and err.value.j_min[0] <= 0.0
        assert isinstance(err.value, ValueError)


def test_bad_model_and_bad_u_are_refused():
    basis = make_basis("P1")
    d = QuadratureData.from_basis(basis)
    with pytest.raises(ValueError, match="model must be one of"):
        internal_force(d, np.zeros(basis.N), LAM, MU, "mooney_rivlin")
    with pytest.raises(ValueError, match="shape"):
        internal_force(d, np.zeros(basis.N + 1), LAM, MU, "neo_hookean")
    with pytest.raises(ValueError, match="non-finite"):
        internal_force(d, np.full(basis.N, np.nan), LAM, MU, "neo_hookean")
