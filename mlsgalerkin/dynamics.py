r"""The contracts the run loop drives: bodies, their solvers, interactions between bodies.

:class:`~mlsgalerkin.simulation.Simulation` knows no physics. It groups the scene's bodies by
the solver that advances them (every :class:`Body` names its solver class), and per time step

1. asks every solver for its stable time step and takes the minimum;
2. calls :meth:`Solver.begin_step` on every solver: each moves its bodies to ``t + Δt``
   (a kick-drift for the fluid; a sub-cycled structure advances completely with the forces
   of the last exchange);
3. calls :meth:`Interaction.exchange` on every interaction: it reads both bodies'
   :class:`Surface` at ``t + Δt`` and adds equal and opposite forces to both
   (:meth:`Solver.add_surface_forces`);
4. calls :meth:`Solver.end_step` on every solver: each evaluates its forces at ``t + Δt``,
   including what the interactions added, and completes the step (the final kick);
5. calls :meth:`Interaction.after_step` on every interaction: forces that one solver computed
   in its ``end_step`` (the fluid's reaction on wall particles riding on a structure) go to the
   other body for its next step;
6. hands the :class:`~mlsgalerkin.simulation.RunState` to the monitors.

A body kind that should take part implements a :class:`Body` (data: geometry, material,
initial state), a :class:`Scheme` (the numerical settings of its solver: the fluid's effects,
approximation and integrator; a structure's largest step) and a :class:`Solver` (state and how
it advances, with its own integrator and sub-steps). A solver is built from its bodies, its
scheme and a :class:`SceneView` (what it may know of the rest of the scene); it never sees the
scene itself. Nothing in the loop changes. See ``docs/architecture.md``.
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from dataclasses import dataclass, field
from typing import Any, ClassVar

import numpy as np
from numpy.typing import NDArray

__all__ = ["Body", "Interaction", "SceneView", "Scheme", "Solver", "Surface"]


class Body:
    """A named part of a scene, advanced by the solver class :attr:`solver`.

    Subclasses are plain data (dataclasses): geometry, material, initial state. All bodies of
    one solver class in a scene are handed to one instance of that class.
    """

    #: The :class:`Solver` subclass that advances bodies of this kind, or its import path
    #: ``"package.module:Class"`` (resolved by the scene; lets a body module avoid importing its
    #: solver module).
    solver: ClassVar[type["Solver"] | str]
    name: str

    @property
    def dim(self) -> int:  # pragma: no cover - every body defines it
        raise NotImplementedError


class Scheme:
    """The numerical settings of one solver (plain data): the fluid's effects, approximation,
    integrator and step limits (:class:`~mlsgalerkin.fluid.scheme.FluidScheme`), a structure's
    largest step (:class:`~mlsgalerkin.structure.scheme.StructureScheme`).

    A scene lists one scheme per solver (``Scene(bodies, schemes=[...])``); a solver whose
    bodies have no scheme in the scene gets ``solver.scheme_class()``, its defaults.
    """

    #: The :class:`Solver` subclass these settings are for, or its import path
    #: ``"package.module:Class"`` (as :attr:`Body.solver`).
    solver: ClassVar[type["Solver"] | str]

    def problems(self) -> list[str]:
        """Problems with these settings alone (called before any work; empty if none)."""
        return []

    def identity(self) -> dict[str, Any]:
        """The settings that make a run this run (JSON-serialisable; compared on restart)."""
        return {}


@dataclass(frozen=True)
class SceneView:
    """What a solver, an effect or an interaction may know of the scene it is part of: read only.

    Attributes
    ----------
    name : str
        The scene's name.
    dim : int
        Dimension of the bodies (0 if they disagree).
    t_end : float
        End time (s).
    bodies : tuple of Body
        Every body of the scene, in scene order (other solvers' bodies too: a fluid checks that
        a structure does not overlap it).
    interactions : tuple of Interaction
        The scene's interactions.
    probes : tuple
        The scene's probes (``name``, ``func``, ``reads``), for checking what they read.
    """

    name: str
    dim: int
    t_end: float
    bodies: tuple = ()
    interactions: tuple = ()
    probes: tuple = ()

    def bodies_of(self, kind: type) -> list:
        """The bodies that are instances of ``kind``, in scene order."""
        return [b for b in self.bodies if isinstance(b, kind)]


@dataclass
class Surface:
    """The touchable boundary of a body at the current time, for an :class:`Interaction`.

    Attributes
    ----------
    body : str
        Name of the body.
    positions, velocities : (n, d) float arrays
        Surface nodes (m, m/s).
    segments : (n_seg, d) int array
        Node indices of each master segment (2D: the two end nodes, ordered so that the
        outward normal is the segment direction turned clockwise; 3D: triangles,
        counter-clockwise seen from outside). Empty ``(0, d)`` for a point set (slave nodes).
    masses : (n,) float array
        Nodal masses (kg, per unit depth in 2D), for penalty stiffness and time-step limits;
        ``None`` for a rigid body (infinite mass as seen by one node).
    accelerations : (n, d) float array, optional
        Surface node accelerations (m/s²), for a wall treatment that sees the surface's
        acceleration (the pressure of wall particles riding on a structure).
    """

    body: str
    positions: NDArray[np.float64]
    velocities: NDArray[np.float64]
    segments: NDArray[np.int64] = field(default_factory=lambda: np.zeros((0, 2), dtype=np.int64))
    masses: NDArray[np.float64] | None = None
    accelerations: NDArray[np.float64] | None = None


class Solver(ABC):
    """Owns the state of a group of bodies and advances it (see the module docstring).

    Parameters
    ----------
    bodies : list of Body
        The scene's bodies of this solver's kind, in scene order.
    scheme : Scheme
        This solver's numerical settings (an instance of :attr:`scheme_class`).
    scene : SceneView
        What the solver may know of the rest of the scene (read only).
    """

    #: Key of this solver's state in :attr:`RunState.systems` and of its part of the summary.
    key: ClassVar[str]
    #: The settings this solver takes; ``scheme_class()`` must give working defaults.
    scheme_class: ClassVar[type[Scheme]] = Scheme

    @classmethod
    def problems(cls, bodies: list[Body], scheme: Scheme, scene: SceneView) -> list[str]:
        """Every problem with these bodies and settings in ``scene`` (called before any work;
        empty if none). Reads only: it changes neither the bodies nor the scheme."""
        return []

    @abstractmethod
    def __init__(self, bodies: list[Body], scheme: Scheme, scene: SceneView) -> None: ...

    @property
    @abstractmethod
    def state(self) -> Any:
        """This solver's state (what monitors and probes see)."""

    @abstractmethod
    def start(self) -> None:
        """First force evaluation at the initial time (rates for the first step)."""

    @abstractmethod
    def stable_time_step(self) -> float:
        """Largest time step (s) this solver can take as one outer step (after sub-cycling)."""

    @abstractmethod
    def begin_step(self, t: float, dt: float) -> None:
        """Move the bodies from ``t`` to ``t + dt`` (positions and what depends only on them)."""

    @abstractmethod
    def end_step(self, t: float, dt: float) -> None:
        """Evaluate the forces at ``t + dt`` (with the interaction forces) and finish the step."""

    def surface(self, body: str) -> Surface:
        """The current :class:`Surface` of ``body`` (for interactions)."""
        raise NotImplementedError(f"{type(self).__name__} exposes no surface for body {body!r}")

    def add_surface_forces(self, body: str, forces: NDArray[np.float64]) -> None:
        """Add ``forces (n, d)`` (N, per unit depth in 2D) on the surface nodes of ``body``,
        to be used by the next :meth:`end_step`."""
        raise NotImplementedError(f"{type(self).__name__} accepts no surface forces for body {body!r}")

    def clear_surface_forces(self) -> None:
        """Forget the forces of the last exchange (called before each exchange)."""

    @abstractmethod
    def checkpoint(self) -> tuple[dict[str, np.ndarray], dict[str, Any]]:
        """Arrays and JSON metadata from which :meth:`restore` continues bit for bit."""

    @abstractmethod
    def restore(self, arrays: dict[str, np.ndarray], meta: dict[str, Any]) -> None:
        """Load what :meth:`checkpoint` returned (into a solver built from the same scene)."""

    @abstractmethod
    def summary(self) -> dict[str, Any]:
        """Sizes, settings, time per stage and diagnostics for ``summary.json``."""


class Interaction(ABC):
    """Exchanges forces between the surfaces of two bodies once per step (between
    :meth:`Solver.begin_step` and :meth:`Solver.end_step`).

    Subclasses name the two bodies (``first``, ``second``), read both
    :meth:`Solver.surface` at ``t + Δt``, and add equal and opposite forces with
    :meth:`Solver.add_surface_forces`; they may limit the time step.
    """

    name: str = "interaction"
    first: str
    second: str

    def problems(self, scene: SceneView) -> list[str]:
        """Every problem with this interaction in ``scene`` (empty if none). Reads only."""
        names = {b.name for b in scene.bodies}
        return [f"interaction {self.name!r}: no body named {b!r}" for b in (self.first, self.second)
                if b not in names]

    @abstractmethod
    def exchange(self, t: float, first: Solver, second: Solver) -> None:
        """Compute the forces at time ``t`` and add them to both bodies."""

    def after_step(self, t: float, first: Solver, second: Solver) -> None:
        """Called once more after every solver's :meth:`Solver.end_step` at time ``t``: for
        forces that only exist once a solver has evaluated its own (the reaction of the fluid on
        wall particles riding on a structure), added to the other body for its next step. The
        surface forces are cleared before the next :meth:`exchange`, not before this call. Also
        called once after every solver's :meth:`Solver.start`, at the initial time."""

    def stable_time_step(self) -> float:
        """Largest stable time step this interaction allows (s); ``inf`` if none."""
        return float("inf")

    #: Whether the run loop repeats each step until this interaction converges (implicit,
    #: partitioned coupling): every solver is restored to the step's start before each repeat.
    iterates: bool = False
    #: The most passes of one step an iterating interaction asks for.
    max_iterations: int = 1

    def begin_iteration(self, k: int, t: float, dt: float, first: Solver, second: Solver) -> None:
        """Before pass ``k`` (from 0) of the step from ``t`` to ``t + dt`` (iterating interactions)."""

    def end_iteration(self, k: int, t: float, first: Solver, second: Solver) -> bool:
        """After pass ``k``, at ``t`` (the step's end): ``True`` when converged (iterating interactions)."""
        return True

    def __repr__(self) -> str:
        """Names the interaction and its bodies; subclasses add their parameters (a run's identity
        compares reprs, so a restart with other parameters is noticed)."""
        return f"{type(self).__name__}(name={self.name!r}, first={self.first!r}, second={self.second!r})"

    def summary(self) -> dict[str, Any]:
        """Diagnostics for ``summary.json``."""
        return {}

    def observables(self) -> dict[str, float]:
        """Time-series quantities of this interaction (columns of ``timeseries.csv``; the same
        keys from the start, before the first exchange): e.g. the energy stored in its contact."""
        return {}

    def state_dict(self) -> dict[str, Any]:
        """What a restart needs to continue bit for bit (JSON-serialisable; stored in every
        checkpoint): e.g. a penalty stiffness fixed at the first exchange, running maxima."""
        return {}

    def load_state_dict(self, d: dict[str, Any]) -> None:
        """Restore what :meth:`state_dict` returned (before the first step after a restart)."""
