r"""Effects: the units of physics a scene lists. Nothing that is not listed is computed.

An :class:`Effect` declares the quantities it ``reads`` and ``provides`` and takes part in
some of the stages of a force evaluation, called in this order by the solver:

============  ===========================================================================
stage         what happens
============  ===========================================================================
kinematics    wall-particle velocities (before the velocity gradient is formed)
(solver)      velocity gradient ``L_k = Σ_j v_j ⊗ ∇N_j(x_k)``, continuity ``ρ̇ = −ρ tr L``
pressure      the pressure model: ``p``, sound speed ``c`` (exactly one effect)
boundary      wall-particle pressure and density
(solver)      stress ``σ = −p I``
stress        added stresses: Newtonian viscosity, bulk artificial viscosity
(solver)      ``V = M/ρ``, mass, internal force ``f_i = −Σ_k σ_k ∇N_i(x_k) V_k``
force         added nodal forces: gravity ``m_i g``, Monaghan pair viscosity
(solver)      acceleration ``a = f/m`` of the fluid particles
after_step    density re-initialisation, free-surface detection (every few steps)
============  ===========================================================================

Each effect can supply a time-step limit; the solver takes the minimum over the listed
effects and the force limit ``0.25 sqrt(h/|a|)``. The solver provides these quantities:
``positions, velocity, density, mass, volume, velocity_gradient, shape_functions, neighbors,
continuity_rate``.

Writing a new effect: subclass :class:`Effect`, set ``name``, ``stages``, ``reads`` and
``provides``, implement the stage methods (they receive the :class:`~mlsgalerkin.fluid.state.FluidState`
and modify its arrays in place), and optionally ``check`` (validation before step 1),
``time_step_limit`` and ``summary``. See ``docs/howto/write_a_scene_and_an_effect.md``.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import ArrayLike

from mlsgalerkin.fluid.eos import TaitEOS
from mlsgalerkin.fluid.state import FluidState

if TYPE_CHECKING:  # pragma: no cover
    from mlsgalerkin.scene import Scene

__all__ = [
    "STAGES",
    "SOLVER_QUANTITIES",
    "Effect",
    "TaitPressure",
    "Gravity",
    "NewtonianViscosity",
    "BulkViscosity",
    "MonaghanViscosity",
    "DensityFilter",
    "FreeSurfaceDetection",
    "Walls",
]

STAGES = ("kinematics", "pressure", "boundary", "stress", "force", "after_step")
SOLVER_QUANTITIES = frozenset({
    "positions", "velocity", "density", "mass", "volume", "velocity_gradient",
    "shape_functions", "neighbors", "continuity_rate",
})


class Effect:
    """Base class of a unit of physics (see the module docstring)."""

    name: str = "effect"
    stages: tuple[str, ...] = ()
    reads: tuple[str, ...] = ()
    provides: tuple[str, ...] = ()
    role: str = "other"  # "pressure" for the pressure model (exactly one per scene)

    def check(self, scene: "Scene") -> list[str]:
        """Problems with this effect in ``scene`` (empty if none); called before step 1."""
        return []

    def setup(self, state: FluidState, scene: "Scene") -> None:
        """Precompute what the effect needs once the particle state exists."""

    def kinematics(self, s: FluidState) -> None: ...
    def pressure(self, s: FluidState) -> None: ...
    def boundary(self, s: FluidState) -> None: ...
    def stress(self, s: FluidState) -> None: ...
    def force(self, s: FluidState) -> None: ...
    def after_step(self, s: FluidState) -> None: ...

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


def _positive(name: str, value: float, problems: list[str], owner: str, allow_zero: bool = False) -> None:
    ok = np.isfinite(value) and (value >= 0 if allow_zero else value > 0)
    if not ok:
        problems.append(f"{owner}: {name} must be {'>= 0' if allow_zero else 'positive'}, got {value!r}")


# --------------------------------------------------------------------------------------
# pressure
# --------------------------------------------------------------------------------------


class TaitPressure(Effect):
    r"""Tait equation of state per phase, ``p = B_φ[(ρ/ρ0_φ)^γ − 1]``, ``B_φ = ρ0_φ c0²/γ``.

    Give ``c0`` (m/s) or ``u_max`` (the expected largest speed; then ``c0 = u_max/mach``).
    A :class:`~mlsgalerkin.fluid.eos.MachNumberWarning` is raised when ``u_max/c0 > 0.1``.
    ``negative_pressure``: ``"allow"`` (default; a tensile-instability diagnostic counts the
    fluid particles with ``p < 0``), ``"clamp"`` (``p = max(p, 0)``; the density may still
    drift below ``ρ0``) or ``"cavitate"`` (a liquid that cannot carry tension: the density is
    floored at ``ρ0``, so ``p ≥ 0`` and a splashing particle's volume never exceeds ``M/ρ0``;
    the floorings are counted). Time-step limit: the acoustic CFL ``cfl · h/(c + |v|)``.
    """

    name = "tait_pressure"
    stages = ("pressure",)
    reads = ("density",)
    provides = ("pressure", "sound_speed")
    role = "pressure"

    def __init__(self, c0: float | None = None, *, u_max: float | None = None, mach: float = 0.1,
                 gamma: float = 7.0, cfl: float = 0.4, negative_pressure: str = "allow") -> None:
        self.c0_arg, self.u_max, self.mach, self.gamma, self.cfl = c0, u_max, mach, gamma, cfl
        self.negative_pressure = negative_pressure
        self.c0 = float(c0) if c0 is not None else (u_max / mach if u_max else float("nan"))
        self.min_pressure = math.inf
        self.max_negative_fraction = 0.0
        self.steps_with_negative = 0
        self.cavitated = 0

    def __repr__(self) -> str:
        return f"TaitPressure(c0={self.c0:g}, gamma={self.gamma:g})"

    def check(self, scene: "Scene") -> list[str]:
        problems: list[str] = []
        if self.c0_arg is None and self.u_max is None:
            problems.append("TaitPressure: give c0 (sound speed) or u_max (expected largest speed)")
        else:
            _positive("c0", self.c0, problems, "TaitPressure")
        _positive("cfl", self.cfl, problems, "TaitPressure")
        if not self.gamma >= 1:
            problems.append(f"TaitPressure: gamma must be >= 1, got {self.gamma}")
        if self.negative_pressure not in ("allow", "clamp", "cavitate"):
            problems.append("TaitPressure: negative_pressure must be 'allow', 'clamp' or 'cavitate'")
        if not problems and self.u_max is not None:
            TaitEOS(1.0, self.c0, self.gamma).check_mach(self.u_max)
        return problems

    def setup(self, state: FluidState, scene: "Scene") -> None:
        self._B_over_rho0 = self.c0**2 / self.gamma  # B = rho0 c0^2/gamma, per particle via s.rho0
        state.c = np.full(state.n, self.c0)

    def pressure(self, s: FluidState) -> None:
        f = s.fluid
        if self.negative_pressure == "cavitate":
            below = s.rho[f] < s.rho0[f]
            self.cavitated += int(np.count_nonzero(below))
            np.maximum(s.rho[f], s.rho0[f], out=s.rho[f])
        ratio = s.rho[f] / s.rho0[f]
        p = (self._B_over_rho0 * s.rho0[f]) * (ratio**self.gamma - 1.0)
        negative = p < 0.0
        n_neg = int(np.count_nonzero(negative))
        if n_neg:
            self.min_pressure = min(self.min_pressure, float(p.min()))
            self.steps_with_negative += 1
            self.max_negative_fraction = max(self.max_negative_fraction, n_neg / max(p.size, 1))
            if self.negative_pressure == "clamp":
                np.maximum(p, 0.0, out=p)
        s.p[f] = p
        s.c[f] = self.c0 * ratio ** (0.5 * (self.gamma - 1.0))

    def time_step_limit(self, s: FluidState) -> float:
        f = s.fluid
        speed = s.c[f] + np.sqrt(np.einsum("ij,ij->i", s.v[f], s.v[f]))
        return self.cfl * float(np.min(s.h[f] / speed)) if s.n_fluid else math.inf

    def summary(self) -> dict[str, Any]:
        return {
            "c0": self.c0, "gamma": self.gamma,
            "tensile_instability": {
                "min_pressure_Pa": None if math.isinf(self.min_pressure) else self.min_pressure,
                "max_fraction_negative": self.max_negative_fraction,
                "steps_with_negative_pressure": self.steps_with_negative,
                "mode": self.negative_pressure,
                "cavitation_floorings": self.cavitated,
            },
        }

    def state_dict(self) -> dict[str, Any]:
        return {"min_pressure": self.min_pressure, "max_negative_fraction": self.max_negative_fraction,
                "steps_with_negative": self.steps_with_negative, "cavitated": self.cavitated}

    def load_state_dict(self, d: dict[str, Any]) -> None:
        self.min_pressure = d["min_pressure"]
        self.max_negative_fraction = d["max_negative_fraction"]
        self.steps_with_negative = d["steps_with_negative"]
        self.cavitated = d.get("cavitated", 0)


# --------------------------------------------------------------------------------------
# forces
# --------------------------------------------------------------------------------------


class Gravity(Effect):
    """Uniform gravity: nodal force ``f_i = m_i g`` with ``m`` the mass in use.

    With the lumped mass this is exactly the Galerkin body force ``Σ_k N_i(x_k) ρ_k g V_k``
    (because ``ρ_k V_k = M_k``); with ``mass="particle"`` it is ``M_i g``; with the consistent
    mass the right-hand side is the lumped vector and the solve returns ``a = g``.
    """

    name = "gravity"
    stages = ("force",)
    reads = ("mass",)
    provides = ("gravity",)

    def __init__(self, g: ArrayLike = (0.0, -9.81)) -> None:
        self.g = np.asarray(g, dtype=float)

    def __repr__(self) -> str:
        return f"Gravity(g={self.g.tolist()})"

    def check(self, scene: "Scene") -> list[str]:
        if self.g.ndim != 1 or self.g.size != scene.dim or not np.all(np.isfinite(self.g)):
            return [f"Gravity: g must be a finite ({scene.dim},) vector, got {self.g.tolist()}"]
        return []

    def force(self, s: FluidState) -> None:
        f = s.fluid
        s.force[f] += s.mass[f, None] * self.g


class NewtonianViscosity(Effect):
    r"""Newtonian viscous stress ``σ += μ (L + Lᵀ − ⅔ tr L I)`` with each phase's viscosity.

    Wall integration points take the viscosity of the first phase. Time-step limit:
    ``0.125 h²/ν``, ``ν = μ/ρ0``.
    """

    name = "newtonian_viscosity"
    stages = ("stress",)
    reads = ("velocity_gradient",)

    def __init__(self, factor: float = 0.125) -> None:
        self.factor = factor

    def __repr__(self) -> str:
        return "NewtonianViscosity()"

    def check(self, scene: "Scene") -> list[str]:
        if not any(getattr(ph, "viscosity", 0) > 0 for b in scene.fluid_bodies for ph in b.phases):
            return ["NewtonianViscosity: every phase has zero viscosity; set Phase(viscosity=...) "
                    "or remove the effect"]
        return []

    def stress(self, s: FluidState) -> None:
        L = s.L
        d = s.dim
        D = L + np.swapaxes(L, 1, 2)
        tr = np.trace(L, axis1=1, axis2=2)
        for a in range(d):
            D[:, a, a] -= (2.0 / 3.0) * tr
        s.stress += s.mu[:, None, None] * D

    def time_step_limit(self, s: FluidState) -> float:
        f = s.fluid
        nu = s.mu[f] / s.rho0[f]
        if not np.any(nu > 0):
            return math.inf
        return self.factor * float(np.min(s.h[f] ** 2 / nu.max()))


class BulkViscosity(Effect):
    r"""Bulk artificial viscosity entered as a pressure-like stress ``σ −= q I`` (seed §7.5):

    ``q = ρ (a_L h c |∇·v| + a_N h² (∇·v)²)`` where ``∇·v < 0`` (compression), else 0 —
    the linear and von Neumann–Richtmyer terms with ``h`` for ``Δx``. It acts on compression
    only and cannot see velocity modes with zero discrete divergence (see the theory page).
    """

    name = "bulk_viscosity"
    stages = ("stress",)
    reads = ("velocity_gradient", "sound_speed", "density")

    def __init__(self, linear: float = 0.5, quadratic: float = 1.0) -> None:
        self.linear, self.quadratic = linear, quadratic

    def __repr__(self) -> str:
        return f"BulkViscosity(linear={self.linear:g}, quadratic={self.quadratic:g})"

    def check(self, scene: "Scene") -> list[str]:
        problems: list[str] = []
        _positive("linear", self.linear, problems, "BulkViscosity", allow_zero=True)
        _positive("quadratic", self.quadratic, problems, "BulkViscosity", allow_zero=True)
        return problems

    def stress(self, s: FluidState) -> None:
        f = s.fluid
        div = np.trace(s.L[f], axis1=1, axis2=2)
        comp = np.minimum(div, 0.0)
        h = s.h[f]
        q = s.rho[f] * (self.linear * h * s.c[f] * (-comp) + self.quadratic * h * h * comp * comp)
        for a in range(s.dim):
            s.stress[f, a, a] -= q

    def time_step_limit(self, s: FluidState) -> float:
        if self.linear <= 0:
            return math.inf
        f = s.fluid
        # diffusion number of the linear term: nu_b = a_L h c  ->  0.125 h^2 / nu_b
        return 0.125 * float(np.min(s.h[f] / (self.linear * s.c[f])))


class MonaghanViscosity(Effect):
    r"""Monaghan's pair artificial viscosity (seed §7.5), a pair force
    ``f_i = −Σ_j M_i M_j Π_ij ∇_i W_ij`` — momentum-conserving and able to damp the velocity
    modes that nodal integration cannot see. ``alpha`` 0.01–0.1 for water, ``beta`` 0.
    Time-step limit ``0.4 h/(c + 0.6(α c + β max φ))``.
    """

    name = "monaghan_viscosity"
    stages = ("force",)
    reads = ("velocity", "density", "sound_speed", "neighbors")

    def __init__(self, alpha: float = 0.05, beta: float = 0.0) -> None:
        self.alpha, self.beta = alpha, beta
        self.max_phi = 0.0

    def __repr__(self) -> str:
        return f"MonaghanViscosity(alpha={self.alpha:g}, beta={self.beta:g})"

    def check(self, scene: "Scene") -> list[str]:
        problems: list[str] = []
        _positive("alpha", self.alpha, problems, "MonaghanViscosity", allow_zero=True)
        _positive("beta", self.beta, problems, "MonaghanViscosity", allow_zero=True)
        return problems

    def setup(self, state: FluidState, scene: "Scene") -> None:
        from mlsgalerkin.kernels import get_kernel

        self._kernel = get_kernel(scene.approximation.kernel)
        self._active = np.zeros(state.n, dtype=bool)
        self._active[state.fluid] = True

    def force(self, s: FluidState) -> None:
        # the solver's own arrays are valid by construction: call the compiled kernel directly
        # (monaghan_viscosity_force re-validates every input, ~2.6 ms per call at 1.6e5 particles)
        from mlsgalerkin.fluid.pair_viscosity import _monaghan_kernel

        k = self._kernel
        f, row_phi = _monaghan_kernel(
            s.x, s.v, s.rho, s.c, s.M, s.h, s.neighbors.indptr, s.neighbors.indices, k.kernel_id,
            float(k.support), float(k.normalisation(s.dim)), float(self.alpha), float(self.beta), self._active,
        )
        self.max_phi = float(row_phi.max()) if row_phi.size else 0.0
        s.force[s.fluid] += f[s.fluid]

    def time_step_limit(self, s: FluidState) -> float:
        from mlsgalerkin.fluid.pair_viscosity import monaghan_time_step_limit

        f = s.fluid
        return monaghan_time_step_limit(s.h[f], s.c[f], self.alpha, self.beta, self.max_phi)

    def state_dict(self) -> dict[str, Any]:
        return {"max_phi": self.max_phi}

    def load_state_dict(self, d: dict[str, Any]) -> None:
        self.max_phi = d["max_phi"]


# --------------------------------------------------------------------------------------
# after-step effects
# --------------------------------------------------------------------------------------


class DensityFilter(Effect):
    r"""Density re-initialisation every ``every`` steps (MLS filter of ``ρ/ρ0``):

    ``ρ_i ← ρ0_i Σ_{j∈fluid} N_j(x_i) (ρ_j/ρ0_j) / Σ_{j∈fluid} N_j(x_i)``.

    Filtering the ratio ``ρ/ρ0`` rather than ``ρ`` keeps a density jump between phases sharp.
    The linear MLS filter reproduces a hydrostatic (linear) density exactly in the interior;
    points whose fluid shape functions sum to less than ``0.5`` keep their density.
    ``method="shepard"`` uses ``N_j = V_j W_ij / Σ V W`` instead (zeroth order).
    """

    name = "density_filter"
    stages = ("after_step",)
    reads = ("density", "shape_functions")

    def __init__(self, every: int = 20, method: str = "mls") -> None:
        self.every, self.method = every, method
        self.applied = 0

    def __repr__(self) -> str:
        return f"DensityFilter(every={self.every}, method={self.method!r})"

    def check(self, scene: "Scene") -> list[str]:
        problems = []
        if not (isinstance(self.every, (int, np.integer)) and self.every >= 1):
            problems.append(f"DensityFilter: every must be a positive integer, got {self.every!r}")
        if self.method not in ("mls", "shepard"):
            problems.append(f"DensityFilter: method must be 'mls' or 'shepard', got {self.method!r}")
        return problems

    def setup(self, state: FluidState, scene: "Scene") -> None:
        self._kernel = scene.approximation.kernel

    def after_step(self, s: FluidState) -> None:
        if s.step % self.every:
            return
        from mlsgalerkin.fluid.filters import mls_ratio_filter, shepard_ratio_filter

        if self.method == "mls":
            mls_ratio_filter(s.table, s.rho, s.rho0, s.n_fluid)
        else:
            shepard_ratio_filter(s.neighbors, s.x, s.rho, s.rho0, s.M, s.h, s.n_fluid, self._kernel)
        self.applied += 1

    def summary(self) -> dict[str, Any]:
        return {"applications": self.applied}

    def state_dict(self) -> dict[str, Any]:
        return {"applied": self.applied}

    def load_state_dict(self, d: dict[str, Any]) -> None:
        self.applied = d["applied"]


class FreeSurfaceDetection(Effect):
    """Flags free-surface particles every ``every`` steps into ``s.extra["free_surface"]``.

    ``method="circle"``: the seed's 2D 360-point circle-coverage test (radius 1.05 Δx);
    ``method="cheap"``: the neighbour-deficit screen of :mod:`mlsgalerkin.fluid.free_surface`.
    The Galerkin weak form needs no surface condition (traction-free is natural); the flags
    serve output and diagnostics.
    """

    name = "free_surface"
    stages = ("after_step",)
    reads = ("positions", "neighbors")
    provides = ("free_surface",)

    def __init__(self, method: str = "circle", every: int = 10) -> None:
        self.method, self.every = method, every
        self.count = 0

    def __repr__(self) -> str:
        return f"FreeSurfaceDetection(method={self.method!r}, every={self.every})"

    def check(self, scene: "Scene") -> list[str]:
        problems = []
        if self.method not in ("circle", "cheap"):
            problems.append(f"FreeSurfaceDetection: method must be 'circle' or 'cheap', got {self.method!r}")
        if self.method == "circle" and scene.dim != 2:
            problems.append("FreeSurfaceDetection: the circle-coverage test is 2D; use method='cheap' in 3D")
        return problems

    def setup(self, state: FluidState, scene: "Scene") -> None:
        state.extra["free_surface"] = np.zeros(state.n, dtype=bool)

    def after_step(self, s: FluidState) -> None:
        if s.step % self.every and s.step > 1:
            return
        from mlsgalerkin.fluid.free_surface import detect_free_surface

        flags = detect_free_surface(s.x, s.neighbors, s.spacing, method=self.method)
        flags[s.walls] = False
        s.extra["free_surface"] = flags
        self.count = int(np.count_nonzero(flags))

    def summary(self) -> dict[str, Any]:
        return {"method": self.method, "last_count": self.count}


# --------------------------------------------------------------------------------------
# walls
# --------------------------------------------------------------------------------------


class Walls(Effect):
    """Fixed wall particles: extrapolated pressure, density and velocity (see
    :mod:`mlsgalerkin.fluid.walls`). ``slip`` is ``"free_slip"`` (default), ``"no_slip"`` or
    ``"fixed"``. The hydrostatic term uses the gravity of a listed :class:`Gravity` effect.
    """

    name = "walls"
    stages = ("kinematics", "boundary")
    reads = ("velocity", "pressure", "density", "neighbors")
    provides = ("wall_state",)

    def __init__(self, slip: str = "free_slip") -> None:
        self.slip = slip

    def __repr__(self) -> str:
        return f"Walls(slip={self.slip!r})"

    def check(self, scene: "Scene") -> list[str]:
        from mlsgalerkin.fluid.walls import SLIP_MODES

        problems = []
        if self.slip not in SLIP_MODES:
            problems.append(f"Walls: slip must be one of {sorted(SLIP_MODES)}, got {self.slip!r}")
        if not scene.wall_bodies:
            problems.append("Walls: the scene has no WallBody; add one or remove the effect")
        if self.slip == "free_slip" and any(w.normals is None for w in scene.wall_bodies):
            problems.append("Walls: free_slip needs wall normals (WallBody(normals=...)); "
                            "wall_box() provides them")
        return problems

    def setup(self, state: FluidState, scene: "Scene") -> None:
        from mlsgalerkin.kernels import get_kernel

        self._kernel = get_kernel(scene.approximation.kernel)
        self._ids = np.arange(state.n_fluid, state.n, dtype=np.int64)
        self._is_fluid = np.zeros(state.n, dtype=bool)
        self._is_fluid[state.fluid] = True
        grav = [e for e in scene.effects if isinstance(e, Gravity)]
        self._g = grav[0].g if grav else np.zeros(state.dim)
        self._rho_ref = state.rho0[state.walls].copy()
        self._rho_w = None

    def _extrapolate(self, s: FluidState):
        from mlsgalerkin.fluid.walls import extrapolate_wall_state

        nb = s.neighbors
        return extrapolate_wall_state(
            self._ids, nb.indptr, nb.indices, s.x, s.v, s.rho, s.p, s.h, self._is_fluid, self._kernel,
            self._g, s.wall_velocity, s.wall_normals, self.slip, self._rho_ref,
        )

    def kinematics(self, s: FluidState) -> None:
        if s.n_walls:
            _, _, v_w = self._extrapolate(s)
            s.v[s.walls] = v_w

    def boundary(self, s: FluidState) -> None:
        if s.n_walls:
            p_w, rho_w, _ = self._extrapolate(s)
            w = s.walls
            s.p[w] = p_w
            s.rho[w] = rho_w
            s.M[w] = rho_w * s.wall_volume
