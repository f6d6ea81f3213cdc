"""The stabilising effects a problem lists, from a few parameters: one place that turns
``delta``, ``shifting``, ``density_filter``, ``negative_pressure`` and a penalty-wall thickness
and the consistent integration into effects (``docs/theory/stabilisation.md`` has what each does and what it costs).

>>> [type(e).__name__ for e in stabilisation(delta=0.1, shifting="local", penalty_thickness=0.001, spacing=0.004)]
['DensityDiffusion', 'ParticleShifting', 'PenaltyWalls']
>>> [type(e).__name__ for e in stabilisation(consistent_integration=True)]
['ConsistentIntegration']
"""

from __future__ import annotations

from mlsgalerkin.fluid.consistent_integration import ConsistentIntegration
from mlsgalerkin.fluid.density_diffusion import DensityDiffusion
from mlsgalerkin.fluid.effect import Effect
from mlsgalerkin.fluid.filters import DensityFilter
from mlsgalerkin.fluid.free_surface import FreeSurfaceDetection
from mlsgalerkin.fluid.penalty_walls import PenaltyWalls
from mlsgalerkin.fluid.shifting import ParticleShifting

__all__ = ["SHIFTING_MODES", "stabilisation"]

#: ``shifting`` choices: each particle's own speed (Skillen et al. 2013), the design speed
#: ``c0/10`` (Sun et al. 2017), or none.
SHIFTING_MODES = ("local", "design", "off")


def stabilisation(*, delta: float = 0.0, shifting: str = "off", density_filter: int = 0,
                  negative_pressure: str = "allow", penalty_thickness: float | None = None,
                  spacing: float | None = None, consistent_integration: bool = False) -> list[Effect]:
    """Effects, in this order: ``DensityFilter(density_filter)`` (if > 0),
    ``DensityDiffusion(delta)`` (if > 0), ``ParticleShifting`` (``shifting`` one of
    :data:`SHIFTING_MODES`), ``FreeSurfaceDetection(every=5)`` (what
    ``negative_pressure="free_surface"`` needs) and ``PenaltyWalls`` with contact thickness
    ``penalty_thickness`` (m) and reach one ``spacing`` (m) (if a thickness is given), and
    ``ConsistentIntegration()`` if ``consistent_integration``."""
    effects: list[Effect] = []
    if density_filter > 0:
        effects.append(DensityFilter(density_filter))
    if delta > 0:
        effects.append(DensityDiffusion(delta))
    if shifting != "off":
        effects.append(ParticleShifting("local" if shifting == "local" else None))
    if negative_pressure == "free_surface":
        effects.append(FreeSurfaceDetection(every=5))
    if penalty_thickness is not None:
        effects.append(PenaltyWalls(thickness=penalty_thickness, reach=spacing))
    if consistent_integration:
        effects.append(ConsistentIntegration())
    return effects
