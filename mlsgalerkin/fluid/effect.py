r"""The :class:`Effect` contract: the units of physics a fluid scene lists. Nothing unlisted runs.

An effect declares the quantities it ``reads`` and ``provides`` and takes part in some of the
stages of a force evaluation, called in this order by the
:class:`~mlsgalerkin.fluid.solver.FluidSolver`:

============  ===========================================================================
stage         what happens
============  ===========================================================================
kinematics    wall-particle velocities (before the velocity gradient is formed)
(solver)      velocity gradient ``L_k = Σ_j v_j ⊗ ∇N_j(x_k)`` and its trace ``tr L``
divergence    corrections of ``tr L`` (the volume balance of a closed tank); then
              (solver) continuity ``ρ̇ = −ρ tr L``
continuity    added terms of the continuity rate ``ρ̇`` (density diffusion)
pressure      the pressure model: ``p``, sound speed ``c`` (exactly one effect)
boundary      wall-particle pressure and density
(solver)      stress ``σ = −p I``
stress        added stresses: Newtonian viscosity, bulk artificial viscosity
(solver)      ``V = M/ρ``, mass, internal force ``f_i = −Σ_k σ_k ∇N_i(x_k) V_k``, forces
              added by interactions
force         added nodal forces: gravity ``m_i g``, Monaghan pair viscosity
(solver)      acceleration ``a = f/m`` of the fluid particles
after_step    density re-initialisation, free-surface detection (every few steps)
drift         at the start of the next step's drift (positions ``xⁿ``, step ``Δt`` known):
              displacements added to the drift (particle shifting)
============  ===========================================================================

Effects talk to each other only through the :class:`~mlsgalerkin.fluid.state.FluidState`:
an effect that provides a quantity writes it into the state in :meth:`Effect.setup` or a
stage (``Gravity`` sets ``state.gravity``, which the wall pressure reads; the pressure model,
set up first, sets the reference sound speed ``state.c0`` that density diffusion, shifting and
the pair viscosity scale with), and validation
checks that every name an effect ``reads`` is provided by the solver or a listed effect.
Each effect supplies its own time-step limit (the formulas are in
:mod:`mlsgalerkin.fluid.time_step`); the solver takes the minimum. The solver provides
:data:`SOLVER_QUANTITIES`.

Writing a new effect: subclass :class:`Effect`, set ``name``, ``stages``, ``reads`` and
``provides``, implement the stage methods (they receive the state and modify its arrays in
place), and optionally ``check`` (validation before step 1), ``setup``, ``time_step_limit``,
``summary``, ``state_dict``/``load_state_dict``. ``check`` and ``setup`` receive an
:class:`EffectContext` (the fluid's :class:`~mlsgalerkin.fluid.scheme.FluidScheme` and a read-only
view of the scene), never the scene itself. See ``docs/howto/write_a_scene_and_an_effect.md``.
"""

from __future__ import annotations

import math
from typing import Any, Protocol, Sequence

import numpy as np

from mlsgalerkin.approximation.settings import Approximation
from mlsgalerkin.fluid.state import FluidState

__all__ = ["SOLVER_QUANTITIES", "STAGES", "Effect", "EffectContext", "check_nonnegative", "check_positive"]

STAGES = ("kinematics", "divergence", "continuity", "pressure", "boundary", "stress", "force", "after_step", "drift")
SOLVER_QUANTITIES = frozenset({
    "positions", "velocity", "density", "mass", "volume", "velocity_gradient",
    "shape_functions", "neighbors", "continuity_rate", "kernel_sum",
})


class EffectContext(Protocol):
    """What an effect sees in :meth:`Effect.check` and :meth:`Effect.setup` (read only):
    :class:`~mlsgalerkin.fluid.scheme.FluidContext` implements it."""

    @property
    def dim(self) -> int:
        """Dimension of the scene's bodies."""

    @property
    def effects(self) -> Sequence["Effect"]:
        """Every listed effect of the fluid, in order."""

    @property
    def approximation(self) -> Approximation:
        """Kernel, smoothing length, basis and method of the fluid."""

    @property
    def safety(self) -> float:
        """Factor on the stable time step."""

    @property
    def dt_max(self) -> float | None:
        """Largest time step (s), if set."""

    @property
    def interactions(self) -> tuple:
        """The scene's interactions."""

    @property
    def probes(self) -> tuple:
        """The scene's probes."""

    def bodies_of(self, kind: type) -> list:
        """The scene's bodies of ``kind``, in scene order."""

    def pressure_model(self) -> "Effect | None":
        """The listed pressure model, if any."""

    def sound_speed(self) -> float | None:
        """The pressure model's reference sound speed ``c0`` (m/s), if it has one."""

    def provides(self, quantity: str) -> bool:
        """Whether a listed effect provides ``quantity``."""


class Effect:
    """Base class of a unit of physics (see the module docstring)."""

    name: str = "effect"
    stages: tuple[str, ...] = ()
    reads: tuple[str, ...] = ()
    provides: tuple[str, ...] = ()
    role: str = "other"  # "pressure" for the pressure model (exactly one per scene)
    #: a numerical stabilisation (artificial viscosity, density diffusion or filtering, shifting,
    #: consistent integration) rather than physics: a scheme that lists none gets the recommended set
    stabilising: bool = False

    def check(self, ctx: EffectContext) -> list[str]:
        """Problems with this effect in the fluid's scheme and scene ``ctx`` (empty if none);
        called before step 1. Reads only."""
        return []

    def setup(self, state: FluidState, ctx: EffectContext) -> None:
        """Precompute what the effect needs once the particle state exists; write what it
        ``provides`` into the state."""

    def kinematics(self, s: FluidState) -> None: ...
    def divergence(self, s: FluidState, div: np.ndarray) -> None: ...
    def continuity(self, s: FluidState) -> None: ...
    def pressure(self, s: FluidState) -> None: ...
    def boundary(self, s: FluidState) -> None: ...
    def stress(self, s: FluidState) -> None: ...
    def force(self, s: FluidState) -> None: ...
    def after_step(self, s: FluidState) -> None: ...
    def drift(self, s: FluidState, dt: float) -> None: ...

    def time_step_limit(self, s: FluidState) -> float:
        """Largest stable time step this effect allows (s); ``inf`` if it sets none."""
        return math.inf

    def summary(self) -> dict[str, Any]:
        """Diagnostics for ``summary.json`` (JSON-serialisable)."""
        return {}

    def state_dict(self) -> dict[str, Any]:
        """Counters to checkpoint (JSON-serialisable) so a restart continues bit for bit."""
        return {}

    def load_state_dict(self, d: dict[str, Any]) -> None:
        """Restore what :meth:`state_dict` returned."""

    def __repr__(self) -> str:
        return f"{type(self).__name__}()"


def check_positive(owner: str, name: str, value: float, problems: list[str]) -> None:
    """Append a problem unless ``value`` is finite and ``> 0``."""
    if not (np.isfinite(value) and value > 0):
        problems.append(f"{owner}: {name} must be positive, got {value!r}")


def check_nonnegative(owner: str, name: str, value: float, problems: list[str]) -> None:
    """Append a problem unless ``value`` is finite and ``>= 0``."""
    if not (np.isfinite(value) and value >= 0):
        problems.append(f"{owner}: {name} must be >= 0, got {value!r}")
