"""Weakly compressible Lagrangian fluid: equation of state, time-step limits (the solver is growing)."""

from mlsgalerkin.fluid.eos import MachNumberWarning, TaitEOS
from mlsgalerkin.fluid.time_step import acoustic_limit, force_limit, viscous_limit

__all__ = ["MachNumberWarning", "TaitEOS", "acoustic_limit", "force_limit", "viscous_limit"]
