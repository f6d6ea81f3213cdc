r"""The particle state the fluid solver advances, as flat struct-of-arrays.

All particles of a scene's fluid and wall bodies live in one set: fluid particles first
(``[0, n_fluid)``), then wall particles; ``bodies`` maps each body's name to its slice. Every
particle is a node of the MLS approximation and an integration point of the nodal Galerkin
sums. Arrays (``n`` particles, ``n_w`` wall particles, ``d`` dimensions, SI units):

=====================  ==========  ========================================================
name                   shape       meaning
=====================  ==========  ========================================================
``x``                  (n, d)      positions (m); wall rows follow the walls' motion
``v``                  (n, d)      nodal velocities (m/s); wall rows hold the extrapolated velocity
``rho``                (n,)        density (kg/m^3); wall rows extrapolated every step
``M``                  (n,)        physical particle mass (kg per unit depth in 2D); constant for fluid
``h``                  (n,)        smoothing length (m)
``rho0``               (n,)        reference density of the particle's phase (walls: reference)
``mu``                 (n,)        dynamic viscosity (Pa s)
``phase``              (n,)        phase index (-1 for walls)
``a``                  (n, d)      acceleration from the last force evaluation (m/s^2)
``drho``               (n,)        continuity rate ``−ρ ∇·v`` from the last evaluation (kg/m^3/s)
``p``                  (n,)        pressure from the last evaluation (Pa)
``wall_velocity``      (n_w, d)    velocity of the wall surface at each wall particle (m/s)
``wall_acceleration``  (n_w, d)    acceleration of the wall at each wall particle (m/s^2)
``wall_normals``       (n_w, d)    unit normals into the fluid (turn with a rotating wall)
``gravity``            (d,)        the body-force acceleration (m/s^2), ``None`` without ``Gravity``
``period``             3 floats    periods of the periodic axes (m), 0 for the others (all 0: none);
                                   every pair kernel takes it (minimum-image offsets)
``wall_surfaces``      dict        each wall body's penalty surface now (:class:`WallSurfaceState`:
                                   facets, node positions and velocities, moved with the wall)
``sensors``            dict        scalar readings of the last evaluation that become time-series
                                   columns (the wall force sensors of ``PenaltyWalls``)
=====================  ==========  ========================================================

Derived per evaluation and not part of a checkpoint: the neighbour and shape tables, the
velocity gradient ``L (n, d, d)``, the sound speed, stress, force, the mass in use, and the
number of fluid particles whose shape functions fell back to a lower order
(``fallback_count``).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any, ClassVar

import numpy as np
from numpy.typing import NDArray

if TYPE_CHECKING:  # pragma: no cover
    from mlsgalerkin.dynamics import Diagnosis

__all__ = ["CHECKPOINT_ARRAYS", "FluidState", "WallSurfaceState"]

#: Arrays that fully determine the continuation of a run (with ``t``, ``step``, ``dt_next``).
CHECKPOINT_ARRAYS = ("x", "v", "rho", "M", "a", "drho", "p", "x_ref")


@dataclass
class WallSurfaceState:
    """A wall body's penalty surface at the current evaluation's time.

    ``facets (k, d)`` node indices (oriented as in
    :class:`~mlsgalerkin.contact.surface.ContactSurface`), node positions ``x (m, d)`` (m) and
    velocities ``v (m, d)`` (m/s); the fluid solver moves them with the wall's motion.
    """

    facets: NDArray[np.int64]
    x: NDArray[np.float64]
    v: NDArray[np.float64]


@dataclass
class FluidState:
    """Flat particle arrays plus the time-stepping counters (see the module docstring)."""

    #: Name of this system's VTU series (``particles.pvd``).
    frame_name: ClassVar[str] = "particles"
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
    wall_acceleration: NDArray[np.float64] = field(default=None)  # type: ignore[assignment]
    gravity: NDArray[np.float64] | None = None
    period: tuple[float, float, float] = (0.0, 0.0, 0.0)
    #: The pressure model's reference sound speed ``c0`` (m/s) and exponent ``γ``, written by it in
    #: its set-up (before any other effect's): what the effects that scale with the sound speed read.
    c0: float = float("nan")
    gamma: float = 7.0
    approximation_order: int = 1
    # per-evaluation quantities (not checkpointed)
    neighbors: Any = None
    table: Any = None
    L: NDArray[np.float64] | None = None
    c: NDArray[np.float64] | None = None
    stress: NDArray[np.float64] | None = None
    force: NDArray[np.float64] | None = None
    mass: NDArray[np.float64] | None = None
    volume: NDArray[np.float64] | None = None
    fallback_count: int = 0
    wall_penetrations: int | None = None
    max_wall_penetration_dx: float | None = None
    extra: dict[str, NDArray] = field(default_factory=dict)
    wall_surfaces: dict[str, WallSurfaceState] = field(default_factory=dict)
    sensors: dict[str, float] = field(default_factory=dict)
    #: The run's volume, distribution and Mach-number checks
    #: (:class:`~mlsgalerkin.fluid.run_checks.FluidRunChecks`; the solver sets it), ``None`` alone.
    run_checks: Any = None

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
        if self.wall_acceleration is None:
            self.wall_acceleration = np.zeros((n - self.n_fluid, d))

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

    def potential_energy(self) -> float | None:
        """``−Σ_f M_f g·x_f`` (J per unit depth in 2D), ``None`` without gravity."""
        if self.gravity is None:
            return None
        f = self.fluid
        return -float(np.einsum("i,ij,j->", self.M[f], self.x[f], self.gravity))  # no BLAS

    def momentum(self) -> NDArray[np.float64]:
        """``Σ_f M_f v_f`` over the fluid particles, ``(d,)``."""
        f = self.fluid
        return np.einsum("i,ij->j", self.M[f], self.v[f])

    def total_mass(self) -> float:
        """``Σ_f M_f`` (constant by construction)."""
        return float(self.M[self.fluid].sum())

    # ------------------------------------------------------------------ what monitors see
    def observables(self) -> dict[str, float]:
        """The built-in time-series columns: kinetic energy, total mass, potential energy
        (with gravity), momentum, largest speed, density-ratio range, shape-function fallbacks
        of the last evaluation, wall penetration (when measured), the :attr:`sensors`, then the
        columns of the :attr:`run_checks` (geometric volume and volume error, pair distances,
        clumped pairs, Mach number; :mod:`mlsgalerkin.fluid.run_checks`)."""
        f = self.fluid
        speed2 = np.einsum("ij,ij->i", self.v[f], self.v[f])
        ratio = self.rho[f] / self.rho0[f]
        row: dict[str, float] = {"kinetic_energy": self.kinetic_energy(), "total_mass": self.total_mass()}
        pe = self.potential_energy()
        if pe is not None:
            row["potential_energy"] = pe
        mom = self.momentum()
        for a in range(self.dim):
            row[f"momentum_{'xyz'[a]}"] = float(mom[a])
        row["max_speed"] = float(np.sqrt(speed2.max())) if speed2.size else 0.0
        row["min_density_ratio"] = float(ratio.min()) if ratio.size else 1.0
        row["max_density_ratio"] = float(ratio.max()) if ratio.size else 1.0
        row["fallback_points"] = int(self.fallback_count)
        if self.wall_penetrations is not None:
            row["wall_penetrations"] = int(self.wall_penetrations)
            row["max_wall_penetration_dx"] = float(self.max_wall_penetration_dx)
        if "outside" in self.extra:      # fluid particles taken out of the run (fluid.domain_exit)
            row["particles_outside"] = int(np.count_nonzero(self.extra["outside"]))
        row.update(self.sensors)
        if self.run_checks is not None:
            row.update(self.run_checks.row(self))
        return row

    def frame(self) -> tuple[NDArray[np.float64], dict[str, NDArray]]:
        """Points ``(n, d)`` and point data of a VTU frame: velocity, pressure, density, density
        ratio, phase, wall flag, speed, MLS order and the ``extra`` fields."""
        data = {
            "velocity": self.v, "pressure": self.p, "density": self.rho, "density_ratio": self.rho / self.rho0,
            "phase": self.phase.astype(np.int32), "is_wall": (np.arange(self.n) >= self.n_fluid).astype(np.int32),
            "speed": np.sqrt(np.einsum("ij,ij->i", self.v, self.v)),
        }
        if self.table is not None:
            data["mls_order"] = self.table.order.astype(np.int32)
        for k, v in self.extra.items():
            data[k] = np.asarray(v).astype(np.int32) if np.asarray(v).dtype == bool else v
        return self.x, data

    def health(self, limits: Any) -> "Diagnosis | None":
        """``None`` if the fluid is sound, else a :class:`~mlsgalerkin.dynamics.Diagnosis`
        (:func:`mlsgalerkin.fluid.health.diagnose`) with ``limits.density_ratio`` and
        ``limits.max_speed`` (a :class:`~mlsgalerkin.monitors.Watchdog`)."""
        from mlsgalerkin.fluid.health import diagnose

        return diagnose(self, limits.density_ratio, limits.max_speed)
