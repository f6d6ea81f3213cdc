r"""What every structure stepper shares: the body it advances, the ramp of the surface load over
an outer step, and the counters of its work.

**Surface forces over a step.** The forces the interactions add at :math:`t_n` (contact, the
fluid's reaction on the wall particles riding on the body) act over the outer step
:math:`[t_n, t_{n+1}]` as a linear ramp from :math:`\mathbf f_n` to its extrapolation

.. math:: \mathbf f_{n+1} \approx \mathbf f_n + \frac{\Delta t_n}{\Delta t_{n-1}}(\mathbf f_n - \mathbf f_{n-1}),

so their mean over the step is the second-order estimate of :math:`\mathbf f(t_{n+1/2})`. Two
simpler choices were measured unstable on the plate under a water column
(``hydrostatic_plate``, 2 m of water on a 5 cm aluminium plate): holding :math:`\mathbf f_n`
over the step (a lag of half a step; the plate gained energy at an e-fold every few
milliseconds) and applying :math:`\mathbf f_n` as impulses at the step boundaries as the fluid's
kick-drift-kick does (every impulse rings the plate's stiff through-thickness modes, which the
fluid then sees). The wall pressure must also see the surface's acceleration
(:class:`~mlsgalerkin.interactions.StructureCoupling`): without it the same plate diverged.
A partitioned iteration may set the step's end load instead of the extrapolation
(:meth:`Stepper.set_step_end_load`).

Every stepper keeps the work of the surface forces (the ramp's mean load on the step's motion
of the surface) for the energy balance of a coupled run.
"""

from __future__ import annotations

import time
from abc import ABC, abstractmethod
from typing import Any, ClassVar

import numpy as np
from numpy.typing import NDArray

from mlsgalerkin.dynamics import Body, Surface

__all__ = ["Stepper", "extrapolated"]

FloatArray = NDArray[np.float64]
Load = FloatArray | float


def extrapolated(now: Load, before: Load, dt: float, dt_prev: float) -> Load:
    """The load at the end of a step of ``dt`` (s): ``now + (dt/dt_prev)(now − before)`` from the
    loads of the last two exchanges, ``dt_prev`` (s) apart; ``now`` (a copy) at the first step
    (``dt_prev == 0``). Arrays of any shape or floats."""
    if dt_prev > 0:
        return now + (dt / dt_prev) * (now - before)
    return now.copy() if isinstance(now, np.ndarray) else now


class Stepper(ABC):
    """The live state of one structure body and how it advances over an outer step.

    The body is the spec (mesh, material, mass, constraint); the stepper holds what changes in a
    run: the motion, the surface load of the last exchange and the one before (for the ramp,
    module docstring), the work of that load (J, per unit depth in 2D) and the counters
    ``substeps``, ``outer_steps`` and ``seconds`` (wall time in :meth:`advance`)."""

    #: The kind of body in ``summary.json``: ``"elastic"`` or ``"rigid"``.
    kind: ClassVar[str]

    def __init__(self, body: Body) -> None:
        self.body = body
        self.dt_prev = 0.0            # the last outer step (s)
        self.work = 0.0               # work of the surface forces (J, per unit depth in 2D)
        self.substeps = 0
        self.outer_steps = 0
        self.seconds = 0.0
        self._end: tuple[Load, ...] | None = None   # the next step's end load, if set

    # ------------------------------------------------------------------ the load ramp
    def _ramp_end(self, start: tuple[Load, ...], before: tuple[Load, ...], dt: float) -> tuple[Load, ...]:
        """The parts of the load at the end of the step ``dt`` (s) from those at its start and at
        the exchange before: as set by :meth:`set_step_end_load`, else extrapolated (module
        docstring). Records ``dt`` as the last step."""
        if self._end is not None:
            end, self._end = self._end, None
        else:
            end = tuple(extrapolated(s, b, dt, self.dt_prev) for s, b in zip(start, before))
        self.dt_prev = dt
        return end

    @abstractmethod
    def step_end_load(self) -> Any:
        """The surface load added since the last clear (for a partitioned iteration)."""

    @abstractmethod
    def set_step_end_load(self, load: Any) -> None:
        """Use ``load`` (as :meth:`step_end_load` gives it) at the end of the next step instead of
        the extrapolation."""

    # ------------------------------------------------------------------ stepping
    def advance(self, dt: float) -> None:
        """Advance over the outer step ``dt`` (s) under the body's own forces and the surface
        load ramped from the last exchange's to the step's end load."""
        t0 = time.perf_counter()
        self.substeps += self._advance(dt)
        self.outer_steps += 1
        self.seconds += time.perf_counter() - t0

    @abstractmethod
    def _advance(self, dt: float) -> int:
        """Advance over ``dt`` (s), add the surface load's work; return the sub-steps taken."""

    @abstractmethod
    def start(self) -> None:
        """Set the accelerations at the start of the run (or after a restore)."""

    # ------------------------------------------------------------------ the surface
    @property
    @abstractmethod
    def n_surface(self) -> int:
        """Nodes of :meth:`surface`."""

    @abstractmethod
    def surface(self) -> Surface:
        """The surface the interactions see now: node positions, velocities, accelerations."""

    @abstractmethod
    def add_forces(self, forces: FloatArray) -> None:
        """Add surface forces ``(n_surface, d)`` (N, per unit depth in 2D) on the surface nodes."""

    @abstractmethod
    def clear_forces(self) -> None:
        """Forget the surface forces added (before an exchange)."""

    # ------------------------------------------------------------------ records
    @abstractmethod
    def energies(self) -> dict[str, float]:
        """The body's energies and the surface work (J, per unit depth in 2D)."""

    @abstractmethod
    def observables(self) -> dict[str, float]:
        """The body's time-series columns (without the body's name)."""

    @abstractmethod
    def frame(self) -> tuple[FloatArray, dict[str, FloatArray]]:
        """Points ``(n_frame_points, d)`` (m) of an output frame and their ``displacement`` and
        ``velocity``."""

    @property
    @abstractmethod
    def n_frame_points(self) -> int:
        """Points of :meth:`frame`."""

    @abstractmethod
    def frame_cells(self) -> tuple[str, NDArray[np.int64]]:
        """The cells on :meth:`frame`'s points: a meshio cell type and the connectivity."""

    @abstractmethod
    def finite(self) -> bool:
        """Whether the motion is finite."""

    @abstractmethod
    def checkpoint(self) -> dict[str, FloatArray]:
        """The arrays :meth:`restore` continues from, bit for bit."""

    @abstractmethod
    def restore(self, arrays: dict[str, FloatArray]) -> None:
        """Continue from :meth:`checkpoint`'s arrays."""

    @abstractmethod
    def summary(self) -> dict[str, Any]:
        """The body's entry in ``summary.json``."""
