"""The :class:`RunState`: what monitors and probes see of a running simulation.

A contract of the run loop (beside :mod:`mlsgalerkin.dynamics`): the time, the step, the last
step size, each system's state and the interactions. It imports nothing from the run layer, so
monitors, probes and solvers can name it without an import circle.
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass, field
from typing import Any, Callable

import numpy as np

from mlsgalerkin.dynamics import Diagnosis

__all__ = ["RunState"]


@dataclass
class RunState:
    """What monitors and probes see: the time, the step, the last step size, the state of every
    system (``systems["fluid"]`` is the :class:`~mlsgalerkin.fluid.state.FluidState`) and the
    scene's interactions."""

    t: float
    step: int
    dt: float
    systems: dict[str, Any]
    interactions: tuple = ()
    _snapshot: Callable[[], tuple[dict, dict]] = field(repr=False, default=None)  # type: ignore[assignment]

    @property
    def fluid(self) -> Any:
        """The fluid state (``None`` without fluid bodies)."""
        return self.systems.get("fluid")

    def observables(self) -> dict[str, dict[str, float]]:
        """Each system's built-in time-series quantities, by system, then the interactions'
        (under ``"interactions"``)."""
        out = {k: s.observables() for k, s in self.systems.items() if hasattr(s, "observables")}
        merged: dict[str, float] = {}
        for i in self.interactions:
            merged.update(i.observables())
        if merged:
            out["interactions"] = merged
        return out

    def health(self, limits: Any) -> Diagnosis | None:
        """The first system's :class:`~mlsgalerkin.dynamics.Diagnosis` of an unsound state, with
        the system's key, the step and the time filled in (``None`` if all are sound)."""
        for key, s in self.systems.items():
            diag = s.health(limits) if hasattr(s, "health") else None
            if diag is None:
                continue
            if not isinstance(diag, Diagnosis):
                warnings.warn(f"the health() of system {key!r} returned a {type(diag).__name__}; return a "
                              "mlsgalerkin.dynamics.Diagnosis (a plain dict is read for one release)",
                              DeprecationWarning, stacklevel=2)
                diag = Diagnosis.from_mapping(diag)
            return diag.completed(system=key, step=self.step, time=self.t)
        return None

    def body(self, name: str) -> Any:
        """The live state of body ``name``, from the system that advances it: for an elastic body
        its nodal displacements ``u`` and velocities ``v`` (m, m/s; ``(n_dofs,)``), for a rigid
        body its centre ``X``, velocity ``V``, angle ``theta`` and surface load ``F`` (SI units).
        This is how a probe reads a structure::

            Probe("tip_x", lambda state: float(state.body("beam").u[k]))

        Raises ``KeyError`` naming the bodies that have a live state."""
        known: list[str] = []
        for system in self.systems.values():
            find = getattr(system, "body", None)
            names = list(getattr(system, "body_names", lambda: [])())
            if find is not None and name in names:
                return find(name)
            known += names
        raise KeyError(f"no body {name!r} with a live state in this run; bodies with one: {known}")

    def snapshot(self) -> tuple[dict[str, np.ndarray], dict[str, Any]]:
        """Arrays and metadata of a checkpoint from which the run continues bit for bit."""
        return self._snapshot()
