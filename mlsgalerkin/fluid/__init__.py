"""Weakly compressible Lagrangian fluid on the Galerkin-MLS assembler: bodies, effects,
equation of state, time-step limits, walls, filters and free-surface detection.

Run a scene with :class:`mlsgalerkin.simulation.Simulation`; ready-made scenes live in
:mod:`mlsgalerkin.problems`.
"""

from mlsgalerkin.fluid.bodies import FluidBody, Phase, WallBody, lattice, wall_box
from mlsgalerkin.fluid.effects import (
    BulkViscosity,
    DensityFilter,
    Effect,
    FreeSurfaceDetection,
    Gravity,
    MonaghanViscosity,
    NewtonianViscosity,
    TaitPressure,
    Walls,
)
from mlsgalerkin.fluid.eos import MachNumberWarning, TaitEOS
from mlsgalerkin.fluid.state import FluidState
from mlsgalerkin.fluid.time_step import acoustic_limit, force_limit, viscous_limit

__all__ = [
    "BulkViscosity",
    "DensityFilter",
    "Effect",
    "FluidBody",
    "FluidState",
    "FreeSurfaceDetection",
    "Gravity",
    "MachNumberWarning",
    "MonaghanViscosity",
    "NewtonianViscosity",
    "Phase",
    "TaitEOS",
    "TaitPressure",
    "WallBody",
    "Walls",
    "acoustic_limit",
    "force_limit",
    "lattice",
    "viscous_limit",
    "wall_box",
]
