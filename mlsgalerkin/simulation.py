r"""The time loop of a fluid :class:`~mlsgalerkin.scene.Scene`.

One force evaluation (design.md §3) is split in two so the integrator can advance the
density between them:

1. :meth:`Simulation.kinematics` — neighbours (rebuilt with a skin), MLS/RKPM shape functions
   and gradients at every particle, wall velocities, ``L_k = Σ_j v_j ⊗ ∇N_j(x_k)``,
   collocated continuity ``ρ̇_k = −ρ_k tr L_k``;
2. :meth:`Simulation.dynamics` — pressure, wall state, stress, ``V = M/ρ``, mass, internal force
   ``f_i = −Σ_k σ_k ∇N_i(x_k) V_k`` by the Galerkin scatter, listed forces, ``a = f/m``.

Integrators (``scene.integrator``):

- ``"kdk"`` (default, one evaluation per step): ``v += ½Δt a``; ``ρ += ½Δt ρ̇(x^n, v^½)``
  (old table, new velocity); ``x += Δt v``; kinematics at ``x^{n+1}``; ``ρ += ½Δt ρ̇(x^{n+1},
  v^½)``; dynamics; ``v += ½Δt a``. Velocity and density form a staggered leapfrog pair,
  stable for ``ω Δt < 2``. (Advancing ``ρ`` with the rate of the *previous* half step instead
  has amplification ``det = 1 + (ωΔt)²/2`` per step: unconditionally unstable.)
- ``"predictor_corrector"`` (explicit midpoint, two evaluations per step; its amplification
  ``|1 − z²/2 + iz|² = 1 + z⁴/4`` grows weakly and relies on some artificial viscosity).

Mass (``scene.mass``): ``"lumped"`` ``m_i = Σ_k N_i(x_k) M_k`` (row sum of the Galerkin mass
matrix; default), ``"particle"`` ``m_i = M_i`` (conserves ``Σ M v`` exactly), or
``"consistent"`` (``m_ij``; each component solved by conjugate gradients warm-started from
the last acceleration). A lumped mass below a quarter of the particle mass (a particle at the
edge of a splash) is floored at ``M_i/4`` and counted.
"""

from __future__ import annotations

import logging
import math
import time
import warnings
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from mlsgalerkin.approximation.build import evaluate_shape_functions
from mlsgalerkin.assembly import internal_force_and_mass, velocity_gradient_divergence
from mlsgalerkin.fluid.effects import STAGES
from mlsgalerkin.fluid.state import CHECKPOINT_ARRAYS, FluidState
from mlsgalerkin.kernels import get_kernel
from mlsgalerkin.neighbors import find_neighbors
from mlsgalerkin.scene import Scene
from mlsgalerkin.io.files import to_jsonable

__all__ = ["Simulation", "SimulationDiverged", "RunResult", "build_state"]

logger = logging.getLogger(__name__)

MASS_FLOOR = 0.25


class SimulationDiverged(RuntimeError):
    """The watchdog stopped a run; ``diagnosis`` says which particle, quantity and step."""

    def __init__(self, message: str, diagnosis: dict, checkpoint: Path | None = None) -> None:
        super().__init__(message)
        self.diagnosis = diagnosis
        self.checkpoint = checkpoint


def build_state(scene: Scene) -> FluidState:
    """Flatten the scene's bodies into one :class:`FluidState` (fluid first, then walls)."""
    fluids = scene.fluid_bodies
    walls = scene.wall_bodies
    dim = scene.dim
    dx = scene.spacing
    h_f = scene.approximation.h_factor
    bodies: dict[str, slice] = {}
    xs, vs, rhos, Ms, hs, rho0s, mus, phases = [], [], [], [], [], [], [], []
    start = 0
    phase_offset = 0
    for b in fluids:
        xs.append(b.positions)
        vs.append(b.velocity)
        rhos.append(b.density)
        Ms.append(b.density * b.spacing**dim)
        hs.append(np.full(b.n, h_f * b.spacing))
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
        xs.append(w.positions)
        vs.append(np.broadcast_to(w.velocity, (w.n, dim)))
        rhos.append(np.full(w.n, w.reference_density))
        Ms.append(np.full(w.n, w.reference_density * w.spacing**dim))
        hs.append(np.full(w.n, h_f * dx))
        rho0s.append(np.full(w.n, w.reference_density))
        mus.append(np.full(w.n, mu_wall))
        phases.append(np.full(w.n, -1))
        wall_vol.append(np.full(w.n, w.spacing**dim))
        wall_n.append(w.normals if w.normals is not None else np.zeros((w.n, dim)))
        wall_v.append(np.broadcast_to(w.velocity, (w.n, dim)))
        bodies[w.name] = slice(start, start + w.n)
        start += w.n
    cat = lambda a, shape: np.ascontiguousarray(np.concatenate(a)) if a else np.zeros(shape)  # noqa: E731
    return FluidState(
        x=cat(xs, (0, dim)), v=cat(vs, (0, dim)).astype(float), rho=cat(rhos, (0,)), M=cat(Ms, (0,)),
        h=cat(hs, (0,)), rho0=cat(rho0s, (0,)), mu=cat(mus, (0,)), phase=cat(phases, (0,)).astype(np.int64),
        n_fluid=n_fluid, spacing=dx, wall_volume=cat(wall_vol, (0,)), wall_normals=cat(wall_n, (0, dim)),
        wall_velocity=cat(wall_v, (0, dim)), bodies=bodies,
    )


@dataclass
class RunResult:
    """What :meth:`Simulation.run` returns: final state, time series, summary, output folder."""

    state: FluidState
    timeseries: dict[str, np.ndarray]
    summary: dict[str, Any]
    out: Path | None = None


class _Timer:
    def __init__(self) -> None:
        self.seconds: dict[str, float] = {}

    def add(self, name: str, t0: float) -> float:
        t1 = time.perf_counter()
        self.seconds[name] = self.seconds.get(name, 0.0) + (t1 - t0)
        return t1


class Simulation:
    """Runs a validated :class:`Scene`. ``Simulation(scene).run(out="DIR")``.

    The scene is validated here (all problems reported at once, before any work). Only the
    listed effects are ever called: each stage calls the effects that declared it.
    """

    def __init__(self, scene: Scene) -> None:
        scene.validate()
        self.scene = scene
        self.kernel = get_kernel(scene.approximation.kernel)
        self.state = build_state(scene)
        s = self.state
        self._order = {"constant": 0, "linear": 1, "quadratic": 2}.get(scene.approximation.basis, 1)
        if scene.approximation.method == "shepard":
            self._order = 0
        self.search_radius = self.kernel.support * s.h + scene.approximation.skin * s.spacing
        self._stage_effects = {st: [e for e in scene.effects if st in e.stages] for st in STAGES}
        self.timer = _Timer()
        self.fallback_points = 0
        self.fallback_steps = 0
        self.mass_floored = 0
        self.neighbor_builds = 0
        self.consistent_mass_unconverged = 0
        self._table = None
        self._table_volumes: np.ndarray | None = None
        self._div: np.ndarray | None = None
        self._probe_rows: list[dict] = []
        for e in scene.effects:
            e.setup(s, scene)
        s.c = s.c if s.c is not None else np.zeros(s.n)
        self._initialised = False
        self.last_dt = 0.0

    # ------------------------------------------------------------------ evaluation
    def _neighbors(self) -> None:
        s = self.state
        t0 = time.perf_counter()
        if s.neighbors is not None:
            f = s.fluid
            disp = s.x[f] - s.x_ref[f]
            moved = float(np.sqrt(np.max(np.einsum("ij,ij->i", disp, disp)))) if s.n_fluid else 0.0
            if moved <= 0.5 * self.scene.approximation.skin * s.spacing:
                return
            s.x_ref = s.x.copy()
        s.neighbors = find_neighbors(s.x_ref, s.x_ref, radius=self.search_radius)
        self.neighbor_builds += 1
        self.timer.add("neighbors", t0)

    def kinematics(self) -> None:
        """Neighbours, shape functions, wall velocities, velocity gradient, continuity rate."""
        s = self.state
        self._neighbors()
        t0 = time.perf_counter()
        self._shape_functions()
        nf = int(np.count_nonzero(self._table.order[: s.n_fluid] < self._order))
        if nf:
            self.fallback_points += nf
            self.fallback_steps += 1
        t0 = self.timer.add("shape_functions", t0)
        self._continuity_rate()

    def _shape_functions(self, volumes: np.ndarray | None = None) -> None:
        """MLS/RKPM table at the current positions with the current neighbour list (RKPM:
        with the volumes ``M/ρ`` of now, or the given ones when restoring a checkpoint)."""
        s = self.state
        ap = self.scene.approximation
        if ap.method == "rkpm":
            self._table_volumes = s.M / s.rho if volumes is None else np.ascontiguousarray(volumes)
        else:
            self._table_volumes = None
        self._table = evaluate_shape_functions(
            s.x, s.x, s.h, s.neighbors, self.kernel, self._order, ap.method, self._table_volumes,
            condition_limit=ap.condition_limit, out=self._table,
        )
        s.table = self._table

    def _continuity_rate(self) -> None:
        """Wall velocities, ``L`` and ``ρ̇ = −ρ tr L`` with the current table and velocities."""
        s = self.state
        t0 = time.perf_counter()
        for e in self._stage_effects["kinematics"]:
            e.kinematics(s)
            t0 = self.timer.add(e.name, t0)
        s.L, self._div = velocity_gradient_divergence(self._table, s.v, s.L, self._div)
        f = s.fluid
        np.multiply(s.rho[f], self._div[f], out=s.drho[f])
        np.negative(s.drho[f], out=s.drho[f])
        self.timer.add("velocity_gradient", t0)

    def dynamics(self) -> None:
        """Pressure, wall state, stress, volumes, mass, forces and acceleration."""
        s = self.state
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
        stress *= s.volume[:, None, None]
        force, m = internal_force_and_mass(self._table, stress, s.M, want_mass=self.scene.mass != "particle")
        if self.scene.mass == "particle":
            m = s.M.copy()
        else:
            floor = MASS_FLOOR * s.M
            low = m[s.fluid] < floor[s.fluid]
            if low.any():
                self.mass_floored += int(np.count_nonzero(low))
                m[: s.n_fluid][low] = floor[: s.n_fluid][low]
        s.mass = m
        s.force = force
        t0 = self.timer.add("internal_force", t0)
        for e in self._stage_effects["force"]:
            e.force(s)
            t0 = self.timer.add(e.name, t0)
        f = s.fluid
        if self.scene.mass == "consistent":
            s.a[f] = self._consistent_solve(s.force[f], s.a[f])
        else:
            s.a[f] = s.force[f] / s.mass[f, None]
        s.a[s.walls] = 0.0
        self.timer.add("acceleration", t0)

    def _consistent_solve(self, force: np.ndarray, guess: np.ndarray) -> np.ndarray:
        from scipy.sparse.linalg import cg

        from mlsgalerkin.assembly import consistent_mass

        from scipy.sparse import diags_array

        s = self.state
        Mc = consistent_mass(self._table, s.M).tocsr()[: s.n_fluid, : s.n_fluid]
        jacobi = diags_array(1.0 / np.maximum(Mc.diagonal(), 1e-300))
        out = np.empty_like(force)
        for a in range(force.shape[1]):
            sol, info = cg(Mc, force[:, a], x0=guess[:, a], rtol=1e-10, atol=0.0, maxiter=200, M=jacobi)
            if info != 0:
                self.consistent_mass_unconverged += 1
                if self.consistent_mass_unconverged == 1:
                    warnings.warn(
                        "consistent-mass CG did not converge in 200 iterations: the MLS consistent "
                        "mass matrix is nearly singular (see docs/theory/galerkin_fluid.md); the "
                        "acceleration is inaccurate — use mass='lumped'", RuntimeWarning, stacklevel=3)
            out[:, a] = sol
        return out

    def evaluate(self) -> None:
        self.kinematics()
        self.dynamics()

    # ------------------------------------------------------------------ time step
    def time_step(self) -> float:
        """``safety · min(effect limits, 0.25 sqrt(h/|a|))``, capped by ``dt_max``."""
        s = self.state
        limits = [e.time_step_limit(s) for e in self.scene.effects]
        f = s.fluid
        amax = float(np.sqrt(np.max(np.einsum("ij,ij->i", s.a[f], s.a[f])))) if s.n_fluid else 0.0
        if amax > 0:
            limits.append(0.25 * math.sqrt(float(s.h[f].min()) / amax))
        dt = self.scene.safety * min(limits)
        if self.scene.dt_max is not None:
            dt = min(dt, self.scene.dt_max)
        # a NaN limit comes from a non-finite state: leave it to the watchdog (check_health),
        # which names the particle and the quantity
        if math.isinf(dt):
            raise ValueError(
                "no time-step limit: no effect supplies one and the acceleration is zero; set "
                "scene.dt_max"
            )
        return dt

    def initialise(self) -> None:
        """First force evaluation at ``t = 0`` (rates for the first kick, ``dt_next``)."""
        s = self.state
        self.evaluate()
        s.dt_next = self.time_step()
        self._initialised = True

    def step(self, dt: float) -> None:
        """Advance the state by ``dt`` with the scene's integrator."""
        s = self.state
        f = s.fluid
        t0 = time.perf_counter()
        if self.scene.integrator == "kdk":
            s.v[f] += 0.5 * dt * s.a[f]
            self.timer.add("integrate", t0)
            # density is advanced with the half-step velocity over both ends of the drift
            # (staggered leapfrog for the v–ρ wave pair; a lagged rate would be unstable)
            self._continuity_rate()
            s.rho[f] += 0.5 * dt * s.drho[f]
            t0 = time.perf_counter()
            s.x[f] += dt * s.v[f]
            self.timer.add("integrate", t0)
            self.kinematics()
            s.rho[f] += 0.5 * dt * s.drho[f]
            self.dynamics()
            t0 = time.perf_counter()
            s.v[f] += 0.5 * dt * s.a[f]
        else:
            x0, v0, rho0 = s.x[f].copy(), s.v[f].copy(), s.rho[f].copy()
            s.v[f] = v0 + 0.5 * dt * s.a[f]
            s.rho[f] = rho0 + 0.5 * dt * s.drho[f]
            s.x[f] = x0 + 0.5 * dt * v0
            self.timer.add("integrate", t0)
            self.evaluate()
            t0 = time.perf_counter()
            s.v[f] = v0 + dt * s.a[f]
            s.rho[f] = rho0 + dt * s.drho[f]
            s.x[f] = x0 + 0.5 * dt * (v0 + s.v[f])
            self.timer.add("integrate", t0)
            self.evaluate()
            t0 = time.perf_counter()
        s.t += dt
        s.step += 1
        self.last_dt = dt
        self.timer.add("integrate", t0)
        t0 = time.perf_counter()
        for e in self._stage_effects["after_step"]:
            e.after_step(s)
            t0 = self.timer.add(e.name, t0)
        s.dt_next = self.time_step()

    # ------------------------------------------------------------------ watchdog
    def check_health(self) -> dict | None:
        """``None`` if the fluid state is sound, else a diagnosis dict (first bad particle)."""
        s = self.state
        f = s.fluid
        wd = self.scene.watchdog
        c0 = float(np.max(s.c[f])) if s.c is not None and s.n_fluid else 0.0
        checks = (("position", s.x[f]), ("velocity", s.v[f]), ("density", s.rho[f]), ("acceleration", s.a[f]))
        for name, arr in checks:
            if not math.isfinite(float(arr.sum())):
                bad = ~np.isfinite(arr.reshape(arr.shape[0], -1)).all(axis=1)
                k = int(np.flatnonzero(bad)[0])
                return self._diagnosis(k, name, arr[k], "is not finite")
        ratio = s.rho[f] / s.rho0[f]
        lo, hi = wd.density_ratio
        if ratio.size and (ratio.min() < lo or ratio.max() > hi):
            k = int(np.argmin(ratio) if ratio.min() < lo else np.argmax(ratio))
            return self._diagnosis(k, "density", s.rho[k], f"ρ/ρ0 = {ratio[k]:.4g} is outside [{lo}, {hi}]")
        vmax = wd.max_speed if wd.max_speed is not None else 2.0 * max(c0, 1e-30)
        speed2 = np.einsum("ij,ij->i", s.v[f], s.v[f])
        if speed2.size and speed2.max() > vmax**2:
            k = int(np.argmax(speed2))
            return self._diagnosis(k, "velocity", s.v[k], f"speed {math.sqrt(speed2[k]):.4g} m/s exceeds {vmax:.4g} m/s")
        return None

    def _diagnosis(self, k: int, quantity: str, value, what: str) -> dict:
        s = self.state
        body = next((name for name, sl in s.bodies.items() if sl.start <= k < sl.stop), "?")
        nnb = int(s.neighbors.indptr[k + 1] - s.neighbors.indptr[k]) if s.neighbors is not None else -1
        return {
            "step": s.step, "time": s.t, "particle": k, "body": body, "quantity": quantity,
            "value": np.atleast_1d(np.asarray(value, dtype=float)).tolist(), "problem": what,
            "position": s.x[k].tolist(), "neighbours": nnb,
        }

    # ------------------------------------------------------------------ checkpoints
    def checkpoint_data(self) -> tuple[dict[str, np.ndarray], dict]:
        """Arrays and metadata that let a new :class:`Simulation` continue bit for bit."""
        s = self.state
        arrays = {k: getattr(s, k).copy() for k in CHECKPOINT_ARRAYS}
        for k, v in s.extra.items():
            arrays[f"extra__{k}"] = np.asarray(v).copy()
        if self._table_volumes is not None:  # RKPM: the volumes of the current table
            arrays["table_volumes"] = self._table_volumes.copy()
        meta = {
            "scene": self.scene.name, "t": s.t, "step": s.step, "dt_next": s.dt_next, "n": s.n,
            "n_fluid": s.n_fluid, "effects": {e.name: e.state_dict() for e in self.scene.effects},
            "counters": {"fallback_points": self.fallback_points, "fallback_steps": self.fallback_steps,
                         "mass_floored": self.mass_floored, "neighbor_builds": self.neighbor_builds},
            "parameters": to_jsonable(self.scene.parameters),
        }
        return arrays, meta

    def restore(self, arrays: dict[str, np.ndarray], meta: dict) -> None:
        """Load a checkpoint into this simulation (same scene); continues bit for bit."""
        s = self.state
        if meta.get("n") != s.n or meta.get("n_fluid") != s.n_fluid:
            raise ValueError(
                f"checkpoint has {meta.get('n')} particles ({meta.get('n_fluid')} fluid) but the scene "
                f"has {s.n} ({s.n_fluid}); restart with the scene that wrote it"
            )
        for k in CHECKPOINT_ARRAYS:
            setattr(s, k, np.ascontiguousarray(arrays[k]).copy())
        for k, v in arrays.items():
            if k.startswith("extra__"):
                s.extra[k[len("extra__"):]] = v.copy()
        s.t, s.step, s.dt_next = float(meta["t"]), int(meta["step"]), float(meta["dt_next"])
        for e in self.scene.effects:
            e.load_state_dict(meta["effects"].get(e.name, {}))
        c = meta["counters"]
        self.fallback_points, self.fallback_steps = c["fallback_points"], c["fallback_steps"]
        self.mass_floored, self.neighbor_builds = c["mass_floored"], c["neighbor_builds"]
        # rebuild the neighbour list from the reference positions it was built from, so the
        # skin logic and the pair order are exactly those of the uninterrupted run
        s.neighbors = find_neighbors(s.x_ref, s.x_ref, radius=self.search_radius)
        # the first kick of the next step forms L with the table of the current positions
        # (kdk); without it a restarted run had no table at all
        self._shape_functions(arrays.get("table_volumes"))
        self._initialised = True

    # ------------------------------------------------------------------ run
    def run(self, out: str | Path | None = None, *, progress: bool = True, restart: str | Path | None = None,
            max_steps: int | None = None) -> RunResult:
        """Run to ``scene.t_end`` (or ``max_steps`` steps) and return a :class:`RunResult`.

        ``out``: run directory for ``timeseries.csv``, the VTU/PVD series, checkpoints,
        ``summary.json`` and pictures (nothing is written without it). ``restart``: a checkpoint
        file (or ``"latest"`` in ``out``) to continue from.
        """
        from mlsgalerkin.run_output import RunOutput

        output = RunOutput(self, out) if out is not None else None
        if restart is not None:
            from mlsgalerkin.io import latest_checkpoint, load_checkpoint

            path = latest_checkpoint(Path(out) / "checkpoints") if str(restart) == "latest" else Path(restart)
            if path is None:
                raise FileNotFoundError(f"no checkpoint found in {Path(out) / 'checkpoints'}")
            arrays, meta = load_checkpoint(path)
            self.restore(arrays, meta)
            logger.info("restarted from %s at t = %.6g s (step %d)", path, self.state.t, self.state.step)
        elif not self._initialised:
            self.initialise()
        s = self.state
        if output is not None:
            output.start(resumed=restart is not None)
        wall0 = time.perf_counter()
        steps0 = s.step
        last_good = self.checkpoint_data()
        bar = _progress_bar(self.scene.t_end, s.t, disable=not progress)
        try:
            while s.t < self.scene.t_end * (1 - 1e-12) and (max_steps is None or s.step - steps0 < max_steps):
                dt = min(s.dt_next, self.scene.t_end - s.t)
                self.step(dt)
                diag = self.check_health()
                if diag is not None:
                    path = output.write_checkpoint(*last_good, name="last_good") if output else None
                    if output is not None:  # keep the time series up to the failure for diagnosis
                        output.ts.flush()
                    msg = (
                        f"run diverged at step {diag['step']} (t = {diag['time']:.6g} s): particle "
                        f"{diag['particle']} of body {diag['body']!r} at {np.round(diag['position'], 6).tolist()} "
                        f"— {diag['quantity']} {diag['problem']} (value {diag['value']}, {diag['neighbours']} "
                        f"neighbours). Last good state (step {last_good[1]['step']}) "
                        + (f"saved to {path}" if path else "kept in memory (no output directory)")
                        + ". Try a smaller time step (scene.safety or dt_max), more artificial viscosity, "
                        "or a finer resolution."
                    )
                    self.last_good = last_good
                    raise SimulationDiverged(msg, diag, path)
                if s.step % self.scene.watchdog.keep_every == 0:
                    last_good = self.checkpoint_data()
                if output is not None:
                    output.after_step()
                bar.update(dt)
                if bar is not None and s.step % 20 == 0:
                    el = time.perf_counter() - wall0
                    bar.set_postfix_str(f"dt={dt:.2e} s, {(s.step - steps0) / max(el, 1e-9):.0f} steps/s")
        finally:
            bar.close()
        wall = time.perf_counter() - wall0
        summary = self.summary(wall, s.step - steps0)
        if output is not None:
            output.finish(summary)
            ts = output.timeseries_dict()
        else:
            ts = {}
        return RunResult(state=s, timeseries=ts, summary=summary, out=Path(out) if out is not None else None)

    def summary(self, wall: float, steps: int) -> dict:
        s = self.state
        total = sum(self.timer.seconds.values()) or 1.0
        return {
            "scene": self.scene.name,
            "parameters": to_jsonable(self.scene.parameters),
            "particles": {"fluid": s.n_fluid, "wall": s.n_walls, "total": s.n},
            "spacing_m": s.spacing, "h_m": float(s.h[0]) if s.n else None,
            "approximation": to_jsonable(self.scene.approximation.__dict__),
            "integrator": self.scene.integrator, "mass": self.scene.mass,
            "effects": [repr(e) for e in self.scene.effects],
            "t_end_s": s.t, "steps": s.step, "steps_this_run": steps, "wall_time_s": wall,
            "particle_steps_per_s": s.n * steps / wall if wall > 0 else None,
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
            "effect_reports": {e.name: to_jsonable(e.summary()) for e in self.scene.effects if e.summary()},
        }


class _NoBar:
    def update(self, n: float) -> None: ...
    def set_postfix_str(self, s: str) -> None: ...
    def close(self) -> None: ...


def _progress_bar(total: float, start: float, disable: bool):
    if disable:
        return _NoBar()
    from tqdm.auto import tqdm

    return tqdm(total=total, initial=start, unit="s", unit_scale=False, desc="simulated time", mininterval=1.0,
                bar_format="{l_bar}{bar}| {n:.4f}/{total:.4f} s [{elapsed}<{remaining}{postfix}]")
