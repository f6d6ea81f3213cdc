"""Is the fluid state sound? The check the watchdog runs after every step.

A fluid state is unsound when a position, velocity, density or acceleration is not finite, a
density ratio ``ρ/ρ0`` leaves ``density_ratio``, or a speed exceeds ``max_speed`` (default
``2 c0``, twice the largest reference sound speed: a weakly compressible flow that fast has
left the model's validity). The :class:`~mlsgalerkin.dynamics.Diagnosis` names the first bad
particle, its body, the quantity, its value and the limit, its position and (in ``extras``) its
neighbour count, so that a user can see *where* a run broke.
"""

from __future__ import annotations

import math
from typing import Any, Protocol

import numpy as np
from numpy.typing import NDArray

from mlsgalerkin.dynamics import Diagnosis

__all__ = ["HINT", "ParticleArrays", "diagnose"]


class ParticleArrays(Protocol):
    """What the check reads of a particle state (the :class:`~mlsgalerkin.fluid.state.FluidState`
    has it): positions ``x`` (m), velocities ``v`` (m/s), accelerations ``a`` (m/s²), ``(n, d)``;
    densities ``rho`` and reference densities ``rho0`` (kg/m³), sound speeds ``c`` (m/s), ``(n,)``;
    the fluid rows ``fluid`` and their count ``n_fluid``; the neighbour table ``neighbors``; each
    body's rows ``bodies``; the step and time."""

    x: NDArray[np.float64]
    v: NDArray[np.float64]
    a: NDArray[np.float64]
    rho: NDArray[np.float64]
    rho0: NDArray[np.float64]
    c: NDArray[np.float64] | None
    n_fluid: int
    neighbors: Any
    bodies: dict[str, slice]
    step: int
    t: float

    @property
    def fluid(self) -> slice: ...

#: What to try when a fluid state is unsound.
HINT = "Try a smaller time step (the fluid scheme's safety or dt_max), more artificial viscosity, or a finer resolution."


def diagnose(s: ParticleArrays, density_ratio: tuple[float, float], max_speed: float | None) -> Diagnosis | None:
    """``None`` if the fluid state is sound, else the :class:`~mlsgalerkin.dynamics.Diagnosis` of
    the first bad particle (``point="particle"``, its index among all particles; ``extras``:
    ``neighbours``, its neighbour count, -1 before the first neighbour search)."""
    f = s.fluid
    c0 = float(np.max(s.c[f])) if s.c is not None and s.n_fluid else 0.0
    checks = (("position", s.x[f]), ("velocity", s.v[f]), ("density", s.rho[f]), ("acceleration", s.a[f]))
    for name, arr in checks:
        if not math.isfinite(float(arr.sum())):
            bad = ~np.isfinite(arr.reshape(arr.shape[0], -1)).all(axis=1)
            k = int(np.flatnonzero(bad)[0])
            return _diagnosis(s, k, name, arr[k], "is not finite", None)
    ratio = s.rho[f] / s.rho0[f]
    lo, hi = density_ratio
    if ratio.size and (ratio.min() < lo or ratio.max() > hi):
        k = int(np.argmin(ratio) if ratio.min() < lo else np.argmax(ratio))
        return _diagnosis(s, k, "density", s.rho[k], f"ρ/ρ0 = {ratio[k]:.4g} is outside [{lo}, {hi}]", (lo, hi))
    vmax = max_speed if max_speed is not None else 2.0 * max(c0, 1e-30)
    speed2 = np.einsum("ij,ij->i", s.v[f], s.v[f])
    if speed2.size and speed2.max() > vmax**2:
        k = int(np.argmax(speed2))
        return _diagnosis(s, k, "velocity", s.v[k], f"speed {math.sqrt(speed2[k]):.4g} m/s exceeds {vmax:.4g} m/s",
                          vmax)
    return None


def _diagnosis(s: ParticleArrays, k: int, quantity: str, value: Any, what: str,
               limit: float | tuple[float, float] | None) -> Diagnosis:
    body = next((name for name, sl in s.bodies.items() if sl.start <= k < sl.stop), "?")
    nnb = int(s.neighbors.indptr[k + 1] - s.neighbors.indptr[k]) if s.neighbors is not None else -1
    return Diagnosis(quantity=quantity, value=value, problem=what, limit=limit, body=body, point="particle",
                     index=k, position=s.x[k], system="fluid", step=s.step, time=s.t, hint=HINT,
                     extras={"neighbours": nnb})
