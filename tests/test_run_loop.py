"""The run loop takes a new kind of body and an interaction without any change to it.

A toy body kind defined here — point masses advanced by their own sub-cycled velocity-Verlet
integrator — runs through :class:`~mlsgalerkin.simulation.Simulation` next to a fluid body;
an interaction reads the surfaces of a point mass and of the fluid and returns equal and
opposite forces to both. This is the shape of the scikit-fem structures, rigid bodies and
penalty contact that come next (not built yet).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any, ClassVar

import numpy as np
import pytest

from mlsgalerkin.dynamics import Body, Diagnosis, Interaction, Solver, Surface, SystemState
from mlsgalerkin.fluid import FluidBody, MonaghanViscosity, Phase, TaitPressure
from mlsgalerkin.fluid.scheme import FluidScheme
from mlsgalerkin.monitors import Monitor
from mlsgalerkin.scene import Scene, SceneError
from mlsgalerkin.simulation import Simulation


# ------------------------------------------------------------------ a new kind of body
@dataclass
class PointMass(Body):
    """A point mass (kg per unit depth) on a spring of stiffness ``k`` (N/m per m) to ``anchor``."""

    solver: ClassVar[type] = None  # set below (the class is defined after)
    name: str
    position: np.ndarray
    velocity: np.ndarray = field(default_factory=lambda: np.zeros(2))
    mass: float = 1.0
    k: float = 0.0
    anchor: np.ndarray = field(default_factory=lambda: np.zeros(2))

    @property
    def dim(self) -> int:
        return len(self.position)


@dataclass
class PointMassState:
    x: np.ndarray
    v: np.ndarray
    m: np.ndarray
    frame_name: ClassVar[str] = "point_masses"

    def observables(self) -> dict[str, float]:
        return {"point_mass_momentum_x": float(self.m @ self.v[:, 0])}

    def frame(self):
        return self.x, {"velocity": self.v}

    def health(self, limits) -> Diagnosis | None:
        bad = np.flatnonzero(~np.isfinite(self.x).all(axis=1))
        if not bad.size:
            return None
        k = int(bad[0])
        return Diagnosis(quantity="position", value=self.x[k], problem="is not finite", point="mass", index=k)


class PointMassSolver(Solver):
    """Velocity Verlet with ``substeps`` sub-steps per outer step; interaction forces are held
    constant over the outer step."""

    key = "point_masses"

    @classmethod
    def problems(cls, bodies, scheme, scene) -> list[str]:
        return [f"point mass {b.name!r}: mass must be positive" for b in bodies if not b.mass > 0]

    def __init__(self, bodies, scheme, scene) -> None:
        self.bodies = bodies
        self.index = {b.name: i for i, b in enumerate(bodies)}
        self._state = PointMassState(np.array([b.position for b in bodies], dtype=float),
                                     np.array([b.velocity for b in bodies], dtype=float),
                                     np.array([b.mass for b in bodies], dtype=float))
        self.k = np.array([b.k for b in bodies])
        self.anchor = np.array([b.anchor for b in bodies], dtype=float)
        self.external = np.zeros_like(self._state.x)
        self.substeps_taken = 0
        self.outer_steps = 0

    @property
    def state(self):
        return self._state

    def _force(self) -> np.ndarray:
        s = self._state
        return -self.k[:, None] * (s.x - self.anchor) + self.external

    def start(self) -> None:
        self.a = self._force() / self._state.m[:, None]

    def stable_time_step(self) -> float:
        return math.inf  # sub-cycles whatever outer step it is given

    def begin_step(self, t: float, dt: float) -> None:
        s = self._state
        own = 0.01 * 2 * math.pi * math.sqrt(float(np.min(s.m / np.maximum(self.k, 1e-300))))
        n = max(1, math.ceil(dt / own))
        h = dt / n
        for _ in range(n):
            s.v += 0.5 * h * self.a
            s.x += h * s.v
            self.a = self._force() / s.m[:, None]
            s.v += 0.5 * h * self.a
        self.substeps_taken += n
        self.outer_steps += 1

    def end_step(self, t: float, dt: float) -> None:
        self.a = self._force() / self._state.m[:, None]  # with the forces of the exchange at t + dt

    def surface(self, body: str) -> Surface:
        i = self.index[body]
        s = self._state
        return Surface(body, s.x[i:i + 1], s.v[i:i + 1], masses=s.m[i:i + 1])

    def clear_surface_forces(self) -> None:
        self.external[:] = 0.0

    def add_surface_forces(self, body: str, forces: np.ndarray) -> None:
        self.external[self.index[body]] += forces.sum(axis=0)

    def checkpoint(self):
        # the surface forces of the last exchange drive the next sub-cycles: part of the state
        s = self._state
        return {"x": s.x.copy(), "v": s.v.copy(), "external": self.external.copy()}, {"substeps": self.substeps_taken}

    def restore(self, arrays, meta) -> None:
        self._state.x[:], self._state.v[:] = arrays["x"], arrays["v"]
        self.external[:] = arrays["external"]
        self.substeps_taken = meta["substeps"]
        self.start()

    def summary(self) -> dict[str, Any]:
        return {"substeps": self.substeps_taken, "outer_steps": self.outer_steps}


PointMass.solver = PointMassSolver


# ------------------------------------------------------------------ an interaction
class Tether(Interaction):
    """A linear spring ``F = k (x_mass − x̄_fluid)`` between a point mass and the centre of mass
    of a fluid body: ``−F`` on the mass, ``+F`` spread over the fluid particles by mass."""

    name = "tether"

    def __init__(self, mass: str, fluid: str, k: float) -> None:
        self.first, self.second, self.k = mass, fluid, k
        self.last_force = np.zeros(2)
        self.exchanges = 0

    def exchange(self, t, first, second) -> None:
        a, b = first.surface(self.first), second.surface(self.second)
        assert a.positions.shape == (1, 2) and b.velocities.shape == b.positions.shape
        centre = (b.masses @ b.positions) / b.masses.sum()
        F = self.k * (a.positions[0] - centre)
        first.add_surface_forces(self.first, -F[None, :])
        second.add_surface_forces(self.second, np.outer(b.masses / b.masses.sum(), F))
        self.last_force = F
        self.exchanges += 1

    def summary(self) -> dict:
        return {"exchanges": self.exchanges}


class MomentumLog(Monitor):
    """Total x-momentum of the fluid and the tethered point mass (the first), per step."""

    name = "momentum_log"

    def __init__(self, tether: Tether) -> None:
        self.tether = tether
        self.rows: list[tuple[float, float, float]] = []

    def handle(self, state, t) -> None:
        fluid = state.fluid.momentum()[0]
        pm = state.systems["point_masses"]
        self.rows.append((state.dt, fluid + pm.m[0] * pm.v[0, 0], self.tether.last_force[0]))


def _scene(t_end=0.02, dt=2e-4):
    blob = FluidBody.block("blob", (0.0, 0.0), (0.04, 0.04), 0.01, [Phase("water", 1000.0)])
    ball = PointMass("ball", np.array([0.2, 0.02]), velocity=np.array([-0.5, 0.0]), mass=0.5)
    bob = PointMass("bob", np.array([1.0, 0.0]), mass=0.1, k=4.0e6, anchor=np.array([1.0, 0.0]),
                    velocity=np.array([0.3, 0.0]))
    tether = Tether("ball", "blob", k=50.0)
    scene = Scene([blob, ball, bob], [FluidScheme([TaitPressure(10.0), MonaghanViscosity(0.1)], mass="particle", dt_max=dt, stabilisation="as_listed")], t_end=t_end, interactions=[tether])
    scene.monitors = [MomentumLog(tether)]
    return scene, tether


def test_a_new_body_kind_and_an_interaction_run_through_the_unchanged_loop():
    scene, tether = _scene()
    sim = Simulation(scene)
    assert [s.key for s in sim.solvers] == ["fluid", "point_masses"]
    res = sim.run(progress=False)
    steps = res.summary["steps"]
    assert steps == 100 and res.summary["status"] == "completed"
    # the point masses kept their own integrator and sub-cycled inside each fluid step
    pm = res.summary["point_masses"]
    assert pm["outer_steps"] == steps and pm["substeps"] > steps
    assert res.summary["interactions"]["tether"]["exchanges"] == steps
    # the oscillator on its anchor spring alone keeps its energy (velocity Verlet, sub-cycled)
    s = res.state.systems["point_masses"]
    e = 0.5 * 0.1 * s.v[1] @ s.v[1] + 0.5 * 4.0e6 * (s.x[1, 0] - 1.0) ** 2
    assert e == pytest.approx(0.5 * 0.1 * 0.3**2, rel=2e-3)
    # the tether pulled the ball towards the fluid and the fluid towards the ball
    assert s.v[0, 0] < -0.5 and res.state.fluid.momentum()[0] > 0
    assert "point_mass_momentum_x" in res.timeseries


def test_interaction_forces_are_equal_and_opposite():
    """With a constant step the total momentum minus the half kick still in flight,
    ``P − (Δt/2) F``, is conserved to round-off (the fluid's kick-drift-kick gives each force
    half a kick at the end of one step and half at the start of the next; the sub-cycled mass
    takes the whole impulse in the next step)."""
    scene, tether = _scene()
    Simulation(scene).run(progress=False)
    rows = np.array(scene.monitors[0].rows)
    dt, P, F = rows[:, 0], rows[:, 1], rows[:, 2]
    assert np.allclose(dt, dt[0])  # dt_max below every stability limit: a constant step
    Q = P - 0.5 * dt * F
    assert abs(F).max() > 0.05
    assert np.abs(Q - Q[0]).max() < 1e-12 * max(1.0, abs(P).max())
    assert np.abs(P - P[0]).max() > 1e3 * np.abs(Q - Q[0]).max()  # the correction matters


def test_a_new_body_kind_is_validated_with_the_scene():
    scene, _ = _scene()
    scene.bodies[1].mass = -1.0
    with pytest.raises(SceneError, match="point mass 'ball': mass must be positive"):
        Simulation(scene)
    scene, tether = _scene()
    tether.second = "nobody"
    with pytest.raises(SceneError, match="interaction 'tether': no body named 'nobody'"):
        Simulation(scene)


def test_checkpoint_of_several_solvers_restarts_bit_for_bit(tmp_path):
    scene, _ = _scene(t_end=0.02)
    straight = Simulation(scene).run(progress=False)
    scene, _ = _scene(t_end=0.02)
    Simulation(scene).run(out=tmp_path, progress=False, max_steps=37)
    scene, _ = _scene(t_end=0.02)
    resumed = Simulation(scene).run(out=tmp_path, progress=False, restart="latest")
    for key in ("fluid", "point_masses"):
        a, b = straight.state.systems[key], resumed.state.systems[key]
        assert np.array_equal(a.x, b.x) and np.array_equal(a.v, b.v), key
    assert (tmp_path / "point_masses.pvd").is_file()  # each system writes its own frame series


def test_summary_names_the_commit_of_the_code_that_ran(tmp_path, monkeypatch):
    """``summary.json``'s ``git_commit`` is the commit when the run started, not a later one
    checked out (or committed) while it ran and current when the summary is written."""
    import importlib
    import json

    import mlsgalerkin.io
    from mlsgalerkin.problem import load_problem

    provenance_module = importlib.import_module("mlsgalerkin.io.provenance")

    mod = load_problem("dam_break")
    scene = mod.make_scene(mod.Parameters(dx=0.02, t_end=0.002))
    monkeypatch.setattr(mlsgalerkin.io, "git_commit", lambda *a, **k: "c0ffee1")
    monkeypatch.setattr(provenance_module, "git_commit", lambda *a, **k: "later99")
    Simulation(scene).run(tmp_path / "run", progress=False)
    summary = json.loads((tmp_path / "run" / "summary.json").read_text())
    assert summary["provenance"]["git_commit"] == "c0ffee1"


def test_a_new_body_kind_that_diverges_is_stopped_with_its_own_diagnosis(tmp_path):
    """The watchdog formats the toy system's :class:`Diagnosis` without knowing its keys: the run
    ends ``diverged``, the summary names the system, the point and the step."""
    import json

    from mlsgalerkin.simulation import SimulationDiverged

    scene, _ = _scene(t_end=0.02)
    sim = Simulation(scene)
    assert isinstance(sim.state.systems["point_masses"], SystemState)
    solver = sim.solver("point_masses")
    step = solver.begin_step

    def poisoned(t, dt):
        step(t, dt)
        if solver.outer_steps == 4:
            solver.state.x[1, 0] = np.inf

    solver.begin_step = poisoned
    with pytest.raises(SimulationDiverged, match=r"at step 4 .*point_masses mass 1 — position is not finite"):
        sim.run(out=tmp_path, progress=False)
    summary = json.loads((tmp_path / "summary.json").read_text())
    d = summary["diagnosis"]
    assert summary["status"] == "diverged"
    assert (d["system"], d["point"], d["index"], d["mass"], d["step"]) == ("point_masses", "mass", 1, 1, 4)
