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
it advances, with its own integrator and sub-steps) whose state is a :class:`SystemState` (what
monitors see: observables, health as a :class:`Diagnosis`, VTU frames). A solver is built from
its bodies, its scheme and a :class:`SceneView` (what it may know of the rest of the scene); it
never sees the scene itself. Nothing in the loop changes. See ``docs/architecture.md``.
"""

from __future__ import annotations

import importlib
from abc import ABC, abstractmethod
from collections.abc import Mapping
from dataclasses import dataclass, field, replace
from typing import Any, ClassVar, Protocol, runtime_checkable

import numpy as np
from numpy.typing import NDArray

__all__ = [
    "Body",
    "CarriesStepEndLoad",
    "Diagnosis",
    "DrivesWalls",
    "Interaction",
    "SceneView",
    "Scheme",
    "Solver",
    "Surface",
    "SystemState",
    "import_class",
    "solver_class_of",
]


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
    def state(self) -> "SystemState":
        """This solver's state (what monitors and probes see): a :class:`SystemState`."""

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
        """Every problem with this interaction in ``scene`` (empty if none). Validation only:
        it changes nothing (what the run needs from the scene is taken in :meth:`setup`)."""
        names = {b.name for b in scene.bodies}
        return [f"interaction {self.name!r}: no body named {b!r}" for b in (self.first, self.second)
                if b not in names]

    def setup(self, scene: SceneView) -> None:
        """Take what the run needs from the validated ``scene`` (called once when the
        :class:`~mlsgalerkin.simulation.Simulation` is built, before the first step or a
        restore)."""

    def capability_problems(self, body: Body, capability: type, doing: str, when: str = "") -> list[str]:
        """``[]`` if the solver of ``body`` implements the optional protocol ``capability``
        (:class:`DrivesWalls`, :class:`CarriesStepEndLoad`), else the problem, naming what the
        solver cannot do (``doing``), the methods it lacks and the kind of interaction (with
        ``when``, the setting that needs it) that needs them."""
        try:
            cls = solver_class_of(body)
        except (ImportError, AttributeError):
            return []  # the scene reports a solver that cannot be imported
        # the methods looked up each time (``issubclass`` on a protocol caches its answers)
        methods = [n for n, v in vars(capability).items() if not n.startswith("_") and callable(v)]
        lacks = [n for n in methods if not callable(getattr(cls, n, None))]
        if not lacks:
            return []
        kind = type(self).__name__ + (f" {when}" if when else "")
        return [f"{type(self).__name__} {self.name!r}: body {body.name!r}'s solver {getattr(cls, '__name__', cls)} cannot {doing} "
                f"(it lacks {', '.join(lacks)}); interactions of kind {kind} need a solver that implements "
                f"mlsgalerkin.dynamics.{capability.__name__}"]

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


def import_class(spec: Any) -> Any:
    """A class given as itself or as its import path ``"package.module:Class"`` (imported here):
    how a :class:`Body` or a :class:`Scheme` names its solver without importing it."""
    if isinstance(spec, str):
        module, _, name = spec.partition(":")
        return getattr(importlib.import_module(module), name)
    return spec


def solver_class_of(body: Body) -> type[Solver]:
    """The :class:`Solver` class that advances ``body`` (its ``solver`` attribute: a class, or
    ``"package.module:Class"``, imported here)."""
    return import_class(body.solver)


# --------------------------------------------------------------------------------------
# what an interaction may need from a solver beyond Solver: optional protocols
# --------------------------------------------------------------------------------------


@runtime_checkable
class DrivesWalls(Protocol):
    """A solver whose wall particles another body moves, and which reports the force on them:
    what :class:`~mlsgalerkin.interactions.StructureCoupling` with ``walls=`` needs from the
    fluid's solver (:class:`~mlsgalerkin.fluid.solver.FluidSolver` implements it)."""

    def drive_walls(self, body: str, t: float, positions: NDArray[np.float64], velocities: NDArray[np.float64],
                    accelerations: NDArray[np.float64], normals: NDArray[np.float64]) -> None:
        """Set the wall particles of wall body ``body`` to their state at time ``t`` (s):
        positions (m), velocities (m/s), accelerations (m/s²) and unit normals into the fluid,
        each ``(n, d)`` over the body's particles in order."""
        ...

    def wall_reactions(self, body: str) -> NDArray[np.float64]:
        """The force the last evaluation put on the wall particles of ``body``, ``(n, d)`` (N,
        per unit depth in 2D)."""
        ...


@runtime_checkable
class CarriesStepEndLoad(Protocol):
    """A solver that can hand out the surface load one of its bodies received during a step
    and advance the body again with a given load at the step's end: the structure's half of a
    partitioned, iterated coupling (:class:`~mlsgalerkin.interactions.StructureCoupling` with
    ``iterations > 1``; :class:`~mlsgalerkin.structure.solver.StructureSolver` implements it)."""

    def step_end_load(self, body: str) -> Any:
        """The surface load ``body`` received since the last clear, in a form only this solver
        reads (handed back unchanged to :meth:`set_step_end_load`)."""
        ...

    def set_step_end_load(self, body: str, load: Any) -> None:
        """Advance ``body`` in the next step with ``load`` (from :meth:`step_end_load`) at the
        step's end."""
        ...


# --------------------------------------------------------------------------------------
# what monitors see of a solver: its state, and why that state is unsound
# --------------------------------------------------------------------------------------


@dataclass(frozen=True)
class Diagnosis:
    """Why a system's state is unsound: what :meth:`SystemState.health` returns, the watchdog
    reports and ``summary.json`` keeps under ``"diagnosis"`` (:meth:`as_dict`).

    A system fills in what it knows; the run loop completes ``system``, ``step`` and ``time``
    (:meth:`completed`).

    Attributes
    ----------
    quantity : str
        What is wrong: ``"velocity"``, ``"density"``, ``"displacement"``, ...
    value : tuple of float
        Its value at the bad point (SI units of the quantity; a vector's components).
    problem : str
        What is wrong with it, to follow the quantity's name: ``"is not finite"``,
        ``"ρ/ρ0 = 2.31 is outside [0.5, 2.0]"``, ``"|u| = 3.2 m exceeds 1 m"``.
    limit : float or tuple of float, optional
        The limit it broke (same units; a range as ``(lo, hi)``); ``None`` for a non-finite value.
    body : str, optional
        Name of the body the bad point belongs to.
    point : str, optional
        What :attr:`index` counts: ``"particle"``, ``"node"``; ``None`` when the whole body is bad.
    index : int, optional
        Index of the bad point within its system (a particle) or its body (a node).
    position : tuple of float, optional
        Where the point is (m, ``(d,)``): its current position, or with :attr:`at_rest` its
        position at rest (a structure node, whose current position may not be finite).
    at_rest : bool
        Whether :attr:`position` is the rest position.
    system : str, optional
        Key of the system in ``RunState.systems`` (``"fluid"``, ``"structure"``).
    step, time : int and float, optional
        The step and time (s) at which the state was found unsound.
    hint : str
        What to try (one sentence; the watchdog appends it to its message).
    extras : mapping
        Further JSON-serialisable facts, kept as keys of :meth:`as_dict` (the fluid's
        ``neighbours``: the bad particle's neighbour count).
    """

    quantity: str
    value: tuple[float, ...]
    problem: str
    limit: float | tuple[float, ...] | None = None
    body: str | None = None
    point: str | None = None
    index: int | None = None
    position: tuple[float, ...] | None = None
    at_rest: bool = False
    system: str | None = None
    step: int | None = None
    time: float | None = None
    hint: str = ""
    extras: Mapping[str, Any] = field(default_factory=dict, hash=False)

    def __post_init__(self) -> None:
        object.__setattr__(self, "value", _floats(self.value))
        if self.position is not None:
            object.__setattr__(self, "position", _floats(self.position))
        if isinstance(self.limit, (tuple, list, np.ndarray)):
            object.__setattr__(self, "limit", _floats(self.limit))
        if self.index is not None:
            object.__setattr__(self, "index", int(self.index))

    def completed(self, *, system: str, step: int, time: float) -> "Diagnosis":
        """This diagnosis with ``system``, ``step`` and ``time`` filled in where it left them out."""
        return replace(self, system=self.system if self.system is not None else system,
                       step=self.step if self.step is not None else int(step),
                       time=self.time if self.time is not None else float(time))

    @property
    def where(self) -> str:
        """The bad point in words: ``"particle 7 of body 'water' at [0.1, 0.2]"``."""
        parts = []
        if self.point is not None and self.index is not None:
            parts.append(f"{self.point} {self.index}")
        if self.body is not None:
            parts.append(f"of body {self.body!r}" if parts else f"body {self.body!r}")
        if self.position is not None:
            at = "at rest at" if self.at_rest else "at"
            parts.append(f"{at} {np.round(self.position, 6).tolist()}")
        where = " ".join(parts) or "the state"
        return f"{self.system} {where}" if self.system else where

    @property
    def message(self) -> str:
        """One line for a human: when, where, what, the value and the limit, the extras."""
        when = f"at step {self.step}" if self.step is not None else "at an unknown step"
        if self.time is not None:
            when += f" (t = {self.time:.6g} s)"
        facts = [f"value {list(self.value)}"]
        if self.limit is not None:
            facts.append(f"limit {list(self.limit) if isinstance(self.limit, tuple) else self.limit}")
        facts += [f"{k} {v}" for k, v in self.extras.items()]
        return f"{when}: {self.where} — {self.quantity} {self.problem} ({', '.join(facts)})"

    def as_dict(self) -> dict[str, Any]:
        """The JSON record of ``summary.json``: every attribute, the :attr:`message`, the
        :attr:`extras` as keys of their own, and the index once more under the name of its
        point (``"particle": 7``, ``"node": 12``)."""
        out: dict[str, Any] = {
            "system": self.system, "body": self.body, "quantity": self.quantity, "value": list(self.value),
            "problem": self.problem, "limit": list(self.limit) if isinstance(self.limit, tuple) else self.limit,
            "point": self.point, "index": self.index,
            "position": None if self.position is None else list(self.position), "at_rest": self.at_rest,
            "step": self.step, "time": self.time, "message": self.message, "hint": self.hint,
        }
        if self.point is not None and self.point not in out:
            out[self.point] = self.index
        out.update({k: v for k, v in self.extras.items() if k not in out})
        return out

    @classmethod
    def from_mapping(cls, d: Mapping[str, Any]) -> "Diagnosis":
        """A diagnosis from a plain dict of the keys of :meth:`as_dict` (what a system's
        ``health`` returned before this record existed); unknown keys go to :attr:`extras`."""
        known = {"quantity", "value", "problem", "limit", "body", "point", "index", "position", "at_rest", "system",
                 "step", "time", "hint"}
        kw: dict[str, Any] = {k: d[k] for k in known if k in d}
        if "index" not in kw and "particle" in d:
            kw["point"], kw["index"] = "particle", d["particle"]
        kw.setdefault("quantity", "state")
        kw.setdefault("value", ())
        kw.setdefault("problem", "is unsound")
        extras = {k: v for k, v in d.items() if k not in known and k not in ("message", kw.get("point"))}
        return cls(**kw, extras=extras)


def _floats(x: Any) -> tuple[float, ...]:
    return tuple(float(v) for v in np.atleast_1d(np.asarray(x, dtype=float)).ravel())


@runtime_checkable
class SystemState(Protocol):
    """What the run loop and the monitors call on a solver's state (``RunState.systems[key]``,
    :attr:`Solver.state`). Monitors never see the solvers, only these.

    Optional members, looked up with ``getattr``: ``frame_name`` (str, the name of the VTU
    series, default the solver's key), ``frame_cells()`` (the cells on :meth:`frame`'s points: a
    list of ``(vtk cell type, (n_cells, k) int array)``, or one such pair) and ``n`` (the number
    of nodes counted in the run's throughput, default 0).
    """

    def observables(self) -> dict[str, float]:
        """The built-in time-series columns of this system, ``name -> value`` (SI units; the
        same names at every step from the first, so the columns of ``timeseries.csv`` stay
        fixed)."""
        ...

    def health(self, limits: Any) -> Diagnosis | None:
        """``None`` if the state is sound, else a :class:`Diagnosis` of its first bad point.
        ``limits`` is the :class:`~mlsgalerkin.monitors.Watchdog`; a system reads the limits that
        concern it (``density_ratio``, ``max_speed``, ``max_displacement``), with ``getattr`` and
        a default for a limit it may not have. Called after every step: cheap when sound."""
        ...

    def frame(self) -> tuple[NDArray[np.float64], dict[str, NDArray]]:
        """A VTU frame: points ``(n, d)`` (m) and point data, name -> ``(n,)`` or ``(n, d)`` array."""
        ...
