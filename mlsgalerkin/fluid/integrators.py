r"""Time integrators of the fluid: staggered kick-drift-kick and predictor-corrector.

An integrator is chosen once (``Scene.integrator``, a name or an instance) and advances a
:class:`~mlsgalerkin.fluid.solver.FluidSolver` by ``Δt``. Its step is split at the point where
the positions at ``t + Δt`` are known and the forces there are not yet: :meth:`Integrator.begin`
goes up to that point, the run loop lets the interactions exchange forces at ``t + Δt``, and
:meth:`Integrator.end` evaluates the forces and completes the step. :meth:`Integrator.advance`
does both, for a fluid on its own.

``"kdk"`` — :class:`KickDriftKick` (default, one evaluation per step)
    ``v += ½Δt a``; ``ρ += ½Δt ρ̇(x^n, v^½)`` (old table, new velocity); drift-stage effects
    (particle shifting, ``x += δr``); ``x += Δt v``; walls to ``t + Δt`` | kinematics at
    ``x^{n+1}`` (after the exchange, so walls riding on a structure are where it put them);
    ``ρ += ½Δt ρ̇(x^{n+1}, v^½)``; dynamics; ``v += ½Δt a``. Velocity and density form a staggered leapfrog pair, stable for
    ``ω Δt < 2``. (Advancing ``ρ`` with the rate of the *previous* half step instead has
    amplification ``det = 1 + (ωΔt)²/2`` per step: unconditionally unstable.)
``"predictor_corrector"`` — :class:`PredictorCorrector` (explicit midpoint, two evaluations)
    ``v, ρ`` to the midpoint with the old rates, ``x`` with the old velocity; evaluation at the
    midpoint; full step with the midpoint rates, ``x`` with the mean velocity | evaluation at
    ``t + Δt``. Its amplification ``|1 − z²/2 + iz|² = 1 + z⁴/4`` grows weakly and relies on
    some artificial viscosity. The midpoint evaluation sees the interaction forces of the last
    exchange.
"""

from __future__ import annotations

import time
from typing import Any, ClassVar, Protocol

__all__ = ["INTEGRATORS", "Integrator", "KickDriftKick", "PredictorCorrector", "Steppable", "make_integrator"]


class Steppable(Protocol):
    """What an integrator drives: the :class:`~mlsgalerkin.fluid.solver.FluidSolver`'s two halves of
    a force evaluation, its drift effects, its walls, its state and its stage timer."""

    @property
    def state(self) -> Any:
        """The :class:`~mlsgalerkin.fluid.state.FluidState` (flat particle arrays)."""

    timer: Any

    def kinematics(self) -> None:
        """Neighbours, shape functions, velocity gradient and continuity rate at the current positions."""

    def dynamics(self) -> None:
        """Pressure, stress, forces and accelerations."""

    def evaluate(self) -> None:
        """Both halves."""

    def continuity_rate(self, reuse_added: bool = False) -> None:
        """``ρ̇`` (kg/m³/s, (n,), into the state) at the current velocities with the last table."""

    def drift_effects(self, dt: float) -> None:
        """Displacements of the drift-stage effects (particle shifting) added before the drift."""

    def move_walls(self, t: float) -> None:
        """Walls with a prescribed motion to time ``t`` (s)."""


class Integrator:
    """Advances a fluid solver by ``dt`` in two phases around the force exchange."""

    name: ClassVar[str] = "integrator"
    #: Force evaluations per step (for cost estimates).
    evaluations: ClassVar[int] = 1

    def begin(self, solver: Steppable, t: float, dt: float) -> None:
        """From ``t`` up to the positions at ``t + dt``."""
        raise NotImplementedError

    def end(self, solver: Steppable, t: float, dt: float) -> None:
        """Forces at ``t + dt`` and the rest of the step."""
        raise NotImplementedError

    def advance(self, solver: Steppable, t: float, dt: float) -> None:
        """One whole step (no interactions in between)."""
        self.begin(solver, t, dt)
        self.end(solver, t, dt)

    def __repr__(self) -> str:
        return f"{type(self).__name__}()"


class KickDriftKick(Integrator):
    """Staggered kick-drift-kick (module docstring): one force evaluation per step."""

    name = "kdk"

    def begin(self, solver: Steppable, t: float, dt: float) -> None:
        s = solver.state
        f = s.fluid
        t0 = time.perf_counter()
        s.v[f] += 0.5 * dt * s.a[f]
        solver.timer.add("integrate", t0)
        # density is advanced with the half-step velocity over both ends of the drift
        # (staggered leapfrog for the v–ρ wave pair; a lagged rate would be unstable). The
        # added terms (density diffusion: positions and densities only) are those of the last
        # evaluation, at these positions
        solver.continuity_rate(reuse_added=True)
        s.rho[f] += 0.5 * dt * s.drho[f]
        solver.drift_effects(dt)  # particle shifting: moves x by δr, re-interpolates v and ρ
        t0 = time.perf_counter()
        s.x[f] += dt * s.v[f]
        solver.move_walls(t + dt)
        solver.timer.add("integrate", t0)

    def end(self, solver: Steppable, t: float, dt: float) -> None:
        s = solver.state
        f = s.fluid
        # kinematics here, after the exchange: walls riding on a structure are where the
        # structure put them at t + dt (the exchange sets them), not where they were predicted
        solver.kinematics()
        s.rho[f] += 0.5 * dt * s.drho[f]
        solver.dynamics()
        t0 = time.perf_counter()
        s.v[f] += 0.5 * dt * s.a[f]
        solver.timer.add("integrate", t0)


class PredictorCorrector(Integrator):
    """Explicit midpoint predictor-corrector (module docstring): two force evaluations per step."""

    name = "predictor_corrector"
    evaluations = 2

    def begin(self, solver: Steppable, t: float, dt: float) -> None:
        s = solver.state
        f = s.fluid
        solver.drift_effects(dt)  # particle shifting at xⁿ (moves x by δr, re-interpolates v and ρ)
        t0 = time.perf_counter()
        x0, v0, rho0 = s.x[f].copy(), s.v[f].copy(), s.rho[f].copy()
        s.v[f] = v0 + 0.5 * dt * s.a[f]
        s.rho[f] = rho0 + 0.5 * dt * s.drho[f]
        s.x[f] = x0 + 0.5 * dt * v0
        solver.move_walls(t + 0.5 * dt)
        solver.timer.add("integrate", t0)
        solver.evaluate()
        t0 = time.perf_counter()
        s.v[f] = v0 + dt * s.a[f]
        s.rho[f] = rho0 + dt * s.drho[f]
        s.x[f] = x0 + 0.5 * dt * (v0 + s.v[f])
        solver.move_walls(t + dt)
        solver.timer.add("integrate", t0)

    def end(self, solver: Steppable, t: float, dt: float) -> None:
        solver.evaluate()


INTEGRATORS: dict[str, type[Integrator]] = {"kdk": KickDriftKick, "predictor_corrector": PredictorCorrector}


def make_integrator(spec: str | Integrator) -> Integrator:
    """The integrator named ``spec`` (``"kdk"``, ``"predictor_corrector"``) or ``spec`` itself."""
    if isinstance(spec, Integrator):
        return spec
    if isinstance(spec, str) and spec in INTEGRATORS:
        return INTEGRATORS[spec]()
    raise ValueError(f"integrator must be 'kdk' or 'predictor_corrector' (or an Integrator), got {spec!r}")
