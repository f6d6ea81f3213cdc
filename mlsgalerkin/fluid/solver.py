r"""The fluid solver: advances the fluid and wall particles of a scene.

One force evaluation (``docs/theory/galerkin_fluid.md``) is split in two so the integrator can
advance the density between them:

1. :meth:`FluidSolver.kinematics` — neighbours (rebuilt with a skin), MLS/RKPM shape functions
   and gradients at every particle, wall velocities, ``L_k = Σ_j v_j ⊗ ∇N_j(x_k)``,
   collocated continuity ``ρ̇_k = −ρ_k tr L_k``;
2. :meth:`FluidSolver.dynamics` — pressure, wall state, stress, ``V = M/ρ``, mass, internal
   force ``f_i = −Σ_k σ_k ∇N_i(x_k) V_k`` by the Galerkin scatter, the forces of interactions,
   the listed forces, ``a = f/m``.

The time integrator (:mod:`mlsgalerkin.fluid.integrators`) is chosen once from
``FluidScheme.integrator``; the mass option (:mod:`mlsgalerkin.fluid.mass`) from
``FluidScheme.mass``.
Walls with a prescribed motion (their particles and penalty surfaces) are moved to each
evaluation's time before its kinematics.
Only the listed effects are ever called: each stage calls the effects that declared it.
"""

from __future__ import annotations

import logging
import math
import time
import warnings
from typing import Any

import numpy as np

from mlsgalerkin.approximation.build import evaluate_shape_functions
from mlsgalerkin.assembly import internal_force_and_mass, velocity_gradient_divergence
from mlsgalerkin.dynamics import SceneView, Solver, Surface
from mlsgalerkin.fluid.bodies import FluidBody, WallBody
from mlsgalerkin.fluid.domain_exit import OUTSIDE, DomainExit
from mlsgalerkin.fluid.effect import SOLVER_QUANTITIES, STAGES, Effect
from mlsgalerkin.fluid.geometry import geometry_problems
from mlsgalerkin.fluid.integrators import make_integrator
from mlsgalerkin.fluid.penetration import PENETRATION_WARNING, penetration_depths, surface_offsets
from mlsgalerkin.fluid.eos import MachNumberWarning
from mlsgalerkin.fluid.run_checks import (
    FluidRunChecks,
    ParticleClumpingWarning,
    ShapeFunctionFallbackWarning,
    VolumeErrorWarning,
)
from mlsgalerkin.fluid.mass import (
    consistent_acceleration,
    floor_lumped_mass,
    warn_consistent_unconverged,
)
from mlsgalerkin.fluid.scheme import SPACING_TOLERANCE, FluidContext, FluidScheme
from mlsgalerkin.fluid.state import CHECKPOINT_ARRAYS, FluidState, WallSurfaceState
from mlsgalerkin.fluid.time_step import force_limit
from mlsgalerkin.io.files import to_jsonable
from mlsgalerkin.kernels import get_kernel
from mlsgalerkin.neighbors import find_neighbors
from mlsgalerkin.periodic import Periodic, kernel_period, minimum_image

__all__ = ["FluidSolver", "MachNumberWarning", "ParticleClumpingWarning", "ShapeFunctionFallbackWarning",
           "StageTimer", "VolumeErrorWarning", "WallPenetrationWarning", "build_state"]


class WallPenetrationWarning(UserWarning):
    """Fluid particles have crossed the first layer of a wall (see :mod:`mlsgalerkin.fluid.penetration`).
    The warnings of the run's other checks (volume, clumping, Mach number, shape-function
    fallbacks; :mod:`mlsgalerkin.fluid.run_checks`) are imported here beside it."""

logger = logging.getLogger(__name__)


class StageTimer:
    """Wall time per named stage (s), accumulated over a run."""

    def __init__(self) -> None:
        self.seconds: dict[str, float] = {}

    def add(self, name: str, t0: float) -> float:
        """Add ``now − t0`` to ``name``; returns now (the start of the next stage)."""
        t1 = time.perf_counter()
        self.seconds[name] = self.seconds.get(name, 0.0) + (t1 - t0)
        return t1


def build_state(fluids: list[FluidBody], walls: list[WallBody], h_factor: float) -> FluidState:
    """Flatten fluid and wall bodies into one :class:`FluidState` (fluid first, then walls).

    The smoothing length is ``h = h_factor · Δx`` with each fluid body's spacing; wall particles
    take the first fluid body's (the fluid bodies share one spacing). A wall body that is only a
    penalty surface adds no particles; its surface is in ``wall_surfaces`` (at rest, velocity
    the wall's ``velocity``).
    """
    dim = (fluids or walls)[0].dim
    dx = fluids[0].spacing
    bodies: dict[str, slice] = {}
    xs, vs, rhos, Ms, hs, rho0s, mus, phases = [], [], [], [], [], [], [], []
    start = 0
    phase_offset = 0
    for b in fluids:
        xs.append(b.positions)
        vs.append(b.velocity)
        rhos.append(b.density)
        Ms.append(b.density * b.spacing**dim)
        hs.append(np.full(b.n, h_factor * b.spacing))
        rho0s.append(b.reference_density)
        mus.append(b.viscosity)
        phases.append(b.phase + phase_offset)
        phase_offset += len(b.phases)
        bodies[b.name] = slice(start, start + b.n)
        start += b.n
    n_fluid = start
    mu_wall = fluids[0].phases[0].viscosity if fluids else 0.0
    wall_vol, wall_n, wall_v = [], [], []
    for w in walls:
        if w.n == 0:
            continue
        xs.append(w.positions)
        vs.append(np.broadcast_to(w.velocity, (w.n, dim)))
        rhos.append(np.full(w.n, w.reference_density))
        volume = w.volumes if w.volumes is not None else np.full(w.n, w.spacing**dim)
        Ms.append(w.reference_density * volume)
        hs.append(np.full(w.n, h_factor * dx))
        rho0s.append(np.full(w.n, w.reference_density))
        mus.append(np.full(w.n, mu_wall))
        phases.append(np.full(w.n, -1))
        wall_vol.append(volume)
        wall_n.append(w.normals if w.normals is not None else np.zeros((w.n, dim)))
        wall_v.append(np.broadcast_to(w.velocity, (w.n, dim)))
        bodies[w.name] = slice(start, start + w.n)
        start += w.n
    cat = lambda a, shape: np.ascontiguousarray(np.concatenate(a)) if a else np.zeros(shape)  # noqa: E731
    for w in walls:
        if w.n == 0:
            bodies[w.name] = slice(start, start)
    surfaces = {w.name: WallSurfaceState(w.surface.facets.copy(), w.surface.nodes.copy(),
                                         np.array(np.broadcast_to(w.velocity, w.surface.nodes.shape), dtype=float))
                for w in walls if w.surface is not None}
    return FluidState(
        x=cat(xs, (0, dim)), v=cat(vs, (0, dim)).astype(float), rho=cat(rhos, (0,)), M=cat(Ms, (0,)),
        h=cat(hs, (0,)), rho0=cat(rho0s, (0,)), mu=cat(mus, (0,)), phase=cat(phases, (0,)).astype(np.int64),
        n_fluid=n_fluid, spacing=dx, wall_volume=cat(wall_vol, (0,)), wall_normals=cat(wall_n, (0, dim)),
        wall_velocity=cat(wall_v, (0, dim)), bodies=bodies, wall_surfaces=surfaces,
    )


class FluidSolver(Solver):
    """Advances the fluid and wall bodies of a scene (see the module docstring).

    Built by :class:`~mlsgalerkin.simulation.Simulation` from the scene's
    :class:`~mlsgalerkin.fluid.bodies.FluidBody` and :class:`~mlsgalerkin.fluid.bodies.WallBody`
    bodies and the fluid's :class:`~mlsgalerkin.fluid.scheme.FluidScheme` (effects,
    ``approximation``, ``integrator``, ``mass``, ``safety``, ``dt_max``, ``spacing``).
    """

    key = "fluid"
    scheme_class = FluidScheme

    # ------------------------------------------------------------------ validation
    @classmethod
    def problems(cls, bodies: list, scheme: FluidScheme, scene: SceneView) -> list[str]:
        """Every problem with the fluid bodies, the effects of ``scheme`` and their spacing
        (the scheme's options alone are checked by :meth:`FluidScheme.problems`)."""
        out: list[str] = []
        fluids = [b for b in bodies if isinstance(b, FluidBody)]
        if not fluids:
            out.append("no FluidBody: wall bodies need at least one fluid body")
        spacings = {b.spacing for b in fluids}
        if len(spacings) > 1:
            out.append(f"fluid bodies must share one particle spacing, got {sorted(spacings)}")
        out.extend(cls._spacing_problems(bodies, scheme, fluids))
        if isinstance(scheme.periodic, Periodic) and fluids and len({b.dim for b in bodies}) == 1:
            out.extend(cls._periodic_problems(bodies, scheme, fluids))
        for w in (b for b in bodies if isinstance(b, WallBody) and b.motion is not None):
            out.extend(f"wall body {w.name!r}: {p}" for p in w.motion.check(w.dim))
        if fluids and len({b.dim for b in bodies}) == 1:
            g = next((np.asarray(e.g, dtype=float) for e in scheme.effects
                      if "gravity" in getattr(e, "provides", ()) and hasattr(e, "g")), None)
            if g is not None and g.shape != (fluids[0].dim,):
                g = None  # reported by the effect's own check
            out.extend(geometry_problems(fluids, [b for b in bodies if isinstance(b, WallBody) and b.n], g))

        effects = list(scheme.effects)
        for e in effects:
            if not isinstance(e, Effect):
                out.append(f"unknown effect {e!r}: effects must be Effect instances")
        effects = [e for e in effects if isinstance(e, Effect)]
        pressure = [e for e in effects if e.role == "pressure"]
        if not pressure:
            out.append("no pressure model: list exactly one of TaitPressure (or another effect with role 'pressure')")
        elif len(pressure) > 1:
            out.append(f"two pressure models listed: {pressure}; keep exactly one")
        kinds = [type(e) for e in effects]
        dup_e = sorted({k.__name__ for k in kinds if kinds.count(k) > 1})
        if dup_e:
            out.append(f"effects listed twice: {dup_e}")
        enames = [e.name for e in effects]
        dup_n = sorted({n for n in enames if enames.count(n) > 1})
        if dup_n:
            out.append(f"effect names must be unique (timings, reports and checkpoints are keyed by "
                       f"name), repeated: {dup_n}; set a distinct `name` on each custom effect")
        provided = set(SOLVER_QUANTITIES)
        for e in effects:
            provided |= set(e.provides)
        for e in effects:
            bad = [s for s in e.stages if s not in STAGES]
            if bad:
                out.append(f"{e!r}: unknown stage(s) {bad}; stages are {STAGES}")
            missing = sorted(set(e.reads) - provided)
            if missing:
                out.append(f"{e!r} reads {missing}, which no listed effect provides")
        if any(isinstance(b, WallBody) and b.n for b in bodies) and "wall_state" not in provided:
            out.append("the scene has wall bodies but no wall treatment: list Walls()")
        for w in (b for b in bodies if isinstance(b, WallBody) and b.follows is not None):
            if not any(getattr(i, "walls", None) == w.name for i in scene.interactions):
                out.append(f"wall body {w.name!r} follows {w.follows!r} but no interaction moves it: list "
                           f"StructureCoupling(..., walls={w.name!r}) in the scene's interactions")
        unused = [b.name for b in bodies if isinstance(b, WallBody) and b.surface is not None]
        if unused and "wall_surface_contact" not in provided:
            out.append(f"wall bodies {unused} have a penalty surface but no listed effect uses it: list PenaltyWalls() "
                       "(or build the walls without a surface)")
        for p in scene.probes:
            missing = sorted(set(p.reads) - provided)
            if missing:
                out.append(f"probe {p.name!r} reads {missing}, which no listed effect provides")
        if scene.dim:
            ctx = FluidContext(scheme, scene)
            for e in effects:
                try:
                    out.extend(e.check(ctx))
                except Exception as exc:  # a check may depend on what failed above
                    out.append(f"{e!r}: check failed ({exc})")
        return out

    @staticmethod
    def _spacing_problems(bodies: list, scheme: FluidScheme, fluids: list) -> list[str]:
        """The one particle spacing: the scheme's (if given) against the fluid bodies', and every
        wall body with particles against it (wall particles are nodes of the fluid's
        approximation, each integrating a ``spacing^d`` volume)."""
        out: list[str] = []
        dx = scheme.spacing if scheme.spacing is not None else (fluids[0].spacing if fluids else None)
        if dx is None or not (isinstance(dx, (int, float)) and dx > 0):
            return out
        close = lambda a: abs(a - dx) <= SPACING_TOLERANCE * dx  # noqa: E731
        if scheme.spacing is not None:
            off = [f"{b.name!r} ({b.spacing:g} m)" for b in fluids if not close(b.spacing)]
            if off:
                out.append(f"fluid bodies {', '.join(off)} are not built at the scheme's spacing {dx:g} m; build them "
                           "with the scheme's spacing, or give the scheme theirs")
        for w in bodies:
            if isinstance(w, WallBody) and w.n and w.spacing is not None and not close(w.spacing):
                out.append(f"wall body {w.name!r} has particles {w.spacing:g} m apart but the fluid's spacing is "
                           f"{dx:g} m: wall particles are nodes of the fluid's approximation; build the walls with "
                           f"spacing {dx:g} (wall_box(..., {dx:g}), WallBody.on_surface(..., spacing={dx:g}))")
        return out

    @staticmethod
    def _periodic_problems(bodies: list, scheme: FluidScheme, fluids: list) -> list[str]:
        """The periodic box against the bodies: the description itself, every particle inside
        ``[lower, upper)`` on the periodic axes, no wall that moves (its particles would leave the
        box; a belt's surface velocity is fine), and a period of at least twice the neighbour
        search radius (a particle would otherwise meet another and its image)."""
        per = scheme.periodic
        dim = fluids[0].dim
        out = per.problems(dim)
        if out:
            return out
        period, lower = per.period(dim), per.lower(dim)
        ap = scheme.approximation
        try:
            reach = get_kernel(ap.kernel).support * ap.h_factor * fluids[0].spacing + ap.skin * fluids[0].spacing
        except (ValueError, TypeError, AttributeError):
            reach = 0.0  # reported by the approximation's own check
        for a in per.axes(dim):
            name = "xyz"[a]
            if period[a] < 2.0 * reach:
                out.append(f"the periodic length along {name} ({period[a]:g} m) is shorter than twice the neighbour "
                           f"search radius ({reach:g} m = kernel support × h + skin): a particle would meet another "
                           f"and its image; lengthen the periodic box to at least {2.0 * reach:g} m")
            for b in bodies:
                if not (isinstance(b, (FluidBody, WallBody)) and b.n):
                    continue
                x = b.positions[:, a]
                if x.min() < lower[a] or x.max() >= lower[a] + period[a]:
                    out.append(f"body {b.name!r} reaches from {x.min():g} to {x.max():g} m along {name}, outside "
                               f"the periodic interval [{lower[a]:g}, {lower[a] + period[a]:g}) m: build it inside "
                               "the box (upper end excluded), or widen the interval")
        for w in bodies:
            if isinstance(w, WallBody) and (w.motion is not None or w.follows is not None):
                out.append(f"wall body {w.name!r} moves, but the domain is periodic: its particles would leave the "
                           "periodic box; give a wall that stays in place a surface velocity (WallBody(velocity=...)) "
                           "instead")
            if isinstance(w, WallBody) and w.surface is not None:
                out.append(f"wall body {w.name!r} has a penalty surface, which does not see across the periodic "
                           "seam; build the walls of a periodic domain without a surface")
        return out

    # ------------------------------------------------------------------ set-up
    def __init__(self, bodies: list, scheme: FluidScheme, scene: SceneView) -> None:
        self.scheme = scheme
        self.fluids = [b for b in bodies if isinstance(b, FluidBody)]
        self.walls = [b for b in bodies if isinstance(b, WallBody)]
        ap = scheme.approximation
        self.approximation = ap
        self.kernel = get_kernel(ap.kernel)
        self.integrator = make_integrator(scheme.integrator)
        self.mass_option = scheme.mass
        self.effects: list[Effect] = list(scheme.effects)
        self._state = build_state(self.fluids, self.walls, ap.h_factor)
        s = self._state
        s.approximation_order = ap.order
        self.periodic = scheme.periodic
        s.period = kernel_period(self.periodic, s.dim)
        self._lower = self.periodic.lower(s.dim) if self.periodic is not None else None
        self.search_radius = self.kernel.support * s.h + ap.skin * s.spacing
        self._stage_effects = {st: [e for e in self.effects if st in e.stages] for st in STAGES}
        # the Shepard sums ride on the shape-function pass when an effect reads them
        self._kernel_sum = any("kernel_sum" in e.reads for e in self.effects)
        self.timer = StageTimer()
        self.fallback_points = 0
        self.fallback_steps = 0
        self.mass_floored = 0
        self.neighbor_builds = 0
        self.consistent_mass_unconverged = 0
        self.checks = FluidRunChecks()   # volume, distribution, Mach number, fallback shares
        s.run_checks = self.checks
        self._table_volumes: np.ndarray | None = None
        self._div: np.ndarray | None = None
        self._external: np.ndarray | None = None
        self._continuity_added: np.ndarray | None = None  # the added continuity terms of the last evaluation
        # walls with a prescribed motion: (rows in the state, rows among the walls, motion,
        # reference positions, reference normals)
        self._moving = []
        self._moving_surfaces = []  # (body name, motion, reference nodes) of moving penalty surfaces
        for w in self.walls:
            if w.motion is not None and w.surface is not None:
                self._moving_surfaces.append((w.name, w.motion, w.surface.nodes.copy()))
            if w.motion is not None and w.n:
                sl = s.bodies[w.name]
                wsl = slice(sl.start - s.n_fluid, sl.stop - s.n_fluid)
                n0 = w.normals if w.normals is not None else np.zeros_like(w.positions)
                self._moving.append((sl, wsl, w.motion, w.positions.copy(), np.asarray(n0, dtype=float).copy()))
        # walls riding on another body's surface (set by an interaction every step):
        # name -> (rows in the state, rows among the walls); their last driven state
        # (time, positions, velocities, accelerations) predicts them between exchanges
        self._driven: dict[str, tuple[slice, slice]] = {}
        for w in self.walls:
            if w.follows is not None and w.n:
                sl = s.bodies[w.name]
                self._driven[w.name] = (sl, slice(sl.start - s.n_fluid, sl.stop - s.n_fluid))
        self._drive: dict[str, list] = {}
        # wall penetration is measured where every wall body has normals (its surface is known)
        self._offsets = None
        particle_walls = [w for w in self.walls if w.n]
        if particle_walls and all(w.normals is not None for w in particle_walls):
            # walls riding on a structure are left out (offset −inf: never behind): their body is
            # thin and has corners, where the half-space test of the nearest wall particle counts
            # the water passing a corner as behind it; the coupling's contact measures the
            # penetration into the structure against its exact surface (summary: max_penetration_m)
            self._offsets = np.concatenate([
                np.full(w.n, -np.inf) if w.anchors is not None
                else surface_offsets(w.positions, np.asarray(w.normals, dtype=float), w.spacing)
                for w in particle_walls])
        self.penetration = {"max_depth_dx": 0.0, "max_count": 0, "time_of_max_depth_s": None, "warned": False}
        # the pressure model first: it sets the reference sound speed the others read (state.c0)
        ctx = FluidContext(scheme, scene)
        pressure = scheme.pressure_model()
        for e in ([pressure] if pressure is not None else []) + [e for e in self.effects if e is not pressure]:
            e.setup(s, ctx)
        s.c = s.c if s.c is not None else np.zeros(s.n)
        # the domain the fluid particles may not leave (after the effects: gravity is known)
        self.domain_exit = None
        if scheme.domain_exit and s.n_fluid and s.n_walls:
            periodic_axes = self.periodic.axes(s.dim) if self.periodic is not None else ()
            self.domain_exit = DomainExit.around(s.x, float(np.max(self.search_radius)), s.gravity, periodic_axes)
            if self.domain_exit is not None:
                self.domain_exit.setup(s)
        self._rebuild_neighbors = False
        self.move_walls(0.0)
        s.x_ref = s.x.copy()
        self.started = False

    @property
    def state(self) -> FluidState:
        return self._state

    # ------------------------------------------------------------------ evaluation
    def move_walls(self, t: float) -> None:
        """Put the walls with a prescribed motion where they are at time ``t`` (positions,
        velocities, accelerations, normals of the wall particles; nodes and node velocities of
        the penalty surfaces); fixed walls are untouched."""
        s = self._state
        for sl, wsl, motion, x0, n0 in self._moving:
            s.x[sl] = motion.positions(x0, t)
            s.wall_velocity[wsl] = motion.velocities(x0, t)
            s.wall_acceleration[wsl] = motion.accelerations(x0, t)
            s.wall_normals[wsl] = motion.rotate(n0, t)
        for name, motion, x0 in self._moving_surfaces:
            surf = s.wall_surfaces[name]
            surf.x = np.ascontiguousarray(motion.positions(x0, t))
            surf.v = np.ascontiguousarray(motion.velocities(x0, t))
        for name, (sl, wsl) in self._driven.items():
            if name not in self._drive:
                continue
            t0, x0, v0, a0 = self._drive[name]
            tau = t - t0
            s.x[sl] = x0 + tau * v0 + 0.5 * tau * tau * a0
            s.wall_velocity[wsl] = v0 + tau * a0
            s.wall_acceleration[wsl] = a0

    def drive_walls(self, body: str, t: float, positions: np.ndarray, velocities: np.ndarray,
                    accelerations: np.ndarray, normals: np.ndarray) -> None:
        """Set the wall particles of ``body`` (a wall that ``follows`` another body) to their
        state at time ``t``: positions (m), velocities (m/s), accelerations (m/s², seen by the
        wall pressure) and normals, each ``(n, d)``. Until the next call, :meth:`move_walls`
        predicts them as ``x + τv + ½τ²a``, ``v + τa`` (``τ`` the time since ``t``)."""
        if body not in self._driven:
            raise ValueError(f"fluid solver: {body!r} is not a wall body that follows a surface")
        s = self._state
        sl, wsl = self._driven[body]
        s.x[sl] = positions
        s.wall_velocity[wsl] = velocities
        s.wall_acceleration[wsl] = accelerations
        s.wall_normals[wsl] = normals
        self._drive[body] = [float(t), np.array(positions, dtype=float), np.array(velocities, dtype=float),
                             np.array(accelerations, dtype=float)]

    def wall_reactions(self, body: str) -> np.ndarray:
        """The nodal force of the fluid's last evaluation on the wall particles of ``body``,
        ``f_w = −Σ_k σ_k ∇N_w(x_k) V_k`` (N, per unit depth in 2D; ``(n, d)``): the force the fluid
        exerts on them (the Galerkin sums over all nodes add to zero, so this is minus what the
        wall gives the fluid through the nodal integration)."""
        s = self._state
        return s.force[s.bodies[body]].copy()

    def _neighbors(self) -> None:
        s = self._state
        t0 = time.perf_counter()
        if s.neighbors is not None:
            rows = slice(0, s.n) if (self._moving or self._driven) else s.fluid
            disp = s.x[rows] - s.x_ref[rows]
            if self.periodic is not None:  # a particle wrapped across the seam moved by its image
                disp = minimum_image(disp, s.period)
            moved = float(np.sqrt(np.max(np.einsum("ij,ij->i", disp, disp)))) if disp.shape[0] else 0.0
            if moved <= 0.5 * self.approximation.skin * s.spacing and not self._rebuild_neighbors:
                return
            s.x_ref = s.x.copy()
        self._rebuild_neighbors = False
        s.neighbors = self._find_neighbors()
        self.neighbor_builds += 1
        self.timer.add("neighbors", t0)

    def _find_neighbors(self):
        """The neighbour table of the reference positions (across the seam of a periodic box)."""
        s = self._state
        x = s.x_ref if self.domain_exit is None else self.domain_exit.search_positions(s.x_ref, s)
        if self.periodic is None:
            return find_neighbors(x, x, radius=self.search_radius)
        return find_neighbors(x, x, radius=self.search_radius, period=s.period, lower=self._lower)

    def kinematics(self) -> None:
        """Neighbours, shape functions, wall velocities, velocity gradient, continuity rate
        (in a periodic box the fluid particles first wrap back into it)."""
        if self.periodic is not None:
            self.periodic.wrap(self._state.x[self._state.fluid])
        self._neighbors()
        t0 = time.perf_counter()
        self._shape_functions()
        nf = self._state.fallback_count
        self.checks.count_evaluation()
        if nf:
            self.fallback_points += nf
            self.fallback_steps += 1
        self.timer.add("shape_functions", t0)
        self.continuity_rate()

    def _shape_functions(self, volumes: np.ndarray | None = None) -> None:
        """MLS/RKPM table at the current positions with the current neighbour list (RKPM:
        with the volumes ``M/ρ`` of now, or the given ones when restoring a checkpoint), with the
        Shepard sums ``table.kernel_sum`` of the volumes ``M/ρ`` of now when an effect reads
        ``kernel_sum``."""
        s = self._state
        ap = self.approximation
        if ap.method == "rkpm":
            self._table_volumes = s.M / s.rho if volumes is None else np.ascontiguousarray(volumes)
        else:
            self._table_volumes = None
        s.table = evaluate_shape_functions(
            s.x, s.x, s.h, s.neighbors, self.kernel, s.approximation_order, ap.method, self._table_volumes,
            condition_limit=ap.condition_limit, out=s.table, period=s.period,
            kernel_sum_volumes=s.M / s.rho if self._kernel_sum else None,
        )
        low = s.table.order[: s.n_fluid] < s.approximation_order
        if self.domain_exit is not None:     # an isolated particle taken out of the run falls back
            low &= ~s.extra[OUTSIDE][: s.n_fluid]
        s.fallback_count = int(np.count_nonzero(low))

    def continuity_rate(self, reuse_added: bool = False) -> None:
        """Wall velocities, ``L``, ``ρ̇ = −ρ tr L`` and the added continuity terms (density
        diffusion) with the current table and velocities.

        The added terms depend on positions and densities only, not on velocities: with
        ``reuse_added`` (the kick-drift-kick's first half update, at the positions of the
        last evaluation) their sum from the last evaluation is reused instead of recomputed,
        which halves their cost (the densities it saw are half a step older).
        """
        s = self._state
        t0 = time.perf_counter()
        for e in self._stage_effects["kinematics"]:
            e.kinematics(s)
            t0 = self.timer.add(e.name, t0)
        s.L, self._div = velocity_gradient_divergence(s.table, s.v, s.L, self._div)
        t0 = self.timer.add("velocity_gradient", t0)
        for e in self._stage_effects["divergence"]:
            e.divergence(s, self._div)
            t0 = self.timer.add(e.name, t0)
        f = s.fluid
        np.multiply(s.rho[f], self._div[f], out=s.drho[f])
        np.negative(s.drho[f], out=s.drho[f])
        t0 = self.timer.add("velocity_gradient", t0)
        added = self._stage_effects["continuity"]
        if not added:
            return
        if reuse_added and self._continuity_added is not None:
            s.drho[f] += self._continuity_added
            return
        base = s.drho[f].copy()
        for e in added:
            e.continuity(s)
            t0 = self.timer.add(e.name, t0)
        self._continuity_added = s.drho[f] - base

    def dynamics(self) -> None:
        """Pressure, wall state, stress, volumes, mass, forces and acceleration."""
        s = self._state
        t0 = time.perf_counter()
        for st in ("pressure", "boundary"):
            for e in self._stage_effects[st]:
                getattr(e, st)(s)
                t0 = self.timer.add(e.name, t0)
        d = s.dim
        stress = np.zeros((s.n, d, d))
        for a in range(d):
            stress[:, a, a] = -s.p
        s.stress = stress
        for e in self._stage_effects["stress"]:
            e.stress(s)
            t0 = self.timer.add(e.name, t0)
        s.volume = s.M / s.rho
        stress_volume = stress * s.volume[:, None, None]
        force, m = internal_force_and_mass(s.table, stress_volume, s.M, want_mass=self.mass_option != "particle")
        if self.mass_option == "particle":
            m = s.M.copy()
        else:
            self.mass_floored += floor_lumped_mass(m, s.M, s.n_fluid)
        s.mass = m
        s.force = force
        if self._external is not None:
            s.force += self._external
        t0 = self.timer.add("internal_force", t0)
        for e in self._stage_effects["force"]:
            e.force(s)
            t0 = self.timer.add(e.name, t0)
        f = s.fluid
        if self.mass_option == "consistent":
            s.a[f], bad = consistent_acceleration(s.table, s.M, s.n_fluid, s.force[f], s.a[f])
            if bad and self.consistent_mass_unconverged == 0:
                warn_consistent_unconverged()
            self.consistent_mass_unconverged += bad
        else:
            s.a[f] = s.force[f] / s.mass[f, None]
        s.a[s.walls] = 0.0
        self.timer.add("acceleration", t0)

    def drift_effects(self, dt: float) -> None:
        """The effects of the ``drift`` stage (particle shifting), called by the integrator at
        the start of a drift of ``dt`` while the positions, neighbours and table are those of
        the start of the step."""
        t0 = time.perf_counter()
        for e in self._stage_effects["drift"]:
            e.drift(self._state, dt)
            t0 = self.timer.add(e.name, t0)

    def evaluate(self) -> None:
        """One full force evaluation at the current positions."""
        self.kinematics()
        self.dynamics()

    def time_step_limit(self) -> float:
        """``safety · min(effect limits, 0.25 sqrt(h/|a|))``, capped by ``dt_max``."""
        s = self._state
        limits = [e.time_step_limit(s) for e in self.effects]
        f = s.fluid
        limits.append(force_limit(s.h[f], s.a[f]))
        dt = self.scheme.safety * min(limits)
        if self.scheme.dt_max is not None:
            dt = min(dt, self.scheme.dt_max)
        # a NaN limit comes from a non-finite state: leave it to the watchdog, which names the
        # particle and the quantity
        if math.isinf(dt):
            raise ValueError(
                "no time-step limit: no effect supplies one and the acceleration is zero; set "
                "scene.dt_max"
            )
        return dt

    # ------------------------------------------------------------------ Solver protocol
    def start(self) -> None:
        """First force evaluation at ``t = 0`` (rates for the first kick, ``dt_next``).

        Added continuity terms (density diffusion) read the pressure of the last evaluation,
        which does not exist before the first one: with such terms listed, the continuity rate
        is formed again once the pressures (fluid and walls) are set. Measured without this on
        a two-layer tank at rest: the first step moved the pressure by 7 % of ``Δρ g D``.
        """
        s = self._state
        self.evaluate()
        if self._stage_effects["continuity"]:
            self.continuity_rate()
        if self._offsets is not None:
            self._measure_penetration()
        s.dt_next = self.time_step_limit()
        self.started = True

    def stable_time_step(self) -> float:
        return self._state.dt_next

    def begin_step(self, t: float, dt: float) -> None:
        self.integrator.begin(self, t, dt)

    def end_step(self, t: float, dt: float) -> None:
        s = self._state
        self.integrator.end(self, t, dt)
        t0 = time.perf_counter()
        s.t += dt
        s.step += 1
        self.timer.add("integrate", t0)
        t0 = time.perf_counter()
        for e in self._stage_effects["after_step"]:
            e.after_step(s)
            t0 = self.timer.add(e.name, t0)
        if self.domain_exit is not None:
            if self.domain_exit.after_step(s):
                self._rebuild_neighbors = True   # the next search parks them away from everyone
            t0 = self.timer.add("domain_exit", t0)
        if self._offsets is not None:
            self._measure_penetration()
            t0 = self.timer.add("wall_penetration", t0)
        self.checks.after_step(s, self.fallback_steps, self.fallback_points)
        self.timer.add("run_checks", t0)
        s.dt_next = self.time_step_limit()

    def _measure_penetration(self) -> None:
        """Count the fluid particles behind a wall surface and the deepest; warn once past
        :data:`~mlsgalerkin.fluid.penetration.PENETRATION_WARNING` spacings."""
        s = self._state
        nb = s.neighbors
        depth = penetration_depths(nb.indptr, nb.indices, s.x, s.n_fluid, s.wall_normals, self._offsets, s.spacing,
                                   s.period)
        deepest = float(depth.max()) / s.spacing if depth.size else 0.0
        count = int(np.count_nonzero(depth > 0.0))
        s.wall_penetrations, s.max_wall_penetration_dx = count, deepest
        rec = self.penetration
        rec["max_count"] = max(rec["max_count"], count)
        if deepest > rec["max_depth_dx"]:
            rec["max_depth_dx"], rec["time_of_max_depth_s"] = deepest, s.t
        if deepest > PENETRATION_WARNING and not rec["warned"]:
            rec["warned"] = True
            k = int(np.argmax(depth))
            body = next((name for name, sl in s.bodies.items() if sl.start <= k < sl.stop), "?")
            warnings.warn(
                f"at t = {s.t:.6g} s, {count} fluid particles are inside walls, behind their surfaces, the deepest "
                f"(particle {k} of "
                f"body {body!r} at {np.round(s.x[k], 6).tolist()}) {deepest:.2f} spacings behind, past the first layer "
                f"of wall particles (threshold {PENETRATION_WARNING} spacings): the walls are leaking. Refine the "
                "resolution or lower the time step; the columns wall_penetrations and max_wall_penetration_dx of "
                "timeseries.csv follow it", WallPenetrationWarning, stacklevel=2)

    def surface(self, body: str) -> Surface:
        """A fluid body's particles as slave nodes (positions, velocities, masses); the particles
        taken out of the run are parked far away (:meth:`DomainExit.search_positions`), out of
        every structure's reach."""
        s = self._state
        sl = s.bodies[body]
        x = s.x if self.domain_exit is None else self.domain_exit.search_positions(s.x, s)
        return Surface(body, x[sl], s.v[sl], np.zeros((0, s.dim), dtype=np.int64), s.M[sl])

    def clear_surface_forces(self) -> None:
        if self._external is not None:
            self._external[:] = 0.0

    def add_surface_forces(self, body: str, forces: np.ndarray) -> None:
        s = self._state
        if self._external is None:
            self._external = np.zeros_like(s.x)
        self._external[s.bodies[body]] += forces

    # ------------------------------------------------------------------ checkpoints
    def checkpoint(self) -> tuple[dict[str, np.ndarray], dict[str, Any]]:
        s = self._state
        arrays = {k: getattr(s, k).copy() for k in CHECKPOINT_ARRAYS}
        for k, v in s.extra.items():
            arrays[f"extra__{k}"] = np.asarray(v).copy()
        if self._table_volumes is not None:  # RKPM: the volumes of the current table
            arrays["table_volumes"] = self._table_volumes.copy()
        if self._external is not None:  # the last exchange's forces (the next midpoint evaluation uses them)
            arrays["surface_forces"] = self._external.copy()
        for name, (t_d, x_d, v_d, a_d) in self._drive.items():  # walls riding on a structure
            arrays[f"drive__{name}"] = np.concatenate([x_d, v_d, a_d], axis=1)
            arrays[f"drive_normals__{name}"] = s.wall_normals[self._driven[name][1]].copy()
            arrays[f"drive_time__{name}"] = np.array([t_d])
        if s.L is not None:  # the last evaluation's velocity gradient (particle shifting re-interpolates with it)
            arrays["velocity_gradient"] = s.L.copy()
        if self._continuity_added is not None:  # the added continuity terms the next half update reuses
            arrays["continuity_added"] = self._continuity_added.copy()
        meta = {
            "t": s.t, "step": s.step, "dt_next": s.dt_next, "n": s.n, "n_fluid": s.n_fluid,
            "effects": {e.name: e.state_dict() for e in self.effects},
            "counters": {"fallback_points": self.fallback_points, "fallback_steps": self.fallback_steps,
                         "mass_floored": self.mass_floored, "neighbor_builds": self.neighbor_builds,
                         "consistent_mass_unconverged": self.consistent_mass_unconverged},
            "penetration": dict(self.penetration),
            "wall_penetration_now": [s.wall_penetrations, s.max_wall_penetration_dx],
            "sensors": dict(s.sensors),
            "run_checks": self.checks.state_dict(),
        }
        return arrays, meta

    def restore(self, arrays: dict[str, np.ndarray], meta: dict[str, Any]) -> None:
        s = self._state
        if meta.get("n") != s.n or meta.get("n_fluid") != s.n_fluid:
            raise ValueError(
                f"checkpoint has {meta.get('n')} particles ({meta.get('n_fluid')} fluid) but the scene "
                f"has {s.n} ({s.n_fluid}); restart with the scene that wrote it"
            )
        missing = [k for k in CHECKPOINT_ARRAYS if k not in arrays]
        if missing:
            raise ValueError(f"checkpoint lacks the fluid arrays {missing}; it was not written by this solver")
        for k in CHECKPOINT_ARRAYS:
            setattr(s, k, np.ascontiguousarray(arrays[k]).copy())
        for k, v in arrays.items():
            if k.startswith("extra__"):
                s.extra[k[len("extra__"):]] = v.copy()
        self._external = arrays["surface_forces"].copy() if "surface_forces" in arrays else None
        if "velocity_gradient" in arrays:
            s.L = np.ascontiguousarray(arrays["velocity_gradient"]).copy()
        if "continuity_added" in arrays:
            self._continuity_added = np.ascontiguousarray(arrays["continuity_added"]).copy()
        s.t, s.step, s.dt_next = float(meta["t"]), int(meta["step"]), float(meta["dt_next"])
        for e in self.effects:
            e.load_state_dict(meta["effects"].get(e.name, {}))
        c = meta["counters"]
        self.fallback_points, self.fallback_steps = c["fallback_points"], c["fallback_steps"]
        self.mass_floored, self.neighbor_builds = c["mass_floored"], c["neighbor_builds"]
        self.consistent_mass_unconverged = c.get("consistent_mass_unconverged", 0)
        self.penetration = dict(meta.get("penetration", self.penetration))
        s.wall_penetrations, s.max_wall_penetration_dx = meta.get("wall_penetration_now", [0, 0.0])
        s.sensors.clear()
        s.sensors.update(meta.get("sensors", {}))
        self.checks.load_state_dict(meta.get("run_checks", {}))
        # wall velocities, accelerations and normals, and the penalty surfaces, of the
        # checkpoint's time (the particle positions are in the checkpoint)
        self._drive = {}
        for name, (sl, wsl) in self._driven.items():
            if f"drive__{name}" in arrays:
                xva = arrays[f"drive__{name}"]
                d = s.dim
                self._drive[name] = [float(arrays[f"drive_time__{name}"][0]), xva[:, :d].copy(),
                                     xva[:, d:2 * d].copy(), xva[:, 2 * d:].copy()]
                s.wall_normals[wsl] = arrays[f"drive_normals__{name}"]
        x_walls = s.x.copy()
        self.move_walls(s.t)
        s.x[:] = x_walls
        # rebuild the neighbour list from the reference positions it was built from, so the
        # skin logic and the pair order are exactly those of the uninterrupted run
        s.neighbors = self._find_neighbors()
        # the first kick of the next step forms L with the table of the current positions
        # (kdk); without it a restarted run had no table at all
        self._shape_functions(arrays.get("table_volumes"))
        self.started = True

    # ------------------------------------------------------------------ report
    def summary(self) -> dict[str, Any]:
        s = self._state
        total = sum(self.timer.seconds.values()) or 1.0
        return {
            "particles": {"fluid": s.n_fluid, "wall": s.n_walls, "total": s.n},
            "spacing_m": s.spacing, "h_m": float(s.h[0]) if s.n else None,
            "approximation": to_jsonable(self.approximation.__dict__),
            "integrator": self.integrator.name, "mass": self.mass_option,
            "effects": [repr(e) for e in self.effects],
            "stabilisation": self.scheme.stabilisation_report(),
            "moving_walls": [f"{w.name}: {w.motion!r}" for w in self.walls if w.motion is not None],
            "time_per_stage_s": {k: round(v, 6) for k, v in sorted(self.timer.seconds.items(), key=lambda kv: -kv[1])},
            "time_per_stage_fraction": {k: round(v / total, 4) for k, v in self.timer.seconds.items()},
            "diagnostics": {
                "shape_function_fallback_points": self.fallback_points,
                "steps_with_fallback": self.fallback_steps,
                "lumped_mass_floored": self.mass_floored,
                "consistent_mass_unconverged_solves": self.consistent_mass_unconverged,
                "neighbour_rebuilds": self.neighbor_builds,
                "total_mass_kg": s.total_mass(),
                "kinetic_energy_J": s.kinetic_energy(),
                "momentum": s.momentum().tolist(),
            },
            "effect_reports": {e.name: to_jsonable(e.summary()) for e in self.effects if e.summary()},
            "wall_penetration": (dict(self.penetration, threshold_dx=PENETRATION_WARNING)
                                 if self._offsets is not None else None),
            "run_checks": to_jsonable(self.checks.summary(s, self.fallback_steps, self.fallback_points)),
            "domain_exit": self.domain_exit.summary(s) if self.domain_exit is not None else None,
        } | ({"periodic": self.periodic.identity()} if self.periodic is not None else {})
