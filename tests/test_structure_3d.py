"""Elastic bodies in 3D with the same API (:mod:`mlsgalerkin.structure.elastic`): hexahedra and
tetrahedra against beam theory, the oriented triangles of the wet surface, and a 3D water block
landing on a clamped plate through node-to-surface penalty contact."""

from __future__ import annotations

import numpy as np
import pytest
from skfem import MeshHex, MeshTet

from mlsgalerkin.contact import PenaltyContact
from mlsgalerkin.fluid import FluidBody, Gravity, MonaghanViscosity, Phase, TaitPressure
from mlsgalerkin.scene import Scene
from mlsgalerkin.simulation import Simulation
from mlsgalerkin.structure import ElasticBody, ElasticMaterial

L, H, E, P = 1.0, 0.1, 1e7, 10.0


@pytest.mark.parametrize("element, mesh, tol", [
    ("Hex2", MeshHex.init_tensor(np.linspace(0, L, 21), np.linspace(0, H, 2), np.linspace(0, H, 2)), 0.005),
    ("Hex1", MeshHex.init_tensor(np.linspace(0, L, 41), np.linspace(0, H, 5), np.linspace(0, H, 5)), 0.04),
])
def test_3d_cantilever_tip_deflection_against_timoshenko(element, mesh, tol):
    """δ = P L³/(3 E I) + P L/(κ G A) for a square 0.1 m section, ν = 0, a shear traction on the
    free end. Measured: 27-node Hex2 −0.10 %, Hex1 −3.1 % (shear locking of the linear brick;
    linear tetrahedra lock worse, −18 % on the same grid)."""
    b = ElasticBody("c", mesh, ElasticMaterial(E, 0.0, 1000.0), element, clamped=lambda x: np.isclose(x[0], 0.0))
    assert b.dim == 3
    u = b.static(b.edge_traction(lambda x: np.isclose(x[0], L), (0.0, -P / H**2, 0.0)))
    tip = b.displacement_at(np.array([[L], [H / 2], [H / 2]]), u)[0, 1]
    ref = -(P * L**3 / (3 * E * H**4 / 12) + P * L / (5 / 6 * E / 2 * H**2))
    assert abs(tip / ref - 1.0) < tol


def test_3d_wet_surface_is_triangles_facing_out_of_the_body():
    mesh = MeshTet.init_tensor(np.linspace(0, 0.4, 5), np.linspace(0, 0.2, 3), np.linspace(0, 0.1, 2))
    b = ElasticBody("box", mesh, ElasticMaterial(1e7, 0.3, 1000.0), "P1")
    surf = b.surface()
    assert surf.dim == 3 and surf.facets.shape[1] == 3
    side = np.einsum("ij,ij->i", surf.normals(), surf.centroids() - np.array([0.2, 0.1, 0.05]))
    assert np.all(side > 0)
    top = b.surface(lambda x: np.isclose(x[2], 0.1))
    assert np.allclose(top.normals(), [0.0, 0.0, 1.0]) and np.isclose(top.measures().sum(), 0.4 * 0.2)


def test_a_3d_water_block_lands_on_a_clamped_plate():
    """216 particles fall 5 mm onto a clamped Hex1 plate: penalty contact holds every particle above
    the plate and pushes the plate down."""
    dx = 0.01
    mesh = MeshHex.init_tensor(np.linspace(0, 0.2, 9), np.linspace(0, 0.2, 9), np.linspace(-0.01, 0.0, 2))
    edge = lambda x: np.isclose(x[0], 0) | np.isclose(x[0], 0.2) | np.isclose(x[1], 0) | np.isclose(x[1], 0.2)
    plate = ElasticBody("plate", mesh, ElasticMaterial(1e7, 0.3, 1000.0), "Hex1", clamped=edge,
                        wet=lambda x: np.isclose(x[2], 0.0), points={"mid": (0.1, 0.1, -0.005)})
    water = FluidBody.block("water", (0.07, 0.07, 0.005), (0.13, 0.13, 0.065), dx, [Phase("water", 1000.0)])
    scene = Scene([water, plate], [TaitPressure(10.0), Gravity((0.0, 0.0, -9.81)), MonaghanViscosity(0.1)],
                  t_end=0.1, interactions=[PenaltyContact("water", "plate", thickness=0.5 * dx)])
    res = Simulation(scene).run(progress=False)
    ts = res.timeseries
    assert res.summary["status"] == "completed"
    assert res.state.fluid.x[:, 2].min() > 0.0
    late = np.asarray(ts["time"]) > 0.07
    assert np.all(np.asarray(ts["plate_force_z"])[late] < 0.0)
    assert np.mean(np.asarray(ts["plate_mid_uz"])[late]) < 0.0


def _box(lo, hi):
    """A closed box surface of 12 triangles, normals out."""
    from mlsgalerkin.contact import ContactSurface

    inner = ContactSurface.tank(lo, hi, open_top=False)
    return inner.flipped()


def test_3d_rigid_body_on_a_hinge_swings_with_its_dry_period():
    """A 3D plank standing on a hinge whose axis is the x axis, gravity along −z: the same
    ``ω² = (K + m g·r⊥)/I_p`` as in 2D; the run loop's period within 0.5 %."""
    from mlsgalerkin.structure import Hinge, RigidBody

    m, L, t = 2.0, 1.0, 0.05
    plank = RigidBody("plank", _box((-0.1, -t / 2, 0.0), (0.1, t / 2, L)), m, m * (L**2 + t**2) / 12.0,
                      (0.0, 0.0, L / 2), constraint=Hinge((0.0, 0.0, 0.0), stiffness=200.0, axis=(1.0, 0.0, 0.0)),
                      gravity=(0.0, 0.0, -9.81), angular_velocity=0.1)
    expected = 2 * np.pi / np.sqrt((200.0 - m * 9.81 * L / 2) / (m * (L**2 + t**2) / 12 + m * (L / 2) ** 2))
    assert plank.natural_period() == pytest.approx(expected, rel=1e-12)
    res = Simulation(Scene([plank], [], t_end=3 * expected, dt_max=expected / 200)).run(progress=False)
    ts = res.timeseries
    t_, a = np.asarray(ts["time"]), np.asarray(ts["plank_angle"])
    k = np.flatnonzero((a[:-1] < 0) & (a[1:] >= 0))
    crossings = t_[k] - a[k] * (t_[k + 1] - t_[k]) / (a[k + 1] - a[k])
    assert np.diff(crossings).mean() == pytest.approx(expected, rel=5e-3)
    # it turns about x: the top moves in y and z, never in x
    top = res.state.systems["structure"].body("plank").nodes()
    assert np.allclose(top[:, 0], plank.surface.nodes[:, 0])


def test_3d_rigid_body_falls_vertically():
    from mlsgalerkin.structure import RigidBody

    box = RigidBody("box", _box((0, 0, 1.0), (0.2, 0.2, 1.2)), 5.0, 0.1, (0.1, 0.1, 1.1), constraint="vertical",
                    gravity=(0.0, 0.0, -9.81))
    res = Simulation(Scene([box], [], t_end=0.2, dt_max=1e-3)).run(progress=False)
    body = res.state.systems["structure"].body("box")
    assert body.V == pytest.approx([0.0, 0.0, -9.81 * 0.2], abs=1e-9)
    assert body.c[2] - 1.1 == pytest.approx(-0.5 * 9.81 * 0.2**2, rel=1e-6)
    with pytest.raises(ValueError, match="free rotation in 3D is not modelled"):
        RigidBody("b", _box((0, 0, 0), (1, 1, 1)), 1.0, 1.0, (0.5, 0.5, 0.5), constraint="free")
