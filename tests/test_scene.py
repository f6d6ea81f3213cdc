"""Scene validation (every problem at once, before any work), only the listed effects run,
and the per-effect time report of the run summary."""

from __future__ import annotations

import numpy as np
import pytest

import mlsgalerkin.fluid as fluid_mod
import mlsgalerkin.fluid.solver as solver_mod
from mlsgalerkin.fluid import (
    BulkViscosity,
    DensityFilter,
    Effect,
    FluidBody,
    FreeSurfaceDetection,
    Gravity,
    MonaghanViscosity,
    NewtonianViscosity,
    Phase,
    TaitPressure,
    WallBody,
    Walls,
    wall_box,
)
from mlsgalerkin.fluid.scheme import FluidScheme
from mlsgalerkin.scene import Approximation, Probe, Scene, SceneError
from mlsgalerkin.simulation import Simulation

DX = 0.02
WATER = [Phase("water", 1000.0)]


def _water(**kw) -> FluidBody:
    return FluidBody.block("water", (0.0, 0.0), (0.2, 0.1), DX, WATER, **kw)


class _Needy(Effect):
    """An effect that reads a quantity no listed effect provides."""

    name = "needy"
    stages = ("force",)
    reads = ("temperature",)


def _problems(scene: Scene) -> str:
    with pytest.raises(SceneError) as err:
        scene.validate()
    return str(err.value)


# ------------------------------------------------------------------------------ validation
def test_validation_lists_every_problem_at_once():
    scene = Scene([_water(), "banana"], [FluidScheme([Gravity(), Walls("free_slip"), _Needy()], stabilisation="as_listed")], t_end=-1.0, name="broken")
    msg = _problems(scene)
    expected = [
        "unknown body 'banana'",
        "t_end must be positive, got -1.0",
        "no pressure model",
        "reads ['temperature'], which no listed effect provides",
        "Walls: the scene has no WallBody",
    ]
    for fragment in expected:
        assert fragment in msg, f"{fragment!r} missing from:\n{msg}"
    # one bullet per problem, and the header counts them
    n = msg.count("\n  - ")
    assert n >= len(expected)
    assert msg.startswith(f"scene 'broken' has {n} problems:")


@pytest.mark.parametrize(
    "make, fragment",
    [
        (lambda: Scene([_water()], [FluidScheme([TaitPressure(10.0), TaitPressure(20.0)], stabilisation="as_listed")], t_end=0.1),
         "two pressure models listed"),
        (lambda: Scene([_water()], [FluidScheme([TaitPressure(10.0), Gravity(), Gravity()], stabilisation="as_listed")], t_end=0.1),
         "effects listed twice: ['Gravity']"),
        (lambda: Scene([_water(), WallBody("w", np.array([[0.0, -0.01], [0.02, -0.01]]), DX)], [FluidScheme([TaitPressure(10.0), Walls("free_slip")], stabilisation="as_listed")], t_end=0.1),
         "free_slip needs wall normals"),
        (lambda: Scene([_water()], [FluidScheme([TaitPressure(10.0)], approximation=Approximation(kernel="no_such_kernel"), stabilisation="as_listed")], t_end=0.1),
         "unknown kernel 'no_such_kernel'"),
        (lambda: Scene([_water()], [FluidScheme([TaitPressure(10.0)], stabilisation="as_listed")], t_end=0.1, probes=[Probe("T_mean", lambda s: 0.0, reads=("temperature",))]),
         "probe 'T_mean' reads ['temperature']"),
        (lambda: Scene([_water(), wall_box((0, 0), (0.2, 0.2), DX)], [FluidScheme([TaitPressure(10.0)], stabilisation="as_listed")], t_end=0.1),
         "no wall treatment: list Walls()"),
        (lambda: Scene([_water()], [FluidScheme([TaitPressure(10.0), "viscosity"], stabilisation="as_listed")], t_end=0.1),
         "unknown effect 'viscosity'"),
    ],
    ids=["two_pressure", "duplicate", "free_slip_no_normals", "kernel", "probe", "walls_untreated",
         "unknown_effect"],
)
def test_single_problems_are_reported(make, fragment):
    assert fragment in _problems(make())


def test_valid_scene_passes():
    Scene([_water(), wall_box((0, 0), (0.2, 0.2), DX)], [FluidScheme([TaitPressure(10.0), Gravity(), Walls("free_slip")], stabilisation="as_listed")], t_end=0.1).validate()


def test_simulation_validates_before_any_work(monkeypatch):
    def forbidden(*a, **k):
        raise AssertionError("work was done before the scene was validated")

    for name in ("find_neighbors", "build_state", "evaluate_shape_functions"):
        monkeypatch.setattr(solver_mod, name, forbidden)
    setups = []

    class Recorder(Effect):
        name = "recorder"

        def setup(self, state, scene):
            setups.append(1)

    scene = Scene([_water()], [FluidScheme([Gravity(), Recorder(), _Needy()], stabilisation="as_listed")], t_end=0.0)
    with pytest.raises(SceneError) as err:
        Simulation(scene)
    assert "no pressure model" in str(err.value) and "t_end must be positive" in str(err.value)
    assert setups == []


# ----------------------------------------------------------------- only listed effects run
STAGE_METHODS = ("kinematics", "pressure", "boundary", "stress", "force", "after_step",
                 "time_step_limit")


@pytest.fixture
def calls(monkeypatch):
    """Record ``(class name of the instance, method)`` for every stage call of every Effect
    class exported by :mod:`mlsgalerkin.fluid` (the base class included)."""
    log: list[tuple[str, str]] = []
    classes = [c for c in vars(fluid_mod).values() if isinstance(c, type) and issubclass(c, Effect)]
    assert len(classes) >= 9  # Effect + the 8 shipped effects
    for cls in classes:
        for meth in STAGE_METHODS:
            if meth not in vars(cls):
                continue  # inherited: the wrapper on the defining class records it
            original = vars(cls)[meth]

            def wrapper(self, *a, _orig=original, _meth=meth, **k):
                log.append((type(self).__name__, _meth))
                return _orig(self, *a, **k)

            monkeypatch.setattr(cls, meth, wrapper)
    return log


def test_only_listed_effects_are_called(calls):
    fl = _water(velocity=(0.1, 0.0))
    Simulation(Scene([fl], [FluidScheme([TaitPressure(10.0)], stabilisation="as_listed")], t_end=0.01)).run(progress=False)
    called = {c for c, _ in calls}
    assert called == {"TaitPressure"}, called
    # the pressure model ran in its stage and supplied a time-step limit
    assert {m for _, m in calls} == {"pressure", "time_step_limit"}


def test_custom_effect_is_called_in_its_declared_stages_only(calls):
    class Probe2(Effect):
        name = "probe2"
        stages = ("stress", "after_step")

        # every stage is implemented; only the declared ones may run
        def kinematics(self, s): calls.append(("Probe2", "kinematics"))
        def pressure(self, s): calls.append(("Probe2", "pressure"))
        def boundary(self, s): calls.append(("Probe2", "boundary"))
        def stress(self, s): calls.append(("Probe2", "stress"))
        def force(self, s): calls.append(("Probe2", "force"))
        def after_step(self, s): calls.append(("Probe2", "after_step"))

    sim = Simulation(Scene([_water()], [FluidScheme([TaitPressure(10.0), Probe2()], stabilisation="as_listed")], t_end=1.0))
    res = sim.run(progress=False, max_steps=5)
    mine = [m for c, m in calls if c == "Probe2"]
    # stress: once per evaluation (initial + one per kdk step); after_step once per step
    assert mine.count("stress") == 1 + res.summary["steps"]
    assert mine.count("after_step") == res.summary["steps"] == 5
    assert set(mine) <= {"stress", "after_step", "time_step_limit"}
    assert {c for c, _ in calls} <= {"TaitPressure", "Probe2"}


# ------------------------------------------------------------------ per-effect time report
def test_time_report_has_one_entry_per_listed_effect():
    walls = wall_box((0, 0), (0.2, 0.2), DX)
    listed = [TaitPressure(20.0), Gravity(), Walls("free_slip"), MonaghanViscosity(0.1),
              DensityFilter(5)]
    res = Simulation(Scene([_water(), walls], [FluidScheme(listed, stabilisation="as_listed")], t_end=0.01)).run(progress=False)
    report = res.summary["fluid"]["time_per_stage_s"]
    for e in listed:
        assert e.name in report and report[e.name] >= 0.0
    unlisted = [BulkViscosity(), NewtonianViscosity(), FreeSurfaceDetection()]
    for e in unlisted:
        assert e.name not in report
    # solver stages are reported next to the effects, fractions sum to one
    for stage in ("neighbors", "shape_functions", "velocity_gradient", "internal_force", "integrate"):
        assert stage in report
    assert sum(res.summary["fluid"]["time_per_stage_fraction"].values()) == pytest.approx(1.0, abs=1e-3)


# ------------------------------------------------------------------------------ schemes
def _legacy_scene(**options):
    walls = wall_box((0.0, 0.0), (0.3, 0.2), DX, layers=3)
    return Scene([_water(), walls], [TaitPressure(10.0), Gravity(), Walls("free_slip")], t_end=0.01, **options)


def test_the_scene_before_schemes_runs_with_a_warning_that_shows_the_new_form():
    with pytest.warns(DeprecationWarning, match=r"schemes=\[FluidScheme\(effects, approximation=\.\.\., dt_max=\.\.\.\)\]"):
        old = _legacy_scene(approximation=Approximation(h_factor=1.5), dt_max=1e-4)
    (fluid,) = old.schemes
    assert isinstance(fluid, FluidScheme)
    assert fluid.approximation.h_factor == 1.5 and fluid.dt_max == 1e-4
    # the old form lists no stabilisation either: it gets the recommended set, like a scheme
    assert [type(e).__name__ for e in fluid.effects] == ["TaitPressure", "Gravity", "Walls", "MonaghanViscosity",
                                                         "DensityDiffusion", "ParticleShifting",
                                                         "LinearConsistentPressure", "VolumeConsistency"]
    with pytest.warns(DeprecationWarning, match="FluidScheme"):
        assert old.effects is fluid.effects and old.dt_max == 1e-4   # old attribute reads still work
    new = Scene(old.bodies, [FluidScheme(list(fluid.effects), approximation=Approximation(h_factor=1.5),
                                         dt_max=1e-4, stabilisation="as_listed")], t_end=0.01)
    a = Simulation(old).run(progress=False).timeseries
    b = Simulation(new).run(progress=False).timeseries
    assert all(np.array_equal(a[k], b[k]) for k in a)          # the same run, bit for bit


def test_validation_reads_only():
    """Validating a scene changes nothing in it (repr of every piece before and after)."""
    scene = Scene([_water(), wall_box((0.0, 0.0), (0.3, 0.2), DX, layers=3)],
                  [fluid_mod.water(10.0, spacing=DX)], t_end=0.01)
    before = repr([scene.schemes, [vars(e) for e in scene.schemes[0].effects]])
    scene.validate()
    scene.validate()
    assert repr([scene.schemes, [vars(e) for e in scene.schemes[0].effects]]) == before


def test_one_spacing_walls_on_another_lattice_are_refused():
    coarse = wall_box((0.0, 0.0), (0.3, 0.2), 2 * DX, layers=3)
    msg = _problems(Scene([_water(), coarse], [FluidScheme([TaitPressure(10.0), Walls()], stabilisation="as_listed")], t_end=0.1))
    assert f"has particles {2 * DX:g} m apart but the fluid's spacing is {DX:g} m" in msg
    msg = _problems(Scene([_water()], [FluidScheme([TaitPressure(10.0)], spacing=0.5 * DX, stabilisation="as_listed")], t_end=0.1))
    assert "are not built at the scheme's spacing" in msg


def test_scheme_problems_and_unknown_or_doubled_schemes_are_reported():
    msg = _problems(Scene([_water()], [FluidScheme([TaitPressure(10.0)], safety=2.0, mass="heavy", stabilisation="as_listed"), "fast"],
                          t_end=0.1))
    assert "safety factor must be in (0, 1.5]" in msg and "mass must be" in msg
    assert "unknown scheme 'fast'" in msg
    msg = _problems(Scene([_water()], [FluidScheme([TaitPressure(10.0)], stabilisation="as_listed"), FluidScheme([TaitPressure(10.0)], stabilisation="as_listed")],
                          t_end=0.1))
    assert "two schemes for one solver" in msg


def test_a_scheme_without_its_bodies_is_reported():
    from mlsgalerkin.structure import StructureScheme

    msg = _problems(Scene([_water()], [FluidScheme([TaitPressure(10.0)], stabilisation="as_listed"), StructureScheme(dt_max=1e-3)], t_end=0.1))
    assert "StructureScheme is listed but no body is advanced by its solver" in msg


def test_water_preset_is_the_recommended_set():
    scheme = fluid_mod.water(20.0, spacing=0.01, penalty_thickness=0.0025)
    assert [type(e).__name__ for e in scheme.effects] == [
        "TaitPressure", "Gravity", "Walls", "MonaghanViscosity", "DensityDiffusion", "ParticleShifting", "PenaltyWalls",
        "LinearConsistentPressure", "VolumeConsistency"]
    pressure, _, _, viscosity, diffusion, *_ = scheme.effects
    assert pressure.c0 == 20.0 and pressure.negative_pressure == "cavitate"
    assert viscosity.alpha == 0.02 and diffusion.delta == 0.1
    assert scheme.spacing == 0.01 and scheme.approximation.h_factor == 1.3
    assert scheme.pressure_model() is pressure and scheme.provides("gravity")


def test_effects_read_the_sound_speed_from_the_state():
    """The pressure model is set up first and writes c0 into the state; the effects that scale
    with it read it there, whatever the listed order."""
    walls = wall_box((0.0, 0.0), (0.3, 0.2), DX, layers=3)
    effects = [MonaghanViscosity(0.1), Gravity(), Walls(), TaitPressure(12.5)]   # pressure listed last
    sim = Simulation(Scene([_water(), walls], [FluidScheme(effects, stabilisation="as_listed")], t_end=0.01))
    assert sim.state.fluid.c0 == 12.5
    assert effects[0].nu == pytest.approx(0.1 * 1.3 * DX * 12.5 / 8)
