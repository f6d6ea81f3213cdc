r"""The particle state a fluid simulation advances, as flat struct-of-arrays.

All particles of all bodies live in one set: fluid particles first (``[0, n_fluid)``), then
wall particles. Every particle is a node of the MLS approximation and an integration point of
the nodal Galerkin sums. Arrays (``n`` particles, ``d`` dimensions, SI units):

==============  ==========  ===============================================================
name            shape       meaning
==============  ==========  ===============================================================
``x``           (n, d)      positions (m)
``v``           (n, d)      nodal velocities (m/s); wall rows hold the extrapolated velocity
``rho``         (n,)        density (kg/m^3); wall rows extrapolated every step
``M``           (n,)        physical particle mass (kg per unit depth in 2D); constant for fluid
``h``           (n,)        smoothing length (m)
``rho0``        (n,)        reference density of the particle's phase (walls: reference)
``mu``          (n,)        dynamic viscosity (Pa s)
``phase``       (n,)        phase index (-1 for walls)
``a``           (n, d)      acceleration from the last force evaluation (m/s^2)
``drho``        (n,)        continuity rate ``−ρ ∇·v`` from the last evaluation (kg/m^3/s)
``p``           (n,)        pressure from the last evaluation (Pa)
==============  ==========  ===============================================================

Derived per evaluation and not part of a checkpoint: the neighbour and shape tables, the
velocity gradient ``L (n, d, d)``, the sound speed, stress, force, the mass in use.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import NDArray

__all__ = ["FluidState", "CHECKPOINT_ARRAYS"]

#: Arrays that fully determine the continuation of a run (with ``t``, ``step``, ``dt_next``).
CHECKPOINT_ARRAYS = ("x", "v", "rho", "M", "a", "drho", "p", "x_ref")


@dataclass
class FluidState:
    """Flat particle arrays plus the time-stepping counters (see the module docstring)."""

    x: NDArray[np.float64]
    v: NDArray[np.float64]
    rho: NDArray[np.float64]
    M: NDArray[np.float64]
    h: NDArray[np.float64]
    rho0: NDArray[np.float64]
    mu: NDArray[np.float64]
    phase: NDArray[np.int64]
    n_fluid: int
    spacing: float
    wall_volume: NDArray[np.float64]
    wall_normals: NDArray[np.float64]
    wall_velocity: NDArray[np.float64]
    bodies: dict[str, slice]
    t: float = 0.0
    step: int = 0
    dt_next: float = 0.0
    a: NDArray[np.float64] = field(default=None)  # type: ignore[assignment]
    drho: NDArray[np.float64] = field(default=None)  # type: ignore[assignment]
    p: NDArray[np.float64] = field(default=None)  # type: ignore[assignment]
    x_ref: NDArray[np.float64] = field(default=None)  # type: ignore[assignment]
    # per-evaluation quantities (not checkpointed)
    neighbors: Any = None
    table: Any = None
    L: NDArray[np.float64] | None = None
    c: NDArray[np.float64] | None = None
    stress: NDArray[np.float64] | None = None
    force: NDArray[np.float64] | None = None
    mass: NDArray[np.float64] | None = None
    volume: NDArray[np.float64] | None = None
    extra: dict[str, NDArray] = field(default_factory=dict)

    def __post_init__(self) -> None:
        n, d = self.x.shape
        if self.a is None:
            self.a = np.zeros((n, d))
        if self.drho is None:
            self.drho = np.zeros(n)
        if self.p is None:
            self.p = np.zeros(n)
        if self.x_ref is None:
            self.x_ref = self.x.copy()

    @property
    def n(self) -> int:
        return self.x.shape[0]

    @property
    def dim(self) -> int:
        return self.x.shape[1]

    @property
    def fluid(self) -> slice:
        """Slice of the fluid particles."""
        return slice(0, self.n_fluid)

    @property
    def walls(self) -> slice:
        """Slice of the wall particles."""
        return slice(self.n_fluid, self.n)

    @property
    def n_walls(self) -> int:
        return self.n - self.n_fluid

    def kinetic_energy(self) -> float:
        """``½ Σ_f M_f |v_f|²`` over the fluid particles (J per unit depth in 2D)."""
        f = self.fluid
        # einsum, not BLAS: OpenBLAS worker threads spin after a call and steal the cores of
        # the numba kernels of the next step (measured 3-7x slower steps with per-step probes)
        return 0.5 * float(np.einsum("i,ij,ij->", self.M[f], self.v[f], self.v[f]))

    def momentum(self) -> NDArray[np.float64]:
        """``Σ_f M_f v_f`` over the fluid particles, ``(d,)``."""
        f = self.fluid
        return np.einsum("i,ij->j", self.M[f], self.v[f])

    def total_mass(self) -> float:
        """``Σ_f M_f`` (constant by construction)."""
        return float(self.M[self.fluid].sum())
