"""The fluid loads a structure (:mod:`mlsgalerkin.interactions.structure_coupling`): wall particles riding on a
surface, their reaction spread back to its nodes, and the plate under a water column of
``hydrostatic_plate`` at a coarse resolution."""

from __future__ import annotations

import numpy as np
import pytest

from mlsgalerkin.contact import ContactSurface
from mlsgalerkin.contact.surface import surface_points
from mlsgalerkin.dynamics import Surface
from mlsgalerkin.fluid import WallBody
from mlsgalerkin.interactions import riding_kinematics
from mlsgalerkin.problem import load_problem
from mlsgalerkin.scene import SceneError
from mlsgalerkin.simulation import Simulation


def test_surface_points_average_the_piece_of_surface_they_stand_for():
    """Points along a polyline of uneven segments: evenly spaced in arc length, each map's rows sum
    to one (a constant is reproduced), and a linear field's footprint mean is its value at the
    point."""
    s = ContactSurface.polyline([(1.0, 0.0), (0.7, 0.0), (0.55, 0.1), (0.2, 0.1), (0.0, 0.3)])
    pts = surface_points(s, 0.05)
    arc = np.concatenate([[0.0], np.cumsum(s.measures())])
    assert pts.segment.size == round(arc[-1] / 0.05)
    for m in (pts.average, pts.start, pts.end):
        np.testing.assert_allclose(np.asarray(m.sum(axis=1)).ravel(), 1.0, atol=1e-12)
    field = s.nodes @ np.array([2.0, -3.0]) + 0.5          # linear in x, and so along each segment
    x_point = s.nodes[s.facets[pts.segment, 0]] + pts.xi[:, None] * (
        s.nodes[s.facets[pts.segment, 1]] - s.nodes[s.facets[pts.segment, 0]])
    inside = (np.abs(pts.xi - 0.5) < 0.5 - pts.width / (2 * s.measures()[pts.segment]))  # footprint on one segment
    np.testing.assert_allclose((pts.average @ field)[inside], (x_point @ np.array([2.0, -3.0]) + 0.5)[inside],
                               atol=1e-12)


def test_riding_wall_particles_follow_a_rigid_motion_exactly():
    """On a straight surface moved rigidly (translation and rotation), riding particles move with
    the same rigid motion: positions, velocities and the normals turned with it."""
    surf = ContactSurface.polyline([(1.0, 0.0), (0.5, 0.0), (0.0, 0.0)])
    walls = WallBody.on_surface("w", surf, 0.1, follows="plate", layers=3)
    theta, omega, shift = 0.3, 2.0, np.array([0.2, -0.1])
    R = np.array([[np.cos(theta), -np.sin(theta)], [np.sin(theta), np.cos(theta)]])
    x = surf.nodes @ R.T + shift
    v = omega * np.stack([-(x - shift)[:, 1], (x - shift)[:, 0]], axis=1)
    pos, vel, acc, n = riding_kinematics(Surface("plate", x, v, surf.facets), walls.footprints, walls.anchors)
    np.testing.assert_allclose(pos, walls.positions @ R.T + shift, atol=1e-12)
    np.testing.assert_allclose(n, walls.normals @ R.T, atol=1e-12)
    r = pos - shift
    np.testing.assert_allclose(vel, omega * np.stack([-r[:, 1], r[:, 0]], axis=1), atol=1e-12)
    assert np.all(acc == 0)


def test_a_wall_that_follows_a_structure_needs_its_coupling():
    mod = load_problem("hydrostatic_plate")
    scene = mod.make_scene(mod.Parameters(dx=0.1, t_end=0.01, elements=10))
    scene.interactions = []
    with pytest.raises(SceneError, match="follows 'plate' but no interaction moves it"):
        Simulation(scene)


def test_validating_a_coupling_changes_nothing_and_setup_takes_what_the_run_needs():
    """``problems()`` is validation only: the coupling's attributes are the same after it
    (it used to resize the reaction records and take the wall body's anchors); the
    ``Simulation`` calls ``setup(scene)`` for that."""
    import copy

    mod = load_problem("hydrostatic_plate")
    scene = mod.make_scene(mod.Parameters(dx=0.1, t_end=0.01, elements=10))
    coupling = scene.interactions[0]
    before = copy.deepcopy(vars(coupling))
    assert scene.problems() == []
    after = vars(coupling)
    assert before.keys() == after.keys()
    for k, v in before.items():
        assert repr(v) == repr(after[k]), k
    assert coupling._anchors is None and coupling.reaction.shape == (2,)
    Simulation(scene)
    walls = next(b for b in scene.bodies if b.name == coupling.walls)
    np.testing.assert_array_equal(coupling._anchors, walls.anchors)


def test_a_coupling_names_the_solver_method_it_needs(monkeypatch):
    """The extra methods a coupling calls on the solvers are declared (``DrivesWalls``,
    ``CarriesStepEndLoad``) and checked before any work, with the body, the solver, what it lacks
    and the kind of interaction that needs it."""
    from mlsgalerkin.dynamics import CarriesStepEndLoad, DrivesWalls
    from mlsgalerkin.fluid.solver import FluidSolver
    from mlsgalerkin.structure.solver import StructureSolver

    assert issubclass(FluidSolver, DrivesWalls) and issubclass(StructureSolver, CarriesStepEndLoad)
    assert not issubclass(StructureSolver, DrivesWalls)
    mod = load_problem("hydrostatic_plate")
    scene = mod.make_scene(mod.Parameters(dx=0.1, t_end=0.01, elements=10))
    monkeypatch.delattr(FluidSolver, "wall_reactions")
    with pytest.raises(SceneError, match=r"StructureCoupling 'coupling': body 'water''s solver FluidSolver "
                                         r"cannot drive wall particles riding on a structure \(it lacks wall_reactions\); "
                                         r"interactions of kind StructureCoupling with walls= need a solver that "
                                         r"implements mlsgalerkin.dynamics.DrivesWalls"):
        Simulation(scene)
    monkeypatch.undo()
    scene.interactions[0].iterations = 3
    Simulation(scene)   # the structure solver carries the step-end load
    monkeypatch.delattr(StructureSolver, "set_step_end_load")
    with pytest.raises(SceneError, match=r"body 'plate''s solver StructureSolver cannot repeat a step with the load at "
                                         r"the step's end \(it lacks set_step_end_load\); interactions of kind "
                                         r"StructureCoupling with iterations > 1 need"):
        Simulation(scene)


@pytest.fixture(scope="module")
def plate_run():
    mod = load_problem("hydrostatic_plate")
    p = mod.Parameters(dx=0.05, t_end=0.26)   # past the two acoustic periods (0.255 s) the analysis waits for
    sim = Simulation(mod.make_scene(p))
    res = sim.run(progress=False, analyse=lambda r: mod.analyse(r, p))
    return mod, p, res, sim.state.systems["fluid"]


def test_plate_under_water_carries_the_water_and_deflects_as_the_plate_model(plate_run):
    """Coarse (20 particles across the 1 m plate), 0.26 s: after settling the plate carries the water's
    weight within 1 % and its mean mid-span deflection is within 2 % of the plate model's own
    static answer under the exact hydrostatic load (measured at dx 0.05 and 0.025: 0.2 %)."""
    mod, p, res, _ = plate_run
    r = res.results
    assert res.summary["status"] == "completed"
    assert abs(r["water_load_mean_N_per_m"] / r["water_weight_N_per_m"] - 1.0) < 0.01
    assert abs(r["error_vs_fe_static"]) < 0.02
    assert r["max_plate_crossings"] == 0


def test_fluid_and_plate_exchange_equal_and_opposite_loads(plate_run):
    """The load the plate receives is the reaction of the fluid's wall particles plus the contact
    force, and the fluid's last evaluation conserves momentum: its nodal forces over all fluid and
    wall nodes add up to the water's weight (the Galerkin sums add to zero; the linear consistency
    gives that up by its integration residual, measured 0.05 % of the weight). The water is not
    at rest at one instant (at the recommended α = 0.02 it still rings acoustically: the plate's
    last load is 3 % above the weight); its mean load is held to the weight in the test above."""
    mod, p, res, fluid = plate_run
    summary = res.summary["interactions"]["coupling"]
    load = np.array(summary["last_wall_reaction_N"]) + np.array(summary["last_contact_force_N"])
    weight = p.rho * p.g * p.depth * p.length
    assert abs(load[0]) < 1e-6 * weight
    on_plate_walls = fluid.force[fluid.bodies["plate_walls"]].sum(axis=0)
    np.testing.assert_allclose(summary["last_wall_reaction_N"], on_plate_walls, rtol=1e-9, atol=1e-9 * weight)
    gravity = -p.g * fluid.M[fluid.fluid].sum()
    total = fluid.force.sum(axis=0)
    assert abs(total[0]) < 1e-9 * weight
    assert abs(total[1] - gravity) < 0.005 * weight


def test_aitken_relaxation_finds_the_fixed_point_of_a_linear_interface_map():
    """For a linear fixed-point map ``x* = a x̃ + b`` of the interface, Aitken's factor is the
    optimal ``1/(1 − a)`` clipped to (0, 1] (``AITKEN_RANGE``), and the relaxed guess converges to
    the fixed point: in one relaxed pass for an expanding map (``a = −3``, where plain iteration
    diverges), at the plain rate 0.5 when the optimum 2 is clipped to 1."""
    from mlsgalerkin.interactions import StructureCoupling

    for a in (0.5, -3.0):
        c = StructureCoupling("water", "plate", walls="w", iterations=50, relaxation=0.5)
        c._anchors = np.array([[0, 0.5, 0.005, 0], [1, 0.5, 0.005, 1], [2, 0.5, 0.015, 2]], dtype=float)
        b = np.array([[0.1, -0.2], [0.3, 0.05], [0.0, 0.4]])
        fixed = b / (1.0 - a)
        x = np.zeros((3, 2))
        z = np.zeros_like(x)
        guess, _, _ = c._relaxed(x, z, z)           # first pass: the structure's answer itself
        for _ in range(60):
            guess, _, _ = c._relaxed(a * guess + b, z, z)
            if c.crms < 1e-12:
                break
        np.testing.assert_allclose(guess, fixed, atol=1e-9)
        assert c._omega == pytest.approx(min(1.0, 1.0 / (1.0 - a)), rel=1e-6)


def test_partitioned_iteration_lets_a_light_gate_see_its_acceleration():
    """The rubber gate (5.5 kg/m² against water) diverges within 0.01 s when the wall pressure sees
    its acceleration and the coupling is explicit; repeating each step until the interface
    converges (CRMS < 1e-7 m, Aitken relaxation) runs it, in 2 to 4 passes a step."""
    from mlsgalerkin.monitors import SimulationDiverged

    mod = load_problem("elastic_gate")
    p = mod.Parameters(dx=0.005, t_end=0.02, elements=16)
    explicit = mod.make_scene(p)
    explicit.interactions[0].wall_acceleration = 1.0
    with pytest.raises((SimulationDiverged, ValueError)):
        Simulation(explicit).run(progress=False)
    scene = mod.make_scene(p)
    c = scene.interactions[0]
    c.wall_acceleration, c.iterations, c.tolerance = 1.0, 20, 1e-7
    res = Simulation(scene).run(progress=False)
    it = res.summary["interactions"]["coupling"]["partitioned_iteration"]
    assert res.summary["status"] == "completed"
    assert it["steps_not_converged"] == 0 and 2.0 <= it["passes_mean"] <= 4.0
    tip = res.timeseries["tip_x"][-1]
    assert 0.0 < tip < 0.02


def test_an_undamped_coupled_run_does_not_gain_energy():
    """The plate under 2 m of water with no artificial viscosity, no density filter and no
    structural damping: the total energy — fluid kinetic + gravity + compression (Tait), plate
    kinetic + strain + weight — rises by about 0.1 % of M g H in the first 15 ms as the
    hydrostatic start settles into the discrete equilibrium, then holds: its mean over the last
    third of 0.2 s is within 0.02 % of M g H of its mean over the second third. The energy stored
    in the penalty contacts (walls and plate) is part of the total. (Held surface loads, or loads
    as impulses, gained an e-fold of energy every few milliseconds.)"""
    mod = load_problem("hydrostatic_plate")
    p = mod.Parameters(dx=0.05, t_end=0.2, alpha=0.0)
    scene = mod.make_scene(p)
    scene.schemes[0].effects = [e for e in scene.schemes[0].effects if type(e).__name__ != "DensityFilter"]
    ts = Simulation(scene).run(progress=False).timeseries
    contact = [k for k in ts if k == "penalty_energy" or k.endswith("contact_energy")]
    assert contact, "the contact's stored energy is a time-series column"
    total = sum(np.asarray(ts[k]) for k in ["kinetic_energy", "potential_energy", "compression_energy",
                                              "plate_kinetic_energy", "plate_strain_energy", "plate_weight_potential"]
                + contact)
    scale = p.rho * p.depth * p.length * p.g * p.depth          # M g H (J per metre)
    rise = total - total[0]
    assert np.max(rise) < 2e-3 * scale
    n = rise.size
    assert abs(rise[2 * n // 3:].mean() - rise[n // 3: 2 * n // 3].mean()) < 2e-4 * scale


def test_structure_frames_join_the_particles_in_one_series(tmp_path):
    """A coupled run writes the structure's mesh (its cells) beside the particles, and
    ``frames.pvd`` lists one multiblock per frame time with both."""
    import meshio

    from mlsgalerkin.io import read_pvd

    mod = load_problem("hydrostatic_plate")
    Simulation(mod.make_scene(mod.Parameters(dx=0.1, t_end=0.01, elements=10))).run(out=tmp_path, progress=False)
    frames = read_pvd(tmp_path / "frames.pvd")
    assert len(frames) == len(read_pvd(tmp_path / "particles.pvd")) == 2
    text = frames[-1][1].read_text()
    assert 'name="particles"' in text and 'name="structure"' in text
    mesh = meshio.read(read_pvd(tmp_path / "structure.pvd")[-1][1])
    assert [c.type for c in mesh.cells] == ["quad"] and len(mesh.cells[0].data) == 20


def test_a_coupled_run_restarts_bit_for_bit(tmp_path):
    """Interrupted after 37 steps and restarted from its checkpoint, the plate under water (Newmark,
    riding wall particles, contact) ends in exactly the state of the run that never stopped."""
    mod = load_problem("hydrostatic_plate")
    p = mod.Parameters(dx=0.1, t_end=0.03, elements=10)
    straight = Simulation(mod.make_scene(p)).run(progress=False)
    Simulation(mod.make_scene(p)).run(out=tmp_path, progress=False, max_steps=37)
    resumed = Simulation(mod.make_scene(p)).run(out=tmp_path, progress=False, restart="latest")
    a, b = straight.state.systems, resumed.state.systems
    assert np.array_equal(a["fluid"].x, b["fluid"].x) and np.array_equal(a["fluid"].v, b["fluid"].v)
    pa, pb = a["structure"].body("plate"), b["structure"].body("plate")
    assert np.array_equal(pa.u, pb.u) and np.array_equal(pa.v, pb.v)
