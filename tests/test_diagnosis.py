"""The system-state contract (:class:`~mlsgalerkin.dynamics.SystemState`) and the watchdog's
:class:`~mlsgalerkin.dynamics.Diagnosis`: a structure that diverges first ends the run
``diverged`` with a diagnosis naming the body (it used to end in a ``KeyError`` of the
watchdog, which formatted the fluid's keys), for any solver's state."""

from __future__ import annotations

import json
import warnings

import numpy as np
import pytest
from skfem import MeshQuad

from mlsgalerkin.structure.scheme import StructureScheme
from mlsgalerkin.dynamics import Diagnosis, SystemState
from mlsgalerkin.io import load_checkpoint
from mlsgalerkin.monitors import SimulationDiverged, Watchdog
from mlsgalerkin.scene import Scene, SceneError
from mlsgalerkin.simulation import Simulation
from mlsgalerkin.structure import ElasticBody, ElasticMaterial, Hinge, RigidBody


def plate(ny: int = 4) -> ElasticBody:
    mesh = MeshQuad.init_tensor(np.linspace(0.0, 0.01, 2), np.linspace(0.0, 0.1, ny + 1))
    return ElasticBody("plate", mesh, ElasticMaterial(1e6, 0.3, 1000.0, plane="stress"),
                       clamped=lambda x: np.isclose(x[1], 0.0))


def poison_after(sim: Simulation, name: str, steps: int, poison) -> None:
    """From outer step ``steps`` of body ``name`` on, ``poison(motion)`` after its advance."""
    m = sim.solver("structure").state.body(name)
    advance = m.advance

    def advance_then_poison(dt):
        advance(dt)
        if m.outer_steps >= steps:
            poison(m)

    m.advance = advance_then_poison


def test_an_elastic_body_that_diverges_first_ends_the_run_diverged_naming_it(tmp_path):
    b = plate()
    sim = Simulation(Scene([b], [StructureScheme(dt_max=1e-3)], t_end=0.01, watchdog=Watchdog(keep_every=2)))
    dof = 5
    node = int(np.flatnonzero((b.basis.nodal_dofs == dof).any(axis=0))[0])

    def poison(m):
        m.u[dof] = np.nan

    poison_after(sim, "plate", 3, poison)
    with pytest.raises(SimulationDiverged) as info:
        sim.run(out=tmp_path, progress=False)
    err = info.value
    assert f"at step 3 (t = 0.003 s): structure node {node} of body 'plate'" in str(err)
    assert "displacement is not finite" in str(err) and "Last good state (step 2)" in str(err)
    rec = err.record
    assert (rec.system, rec.body, rec.point, rec.index, rec.quantity, rec.step) == (
        "structure", "plate", "node", node, "displacement", 3)
    assert rec.at_rest and rec.position == tuple(b.mesh.p[:, node])
    assert not np.all(np.isfinite(rec.value))
    summary = json.loads((tmp_path / "summary.json").read_text())
    assert summary["status"] == "diverged"
    d = summary["diagnosis"]
    assert (d["system"], d["body"], d["node"], d["step"], d["quantity"]) == ("structure", "plate", node, 3,
                                                                               "displacement")
    assert d["time"] == pytest.approx(0.003) and d["message"] in str(err)
    _, meta = load_checkpoint(err.checkpoint)
    assert meta["step"] == 2


def test_a_structure_displaced_past_the_watchdog_limit_is_stopped():
    """A finite but huge displacement (a blown-up explicit body before it overflows) stops the
    run once the scene sets ``Watchdog(max_displacement=...)``; without it the run goes on."""
    def shove(m):
        m.u[5] = 7.0

    def run(watchdog):
        sim = Simulation(Scene([plate()], [StructureScheme(dt_max=1e-3)], t_end=0.005, watchdog=watchdog))
        poison_after(sim, "plate", 2, shove)
        return sim.run(progress=False)

    assert run(Watchdog()).summary["status"] == "completed"
    with pytest.raises(SimulationDiverged, match=r"displacement \|u\| = 7 m exceeds 0.5 m") as info:
        run(Watchdog(max_displacement=0.5))
    rec = info.value.record
    assert rec.body == "plate" and rec.limit == 0.5 and rec.step == 2 and max(abs(v) for v in rec.value) == 7.0
    with pytest.raises(SceneError, match="watchdog.max_displacement must be positive"):
        Simulation(Scene([plate()], [StructureScheme(dt_max=1e-3)], t_end=0.005, watchdog=Watchdog(max_displacement=-1.0)))


def test_a_rigid_body_that_diverges_is_named():
    beam = RigidBody.beam("beam", base=(0.0, 0.0), length=1.0, mass=1.0, thickness=0.02,
                          constraint=Hinge((0.0, 0.0), stiffness=100.0))
    sim = Simulation(Scene([plate(), beam], [StructureScheme(dt_max=1e-3)], t_end=0.01))

    def poison(m):
        m.theta = np.nan

    poison_after(sim, "beam", 4, poison)
    with pytest.raises(SimulationDiverged, match="structure node 0 of body 'beam'") as info:
        sim.run(progress=False)
    assert info.value.record.body == "beam" and info.value.record.step == 4


def test_every_shipped_solver_state_is_a_system_state():
    from mlsgalerkin.problem import load_problem

    mod = load_problem("dam_break")
    sim = Simulation(mod.make_scene(mod.Parameters(dx=0.04, t_end=0.001)))
    assert isinstance(sim.state.fluid, SystemState)
    assert isinstance(Simulation(Scene([plate()], [StructureScheme(dt_max=1e-3)], t_end=0.01)).state.systems["structure"],
                      SystemState)


def test_a_state_that_is_not_a_system_state_is_refused_with_what_it_lacks(monkeypatch):
    from mlsgalerkin.structure.solver import StructureSolver

    monkeypatch.setattr(StructureSolver, "state", property(lambda self: object()))
    with pytest.raises(TypeError, match=r"StructureSolver.state is a object, which lacks .*health\(limits\)"):
        Simulation(Scene([plate()], [StructureScheme(dt_max=1e-3)], t_end=0.01))


def test_a_health_that_returns_a_plain_dict_still_stops_the_run_with_a_deprecation_warning(monkeypatch):
    from mlsgalerkin.structure.solver import StructureState

    monkeypatch.setattr(StructureState, "health",
                        lambda self, limits: {"quantity": "stress", "body": "plate", "hint": "h"}
                        if self.motions["plate"].outer_steps >= 2 else None)
    sim = Simulation(Scene([plate()], [StructureScheme(dt_max=1e-3)], t_end=0.01))
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        with pytest.raises(SimulationDiverged, match="at step 2 .*structure body 'plate' — stress is unsound"):
            sim.run(progress=False)
    assert any(issubclass(w.category, DeprecationWarning) and "return a mlsgalerkin.dynamics.Diagnosis"
               in str(w.message) for w in caught)


def test_diagnosis_record_and_its_json_form():
    d = Diagnosis(quantity="density", value=np.float64(2100.0), problem="ρ/ρ0 = 2.1 is outside [0.5, 2.0]",
                  limit=(0.5, 2.0), body="water", point="particle", index=np.int64(7), position=np.array([0.1, 0.2]),
                  extras={"neighbours": 12})
    full = d.completed(system="fluid", step=5, time=0.01)
    assert d.step is None and full.step == 5 and full.completed(system="x", step=9, time=1.0) == full
    with pytest.raises(AttributeError):
        full.step = 6  # frozen
    assert hash(full) == hash(d.completed(system="fluid", step=5, time=0.01))
    j = full.as_dict()
    json.dumps(j)
    # the fluid's keys of summary.json before the record existed are all still there
    assert {k: j[k] for k in ("step", "time", "particle", "body", "quantity", "value", "problem", "position",
                              "neighbours")} == {
        "step": 5, "time": 0.01, "particle": 7, "body": "water", "quantity": "density", "value": [2100.0],
        "problem": "ρ/ρ0 = 2.1 is outside [0.5, 2.0]", "position": [0.1, 0.2], "neighbours": 12}
    assert j["limit"] == [0.5, 2.0] and j["system"] == "fluid" and "\n" not in j["message"]
    assert full.message == ("at step 5 (t = 0.01 s): fluid particle 7 of body 'water' at [0.1, 0.2] — density "
                            "ρ/ρ0 = 2.1 is outside [0.5, 2.0] (value [2100.0], limit [0.5, 2.0], neighbours 12)")
    assert Diagnosis.from_mapping(j) == full
