"""The structure steppers: two identical runs of an elastic body give identical numbers, bit for
bit, and so does a restart; the stepper of each body; the old names; one Lamé conversion.

The explicit stepper takes its sub-step and its high-mode damping from the highest frequency
``ω_max`` (scipy ``eigsh``); ARPACK must start from a fixed vector, or ``ω_max`` (and every number
after the first step) differs at round-off from run to run.
"""

from __future__ import annotations

import numpy as np
import pytest
from skfem import MeshQuad

from mlsgalerkin.structure.scheme import StructureScheme
from mlsgalerkin.contact import ContactSurface
from mlsgalerkin.scene import Scene
from mlsgalerkin.simulation import Simulation
from mlsgalerkin.structure import ElasticBody, ElasticMaterial, RigidBody
from mlsgalerkin.structure.rigid import Hinge
from mlsgalerkin.structure.steppers import FreeRigidMotion, RigidMotion, stepper_for


def gate_like() -> ElasticBody:
    """A plane-strain Q2 plate hanging from its clamped top (as ``elastic_gate``)."""
    mesh = MeshQuad.init_tensor(np.linspace(0.5, 0.512, 3), np.linspace(0.0, 0.1, 9))
    return ElasticBody("gate", mesh, ElasticMaterial(1e7, 0.4, 1100.0, plane="strain"), "Q2",
                       clamped=lambda x: np.isclose(x[1], 0.1), gravity=(0.0, -9.81),
                       points={"tip": (0.506, 0.0)})


def beam_like() -> ElasticBody:
    """A plane-stress Q2 beam standing on its clamped foot (as ``beam_clamped``)."""
    mesh = MeshQuad.init_tensor(np.array([0.3, 0.306]), np.linspace(0.0, 0.08, 9))
    return ElasticBody("beam", mesh, ElasticMaterial(1e6, 0.3, 2500.0, plane="stress"), "Q2",
                       clamped=lambda x: np.isclose(x[1], 0.0), gravity=(0.0, -9.81),
                       points={"tip": (0.303, 0.08)})


@pytest.mark.parametrize("make", [gate_like, beam_like])
def test_the_frequencies_are_the_same_in_every_call(make):
    one, two = make(), make()
    assert one.highest_frequency() == two.highest_frequency() == one.highest_frequency()
    assert one.lowest_frequency() == two.lowest_frequency()


@pytest.mark.parametrize("make", [gate_like, beam_like])
def test_two_identical_runs_of_an_explicit_elastic_body_are_bit_for_bit(make):
    """Sub-cycled central differences with the default high-mode damping (which depends on
    ``ω_max``), sagging under its weight: every time-series column and the summary's numbers
    agree exactly."""
    runs = [Simulation(Scene([make()], [StructureScheme(dt_max=5e-4)], t_end=0.01)).run(progress=False) for _ in range(2)]
    first, second = (r.timeseries for r in runs)
    assert list(first) == list(second)
    name = make().name
    assert np.ptp(first[f"{name}_tip_uy"]) > 0          # the body moved
    for column in first:
        assert np.array_equal(np.asarray(first[column]), np.asarray(second[column])), column
    bodies = [r.summary["structure"]["bodies"][name] for r in runs]
    for key in ("omega_max_rad_s", "first_mode_damping_ratio", "substep_limit_s", "high_mode_damping_a1_s"):
        assert bodies[0][key] == bodies[1][key], key


@pytest.mark.parametrize("old, new", [
    ("ElasticMotion", "mlsgalerkin.structure.steppers.stepper_for"),
    ("RigidMotion", "mlsgalerkin.structure.steppers.stepper_for"),
    ("quaternion_matrix", "mlsgalerkin.structure.steppers.rotation.quaternion_matrix"),
    ("SUBSTEP_SAFETY", "mlsgalerkin.structure.steppers.central_difference.SUBSTEP_SAFETY"),
])
def test_the_old_integrators_module_still_imports_with_a_warning_naming_the_new_name(old, new):
    import importlib

    integrators = importlib.import_module("mlsgalerkin.structure.integrators")
    vars(integrators).pop(old, None)   # read (and kept) before in this process: each old name warns once
    module, _, name = new.rpartition(".")
    with pytest.warns(DeprecationWarning, match=f"write 'from {module} import {name}'".replace(".", r"\.")):
        value = getattr(integrators, old)
    assert value is getattr(importlib.import_module(module), name)


def test_the_old_elastic_motion_makes_the_stepper_of_the_body_s_method():
    from mlsgalerkin.structure.steppers import CentralDifference, Newmark

    import mlsgalerkin.structure.integrators as integrators

    vars(integrators).pop("ElasticMotion", None)   # read (and kept) by a test above: each old name warns once
    with pytest.warns(DeprecationWarning):
        from mlsgalerkin.structure.integrators import ElasticMotion
    assert type(ElasticMotion(beam_like())) is CentralDifference
    mesh = MeshQuad.init_tensor(np.array([0.0, 0.01]), np.linspace(0.0, 0.1, 5))
    newmark = ElasticBody("b", mesh, ElasticMaterial(1e6, 0.3, 1000.0), "Q2", integrator="newmark",
                          clamped=lambda x: np.isclose(x[1], 0.0))
    assert type(ElasticMotion(newmark)) is Newmark


def test_one_lame_conversion():
    """``lame(dim)`` is the one conversion: 3D and plane strain the same pair, plane stress the
    reduced λ in 2D only; the deprecated ``lame3d()`` is ``lame(3)``."""
    stress = ElasticMaterial(1e7, 0.3, 1000.0, plane="stress")
    strain = ElasticMaterial(1e7, 0.3, 1000.0, plane="strain")
    lam, mu = 1e7 * 0.3 / (1.3 * 0.4), 1e7 / 2.6
    assert strain.lame(2) == strain.lame(3) == stress.lame(3) == pytest.approx((lam, mu))
    assert stress.lame() == stress.lame(2) == pytest.approx((2 * lam * mu / (lam + 2 * mu), mu))
    with pytest.warns(DeprecationWarning, match=r"lame\(3\)"):
        assert stress.lame3d() == stress.lame(3)
    with pytest.raises(ValueError, match="2D or 3D"):
        strain.lame(1)


def test_an_explicit_elastic_body_with_high_mode_damping_restarts_bit_for_bit(tmp_path):
    """Stopped after 7 steps and continued from its checkpoint in a new process-like run (the
    stepper and ``ω_max`` made again), the gate ends in exactly the state of the run that never
    stopped."""
    def scene():
        return Scene([gate_like()], [StructureScheme(dt_max=5e-4)], t_end=0.01)

    straight = Simulation(scene()).run(progress=False)
    Simulation(scene()).run(out=tmp_path, progress=False, max_steps=7)
    resumed = Simulation(scene()).run(out=tmp_path, progress=False, restart="latest")
    a, b = (r.state.systems["structure"].body("gate") for r in (straight, resumed))
    assert a.outer_steps == b.outer_steps == 20
    for x, y in ((a.u, b.u), (a.v, b.v), (a.a, b.a)):
        assert np.array_equal(x, y)
    assert a.observables() == b.observables()


def test_each_rigid_body_gets_the_stepper_of_its_method_and_a_wrong_one_is_refused_clearly():
    hinged = RigidBody.beam("beam", base=(0.0, 0.0), length=1.0, mass=1.0, thickness=0.02,
                            constraint=Hinge((0.0, 0.0), stiffness=100.0))
    surface = ContactSurface.tank((-0.1, -0.1, -0.1), (0.1, 0.1, 0.1), open_top=False).flipped()
    box = RigidBody("box", surface, 1.0, (0.01, 0.02, 0.03), (0.0, 0.0, 0.0), constraint="free")
    assert type(stepper_for(hinged)) is RigidMotion
    assert type(stepper_for(box)) is FreeRigidMotion
    with pytest.raises(TypeError, match="FreeRigidMotion"):
        RigidMotion(box)
    with pytest.raises(TypeError, match="turns about one axis"):
        FreeRigidMotion(hinged)
    with pytest.raises(TypeError, match="ElasticBody and RigidBody"):
        stepper_for(object.__new__(type("Other", (), {"name": "x"})))
