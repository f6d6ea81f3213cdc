r"""How each kind of structure body advances over one outer step, with the surface forces held.

:class:`ElasticMotion` advances an :class:`~mlsgalerkin.structure.elastic.ElasticBody`:

- ``integrator="explicit"``: central differences (velocity Verlet) sub-cycled ``n`` times inside
  the outer step, ``n = ceil(Δt/(C·2/ω_max))`` with the safety ``C`` = :data:`SUBSTEP_SAFETY`
  (:mod:`mlsgalerkin.structure.explicit`; the nonlinear models evaluate the total-Lagrangian
  internal force of :mod:`mlsgalerkin.structure.hyperelastic` at each sub-step);
- ``integrator="newmark"``: one implicit average-acceleration Newmark step
  (:math:`\beta = 1/4, \gamma = 1/2`, unconditionally stable, no numerical damping),

  .. math:: (M + \gamma\Delta t\,C + \beta\Delta t^2K)\,\mathbf a^{n+1} = \mathbf f
            - C(\mathbf v^n + (1-\gamma)\Delta t\,\mathbf a^n)
            - K(\mathbf u^n + \Delta t\,\mathbf v^n + (\tfrac12-\beta)\Delta t^2\mathbf a^n),

  with the factorisation kept while the outer step does not change.

:class:`RigidMotion` advances a :class:`~mlsgalerkin.structure.rigid.RigidBody` by velocity
Verlet in its constrained coordinates, sub-cycled so that :math:`\omega_n\,\delta t \le 0.05`
for a hinge spring.

The held force of an outer step is the weight plus what the interactions added at the last
exchange (contact, the fluid's reaction on the wall particles riding on the body). Both keep the
work done by those forces, :math:`W = \sum \mathbf f\cdot\Delta\mathbf u` over each outer step
(exact for a force held constant), for the energy balance of a coupled run.
"""

from __future__ import annotations

import math
import time
from typing import Any

import numpy as np
import scipy.sparse as sp
from numpy.typing import NDArray
from scipy.sparse.linalg import splu

from mlsgalerkin.dynamics import Surface
from mlsgalerkin.structure.elastic import ElasticBody
from mlsgalerkin.structure.explicit import subcycle_linear
from mlsgalerkin.structure.rigid import Hinge, RigidBody

__all__ = ["ElasticMotion", "RigidMotion", "SUBSTEP_SAFETY"]

FloatArray = NDArray[np.float64]

#: Fraction of the central-difference limit ``2/ω_max`` a sub-step takes (linear; the nonlinear
#: models take 0.8 of it, their tangent stiffens under stretch).
SUBSTEP_SAFETY = 0.9
#: Largest ``ω δt`` of a rigid body's sub-steps on its hinge spring.
RIGID_PHASE_PER_SUBSTEP = 0.05


def _cross(r: FloatArray, f: FloatArray) -> FloatArray:
    """``r × f`` (z-component) of ``(n, 2)`` rows."""
    return r[..., 0] * f[..., 1] - r[..., 1] * f[..., 0]


class ElasticMotion:
    """State and integrator of one :class:`ElasticBody` (module docstring)."""

    kind = "elastic"

    def __init__(self, body: ElasticBody) -> None:
        self.body = body
        n = body.n_dofs
        self.K = body.stiffness.tocsr()
        self.K.sort_indices()
        self.inv_m = 1.0 / body.lumped_mass
        self.fixed = np.zeros(n, dtype=np.bool_)
        self.fixed[body.clamped_dofs] = True
        self.a0, self.a1 = body.damping
        self.omega_max = body.highest_frequency()
        # with stiffness-proportional damping the central-difference limit shrinks to
        # (2/ω)(sqrt(1 + ξ²) − ξ), ξ = a1 ω/2 + a0/(2ω) at the highest mode
        xi = 0.5 * (self.a1 * self.omega_max + self.a0 / self.omega_max)
        safety = SUBSTEP_SAFETY if body.model == "linear" else 0.8
        self.substep_limit = safety * 2.0 / self.omega_max * (math.sqrt(1.0 + xi * xi) - xi)
        self.u = np.zeros(n)
        self.v = np.zeros(n)
        self.a = np.zeros(n)
        self.f = np.zeros(n)          # surface forces of the last exchange (N)
        self.work = 0.0               # work of the held surface forces (J per unit depth)
        self.substeps = 0
        self.outer_steps = 0
        self.max_substeps = 0
        self.seconds = 0.0
        self._lu: Any = None
        self._lu_dt: float | None = None
        self._internal = None
        if body.model != "linear":
            from mlsgalerkin.structure.hyperelastic import QuadratureData

            self._quadrature = QuadratureData.from_basis(body.basis)
            self._lame = body.material.lame()

    # ------------------------------------------------------------------ forces
    def internal_force(self, u: FloatArray) -> FloatArray:
        """``K u`` (linear) or the total-Lagrangian ``∫ P : ∇δu`` (N)."""
        if self.body.model == "linear":
            return self.K @ u
        from mlsgalerkin.structure.hyperelastic import internal_force

        return internal_force(self._quadrature, u, *self._lame, self.body.model)

    def acceleration(self) -> FloatArray:
        """``M⁻¹(f_g + f − f_int(u) − C v)`` with the clamped degrees of freedom at zero."""
        b = self.body
        a = (b.weight + self.f - self.internal_force(self.u) - self.a1 * (self.K @ self.v)) * self.inv_m - self.a0 * self.v
        a[self.fixed] = 0.0
        return a

    def start(self) -> None:
        self.a = self.acceleration()

    # ------------------------------------------------------------------ stepping
    def advance(self, dt: float) -> None:
        """Advance ``u, v, a`` by the outer step ``dt`` (s) with the forces held."""
        t0 = time.perf_counter()
        b = self.body
        u_start = self.u[self.body.wet.dofs].copy()
        if b.integrator == "newmark":
            self._newmark(dt)
            n = 1
        else:
            n = max(1, math.ceil(dt / self.substep_limit * (1.0 - 1e-12)))
            h = dt / n
            if b.model == "linear":
                subcycle_linear(self.K, self.inv_m, self.fixed, b.weight + self.f, self.u, self.v, self.a, h, n,
                                self.a0, self.a1)
            else:
                for _ in range(n):
                    self.v += 0.5 * h * self.a
                    self.u += h * self.v
                    self.a = self.acceleration()
                    self.v += 0.5 * h * self.a
        du = self.u[b.wet.dofs] - u_start
        self.work += float(np.sum(self.f[b.wet.dofs] * du))
        self.substeps += n
        self.max_substeps = max(self.max_substeps, n)
        self.outer_steps += 1
        self.seconds += time.perf_counter() - t0

    def _newmark(self, dt: float) -> None:
        beta, gamma = 0.25, 0.5
        free = self.body.free
        if self._lu is None or self._lu_dt != dt:
            M = sp.diags(1.0 / self.inv_m)
            C = self.a0 * M + self.a1 * self.K
            A = (M + gamma * dt * C + beta * dt * dt * self.K).tocsr()[free][:, free]
            self._lu, self._lu_dt = splu(A.tocsc()), dt
        u, v, a = self.u, self.v, self.a
        u_pred = u + dt * v + (0.5 - beta) * dt * dt * a
        v_pred = v + (1.0 - gamma) * dt * a
        rhs = self.body.weight + self.f - self.K @ u_pred - self.a1 * (self.K @ v_pred) - self.a0 * v_pred / self.inv_m
        a_new = np.zeros_like(a)
        a_new[free] = self._lu.solve(rhs[free])
        self.u = u_pred + beta * dt * dt * a_new
        self.v = v_pred + gamma * dt * a_new
        self.a = a_new

    # ------------------------------------------------------------------ surface
    def surface(self) -> Surface:
        w = self.body.wet
        return Surface(self.body.name, w.reference + self.u[w.dofs], self.v[w.dofs].copy(),
                       w.segments, 1.0 / self.inv_m[w.dofs[:, 0]], self.a[w.dofs].copy())

    def add_forces(self, forces: FloatArray) -> None:
        np.add.at(self.f, self.body.wet.dofs, forces)

    def clear_forces(self) -> None:
        self.f[:] = 0.0

    # ------------------------------------------------------------------ energy and report
    def energies(self) -> dict[str, float]:
        """Kinetic ``½vᵀMv``, strain (``½uᵀKu`` or ``∫W``), potential of the weight ``−f_g·u``, and
        the work of the surface forces so far (J per unit depth)."""
        b = self.body
        kinetic = 0.5 * float(np.dot(self.v / self.inv_m, self.v))
        if b.model == "linear":
            strain = 0.5 * float(self.u @ (self.K @ self.u))
        else:
            from mlsgalerkin.structure.hyperelastic import strain_energy

            strain = float(strain_energy(self._quadrature, self.u, *self._lame, b.model))
        return {"kinetic_energy": kinetic, "strain_energy": strain,
                "weight_potential": -float(b.weight @ self.u), "surface_work": self.work}

    def observables(self) -> dict[str, float]:
        row = self.energies()
        for key, d in self.body.point_displacements(self.u).items():
            row[f"{key}_ux"], row[f"{key}_uy"] = float(d[0]), float(d[1])
        return row

    def frame(self) -> tuple[FloatArray, dict[str, FloatArray]]:
        b = self.body
        loc = b.basis.doflocs[:, b.basis.nodal_dofs[0]].T
        dofs = b.basis.nodal_dofs.T
        return loc + self.u[dofs], {"displacement": self.u[dofs], "velocity": self.v[dofs]}

    def finite(self) -> bool:
        return bool(np.all(np.isfinite(self.u)) and np.all(np.isfinite(self.v)))

    def checkpoint(self) -> dict[str, FloatArray]:
        return {"u": self.u.copy(), "v": self.v.copy(), "a": self.a.copy(), "f": self.f.copy(),
                "counters": np.array([self.work, self.substeps, self.outer_steps, self.max_substeps], dtype=float)}

    def restore(self, arrays: dict[str, FloatArray]) -> None:
        self.u, self.v, self.a, self.f = (arrays[k].copy() for k in ("u", "v", "a", "f"))
        work, sub, outer, mx = arrays["counters"]
        self.work, self.substeps, self.outer_steps, self.max_substeps = float(work), int(sub), int(outer), int(mx)

    def summary(self) -> dict[str, Any]:
        b = self.body
        return {"kind": "elastic", "model": b.model, "integrator": b.integrator, "element": b.element,
                "dofs": b.n_dofs, "elements": int(b.mesh.t.shape[1]), "omega_max_rad_s": self.omega_max,
                "substep_limit_s": self.substep_limit, "outer_steps": self.outer_steps, "substeps": self.substeps,
                "substeps_per_step_max": self.max_substeps,
                "substeps_per_step_mean": self.substeps / self.outer_steps if self.outer_steps else None,
                "time_s": self.seconds, **{f"end_{k}_J": v for k, v in self.energies().items()}}


class RigidMotion:
    """State and integrator of one :class:`RigidBody` (module docstring)."""

    kind = "rigid"

    def __init__(self, body: RigidBody) -> None:
        self.body = body
        self.X = body.surface.nodes.copy()
        self.c0 = body.centre.copy()
        self.c = body.centre.copy()
        self.theta = 0.0
        self.V = body.velocity.copy()
        self.omega = float(body.angular_velocity)
        self.A = np.zeros(2)
        self.alpha = 0.0
        self.F = np.zeros(2)          # resultant of the surface forces of the last exchange (N)
        self.M = 0.0                  # their moment about the centre of mass (N m)
        self.work = 0.0
        self.substeps = 0
        self.outer_steps = 0
        self.seconds = 0.0
        h = body.constraint
        self.g = np.zeros(2) if body.gravity is None else body.gravity
        if isinstance(h, Hinge):
            self.p = np.asarray(h.point, dtype=float)
            self.I = body.hinge_inertia()
            w2 = max(body.natural_frequency_squared(), 0.0)
            self.omega_n = math.sqrt(w2)
        else:
            self.p = None
            self.I = body.inertia
            self.omega_n = 0.0

    def _rotation(self, theta: float) -> FloatArray:
        c, s = math.cos(theta), math.sin(theta)
        return np.array([[c, -s], [s, c]])

    def nodes(self) -> FloatArray:
        """Surface node positions ``(m, 2)`` now (m)."""
        return self.c + (self.X - self.c0) @ self._rotation(self.theta).T

    def _accelerations(self) -> None:
        b, m = self.body, self.body.mass
        con = b.constraint
        if isinstance(con, Hinge):
            r = self.c - self.p
            moment = self.M + float(_cross(r, self.F)) + float(_cross(r, m * self.g))
            self.alpha = (moment - con.stiffness * self.theta - con.damping * self.omega) / self.I
            self.A = self.alpha * np.array([-r[1], r[0]]) - self.omega**2 * r
        elif con == "free":
            self.A = self.F / m + self.g
            self.alpha = self.M / self.I
        elif con == "vertical":
            self.A = np.array([0.0, self.F[1] / m + self.g[1]])
            self.alpha = 0.0
        else:
            self.A, self.alpha = np.zeros(2), 0.0

    def start(self) -> None:
        self._accelerations()

    def advance(self, dt: float) -> None:
        t0 = time.perf_counter()
        con = self.body.constraint
        nodes_start = self.nodes()
        n = 1
        if self.omega_n > 0:
            n = max(1, math.ceil(dt * self.omega_n / RIGID_PHASE_PER_SUBSTEP * (1.0 - 1e-12)))
        h = dt / n
        for _ in range(n):
            if isinstance(con, Hinge):
                self.omega += 0.5 * h * self.alpha
                self.theta += h * self.omega
                self.c = self.p + self._rotation(self.theta) @ (self.c0 - self.p)
                r = self.c - self.p
                self.V = self.omega * np.array([-r[1], r[0]])
                self._accelerations()
                self.omega += 0.5 * h * self.alpha
                self.V = self.omega * np.array([-r[1], r[0]])
            else:
                self.V += 0.5 * h * self.A
                self.omega += 0.5 * h * self.alpha
                self.c = self.c + h * self.V
                self.theta += h * self.omega
                self._accelerations()
                self.V += 0.5 * h * self.A
                self.omega += 0.5 * h * self.alpha
        self.work += float(np.sum(self._held * (self.nodes() - nodes_start))) if self._held is not None else 0.0
        self.substeps += n
        self.outer_steps += 1
        self.seconds += time.perf_counter() - t0

    _held: FloatArray | None = None

    def surface(self) -> Surface:
        r = self.nodes() - self.c
        perp = np.stack([-r[:, 1], r[:, 0]], axis=1)
        v = self.V + self.omega * perp
        a = self.A + self.alpha * perp - self.omega**2 * r
        return Surface(self.body.name, self.c + r, v, self.body.surface.facets, None, a)

    def add_forces(self, forces: FloatArray) -> None:
        r = self.nodes() - self.c
        self.F = self.F + forces.sum(axis=0)
        self.M += float(np.sum(_cross(r, forces)))
        self._held = forces.copy() if self._held is None else self._held + forces

    def clear_forces(self) -> None:
        self.F = np.zeros(2)
        self.M = 0.0
        self._held = None

    def energies(self) -> dict[str, float]:
        b = self.body
        con = b.constraint
        if isinstance(con, Hinge):
            kinetic, spring = 0.5 * self.I * self.omega**2, 0.5 * con.stiffness * self.theta**2
        else:
            kinetic, spring = 0.5 * b.mass * float(self.V @ self.V) + 0.5 * b.inertia * self.omega**2, 0.0
        return {"kinetic_energy": kinetic, "spring_energy": spring,
                "weight_potential": -b.mass * float(self.g @ (self.c - self.c0)), "surface_work": self.work}

    def observables(self) -> dict[str, float]:
        row = self.energies()
        d = self.c - self.c0
        row.update({"x": float(d[0]), "y": float(d[1]), "angle": self.theta, "vx": float(self.V[0]),
                    "vy": float(self.V[1]), "omega": self.omega, "force_x": float(self.F[0]),
                    "force_y": float(self.F[1]), "moment": self.M})
        return row

    def frame(self) -> tuple[FloatArray, dict[str, FloatArray]]:
        x = self.nodes()
        return x, {"displacement": x - self.X, "velocity": self.surface().velocities}

    def finite(self) -> bool:
        return bool(np.all(np.isfinite(self.c)) and math.isfinite(self.theta) and math.isfinite(self.omega))

    def checkpoint(self) -> dict[str, FloatArray]:
        held = np.zeros_like(self.X) if self._held is None else self._held
        return {"c": self.c.copy(), "V": self.V.copy(), "A": self.A.copy(), "F": self.F.copy(), "held": held.copy(),
                "scalars": np.array([self.theta, self.omega, self.alpha, self.M, self.work, self.substeps,
                                     self.outer_steps], dtype=float)}

    def restore(self, arrays: dict[str, FloatArray]) -> None:
        self.c, self.V, self.A, self.F = (arrays[k].copy() for k in ("c", "V", "A", "F"))
        self._held = arrays["held"].copy()
        th, om, al, M, work, sub, outer = arrays["scalars"]
        self.theta, self.omega, self.alpha, self.M, self.work = float(th), float(om), float(al), float(M), float(work)
        self.substeps, self.outer_steps = int(sub), int(outer)

    def summary(self) -> dict[str, Any]:
        b = self.body
        con = b.constraint
        return {"kind": "rigid", "constraint": repr(con) if isinstance(con, Hinge) else con, "mass_kg": b.mass,
                "inertia_kg_m2": self.I, "natural_period_s": b.natural_period() if isinstance(con, Hinge) else None,
                "outer_steps": self.outer_steps, "substeps": self.substeps, "time_s": self.seconds,
                **{f"end_{k}_J": v for k, v in self.energies().items()}}
