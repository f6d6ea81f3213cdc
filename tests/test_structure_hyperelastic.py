"""Total-Lagrangian hyperelastic internal force (:mod:`mlsgalerkin.structure.hyperelastic`): the
numba kernel against the scikit-fem ``LinearForm`` reference on Q1, 9-node Q2 and P1 meshes in 2D
and Hex1, 27-node Hex2 and tetrahedral P1 meshes in 3D, the small-displacement limit against
``linear_elasticity`` (3D: the stiffness of the same ``ElasticBody``), objectivity under a rigid
rotation, ``f = dW/du`` and the tangent against finite differences, the refused inputs (plane
stress, inverted elements), and a 3D neo-Hookean cantilever stepped by the explicit integrator
against the linear answer."""

from __future__ import annotations

import numpy as np
import pytest
from skfem import (
    Basis,
    ElementQuad1,
    ElementQuad2,
    ElementTriP1,
    ElementVector,
    MeshHex,
    MeshQuad,
    MeshTet,
    MeshTri,
    asm,
)
from skfem.models.elasticity import lame_parameters, linear_elasticity

from mlsgalerkin.structure.elastic import ElasticBody, ElasticMaterial
from mlsgalerkin.structure.hyperelastic import (
    MODELS,
    InvertedElementError,
    QuadratureData,
    internal_force,
    internal_force_reference,
    lame_for_dimension,
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
    """The displacement ``u (N,)`` of the map ``X -> phi(X)`` at the degrees of freedom (2D or
    3D: degree of freedom ``i`` is component ``i % d``)."""
    X = basis.doflocs                                   # (d, N): location of each dof
    disp = phi(X) - X
    return disp[np.arange(basis.N) % X.shape[0], np.arange(basis.N)]


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


# ---------------------------------------------------------------------------- 3D
MATERIAL_3D = ElasticMaterial(1.0e7, 0.3, 1000.0)     # LAM, MU are its 3D Lamé parameters
ELEMENTS_3D = ["Hex1", "Hex2", "P1"]
BOX = (1.0, 0.6, 0.4)                                  # m


def make_body_3d(element: str, cells: tuple[int, int, int] = (2, 2, 1), model: str = "linear") -> ElasticBody:
    """A small 3D ``ElasticBody`` on the box ``BOX``: ``MeshHex`` for Hex1/Hex2, ``MeshTet`` for P1."""
    axes = [np.linspace(0.0, side, n + 1) for side, n in zip(BOX, cells)]
    mesh = (MeshTet if element == "P1" else MeshHex).init_tensor(*axes)
    return ElasticBody("box", mesh, MATERIAL_3D, element, model=model)


def rotation_3d(angle_deg: float, axis) -> np.ndarray:
    """Rotation by ``angle_deg`` about ``axis`` (Rodrigues)."""
    k = np.asarray(axis, dtype=float) / np.linalg.norm(axis)
    K = np.array([[0.0, -k[2], k[1]], [k[2], 0.0, -k[0]], [-k[1], k[0], 0.0]])
    a = np.deg2rad(angle_deg)
    return np.eye(3) + np.sin(a) * K + (1.0 - np.cos(a)) * K @ K


def moderate_3d(basis: Basis, rng: np.random.Generator) -> np.ndarray:
    """5–10 % strains with shear, a bending-like quadratic term, a 30° rotation about an oblique
    axis and nodal noise."""
    G = np.array([[0.08, 0.05, 0.02], [-0.03, -0.06, 0.04], [0.01, 0.03, 0.05]])
    R = rotation_3d(30.0, (1.0, 2.0, 3.0))

    def phi(X):
        return R @ (X + G @ X + 0.05 * np.array([X[1] ** 2, X[2] ** 2, X[0] ** 2]))

    return nodal(basis, phi) + 2e-3 * rng.standard_normal(basis.N)


def test_lame_parameters_by_dimension():
    """2D: the plane-strain pair (plane stress refused); 3D: ``lame(3)``, whatever ``plane`` says."""
    assert lame_for_dimension(MATERIAL_3D, 3) == MATERIAL_3D.lame(3) == pytest.approx((LAM, MU))
    stress = ElasticMaterial(1e7, 0.3, 1000.0, plane="stress")
    assert lame_for_dimension(stress, 3) == pytest.approx((LAM, MU))
    assert lame_for_dimension(MATERIAL_3D, 2) == plane_strain_lame(MATERIAL_3D)
    with pytest.raises(ValueError, match="plane strain only"):
        lame_for_dimension(stress, 2)
    with pytest.raises(ValueError, match="2D or 3D"):
        lame_for_dimension(MATERIAL_3D, 1)


@pytest.mark.parametrize("element", ELEMENTS_3D)
def test_quadrature_data_layout_3d(element):
    """As in 2D: documented shapes, the weights add up to the volume, the gradients to zero, the
    nodes are the vector dofs / 3."""
    basis = make_body_3d(element).basis
    d = QuadratureData.from_basis(basis)
    ne, nq = basis.dx.shape
    n_local = {"Hex1": 8, "Hex2": 27, "P1": 4}[element]
    assert d.dim == 3 and d.dofs.dtype == np.int64 and d.dofs.shape == (ne, n_local)
    assert d.grads.shape == (ne, nq, n_local, 3) and d.grads.flags.c_contiguous
    assert d.weights.shape == (ne, nq) and d.n_dofs == basis.N
    assert d.weights.sum() == pytest.approx(np.prod(BOX), rel=1e-13)
    assert np.abs(d.grads.sum(axis=2)).max() < 1e-10
    assert np.array_equal(3 * d.dofs.T, basis.element_dofs[0::3])


@pytest.mark.parametrize("model", MODELS)
@pytest.mark.parametrize("element", ELEMENTS_3D)
def test_3d_numba_force_matches_the_scikit_fem_linear_form(element, model, rng):
    basis = make_body_3d(element).basis
    u = moderate_3d(basis, rng)
    d = QuadratureData.from_basis(basis)
    f = internal_force(d, u, LAM, MU, model)
    ref = internal_force_reference(basis, u, LAM, MU, model)
    assert np.linalg.norm(ref) > 1e3
    assert np.linalg.norm(f - ref) <= 1e-12 * np.linalg.norm(ref)
    W = strain_energy(d, u, LAM, MU, model)
    assert W > 0 and W == pytest.approx(strain_energy_reference(basis, u, LAM, MU, model), rel=1e-12)


@pytest.mark.parametrize("model", MODELS)
@pytest.mark.parametrize("element", ELEMENTS_3D)
def test_3d_small_displacements_give_the_linear_stiffness_of_the_body(element, model, rng):
    """For tiny u the force is ``ElasticBody.stiffness @ u`` of the same 3D body (``lame(3)``), and
    the tangent at rest is that stiffness."""
    body = make_body_3d(element)
    basis = body.basis
    ubar = rng.uniform(-1.0, 1.0, basis.N)
    eps = 1e-7
    f = internal_force(QuadratureData.from_basis(basis), eps * ubar, LAM, MU, model) / eps
    Ku = body.stiffness @ ubar
    assert np.linalg.norm(f - Ku) <= 1e-5 * np.linalg.norm(Ku)
    K0 = tangent_stiffness_reference(basis, np.zeros(basis.N), LAM, MU, model)
    assert abs(K0 - body.stiffness).max() <= 1e-10 * abs(K0).max()


@pytest.mark.parametrize("model", MODELS)
@pytest.mark.parametrize("element", ELEMENTS_3D)
def test_3d_objectivity(element, model, rng):
    """u = (R − I) X, R a 60° rotation about an oblique axis, is stress free (compared with a
    1e-3 strain); rotating a deformed state, x -> R x, rotates each nodal force and keeps the
    energy."""
    basis = make_body_3d(element).basis
    d = QuadratureData.from_basis(basis)
    R = rotation_3d(60.0, (1.0, -1.0, 2.0))
    u_rot = nodal(basis, lambda X: R @ X)
    u_strain = nodal(basis, lambda X: X + 1e-3 * np.array([X[0], -0.5 * X[1] + X[0], 0.3 * X[2] - X[1]]))
    f_strain = internal_force(d, u_strain, LAM, MU, model)
    W_strain = strain_energy(d, u_strain, LAM, MU, model)
    assert np.linalg.norm(internal_force(d, u_rot, LAM, MU, model)) <= 1e-9 * np.linalg.norm(f_strain)
    assert abs(strain_energy(d, u_rot, LAM, MU, model)) <= 1e-8 * W_strain
    u = moderate_3d(basis, rng)
    X = basis.doflocs[:, 0::3].T                       # (n_nodes, 3): dof 3 s + c is component c of node s
    x = X + u.reshape(-1, 3)
    u_turned = (x @ R.T - X).ravel()
    f = internal_force(d, u, LAM, MU, model)
    f_turned = internal_force(d, u_turned, LAM, MU, model)
    assert np.linalg.norm(f_turned - (f.reshape(-1, 3) @ R.T).ravel()) <= 1e-11 * np.linalg.norm(f)
    assert strain_energy(d, u_turned, LAM, MU, model) == pytest.approx(strain_energy(d, u, LAM, MU, model),
                                                                      rel=1e-11)


@pytest.mark.parametrize("model", MODELS)
@pytest.mark.parametrize("element", ["Hex2", "P1"])
def test_3d_force_is_the_gradient_of_the_strain_energy(element, model, rng):
    basis = make_body_3d(element).basis
    d = QuadratureData.from_basis(basis)
    u = moderate_3d(basis, rng)
    f = internal_force(d, u, LAM, MU, model)
    h = 1e-6
    for i in rng.choice(basis.N, size=6, replace=False):
        e = np.zeros(basis.N)
        e[i] = h
        fd = (strain_energy(d, u + e, LAM, MU, model) - strain_energy(d, u - e, LAM, MU, model)) / (2 * h)
        assert abs(fd - f[i]) <= 1e-6 * np.abs(f).max(), (i, fd, f[i])


@pytest.mark.parametrize("model", MODELS)
def test_3d_tangent_stiffness_is_the_derivative_of_the_force(model, rng):
    basis = make_body_3d("Hex2", (2, 1, 1)).basis
    d = QuadratureData.from_basis(basis)
    u = moderate_3d(basis, rng)
    K = tangent_stiffness_reference(basis, u, LAM, MU, model)
    du = rng.standard_normal(basis.N)
    h = 1e-6
    fd = (internal_force(d, u + h * du, LAM, MU, model) - internal_force(d, u - h * du, LAM, MU, model)) / (2 * h)
    assert np.linalg.norm(K @ du - fd) <= 1e-6 * np.linalg.norm(fd)
    assert abs(K - K.T).max() <= 1e-10 * abs(K).max()


@pytest.mark.parametrize("model", MODELS)
def test_an_inverted_3d_element_is_named(model):
    """Pull the corner node (0, 0, 0) of a Hex1 mesh past the opposite corner of its only element."""
    body = make_body_3d("Hex1", (2, 2, 2))
    basis, mesh = body.basis, body.mesh
    corner = int(np.flatnonzero(np.all(mesh.p == 0.0, axis=0))[0])
    element = int(np.flatnonzero(np.any(mesh.t == corner, axis=0))[0])
    assert np.sum(np.any(mesh.t == corner, axis=0)) == 1
    u = np.zeros(basis.N)
    u[basis.nodal_dofs[:, corner]] = [0.8, 0.5, 0.35]   # element size 0.5 x 0.3 x 0.2
    d = QuadratureData.from_basis(basis)
    for call in (lambda: internal_force(d, u, LAM, MU, model), lambda: strain_energy(d, u, LAM, MU, model),
                 lambda: internal_force_reference(basis, u, LAM, MU, model)):
        with pytest.raises(InvertedElementError, match=rf"mesh element {element} \(mesh.t\[:, {element}\]\)") as err:
            call()
        assert err.value.elements.tolist() == [element] and err.value.j_min[0] <= 0.0


def test_3d_nonlinear_body_is_explicit_only():
    with pytest.raises(ValueError, match="explicit integrator only"):
        ElasticBody("b", MeshHex(), MATERIAL_3D, "Hex1", model="neo_hookean", integrator="newmark")
    # the material's plane does not apply in 3D: a plane-stress material is accepted
    body = ElasticBody("b", MeshHex(), ElasticMaterial(1e7, 0.3, 1000.0, plane="stress"), "Hex1",
                       model="stvenant_kirchhoff")
    assert body.model == "stvenant_kirchhoff" and body.dim == 3


def test_3d_neo_hookean_cantilever_under_a_small_tip_load_matches_the_linear_answer():
    """A 1 m Hex2 cantilever of 0.1 m square section (10 × 1 × 1 cells), neo-Hookean, a 10 N shear
    traction on its free end (tip deflection 0.4 % of its length), stepped by the explicit
    stepper :class:`CentralDifference` (sub-cycled central differences, 1 ms outer steps) with
    Rayleigh mass damping ``a0 = 2 ω₁``: after ``10/ω₁`` the tip is within 1 % of the linear
    static answer of the same body (measured −0.05 %), and the strain energy is ½ f·u."""
    from mlsgalerkin.structure.steppers import CentralDifference

    L, H, P = 1.0, 0.1, 10.0
    mesh = MeshHex.init_tensor(np.linspace(0.0, L, 11), np.linspace(0.0, H, 2), np.linspace(0.0, H, 2))
    mat = ElasticMaterial(1e8, 0.3, 1000.0)
    kw = {"clamped": lambda x: np.isclose(x[0], 0.0), "points": {"tip": (L, H / 2, H / 2)}}
    lin = ElasticBody("lin", mesh, mat, "Hex2", **kw)
    load = lin.edge_traction(lambda x: np.isclose(x[0], L), (0.0, -P / H**2, 0.0))
    static = lin.static(load)
    tip_linear = lin.point_displacements(static)["tip"][1]
    omega1 = lin.lowest_frequency()
    body = ElasticBody("beam", mesh, mat, "Hex2", model="neo_hookean", damping=(2.0 * omega1, 0.0), **kw)
    motion = CentralDifference(body)
    motion.f[:] = load                       # the surface forces held over every step
    motion.start()
    dt = 1e-3
    for _ in range(int(np.ceil(10.0 / omega1 / dt))):
        motion.advance(dt)
    tip = body.point_displacements(motion.u)["tip"][1]
    assert abs(tip_linear) > 3e-3 and motion.max_substeps > 10
    assert abs(tip - tip_linear) < 0.01 * abs(tip_linear)
    assert motion.energies()["strain_energy"] == pytest.approx(0.5 * load @ static, rel=0.02)
