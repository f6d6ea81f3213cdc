"""Elastic bodies on scikit-fem (:mod:`mlsgalerkin.structure.elastic`): the cantilever against
Timoshenko beam theory, the first bending period of the clamped beam of the dam-break case
against Euler–Bernoulli, energy of undamped central differences, and bad input."""

from __future__ import annotations

import numpy as np
import pytest
import scipy.sparse as sp
from scipy.sparse.linalg import eigsh
from skfem import MeshQuad

from mlsgalerkin.structure import ElasticBody, ElasticMaterial
from mlsgalerkin.structure.explicit import leapfrog_step


def cantilever(nx: int, ny: int, element: str, L=1.0, h=0.1, E=1e7, nu=0.0, rho=1000.0, plane="stress"):
    mesh = MeshQuad.init_tensor(np.linspace(0.0, L, nx + 1), np.linspace(0.0, h, ny + 1))
    return ElasticBody("beam", mesh, ElasticMaterial(E, nu, rho, plane=plane), element=element,
                       clamped=lambda x: np.isclose(x[0], 0.0))


@pytest.mark.parametrize("element, tol", [("Q2", 1e-3), ("Q1", 2e-2)])
def test_cantilever_tip_deflection_against_timoshenko(element, tol):
    """δ = P L³/(3 E I) + P L/(κ G A), κ = 5/6, a shear traction P/h on the free end (ν = 0,
    plane stress: the 2D body is the beam). Measured: Q2 −0.005 %, Q1 −0.8 % (shear locking)."""
    L, h, E, P = 1.0, 0.1, 1e7, 10.0
    b = cantilever(40 if element == "Q2" else 80, 4 if element == "Q2" else 8, element)
    u = b.static(b.edge_traction(lambda x: np.isclose(x[0], L), (0.0, -P / h)))
    tip = b.displacement_at(np.array([[L], [h / 2]]), u)[0, 1]
    ref = -(P * L**3 / (3 * E * h**3 / 12) + P * L / (5 / 6 * E / 2 * h))
    assert abs(tip - ref) < tol * abs(ref)


def test_clamped_beam_first_period():
    """The clamped elastic beam of the dam break on a beam: E = 0.2 GPa, 6 mm thick, 47.16 kg/m²
    (ρ = 7860 kg/m³), 0.304 m long. Euler–Bernoulli: T1 = 2π L² / (1.8751² sqrt(EI/m)) = 0.5977 s
    (0.5971 s quoted). Plane stress maps the 2D body to the beam (plane strain would stiffen it by
    1/(1 − ν²), shortening the period by about 5 % at ν = 0.3)."""
    L, h, E, rho = 0.304, 0.006, 0.2e9, 47.16 / 0.006
    b = cantilever(76, 3, "Q2", L=L, h=h, E=E, nu=0.3, rho=rho, plane="stress")
    free = b.free
    K = b.stiffness[free][:, free]
    M = sp.diags(b.lumped_mass[free])
    w2 = eigsh(K, k=1, M=M, sigma=0.0, which="LM", return_eigenvectors=False)[0]
    period = 2 * np.pi / np.sqrt(w2)
    beam = 2 * np.pi * L**2 / (1.8751**2 * np.sqrt(E * h**3 / 12 / (rho * h)))
    assert abs(period - beam) < 0.02 * beam
    assert abs(period - 0.5971) < 0.02 * 0.5971


def test_central_differences_keep_the_energy_of_free_vibration():
    """Released from its static deflection, the undamped cantilever keeps kinetic + strain
    energy within 0.5 % over 10 periods at 0.9 of the stable step."""
    L, h, P = 1.0, 0.1, 10.0
    b = cantilever(10, 2, "Q2")
    u = b.static(b.edge_traction(lambda x: np.isclose(x[0], L), (0.0, -P / h)))
    e0 = b.strain_energy(u)
    dt = 0.9 * b.stable_time_step()
    free = b.free
    w2 = eigsh(b.stiffness[free][:, free], k=1, M=sp.diags(b.lumped_mass[free]), sigma=0.0, which="LM",
               return_eigenvectors=False)[0]
    steps = int(10 * 2 * np.pi / np.sqrt(w2) / dt)
    drift = 0.0
    v = 0.5 * dt * b.internal_force(u) / b.lumped_mass   # v^{-1/2} = -(dt/2) a^0: at rest at t = 0
    for _ in range(steps):
        u_old = u.copy()
        leapfrog_step(b, u, v, dt)
        # energy at the half step: kinetic of v^{n+1/2}, strain of the mean displacement
        e = b.kinetic_energy(v) + b.strain_energy(0.5 * (u_old + u))
        drift = max(drift, abs(e - e0) / e0)
    assert drift < 5e-3


def test_bad_input():
    with pytest.raises(ValueError, match="poisson"):
        ElasticMaterial(1e7, 0.5, 1000.0)
    with pytest.raises(ValueError, match="plane"):
        ElasticMaterial(1e7, 0.3, 1000.0, plane="axisymmetric")
    mesh = MeshQuad.init_tensor(np.linspace(0, 1, 3), np.linspace(0, 1, 3))
    with pytest.raises(ValueError, match="element"):
        ElasticBody("b", mesh, ElasticMaterial(1e7, 0.3, 1000.0), element="Q8")


def test_wet_surface_is_oriented_out_of_the_body_and_follows_the_displacement():
    """scikit-fem sorts facet vertices; each segment is re-oriented from its owning element so
    that the contact normal points out of the body (on a rectangle: left, right, up, down); a Q2
    facet is two segments through its mid-side node."""
    b = cantilever(8, 2, "Q2")
    surf = b.surface()
    centroids = surf.centroids()
    n = surf.normals()
    outward = np.where(np.isclose(centroids[:, 0], 0.0)[:, None], [-1.0, 0.0],
                       np.where(np.isclose(centroids[:, 0], 1.0)[:, None], [1.0, 0.0],
                                np.where(np.isclose(centroids[:, 1], 0.0)[:, None], [0.0, -1.0], [0.0, 1.0])))
    np.testing.assert_allclose(n, outward, atol=1e-12)
    assert surf.n_facets == 2 * 2 * (8 + 2)
    assert surf.n_nodes == 2 * 2 * (8 + 2)                    # a closed chain: as many nodes as segments
    top = b.surface(lambda x: np.isclose(x[1], 0.1))
    assert top.n_facets == 16 and top.n_nodes == 17 and np.allclose(top.normals(), [0.0, 1.0])
    u = np.zeros(b.n_dofs)
    u[b.basis.nodal_dofs[1]] = -0.01                        # every vertex 1 cm down
    u[b.basis.facet_dofs[1]] = -0.01                        # and every mid-side node
    moved = b.surface(lambda x: np.isclose(x[1], 0.1), u)
    np.testing.assert_allclose(moved.nodes - top.nodes, [[0.0, -0.01]] * top.n_nodes)
    q1 = cantilever(8, 2, "Q1").surface(lambda x: np.isclose(x[1], 0.1))
    assert q1.n_facets == 8 and q1.n_nodes == 9


@pytest.mark.parametrize("model", ["neo_hookean", "stvenant_kirchhoff"])
def test_large_deflection_of_a_cantilever_against_the_elastica(model):
    """A tip dead load ``P = EI/L²`` on a slender cantilever (L/h = 50, ν = 0, plane strain = the
    beam): the elastica gives the tip's vertical deflection 0.3017 L and its horizontal pull-in
    0.0564 L (Bisshopp & Drucker 1945); linear theory gives L/3 and no pull-in. ``equilibrium``
    solves the body's own total-Lagrangian model. Measured (neo-Hookean): 0.30179 L and 0.05644 L;
    the tolerances are the table's four digits plus the shear and thickness of the 2D body."""
    L, h, E = 1.0, 0.02, 1e7
    b = cantilever(40, 2, "Q2", L=L, h=h, E=E, nu=0.0, plane="strain")
    body = ElasticBody("beam", b.mesh, b.material, "Q2", clamped=lambda x: np.isclose(x[0], 0.0), model=model)
    P = E * h**3 / 12 / L**2
    u = body.equilibrium(body.edge_traction(lambda x: np.isclose(x[0], L), (0.0, -P / h)), increments=8)
    ux, uy = body.displacement_at(np.array([[L], [h / 2]]), u)[0]
    assert abs(-uy / L - 0.3017) < 0.002 * 0.3017
    assert abs(-ux / L - 0.0564) < 0.005 * 0.0564
    assert np.allclose(body.equilibrium(np.zeros(body.n_dofs), increments=1), 0.0)


def test_a_body_holds_no_motion_and_the_old_live_state_still_works_with_a_warning():
    """The body is a spec: a run's displacement lives in its stepper, a script's in its own
    arrays. The old ``body.u``, ``body.v``, ``body.step()`` and ``body.energies()`` keep working for
    one release with a DeprecationWarning naming what to write instead, and give the numbers of
    the pure functions."""
    b = cantilever(4, 1, "Q2")
    assert "u" not in vars(b) and "v" not in vars(b)
    f = b.edge_traction(lambda x: np.isclose(x[0], 1.0), (0.0, -100.0))
    u, v = np.zeros(b.n_dofs), np.zeros(b.n_dofs)
    leapfrog_step(b, u, v, 1e-4, f)
    with pytest.warns(DeprecationWarning, match="leapfrog_step"):
        b.step(1e-4, f)
    with pytest.warns(DeprecationWarning, match=r"body\(name\)\.u"):
        assert np.array_equal(b.u, u) and np.array_equal(b.v, v)
    with pytest.warns(DeprecationWarning, match="kinetic_energy"):
        assert b.energies() == (b.kinetic_energy(v), b.strain_energy(u))
    np.testing.assert_array_equal(b.surface().nodes, b.surface(None, u).nodes)   # u=None: the old b.u
    fresh = cantilever(4, 1, "Q2")
    np.testing.assert_array_equal(fresh.internal_force(), np.zeros(fresh.n_dofs))  # at rest
