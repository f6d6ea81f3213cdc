"""The structure input checks (:mod:`mlsgalerkin.structure.checks`): the step estimate against
``eigsh`` and the integrator, valid meshes accepted, the inside test, the rotation warning."""

from __future__ import annotations

import dataclasses
import math
import warnings

import numpy as np
import pytest
from skfem import MeshHex, MeshQuad, MeshTet, MeshTri

from mlsgalerkin.structure.scheme import StructureScheme
from mlsgalerkin.problem import load_problem
from mlsgalerkin.scene import Scene
from mlsgalerkin.structure import ElasticBody, ElasticMaterial
from mlsgalerkin.structure.checks import (
    LINEAR_ROTATION_LIMIT,
    LargeRotationWarning,
    SUBSTEP_FRACTION,
    dilatational_speed,
    element_problems,
    explicit_step_estimate,
    inside_surface,
    material_problems,
    node_spacing,
    placement_problems,
)
from mlsgalerkin.structure.steppers import stepper_for
from mlsgalerkin.structure.solver import StructureSolver

MESHES = {
    "tri tensor": lambda: MeshTri.init_tensor(np.linspace(0, 1, 5), np.linspace(0, 0.5, 3)),
    "tri symmetric": lambda: MeshTri.init_symmetric().refined(2),
    "tri circle": lambda: MeshTri.init_circle(2),
    "quad tensor": lambda: MeshQuad.init_tensor(np.linspace(0, 1, 5), np.linspace(0, 0.1, 3)),
    "quad refined": lambda: MeshQuad().refined(2),
    "tet tensor": lambda: MeshTet.init_tensor(*(np.linspace(0, 1, 3),) * 3),
    "tet ball": lambda: MeshTet.init_ball(1),
    "hex tensor": lambda: MeshHex.init_tensor(*(np.linspace(0, 1, 3),) * 3),
    "hex refined": lambda: MeshHex().refined(1),
}


@pytest.mark.parametrize("make", MESHES.values(), ids=MESHES.keys())
def test_scikit_fem_meshes_pass_the_element_checks(make):
    """scikit-fem's own meshes (half their triangles and tetrahedra clockwise) are valid."""
    m = make()
    assert element_problems(m.p, m.t, m.facets, m.f2t) == []


def test_a_mesh_reflected_as_a_whole_is_valid():
    """A mirror image turns every element's orientation: still a valid mesh (scikit-fem
    integrates with |det J|), so the sign of det J alone is not the criterion."""
    m = MeshQuad.init_tensor(np.linspace(0, 1, 4), np.linspace(0, 1, 3))
    p = m.p * np.array([[-1.0], [1.0]])
    assert element_problems(p, m.t, m.facets, m.f2t) == []


@pytest.mark.parametrize("element, make", [
    ("Q1", lambda: MeshQuad.init_tensor(np.linspace(0, 1, 11), np.linspace(0, 0.1, 3))),
    ("Q2", lambda: MeshQuad.init_tensor(np.linspace(0, 1, 21), np.linspace(0, 0.05, 3))),
    ("P1", lambda: MeshTri.init_tensor(np.linspace(0, 1, 11), np.linspace(0, 1, 11))),
    ("Hex1", lambda: MeshHex.init_tensor(np.linspace(0, 1, 6), np.linspace(0, 0.2, 3), np.linspace(0, 0.2, 3))),
], ids=["Q1", "Q2", "P1", "Hex1"])
@pytest.mark.parametrize("poisson", [0.0, 0.3, 0.49])
def test_the_step_estimate_agrees_with_eigsh(element, make, poisson):
    """``2h/(κ c_d)`` within the measured band of ``2/ω_max`` (``ω_max h/c_d`` in 2.0–3.3)."""
    m = make()
    mat = ElasticMaterial(1e9, poisson, 1000.0)
    body = ElasticBody("b", m, mat, element, clamped=lambda x: np.isclose(x[0], 0.0))
    h = node_spacing(m.p, m.t, quadratic=element == "Q2")
    estimate = explicit_step_estimate(mat.young, poisson, mat.density, h, dim=m.p.shape[0], plane=mat.plane)
    ratio = estimate / (2.0 / body.highest_frequency())
    assert 2.0 / 3.0 - 0.01 < ratio < 3.4 / 3.0, ratio


@pytest.mark.parametrize("name, make_body", [("elastic_gate", "_gate"), ("beam_clamped", "_beam"),
                                             ("hydrostatic_plate", "_plate")])
def test_the_shipped_problems_estimate_agrees_with_the_integrator(name, make_body):
    """The sub-step a problem's ``check`` estimates from its parameters is within 35 % of the one
    the integrator takes (the explicit integrator, the default damping of the highest mode)."""
    mod = load_problem(name)
    p = mod.Parameters()
    if name == "hydrostatic_plate":
        p = dataclasses.replace(p, integrator="explicit")
    body = getattr(mod, make_body)(p)
    mat = body.material
    h = node_spacing(body.mesh.p, body.mesh.t, quadratic=True)
    estimate = SUBSTEP_FRACTION * explicit_step_estimate(mat.young, mat.poisson, mat.density, h, plane=mat.plane)
    ratio = estimate / stepper_for(body).substep_limit
    assert 0.65 < ratio < 1.35, ratio


def test_the_plane_stress_speed_is_the_bar_speed_at_zero_poisson():
    assert math.isclose(dilatational_speed(2e11, 0.0, 7850.0, plane="stress"), math.sqrt(2e11 / 7850.0))
    assert dilatational_speed(1e7, 0.499, 1000.0) > 12 * dilatational_speed(1e7, 0.0, 1000.0)


def test_material_limits_hold_at_their_ends():
    assert material_problems(1e7, 0.499, 1000.0) == [] and material_problems(1e7, -0.99, 1000.0) == []
    assert material_problems(1e7, 0.4991, 1000.0) and material_problems(1e7, -0.991, 1000.0)
    assert len(material_problems(float("nan"), 0.3, -1.0)) == 2


@pytest.mark.parametrize("flip", [False, True])
def test_inside_a_closed_outline(flip):
    square = np.array([[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]])
    segments = np.array([[0, 1], [1, 2], [2, 3], [3, 0]])
    if flip:
        segments = segments[:, ::-1]
    points = np.array([[0.5, 0.5], [0.99, 0.01], [1.5, 0.5], [-0.01, 0.5], [0.5, 2.0]])
    assert inside_surface(points, square, segments).tolist() == [True, True, False, False, False]
    cube = np.array([[x, y, z] for z in (0, 1) for y in (0, 1) for x in (0, 1)], dtype=float)
    tris = np.array([[0, 2, 1], [1, 2, 3], [4, 5, 6], [5, 7, 6], [0, 1, 4], [1, 5, 4], [2, 6, 3], [3, 6, 7],
                     [0, 4, 2], [2, 4, 6], [1, 3, 5], [3, 7, 5]])
    if flip:
        tris = tris[:, ::-1]
    points = np.array([[0.5, 0.5, 0.5], [0.9, 0.1, 0.95], [1.2, 0.5, 0.5], [0.5, 0.5, -0.1]])
    assert inside_surface(points, cube, tris).tolist() == [True, True, False, False]


def test_placement_in_the_tank_and_outside():
    tank = (np.array([0.0, 0.0]), np.array([1.0, 1.0]))
    assert placement_problems("b", np.array([[0.2, 0.0], [0.4, 0.1]]), tank) == []
    assert placement_problems("b", np.array([[0.95, 0.0], [1.3, 0.1]]), tank) == []   # partly in a wall
    assert "under the floor" in placement_problems("b", np.array([[0.2, -2.0], [0.4, -1.0]]), tank)[0]
    assert "outside the tank" in placement_problems("b", np.array([[2.0, 0.0], [3.0, 0.1]]), tank)[0]
    assert placement_problems("b", np.array([[0.2, 5.0], [0.4, 6.0]]), tank) == []       # open above


def _solver(model: str):
    mesh = MeshQuad.init_tensor(np.linspace(0.0, 1.0, 11), np.linspace(0.0, 0.1, 3))
    body = ElasticBody("bar", mesh, ElasticMaterial(1e7, 0.3, 1000.0), "Q1", clamped=lambda x: np.isclose(x[0], 0.0),
                       model=model)
    scene = Scene([body], [StructureScheme(dt_max=1e-3)], t_end=0.1)
    solver = StructureSolver([body], scene.schemes[0], scene.view())
    return solver, solver.state.body("bar")


@pytest.mark.parametrize("angle, warns", [(0.5 * LINEAR_ROTATION_LIMIT, 0), (2.0 * LINEAR_ROTATION_LIMIT, 1)])
def test_a_linear_body_turned_too_far_warns_once(angle, warns):
    solver, m = _solver("linear")
    x = m.body.basis.doflocs
    m.u[0::2] = -angle * x[1, 0::2]          # a small-rotation field θ e_z × X (Q1: interleaved x, y)
    m.u[1::2] = angle * x[0, 1::2]
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        for k in range(3):
            solver.end_step(k * 1e-3, 1e-3)
    found = [w for w in caught if issubclass(w.category, LargeRotationWarning)]
    assert len(found) == warns
    if warns:
        assert "neo_hookean" in str(found[0].message) and "'bar'" in str(found[0].message)


def test_a_nonlinear_body_is_not_watched():
    solver, m = _solver("neo_hookean")
    m.u[1::2] = 0.5 * m.body.basis.doflocs[0, 1::2]
    with warnings.catch_warnings():
        warnings.simplefilter("error", LargeRotationWarning)
        solver.end_step(0.0, 1e-3)
