"""Weakly compressible Lagrangian fluid on the Galerkin-MLS assembler.

=====================================  =======================================================
module                                 contents
=====================================  =======================================================
:mod:`~mlsgalerkin.fluid.bodies`       :class:`FluidBody`, :class:`Phase`, :class:`WallBody`
                                       (particles and/or a penalty surface; fixed or moving),
                                       :func:`lattice`, :func:`wall_box`
:mod:`~mlsgalerkin.fluid.state`        :class:`FluidState`, the flat particle arrays
:mod:`~mlsgalerkin.fluid.solver`       :class:`FluidSolver`: neighbours, shape functions,
                                       kinematics, dynamics, time step, checkpoints
:mod:`~mlsgalerkin.fluid.integrators`  :class:`KickDriftKick`, :class:`PredictorCorrector`
:mod:`~mlsgalerkin.fluid.effect`       the :class:`Effect` contract and its stages
:mod:`~mlsgalerkin.fluid.scheme`       :class:`FluidScheme`: effects, approximation, integrator,
                                       mass, safety, ``dt_max``, spacing, periodic axes
                                       (:class:`~mlsgalerkin.periodic.Periodic`); :class:`FluidContext`
:mod:`~mlsgalerkin.fluid.presets`      :func:`water`: the recommended scheme for water
:mod:`~mlsgalerkin.fluid.eos`          the Tait equation and :class:`TaitPressure`
:mod:`~mlsgalerkin.fluid.gravity`      :class:`Gravity`
:mod:`~mlsgalerkin.fluid.viscosity`    :class:`NewtonianViscosity`, :class:`BulkViscosity`
:mod:`~mlsgalerkin.fluid.pair_viscosity`  :class:`MonaghanViscosity` and its numba kernel
:mod:`~mlsgalerkin.fluid.walls`        :class:`Walls` and the wall-state kernel
:mod:`~mlsgalerkin.fluid.penalty_walls`  :class:`PenaltyWalls`: walls as penalty contact
                                       surfaces, and the wall force sensors
:mod:`~mlsgalerkin.fluid.filters`      :class:`DensityFilter` and its kernels
:mod:`~mlsgalerkin.fluid.density_diffusion`  :class:`DensityDiffusion` (δ-SPH) and its kernel
:mod:`~mlsgalerkin.fluid.shifting`     :class:`ParticleShifting` and its kernel
:mod:`~mlsgalerkin.fluid.consistent_integration`  :class:`ConsistentIntegration`: nodal
                                       integration that meets the integration constraint
:mod:`~mlsgalerkin.fluid.linear_consistency`  :class:`LinearConsistentPressure`: the pressure's
                                       linear part integrated exactly, with the free-surface term
:mod:`~mlsgalerkin.fluid.volume_consistency`  :class:`VolumeConsistency`: the density relaxed
                                       towards the particles' packing (the Shepard sum)
:mod:`~mlsgalerkin.fluid.sponge`       :class:`SpongeZone`: a damping zone that absorbs waves
:mod:`~mlsgalerkin.fluid.closed_volume`  :class:`ClosedVolume`: the volume balance of a closed tank
:mod:`~mlsgalerkin.fluid.recommended`  :data:`RECOMMENDED`: the one recommended stabilisation set
:mod:`~mlsgalerkin.fluid.stabilisation`  :func:`stabilisation`: the stabilising effects from a few parameters
:mod:`~mlsgalerkin.fluid.corrected_gradient`  the renormalised gradient of the density ratio
:mod:`~mlsgalerkin.fluid.free_surface` :class:`FreeSurfaceDetection` and its kernels
:mod:`~mlsgalerkin.fluid.time_step`    every time-step limit
:mod:`~mlsgalerkin.fluid.mass`         lumped, particle and consistent mass
:mod:`~mlsgalerkin.fluid.health`       the watchdog's check of a fluid state
=====================================  =======================================================

Run a scene with :class:`mlsgalerkin.simulation.Simulation`; ready-made scenes live in
:mod:`mlsgalerkin.problems`.
"""

from mlsgalerkin.deprecation import moved_names
from mlsgalerkin.fluid.bodies import (
    FluidBody,
    ParticleLimitError,
    Phase,
    WallBody,
    lattice,
    particle_limit,
    wall_box,
)
from mlsgalerkin.fluid.consistent_integration import ConsistentIntegration
from mlsgalerkin.fluid.linear_consistency import LinearConsistentPressure
from mlsgalerkin.fluid.sponge import SpongeZone
from mlsgalerkin.fluid.density_diffusion import DensityDiffusion
from mlsgalerkin.fluid.effect import Effect
from mlsgalerkin.fluid.eos import (
    MachNumberWarning,
    TaitEOS,
    TaitPressure,
    hydrostatic_density,
    hydrostatic_pressure,
    tait_density,
    tait_pressure,
    tait_sound_speed,
    tait_stored_energy,
)
from mlsgalerkin.fluid.filters import DensityFilter
from mlsgalerkin.fluid.free_surface import FreeSurfaceDetection
from mlsgalerkin.fluid.gravity import Gravity
from mlsgalerkin.fluid.integrators import Integrator, KickDriftKick, PredictorCorrector
from mlsgalerkin.fluid.pair_viscosity import (
    MonaghanViscosity,
    NumericalViscosityWarning,
    numerical_viscosity,
)
from mlsgalerkin.fluid.penalty_walls import PenaltyWalls
from mlsgalerkin.fluid.closed_volume import ClosedVolume
from mlsgalerkin.fluid.presets import RECOMMENDED, StabilisationSet, water
from mlsgalerkin.fluid.run_checks import ParticleClumpingWarning, ShapeFunctionFallbackWarning, VolumeErrorWarning
from mlsgalerkin.fluid.scheme import FluidContext, FluidScheme
from mlsgalerkin.fluid.shifting import ParticleShifting
from mlsgalerkin.fluid.solver import FluidSolver, WallPenetrationWarning
from mlsgalerkin.fluid.stabilisation import SHIFTING_MODES, stabilisation
from mlsgalerkin.fluid.state import FluidState
from mlsgalerkin.fluid.time_step import (
    acoustic_limit,
    bulk_viscosity_limit,
    density_diffusion_limit,
    force_limit,
    pair_viscosity_limit,
    viscous_limit,
)
from mlsgalerkin.fluid.viscosity import BulkViscosity, NewtonianViscosity
from mlsgalerkin.fluid.volume_consistency import VolumeConsistency
from mlsgalerkin.fluid.walls import Walls
from mlsgalerkin.periodic import Periodic

__all__ = [
    "BulkViscosity",
    "ClosedVolume",
    "ConsistentIntegration",
    "LinearConsistentPressure",
    "SpongeZone",
    "DensityDiffusion",
    "DensityFilter",
    "Effect",
    "FluidBody",
    "FluidContext",
    "FluidScheme",
    "FluidSolver",
    "FluidState",
    "FreeSurfaceDetection",
    "Gravity",
    "Integrator",
    "KickDriftKick",
    "MachNumberWarning",
    "MonaghanViscosity",
    "NewtonianViscosity",
    "NumericalViscosityWarning",
    "ParticleClumpingWarning",
    "ParticleLimitError",
    "ParticleShifting",
    "PenaltyWalls",
    "Periodic",
    "Phase",
    "PredictorCorrector",
    "ShapeFunctionFallbackWarning",
    "TaitEOS",
    "TaitPressure",
    "VolumeErrorWarning",
    "WallBody",
    "WallPenetrationWarning",
    "Walls",
    "SHIFTING_MODES",
    "acoustic_limit",
    "bulk_viscosity_limit",
    "density_diffusion_limit",
    "force_limit",
    "hydrostatic_density",
    "hydrostatic_pressure",
    "lattice",
    "numerical_viscosity",
    "pair_viscosity_limit",
    "particle_limit",
    "stabilisation",
    "tait_density",
    "tait_pressure",
    "tait_sound_speed",
    "tait_stored_energy",
    "viscous_limit",
    "wall_box",
    "water",
    "RECOMMENDED",
    "StabilisationSet",
    "VolumeConsistency",
]


#: ``StructureCoupling`` moved to :mod:`mlsgalerkin.interactions`: read here for one more release, with a
#: ``DeprecationWarning``.
__getattr__ = moved_names(__name__, {"StructureCoupling": "mlsgalerkin.interactions"})
