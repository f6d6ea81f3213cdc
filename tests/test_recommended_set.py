"""The one recommended stabilisation set (:mod:`mlsgalerkin.fluid.recommended`): every shipped
fluid problem defaults to it, ``water()`` builds it, a scheme that lists no stabilisation gets it
and says so in ``summary.json``, a scheme that lists part of it is warned, and ``as_listed`` runs
exactly the list."""

from __future__ import annotations

import dataclasses
import json
import warnings

import pytest

from mlsgalerkin.fluid import (
    RECOMMENDED,
    DensityDiffusion,
    DensityFilter,
    FluidBody,
    Gravity,
    LinearConsistentPressure,
    MonaghanViscosity,
    ParticleShifting,
    Phase,
    TaitPressure,
    VolumeConsistency,
    Walls,
    hydrostatic_density,
    wall_box,
    water,
)
from mlsgalerkin.fluid.scheme import FluidScheme, PartialStabilisationWarning
from mlsgalerkin.problem import load_problem, shipped_problems
from mlsgalerkin.scene import Scene
from mlsgalerkin.simulation import Simulation

#: Problems whose flow has a physical viscosity that sets it (periodic viscous checks at Re <= 100):
#: they list no artificial viscosity; everything else of the set applies.
VISCOUS_CHECKS = {"taylor_green", "poiseuille", "couette"}
#: The documented departures from the set (the problem's docs say why and what the set gives there).
DEPARTURES = {"gravity_current": {"alpha": 0.01}}


def _names(effects) -> list[str]:
    return [type(e).__name__ for e in effects]


def fluid_problems() -> list[str]:
    return [name for name in shipped_problems() if "alpha" in load_problem(name).Parameters.__dataclass_fields__]


@pytest.mark.parametrize("name", fluid_problems())
def test_every_fluid_problem_defaults_to_the_recommended_set(name):
    params = load_problem(name).Parameters()
    expected = {k: v for k, v in RECOMMENDED.as_dict().items() if hasattr(params, k)}
    if name in VISCOUS_CHECKS:
        expected.pop("alpha")
        assert params.alpha == 0.0
    assert "linear_consistency" in expected
    expected.update({k: v for k, v in DEPARTURES.get(name, {}).items() if k in expected})
    got = {k: getattr(params, k) for k in expected}
    assert got == expected, f"{name} departs from the recommended set: {got} != {expected}"


def test_every_fluid_problem_scene_runs_the_recommended_effects():
    for name in fluid_problems():
        module = load_problem(name)
        scene = module.make_scene(module.Parameters(**getattr(module, "SMOKE", {})))
        names = _names(next(sc for sc in scene.schemes if isinstance(sc, FluidScheme)).effects)
        assert "LinearConsistentPressure" in names and "VolumeConsistency" in names, name
        assert "DensityDiffusion" in names and "ParticleShifting" in names or name == "taylor_green", name
        assert "DensityFilter" not in names and "ConsistentIntegration" not in names, name


def test_water_builds_exactly_the_recommended_set_without_warning():
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        scheme = water(20.0)
        bare = water(20.0, alpha=0.0, delta=0.0, shifting="off", linear_consistency=False, volume_consistency=0.0)
    assert _names(scheme.effects)[3:] == ["MonaghanViscosity", "DensityDiffusion", "ParticleShifting",
                                          "LinearConsistentPressure", "VolumeConsistency"]
    assert scheme.effects[-1].rate == RECOMMENDED.volume_consistency
    assert scheme.stabilisation == "as_listed" and scheme.added_stabilisation == []
    assert _names(bare.effects) == ["TaitPressure", "Gravity", "Walls"]  # an ablation stays an ablation


def test_a_scheme_without_stabilisation_gets_the_recommended_set():
    scheme = FluidScheme([TaitPressure(20.0), Gravity((0.0, -9.81))])
    assert _names(scheme.effects) == ["TaitPressure", "Gravity", "MonaghanViscosity", "DensityDiffusion",
                                      "ParticleShifting", "LinearConsistentPressure", "VolumeConsistency"]
    report = scheme.stabilisation_report()
    assert report["mode"] == "auto" and len(report["added"]) == 5 and report["missing_from_recommended"] == []
    assert scheme.effects[2].alpha == RECOMMENDED.alpha and scheme.effects[3].delta == RECOMMENDED.delta
    assert "MonaghanViscosity" in " ".join(scheme.identity()["effects"])  # a restart sees what ran


def test_part_of_the_set_is_warned_and_as_listed_is_exact():
    listed = [TaitPressure(20.0), Walls(), MonaghanViscosity(0.1), DensityFilter(20)]
    with pytest.warns(PartialStabilisationWarning, match="DensityDiffusion, ParticleShifting, LinearConsistentPressure, VolumeConsistency"):
        scheme = FluidScheme(list(listed))
    assert _names(scheme.effects) == _names(listed)
    assert scheme.stabilisation_report()["missing_from_recommended"] == ["DensityDiffusion", "ParticleShifting",
                                                                         "LinearConsistentPressure",
                                                                         "VolumeConsistency"]
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        exact = FluidScheme([TaitPressure(20.0)], stabilisation="as_listed")
        full = FluidScheme([TaitPressure(20.0), MonaghanViscosity(0.02), DensityDiffusion(), ParticleShifting(),
                            LinearConsistentPressure(), VolumeConsistency()])
    assert _names(exact.effects) == ["TaitPressure"]
    assert full.stabilisation_report()["missing_from_recommended"] == []


def test_a_bad_stabilisation_mode_is_reported():
    assert any("stabilisation must be one of auto, as_listed" in p
               for p in FluidScheme([TaitPressure(20.0)], stabilisation="none").problems())


def test_summary_says_what_was_added(tmp_path):
    dx, depth = 0.02, 0.1
    water_body = FluidBody.block("water", (0.0, 0.0), (0.2, depth), dx, [Phase("water", 1000.0)])
    c0 = 10.0 * (2 * 9.81 * depth) ** 0.5
    water_body.density[:] = hydrostatic_density(water_body.density, depth - water_body.positions[:, 1], 9.81, c0)
    walls = wall_box((0.0, 0.0), (0.2, 0.2), dx)
    scene = Scene([water_body, walls], [FluidScheme([TaitPressure(c0), Gravity((0.0, -9.81)), Walls()])],
                  t_end=0.01)
    Simulation(scene).run(out=tmp_path / "run", progress=False)
    stab = json.loads((tmp_path / "run" / "summary.json").read_text())["fluid"]["stabilisation"]
    assert stab["mode"] == "auto"
    assert [a.split("(")[0] for a in stab["added"]] == ["MonaghanViscosity", "DensityDiffusion", "ParticleShifting",
                                                         "LinearConsistentPressure", "VolumeConsistency"]


def test_recommended_set_is_frozen():
    with pytest.raises(dataclasses.FrozenInstanceError):
        RECOMMENDED.alpha = 0.1  # type: ignore[misc]
