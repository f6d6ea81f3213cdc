r"""Ready-made fluid schemes: :func:`water`, the recommended settings for water with a free surface.

A problem states what its flow is (sound speed, gravity, the speed and length that set the
Reynolds number of the artificial viscosity) and what it changes; everything else comes from one
place, so every problem runs the same numerics unless it says otherwise:

>>> scheme = water(c0=20.0, spacing=0.01)
>>> [type(e).__name__ for e in scheme.effects]  # doctest: +NORMALIZE_WHITESPACE
['TaitPressure', 'Gravity', 'Walls', 'MonaghanViscosity', 'DensityDiffusion', 'ParticleShifting',
 'LinearConsistentPressure', 'VolumeConsistency']
>>> scheme.spacing, scheme.approximation.h_factor
(0.01, 1.3)

The defaults are :data:`RECOMMENDED`, the one numerical set every shipped fluid problem runs:
Monaghan's pair viscosity ``α = 0.02``, density diffusion ``δ = 0.1`` (Antuono et al. 2010),
particle shifting at each particle's own speed (Skillen et al. 2013), no density filter, the
pressure's local linear fit integrated exactly with the free-surface boundary term
(:class:`~mlsgalerkin.fluid.linear_consistency.LinearConsistentPressure`), the density relaxed
towards the particles' packing where the fluid has a free surface at ``ε = 0.02``
(:class:`~mlsgalerkin.fluid.volume_consistency.VolumeConsistency`), and a cubic-spline
MLS approximation with ``h = 1.3 Δx``. Tension released by cavitation (the density floored at the
rest density) is the default model of a liquid against air; a problem whose physics differs
(a closed tank, a surface that separates) says so (``docs/theory/stabilisation.md`` has what
each setting does and costs, ``verification/results/quiet_state/investigation.md`` how the set
was chosen).
"""

from __future__ import annotations

from typing import Any, Sequence

from mlsgalerkin.approximation.settings import Approximation
from mlsgalerkin.fluid.effect import Effect
from mlsgalerkin.fluid.eos import TaitPressure
from mlsgalerkin.fluid.gravity import Gravity
from mlsgalerkin.fluid.linear_consistency import LinearConsistentPressure
from mlsgalerkin.fluid.pair_viscosity import MonaghanViscosity
from mlsgalerkin.fluid.recommended import RECOMMENDED, StabilisationSet
from mlsgalerkin.fluid.scheme import FluidScheme
from mlsgalerkin.fluid.stabilisation import stabilisation
from mlsgalerkin.fluid.viscosity import NewtonianViscosity
from mlsgalerkin.fluid.volume_consistency import VolumeConsistency
from mlsgalerkin.fluid.walls import Walls

__all__ = ["RECOMMENDED", "StabilisationSet", "water"]


def water(c0: float, *, u_max: float | None = None, gravity: Sequence[float] | None = (0.0, -9.81),
          slip: str | None = "free_slip", alpha: float = RECOMMENDED.alpha,
          flow: tuple[float, float] | None = None, residual_viscosity: bool = False, newtonian: bool = False,
          delta: float = RECOMMENDED.delta, shifting: str = RECOMMENDED.shifting,
          density_filter: int = RECOMMENDED.density_filter, negative_pressure: str = "cavitate",
          void_memory: float = 0.0,
          penalty_thickness: float | None = None,
          consistent_integration: bool = RECOMMENDED.consistent_integration,
          linear_consistency: bool = RECOMMENDED.linear_consistency,
          hydrostatic_reference: bool = RECOMMENDED.hydrostatic_reference,
          volume_consistency: float = RECOMMENDED.volume_consistency, loose_band: float | None = None,
          droplet_rate: float = RECOMMENDED.droplet_rate, loose_local: float = RECOMMENDED.loose_local,
          spacing: float | None = None,
          h_factor: float = 1.3,
          approximation: Approximation | None = None, extra: Sequence[Effect] = (), **options: Any) -> FluidScheme:
    """The recommended :class:`~mlsgalerkin.fluid.scheme.FluidScheme` for water (module docstring).

    Effects, in this order: ``TaitPressure(c0, u_max, negative_pressure, void_memory)``; ``Gravity(gravity)``
    (unless ``gravity`` is ``None``); ``Walls(slip)`` (unless ``slip`` is ``None``);
    ``NewtonianViscosity()`` if ``newtonian`` (each phase's own viscosity); ``MonaghanViscosity(alpha,
    residual=residual_viscosity, flow=flow)`` if ``alpha > 0``; then
    :func:`~mlsgalerkin.fluid.stabilisation.stabilisation` of ``delta``, ``shifting``,
    ``density_filter``, ``negative_pressure``, ``penalty_thickness`` (m; the tank's penalty surface
    as a backstop, reaching one ``spacing``) and ``consistent_integration``;
    ``LinearConsistentPressure(hydrostatic_reference=hydrostatic_reference)`` if ``linear_consistency``
    (the pressure's local linear fit integrated exactly, with the free-surface boundary term; in a
    closed tank with ``hydrostatic_reference`` a fixed hydrostatic field integrated exactly where
    the fit falls back; it is part of the linear consistency, so ``linear_consistency=False``
    leaves it out too); ``VolumeConsistency(volume_consistency)``
    unless ``volume_consistency`` is 0 (the density relaxed towards the particles' packing where the
    fluid has a free surface, ``docs/theory/stabilisation.md`` §10), with its loose side past the
    volume error ``loose_band`` (``None``, the default: :data:`RECOMMENDED`'s 0.005 when the volume
    consistency is on; 0: off), its local part of weight ``loose_local`` (each loose particle away
    from the walls relaxes by that many times its neighbourhood's volume excess on top; 0: off) and
    its droplets relaxed down to their rest density at ``droplet_rate`` ``c0/h``;
    then ``extra``. The stabilisation defaults are :data:`RECOMMENDED`.

    Parameters
    ----------
    c0 : float
        Reference sound speed (m/s): at least ten times the largest flow speed.
    u_max : float, optional
        The largest expected speed (m/s), for the Mach-number check.
    gravity : (d,) floats, optional
        Gravitational acceleration (m/s²); ``None`` for none.
    flow : (speed, length), optional
        The flow's speed (m/s) and length (m): the artificial viscosity's Reynolds number is
        reported, and warned about below 100.
    spacing : float, optional
        The particle spacing ``Δx`` (m) the bodies are built with; checked against them.
    h_factor : float
        ``h/Δx`` of the default approximation (ignored when ``approximation`` is given).
    **options
        ``integrator``, ``mass``, ``safety``, ``dt_max``, ``periodic`` of the scheme
        (``stabilisation`` is ``"as_listed"``: the effects above are exactly what is asked for).
    """
    if loose_band is None:
        loose_band = RECOMMENDED.loose_band if volume_consistency != 0 else 0.0
    if loose_band and volume_consistency == 0:
        raise ValueError(f"water(loose_band={loose_band:g}) is the volume consistency's loose side, which "
                         "volume_consistency=0 leaves out: give volume_consistency > 0 (the default) or loose_band=0")
    effects: list[Effect] = [TaitPressure(c0, u_max=u_max, negative_pressure=negative_pressure,
                                          void_memory=void_memory)]
    if gravity is not None:
        effects.append(Gravity(tuple(gravity)))
    if slip is not None:
        effects.append(Walls(slip))
    if newtonian:
        effects.append(NewtonianViscosity())
    if alpha > 0:
        effects.append(MonaghanViscosity(alpha, residual=residual_viscosity, flow=flow))
    effects += stabilisation(delta=delta, shifting=shifting, density_filter=density_filter,
                             negative_pressure=negative_pressure, penalty_thickness=penalty_thickness,
                             spacing=spacing, consistent_integration=consistent_integration)
    if linear_consistency:
        effects.append(LinearConsistentPressure(hydrostatic_reference=hydrostatic_reference))
    if volume_consistency != 0:     # a negative rate is listed, so the effect's check refuses it
        effects.append(VolumeConsistency(volume_consistency, loose_band=loose_band, droplet_rate=droplet_rate,
                                         loose_local=loose_local))
    effects += list(extra)
    approximation = approximation if approximation is not None else Approximation(h_factor=h_factor)
    options.setdefault("stabilisation", "as_listed")  # the list above is explicit: nothing is added to it
    return FluidScheme(effects, approximation=approximation, spacing=spacing, **options)
