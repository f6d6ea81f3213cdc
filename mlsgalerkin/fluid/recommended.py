r"""The one recommended numerical set of the fluid, :data:`RECOMMENDED`, and the effects it
stands for.

Every shipped fluid problem runs this set (its parameters default to it), :func:`water` builds it,
and a :class:`~mlsgalerkin.fluid.scheme.FluidScheme` that lists no stabilising effect at all
gets it added (``stabilisation="auto"``, the default; ``summary.json`` says what was added):

>>> RECOMMENDED.alpha, RECOMMENDED.delta, RECOMMENDED.shifting, RECOMMENDED.linear_consistency
(0.02, 0.1, 'local', True)
>>> RECOMMENDED.volume_consistency, RECOMMENDED.loose_band, RECOMMENDED.droplet_rate
(0.02, 0.005, 0.1)
>>> [type(e).__name__ for e in recommended_stabilisation()]
['MonaghanViscosity', 'DensityDiffusion', 'ParticleShifting', 'LinearConsistentPressure', 'VolumeConsistency']

An effect is *stabilising* when its class says ``stabilising = True``: numerical terms that keep
the particle method stable and accurate (artificial viscosity, density diffusion or filtering,
shifting, consistent integration), as opposed to the physics the scene calls for.
``verification/results/quiet_state/investigation.md`` has the measurements the set rests on.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Sequence

from mlsgalerkin.fluid.density_diffusion import DensityDiffusion
from mlsgalerkin.fluid.effect import Effect
from mlsgalerkin.fluid.linear_consistency import LinearConsistentPressure
from mlsgalerkin.fluid.pair_viscosity import MonaghanViscosity
from mlsgalerkin.fluid.shifting import ParticleShifting
from mlsgalerkin.fluid.volume_consistency import VolumeConsistency

__all__ = ["RECOMMENDED", "STABILISATION_MODES", "StabilisationSet", "is_stabilising", "missing_from_recommended",
           "recommended_stabilisation"]

#: ``FluidScheme(stabilisation=...)``: ``"auto"`` adds the recommended set when no stabilising
#: effect is listed and warns when only part of it is; ``"as_listed"`` runs exactly the list.
STABILISATION_MODES = ("auto", "as_listed")


@dataclass(frozen=True)
class StabilisationSet:
    """The numerical stabilisation of the fluid, as :func:`~mlsgalerkin.fluid.presets.water` takes it.

    ``alpha`` Monaghan's pair viscosity (–; its kinematic viscosity ``ν = α h c0 / 8`` is
    reported with the Reynolds number it implies), ``delta`` the δ-SPH density diffusion (–),
    ``shifting`` one of ``"local"``, ``"design"``, ``"off"``, ``density_filter`` a Shepard
    filter every this many steps (0: none), ``consistent_integration`` the constant-only VCI,
    ``linear_consistency`` the pressure's linear fit integrated exactly, ``hydrostatic_reference``
    with it, in a closed tank, a fixed hydrostatic field integrated exactly at the nodes that fall
    back (:class:`~mlsgalerkin.fluid.linear_consistency.LinearConsistentPressure`; on since
    2026-12-05), ``volume_consistency``
    the rate ε at which the density relaxes towards the particles' packing where the fluid has a
    free surface (–; 0: off; :class:`~mlsgalerkin.fluid.volume_consistency.VolumeConsistency`),
    ``loose_band`` its loose side: past this volume error of the whole fluid (geometric volume over
    ``Σ M/ρ``, minus one) the density of the particles that are neither deep nor splashes relaxes
    too (–; 0: off), ``loose_local`` the weight ``w`` of the loose side's local part: each loose
    particle away from the walls relaxes by ``w`` times its neighbourhood's volume excess past
    ``0.05`` on top (–; 0: off), ``droplet_rate`` the rate ``r_d`` at which a droplet (a particle with fewer
    neighbours than a line of particles) relaxes down to its rest density, in units of ``c0/h``
    (–; 0: off).
    """

    alpha: float = 0.02
    delta: float = 0.1
    shifting: str = "local"
    density_filter: int = 0
    consistent_integration: bool = False
    linear_consistency: bool = True
    hydrostatic_reference: bool = True
    volume_consistency: float = 0.02
    loose_band: float = 0.005
    loose_local: float = 2.0
    droplet_rate: float = 0.1

    def as_dict(self) -> dict[str, Any]:
        """The set as keyword arguments of :func:`~mlsgalerkin.fluid.presets.water`."""
        return dict(self.__dict__)


#: The one recommended set: every shipped fluid problem's defaults (quiet water, impacts, waves,
#: stratified flows).
RECOMMENDED = StabilisationSet()


def recommended_stabilisation() -> list[Effect]:
    """The stabilising effects of :data:`RECOMMENDED`, in the order :func:`water` lists them:
    ``MonaghanViscosity(α)``, ``DensityDiffusion(δ)``, ``ParticleShifting("local")``,
    ``LinearConsistentPressure(hydrostatic_reference=…)``, ``VolumeConsistency(ε, loose_band=e_0, droplet_rate=r_d, loose_local=w)``."""
    return [MonaghanViscosity(RECOMMENDED.alpha), DensityDiffusion(RECOMMENDED.delta),
            ParticleShifting(RECOMMENDED.shifting),
            LinearConsistentPressure(hydrostatic_reference=RECOMMENDED.hydrostatic_reference),
            VolumeConsistency(RECOMMENDED.volume_consistency, loose_band=RECOMMENDED.loose_band,
                              droplet_rate=RECOMMENDED.droplet_rate, loose_local=RECOMMENDED.loose_local)]


def is_stabilising(effect: object) -> bool:
    """Whether ``effect`` is a numerical stabilisation (its class says ``stabilising = True``)."""
    return bool(getattr(effect, "stabilising", False))


def missing_from_recommended(effects: Sequence[object]) -> list[str]:
    """Class names of the recommended stabilising effects that ``effects`` does not list."""
    listed = {type(e) for e in effects}
    return [type(e).__name__ for e in recommended_stabilisation() if type(e) not in listed]
