r"""How each kind of structure body advances over one outer step.

**Surface forces over a step.** The forces the interactions add at :math:`t_n` (contact, the
fluid's reaction on the wall particles riding on the body) act over the outer step
:math:`[t_n, t_{n+1}]` as a linear ramp from :math:`\mathbf f_n` to its extrapolation
:math:`\mathbf f_n + (\Delta t_n/\Delta t_{n-1})(\mathbf f_n - \mathbf f_{n-1})`, so their mean
over the step is the second-order estimate of :math:`\mathbf f(t_{n+1/2})`. Two simpler choices
were measured unstable on the plate under a water column (``hydrostatic_plate``, 2 m of water on
a 5 cm aluminium plate): holding :math:`\mathbf f_n` over the step (a lag of half a step; the
plate gained energy at an e-fold every few milliseconds) and applying :math:`\mathbf f_n` as
impulses at the step boundaries as the fluid's kick-drift-kick does (every impulse rings the
plate's stiff through-thickness modes, which the fluid then sees). The wall pressure must also
see the surface's acceleration (:class:`~mlsgalerkin.interactions.StructureCoupling`): without
it the same plate diverged.

:class:`ElasticMotion` advances an :class:`~mlsgalerkin.structure.elastic.ElasticBody`:

- ``integrator="explicit"``: central differences (velocity Verlet) sub-cycled ``n`` times inside
  the outer step, ``n = ceil(Δt/(C·2/ω_max))`` with the safety ``C`` = :data:`SUBSTEP_SAFETY`
  (:mod:`mlsgalerkin.structure.explicit`; the nonlinear models evaluate the total-Lagrangian
  internal force of :mod:`mlsgalerkin.structure.hyperelastic` at each sub-step). The
  stiffness-proportional damping ``a1`` includes the body's ``high_mode_damping`` (a damping
  ratio at ``ω_max``), which keeps the resolved but irrelevant stiff modes from ringing at the
  surface the fluid sees; the damping ratio it implies at the first mode is reported.
- ``integrator="newmark"``: one implicit average-acceleration Newmark step
  (:math:`\beta = 1/4, \gamma = 1/2`, unconditionally stable, no numerical damping),

  .. math:: (M + \gamma\Delta t\,C + \beta\Delta t^2K)\,\mathbf a^{n+1} = \mathbf f_g + \mathbf f^{n+1}
            - C(\mathbf v^n + (1-\gamma)\Delta t\,\mathbf a^n)
            - K(\mathbf u^n + \Delta t\,\mathbf v^n + (\tfrac12-\beta)\Delta t^2\mathbf a^n),

  with :math:`\mathbf a^n` in equilibrium with the surface forces at :math:`t_n` and
  :math:`\mathbf f^{n+1}` their extrapolation; the factorisation is kept while the step stays
  within 1 % below the one it was made for (:data:`NEWMARK_REUSE`; ``β`` then lies in
  ``[1/4, 0.255]``).

:class:`RigidMotion` advances a :class:`~mlsgalerkin.structure.rigid.RigidBody` by velocity
Verlet in its constrained coordinates, sub-cycled so that :math:`\omega_n\,\delta t \le 0.05`
for a hinge spring, with the same ramp of the surface force and moment.

A free 3D body (six degrees of freedom) keeps its orientation as a unit quaternion :math:`q`
(:math:`R(q)` turns the body from rest, :math:`\mathbf x_a = \mathbf c + R(\mathbf X_a -
\mathbf c_0)`) and its angular momentum about the centre in the world frame :math:`\mathbf L`
(kg m²/s, (3,)). With the inertia tensor at rest :math:`I_c = E\,\mathrm{diag}(I_1, I_2, I_3)E^{\mathsf T}`
(principal moments :math:`I_i` in kg m², ascending; principal axes :math:`\mathbf u_i = E\mathbf e_i`
in the rest frame, :math:`\det E = 1`), a sub-step :math:`\delta t` (s) is the kick–rotate–kick
splitting of Dullweber, Leimkuhler & McLachlan (1997, J. Chem. Phys. 107, 5840), with the
translation by velocity Verlet:

.. math:: \mathbf V \mathrel{+}= \tfrac{\delta t}2\mathbf A_k,\quad
          \mathbf L \mathrel{+}= \tfrac{\delta t}2\mathbf M_k,\quad
          \mathbf c \mathrel{+}= \delta t\,\mathbf V,\quad
          q \leftarrow \Phi^{1}_{\delta t/2}\circ\Phi^{2}_{\delta t/2}\circ\Phi^{3}_{\delta t}
          \circ\Phi^{2}_{\delta t/2}\circ\Phi^{1}_{\delta t/2}\,(q),\quad
          \mathbf V \mathrel{+}= \tfrac{\delta t}2\mathbf A_{k+1},\quad
          \mathbf L \mathrel{+}= \tfrac{\delta t}2\mathbf M_{k+1},

with :math:`\mathbf A = \mathbf F/m + \mathbf g` and :math:`\mathbf M` (N m, world frame, about
the centre) the ramped surface load at the sub-step's ends. :math:`\Phi^i_\tau` is the exact
flow of :math:`T_i = \Pi_i^2/(2I_i)`, one part of the kinetic energy of the free body
:math:`T = \sum_i T_i`: a rotation about the principal axis :math:`\mathbf u_i` by the angle
:math:`\varphi = \tau\,\Pi_i/I_i`, :math:`\Pi_i = \mathbf u_i\cdot R(q)^{\mathsf T}\mathbf L`
(kg m²/s, the principal component in the body frame, constant along :math:`\Phi^i`),

.. math:: q \leftarrow q\otimes\bigl(\cos\tfrac\varphi2,\ \sin\tfrac\varphi2\,\mathbf u_i\bigr),

which leaves :math:`\mathbf L` in the world frame unchanged (in the body frame
:math:`\boldsymbol\Pi` turns by :math:`-\varphi` about :math:`\mathbf u_i`); :math:`q` is
renormalised after the sub-step. The scheme is explicit, symplectic, time-reversible and second
order; without torque it keeps :math:`\mathbf L` exactly (to round-off) and the kinetic energy
within :math:`O(\delta t^2)` without drift. It sub-cycles so that :math:`|\boldsymbol\omega|\,
\delta t \le 0.05` at the step's start. After the sub-step the world angular velocity and
acceleration (for the surface's velocities and accelerations) are

.. math:: \boldsymbol\omega = I_w^{-1}\mathbf L,\qquad
          \boldsymbol\alpha = I_w^{-1}(\mathbf M - \boldsymbol\omega\times\mathbf L),\qquad
          I_w = R\,I_c R^{\mathsf T},

and the rotational work of the surface load over a sub-step is
:math:`\tfrac12(\mathbf M_k + \mathbf M_{k+1})\cdot\tfrac12(\boldsymbol\omega_k + \boldsymbol\omega_{k+1})\,\delta t`.

Both keep the work of the surface forces (the ramp's mean force on the step's displacement of
the surface nodes) for the energy balance of a coupled run.
"""

from __future__ import annotations

import math
import time
from typing import Any

import numpy as np
import scipy.sparse as sp
from numpy.typing import NDArray
from scipy.sparse.linalg import splu
from skfem import Basis

from mlsgalerkin.dynamics import Surface
from mlsgalerkin.structure import hyperelastic
from mlsgalerkin.structure.elastic import ElasticBody
from mlsgalerkin.structure.explicit import subcycle_linear
from mlsgalerkin.structure.rigid import Hinge, RigidBody

__all__ = ["SUBSTEP_SAFETY", "ElasticMotion", "RigidMotion", "free_rotation", "quaternion_matrix"]

FloatArray = NDArray[np.float64]

#: Fraction of the central-difference limit ``2/ω_max`` a sub-step takes (linear; the nonlinear
#: models take 0.8 of it, their tangent stiffens under stretch).
SUBSTEP_SAFETY = 0.9
#: Quadrature order of the total-Lagrangian internal force (4: 3 × 3 Gauss points on a
#: quadrilateral, 6 on a triangle; 3 × 3 × 3 on a hexahedron, 11 on a tetrahedron).
NONLINEAR_ORDER = 4
#: A Newmark factorisation made for ``Δt'`` is reused for steps in ``[Δt'/NEWMARK_REUSE, Δt']``,
#: and made for ``NEWMARK_MARGIN`` times the step that asks for a new one.
NEWMARK_REUSE = 1.01
NEWMARK_MARGIN = 1.005
#: Largest ``ω δt`` of a rigid body's sub-steps on its hinge spring, and of a free 3D body's
#: spin ``|ω| δt`` (rad).
RIGID_PHASE_PER_SUBSTEP = 0.05
#: The free rotation's splitting ``Φ¹_{δt/2} Φ²_{δt/2} Φ³_{δt} Φ²_{δt/2} Φ¹_{δt/2}``: (principal
#: axis, fraction of the sub-step) in the order applied, principal moments ascending.
FREE_ROTATION_SPLITTING = ((0, 0.5), (1, 0.5), (2, 1.0), (1, 0.5), (0, 0.5))


def _cross(r: FloatArray, f: FloatArray) -> FloatArray:
    """``r × f`` (z-component) of ``(n, 2)`` rows."""
    return r[..., 0] * f[..., 1] - r[..., 1] * f[..., 0]


def quaternion_matrix(q: FloatArray) -> FloatArray:
    """The rotation matrix (3, 3) of the unit quaternion ``q = (w, x, y, z)``."""
    w, x, y, z = q
    return np.array([[1.0 - 2.0 * (y * y + z * z), 2.0 * (x * y - w * z), 2.0 * (x * z + w * y)],
                     [2.0 * (x * y + w * z), 1.0 - 2.0 * (x * x + z * z), 2.0 * (y * z - w * x)],
                     [2.0 * (x * z - w * y), 2.0 * (y * z + w * x), 1.0 - 2.0 * (x * x + y * y)]])


def _quaternion_product(a: FloatArray, b: FloatArray) -> FloatArray:
    """Hamilton's product ``a ⊗ b`` (the rotation ``R(a) R(b)``)."""
    aw, ax, ay, az = a
    bw, bx, by, bz = b
    return np.array([aw * bw - ax * bx - ay * by - az * bz, aw * bx + ax * bw + ay * bz - az * by,
                     aw * by - ax * bz + ay * bw + az * bx, aw * bz + ax * by - ay * bx + az * bw])


def free_rotation(q: FloatArray, L: FloatArray, axes: FloatArray, moments: FloatArray, h: float) -> FloatArray:
    """The orientation ``q`` (unit quaternion) after the torque-free motion over ``h`` (s) with the
    world angular momentum ``L`` (kg m²/s, unchanged), by the splitting of Dullweber, Leimkuhler
    & McLachlan (1997) (module docstring): exact rotations about the principal ``axes`` (columns
    of (3, 3), rest frame) with the principal ``moments`` (3,) (kg m²); renormalised."""
    for i, part in FREE_ROTATION_SPLITTING:
        u = axes[:, i]
        phi = part * h * float(u @ (quaternion_matrix(q).T @ L)) / moments[i]
        s = math.sin(0.5 * phi)
        q = _quaternion_product(q, np.array([math.cos(0.5 * phi), s * u[0], s * u[1], s * u[2]]))
    return q / math.sqrt(float(q @ q))


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
        self.a1_high = 0.0
        if body.integrator == "explicit" and body.high_mode_damping > 0:
            self.a1_high = 2.0 * body.high_mode_damping / self.omega_max
            self.a1 += self.a1_high
        # with stiffness-proportional damping the central-difference limit shrinks to
        # (2/ω)(sqrt(1 + ξ²) − ξ), ξ = a1 ω/2 + a0/(2ω) at the highest mode
        xi = 0.5 * (self.a1 * self.omega_max + self.a0 / self.omega_max)
        safety = SUBSTEP_SAFETY if body.model == "linear" else 0.8
        self.substep_limit = safety * 2.0 / self.omega_max * (math.sqrt(1.0 + xi * xi) - xi)
        self.u = np.zeros(n)
        self.v = np.zeros(n)
        self.a = np.zeros(n)
        self.f = np.zeros(n)          # surface forces of the last exchange (N)
        self.f_last = np.zeros(n)     # the surface forces of the exchange before (N), for the extrapolation
        self.dt_prev = 0.0            # the last outer step (s)
        self.work = 0.0               # work of the surface forces (J per unit depth)
        self.substeps = 0
        self.outer_steps = 0
        self.max_substeps = 0
        self.seconds = 0.0
        self._f_end: FloatArray | None = None
        self._lu: Any = None
        self._lu_dt = 0.0
        self.factorisations = 0
        self._internal = None
        if body.model != "linear":
            # 3 × 3 Gauss points per quadrilateral (scikit-fem's default for Q2 is 5 × 5, exact for the
            # mass): the usual full integration of the internal force, 2.8 times fewer points (3 × 3 × 3
            # per hexahedron against 7 × 7 × 7 for Hex2: 12.7 times fewer)
            self._quadrature = hyperelastic.QuadratureData.from_basis(Basis(body.mesh, body.basis.elem, intorder=NONLINEAR_ORDER))
            # plane strain in 2D (ElasticBody refuses plane stress), the 3D Lamé parameters in 3D
            self._lame = hyperelastic.lame_for_dimension(body.material, body.dim)

    # ------------------------------------------------------------------ forces
    def internal_force(self, u: FloatArray) -> FloatArray:
        """``K u`` (linear) or the total-Lagrangian ``∫ P : ∇δu`` (N)."""
        if self.body.model == "linear":
            return self.K @ u
        return hyperelastic.internal_force(self._quadrature, u, *self._lame, self.body.model)

    def acceleration(self) -> FloatArray:
        """``M⁻¹(f_g − f_int(u) − C v)``, the body's own forces, with the clamped degrees of
        freedom at zero."""
        b = self.body
        f = b.weight - self.internal_force(self.u)
        if self.a1:
            f = f - self.a1 * (self.K @ self.v)
        a = f * self.inv_m - self.a0 * self.v
        a[self.fixed] = 0.0
        return a

    def step_end_load(self) -> FloatArray:
        """The surface forces added since the last clear (N per degree of freedom)."""
        return self.f.copy()

    def set_step_end_load(self, load: FloatArray) -> None:
        """Use ``load`` as the surface forces at the end of the next step instead of the
        extrapolation (a partitioned iteration's load of its last pass)."""
        self._f_end = np.asarray(load, dtype=float).copy()

    def load_ramp(self, dt: float) -> tuple[FloatArray, FloatArray]:
        """The surface forces at the start of the outer step (those of the last exchange) and at
        its end, extrapolated linearly from the exchange before, or as set by
        :meth:`set_step_end_load` (module docstring)."""
        f0 = self.f.copy()
        f0[self.fixed] = 0.0
        if self._f_end is not None:
            f1, self._f_end = self._f_end, None
            f1[self.fixed] = 0.0
        else:
            f1 = f0 + (dt / self.dt_prev) * (f0 - self.f_last) if self.dt_prev > 0 else f0.copy()
        self.f_last[:] = f0
        self.dt_prev = dt
        return f0, f1

    def start(self) -> None:
        self.a = self.acceleration()

    # ------------------------------------------------------------------ stepping
    def advance(self, dt: float) -> None:
        """``u, v, a`` over the outer step ``dt`` (s) under the body's own forces and the surface
        forces ramped from the last exchange's to their extrapolation at the step's end."""
        t0 = time.perf_counter()
        b = self.body
        f0, f1 = self.load_ramp(dt)
        wet = b.wet.dofs
        u_start = self.u[wet].copy()
        self.a = self.acceleration() + f0 * self.inv_m       # equilibrium at the step's start
        if b.integrator == "newmark":
            self._newmark(dt, f1)
            n = 1
        else:
            n = max(1, math.ceil(dt / self.substep_limit * (1.0 - 1e-12)))
            h = dt / n
            if b.model == "linear":
                subcycle_linear(self.K, self.inv_m, self.fixed, b.weight + f0, f1 - f0, self.u, self.v, self.a, h, n,
                                self.a0, self.a1)
            else:
                for k in range(n):
                    self.v += 0.5 * h * self.a
                    self.u += h * self.v
                    self.a = self.acceleration() + (f0 + (k + 1.0) / n * (f1 - f0)) * self.inv_m
                    self.v += 0.5 * h * self.a
        self.work += 0.5 * float(np.sum((f0[wet] + f1[wet]) * (self.u[wet] - u_start)))
        self.substeps += n
        self.max_substeps = max(self.max_substeps, n)
        self.outer_steps += 1
        self.seconds += time.perf_counter() - t0

    def _newmark(self, dt: float, f1: FloatArray) -> None:
        # the factorisation of M + γΔt'C + β'Δt'²K is kept while the step stays within 1 % below
        # the Δt' it was made for; the step then uses β = β'(Δt'/Δt)² ∈ [1/4, 0.255] (γ = ½:
        # still unconditionally stable and free of numerical damping) and the matching γΔt'C
        gamma = 0.5
        free = self.body.free
        fits = self._lu_dt / NEWMARK_REUSE <= dt <= self._lu_dt
        if self._lu is None or not fits:
            # after a restart the factorisation is remade for the step it was made for, so the
            # run continues bit for bit
            lu_dt = self._lu_dt if (self._lu is None and fits) else dt * NEWMARK_MARGIN
            M = sp.diags(1.0 / self.inv_m)
            C = self.a0 * M + self.a1 * self.K
            A = (M + gamma * lu_dt * C + 0.25 * lu_dt * lu_dt * self.K).tocsr()[free][:, free]
            self._lu, self._lu_dt = splu(A.tocsc()), lu_dt
            self.factorisations += 1
        beta = 0.25 * (self._lu_dt / dt) ** 2
        if self.a0 or self.a1:  # damping: the matrix's γΔt'C must match the step's γΔt C
            gamma = 0.5 * self._lu_dt / dt
        u, v, a = self.u, self.v, self.a
        u_pred = u + dt * v + (0.5 - beta) * dt * dt * a
        v_pred = v + (1.0 - gamma) * dt * a
        rhs = (self.body.weight + f1 - self.K @ u_pred - self.a1 * (self.K @ v_pred)
               - self.a0 * v_pred / self.inv_m)
        a_new = np.zeros_like(a)
        a_new[free] = self._lu.solve(rhs[free])
        self.u = u_pred + beta * dt * dt * a_new
        self.v = v_pred + gamma * dt * a_new
        self.a = a_new

    # ------------------------------------------------------------------ surface
    @property
    def n_surface(self) -> int:
        return self.body.wet.n_nodes

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
            strain = float(hyperelastic.strain_energy(self._quadrature, self.u, *self._lame, b.model))
        return {"kinetic_energy": kinetic, "strain_energy": strain,
                "weight_potential": -float(b.weight @ self.u), "surface_work": self.work}

    def first_mode_damping(self) -> float | None:
        """Damping ratio ``a0/(2ω₁) + a1 ω₁/2`` of the body's lowest mode (``None`` without a
        clamped boundary: the lowest mode is a rigid motion)."""
        b = self.body
        if b.clamped_dofs.size == 0:
            return None
        w1 = b.lowest_frequency()
        return 0.5 * self.a0 / w1 + 0.5 * self.a1 * w1

    def observables(self) -> dict[str, float]:
        row = self.energies()
        dim = self.body.dim
        total = self.f.reshape(-1, dim).sum(axis=0)
        for c in range(dim):
            row[f"force_{'xyz'[c]}"] = float(total[c])
        for key, d in self.body.point_displacements(self.u).items():
            for c in range(dim):
                row[f"{key}_u{'xyz'[c]}"] = float(d[c])
        return row

    def frame(self) -> tuple[FloatArray, dict[str, FloatArray]]:
        b = self.body
        loc = b.basis.doflocs[:, b.basis.nodal_dofs[0]].T
        dofs = b.basis.nodal_dofs.T
        return loc + self.u[dofs], {"displacement": self.u[dofs], "velocity": self.v[dofs]}

    @property
    def n_frame_points(self) -> int:
        """Points of :meth:`frame`: the mesh's vertices."""
        return int(self.body.mesh.p.shape[1])

    def frame_cells(self) -> tuple[str, NDArray[np.int64]]:
        """The mesh's cells on :meth:`frame`'s points (the vertices), in VTK's node order
        (scikit-fem's meshio conversion)."""
        from skfem.io.meshio import to_meshio

        block = to_meshio(self.body.mesh).cells[0]
        return block.type, np.asarray(block.data, dtype=np.int64)

    def finite(self) -> bool:
        return bool(np.all(np.isfinite(self.u)) and np.all(np.isfinite(self.v)))

    def checkpoint(self) -> dict[str, FloatArray]:
        return {"u": self.u.copy(), "v": self.v.copy(), "a": self.a.copy(), "f": self.f.copy(),
                "f_last": self.f_last.copy(),
                "counters": np.array([self.work, self.substeps, self.outer_steps, self.max_substeps, self.dt_prev,
                                      self._lu_dt, self.factorisations])}

    def restore(self, arrays: dict[str, FloatArray]) -> None:
        self.u, self.v, self.a, self.f, self.f_last = (arrays[k].copy() for k in ("u", "v", "a", "f", "f_last"))
        work, sub, outer, mx, dt_prev, lu_dt, factorisations = arrays["counters"]
        self.work, self.substeps, self.outer_steps, self.max_substeps = float(work), int(sub), int(outer), int(mx)
        self.dt_prev, self._lu_dt, self.factorisations = float(dt_prev), float(lu_dt), int(factorisations)
        self._lu = None

    def summary(self) -> dict[str, Any]:
        b = self.body
        return {"kind": "elastic", "model": b.model, "integrator": b.integrator, "element": b.element,
                "dofs": b.n_dofs, "elements": int(b.mesh.t.shape[1]), "omega_max_rad_s": self.omega_max,
                "rayleigh_a0_per_s": self.a0, "rayleigh_a1_s": self.a1,
                "high_mode_damping_a1_s": self.a1_high, "high_mode_damping_ratio": b.high_mode_damping,
                "first_mode_damping_ratio": self.first_mode_damping(),
                "substep_limit_s": self.substep_limit, "outer_steps": self.outer_steps, "substeps": self.substeps,
                "substeps_per_step_max": self.max_substeps,
                "substeps_per_step_mean": self.substeps / self.outer_steps if self.outer_steps else None,
                "newmark_factorisations": self.factorisations if b.integrator == "newmark" else None,
                "time_s": self.seconds, **{f"end_{k}_J": v for k, v in self.energies().items()}}


class RigidMotion:
    """State and integrator of one :class:`RigidBody` (module docstring).

    A free 3D body (``body.free_rotation``) keeps the orientation ``q`` (unit quaternion, (4,)),
    the world angular momentum about the centre ``L`` (kg m²/s, (3,)), and ``omega``, ``alpha``,
    ``M`` as world (3,) vectors (rad/s, rad/s², N m); its ``theta`` stays 0 (the ``angle``
    observable is the angle of ``q``). The other bodies keep scalars about their axis."""

    kind = "rigid"

    def __init__(self, body: RigidBody) -> None:
        self.body = body
        self.X = body.surface.nodes.copy()
        self.c0 = body.centre.copy()
        self.c = body.centre.copy()
        self.theta = 0.0
        self.V = body.velocity.copy()
        self.free3d = body.free_rotation
        d = body.dim
        self.dim = d
        self.A = np.zeros(d)          # acceleration of the centre under the body's own forces (m/s²)
        self.F = np.zeros(d)          # resultant of the surface forces of the last exchange (N)
        self.F_last = np.zeros(d)     # resultant and moment of the exchange before, for the extrapolation
        if self.free3d:
            self.omega = np.array(body.angular_velocity, dtype=float)   # world angular velocity (rad/s)
            self.alpha = np.zeros(3)  # world angular acceleration (rad/s²)
            self.M = np.zeros(3)      # moment of the surface forces about the centre, world frame (N m)
            self.M_last = np.zeros(3)
            self.q = np.array([1.0, 0.0, 0.0, 0.0])   # orientation from rest (unit quaternion)
            tensor = body.inertia_tensor()
            if np.count_nonzero(tensor - np.diag(np.diag(tensor))) == 0:
                # principal at rest along x, y, z: exact axes (a permutation, no round-off)
                order = np.argsort(np.diag(tensor), kind="stable")
                self.moments, self.axes = np.diag(tensor)[order], np.eye(3)[:, order]
            else:
                self.moments, self.axes = np.linalg.eigh(tensor)
            if np.linalg.det(self.axes) < 0:
                self.axes[:, 2] = -self.axes[:, 2]
            self.L = tensor @ self.omega                 # at rest R = 1: L = I_c ω
        else:
            self.omega = float(body.angular_velocity)
            self.alpha = 0.0          # angular acceleration about the axis (rad/s²)
            self.M = 0.0              # moment of the surface forces about the centre of mass, about the axis (N m)
            self.M_last = 0.0
        self._end: tuple[FloatArray, float] | None = None
        self.dt_prev = 0.0
        self.work = 0.0
        self.substeps = 0
        self.outer_steps = 0
        self.seconds = 0.0
        con = body.constraint
        self.g = np.zeros(d) if body.gravity is None else body.gravity
        self.axis = con.unit_axis(d) if isinstance(con, Hinge) else np.array([0.0, 0.0, 1.0])
        if isinstance(con, Hinge):
            self.p = np.asarray(con.point, dtype=float)
            self.I = body.hinge_inertia()
            self.omega_n = math.sqrt(max(body.natural_frequency_squared(), 0.0))
        else:
            self.p = None
            self.I = body.inertia_tensor() if self.free3d else body.axis_inertia(self.axis)
            self.omega_n = 0.0

    @property
    def n_surface(self) -> int:
        return self.X.shape[0]

    def _rotation(self, theta: float) -> FloatArray:
        """The rotation by ``theta`` about the axis (2 × 2 in 2D; Rodrigues' formula in 3D)."""
        c, s = math.cos(theta), math.sin(theta)
        if self.dim == 2:
            return np.array([[c, -s], [s, c]])
        a = self.axis
        K = np.array([[0.0, -a[2], a[1]], [a[2], 0.0, -a[0]], [-a[1], a[0], 0.0]])
        return np.eye(3) + s * K + (1.0 - c) * (K @ K)

    def _turn(self, r: FloatArray) -> FloatArray:
        """``e × r`` for the unit axis ``e`` (rows of ``r``): the velocity of a unit rate of turn."""
        if self.dim == 2:
            return np.stack([-r[..., 1], r[..., 0]], axis=-1)
        return np.cross(self.axis, r)

    def _torque(self, r: FloatArray, f: FloatArray) -> FloatArray:
        """``(r × f)·e``, the moment about the axis, of rows ``r``, ``f``."""
        if self.dim == 2:
            return _cross(r, f)
        return np.cross(r, f) @ self.axis

    def _axis_d(self) -> FloatArray:
        """The axis in the body's dimension (zero in 2D: no component of ``r`` lies along it)."""
        return np.zeros(2) if self.dim == 2 else self.axis

    def rotation(self) -> FloatArray:
        """The body's rotation from rest now: (2, 2) or (3, 3)."""
        if self.free3d:
            return quaternion_matrix(self.q)
        return self._rotation(self.theta)

    def nodes(self) -> FloatArray:
        """Surface node positions ``(m, d)`` now (m)."""
        return self.c + (self.X - self.c0) @ self.rotation().T

    def body_angular_velocity(self) -> FloatArray:
        """A free 3D body's angular velocity in its own frame (the rest frame turned with it),
        ``Rᵀω = I_c⁻¹ Rᵀ L`` (rad/s, (3,))."""
        if not self.free3d:
            raise ValueError(f"rigid body {self.body.name!r}: only a free 3D body has a body-frame angular velocity")
        principal = self.axes.T @ (quaternion_matrix(self.q).T @ self.L)
        return self.axes @ (principal / self.moments)

    def _spin(self, M: FloatArray) -> None:
        """A free 3D body's world ``ω = I_w⁻¹ L`` and ``α = I_w⁻¹(M − ω × L)`` under the moment
        ``M`` about the centre (module docstring), ``I_w = R I_c Rᵀ``."""
        P = quaternion_matrix(self.q) @ self.axes        # principal frame → world
        self.omega = P @ ((P.T @ self.L) / self.moments)
        self.alpha = P @ ((P.T @ (M - np.cross(self.omega, self.L))) / self.moments)

    def _generalised(self, F: FloatArray, M: float) -> tuple[FloatArray, float]:
        """Acceleration of the centre and angular acceleration from a force ``F`` and a moment
        ``M`` about the centre, under the constraint (no body forces)."""
        con, m = self.body.constraint, self.body.mass
        if isinstance(con, Hinge):
            r = self.c - self.p
            alpha = (M + float(self._torque(r, F))) / self.I
            return alpha * self._turn(r), alpha
        if con == "free":
            return F / m, M / self.I
        if con == "vertical":
            A = np.zeros(self.dim)
            A[-1] = F[-1] / m
            return A, 0.0
        return np.zeros(self.dim), 0.0

    def _own_accelerations(self) -> None:
        """``A, α`` under the body's own forces: weight, hinge spring and damper."""
        b, m = self.body, self.body.mass
        con = b.constraint
        if isinstance(con, Hinge):
            r = self.c - self.p
            moment = float(self._torque(r, m * self.g)) - con.stiffness * self.theta - con.damping * self.omega
            self.alpha = moment / self.I
            self.A = self.alpha * self._turn(r) - self.omega**2 * (r - (r @ self._axis_d()) * self._axis_d())
        else:
            self.A, self.alpha = self._generalised(m * self.g, 0.0)

    def start(self) -> None:
        if self.free3d:
            self.A = self.F / self.body.mass + self.g
            self._spin(self.M)
            return
        self._accelerations(self.F, self.M)

    def _accelerations(self, F: FloatArray, M: float) -> None:
        """``A, α`` under the body's own forces and the surface force ``F`` with moment ``M``."""
        self._own_accelerations()
        dA, dalpha = self._generalised(F, M)
        self.A, self.alpha = self.A + dA, self.alpha + dalpha

    def advance(self, dt: float) -> None:
        """Over the outer step ``dt`` (s), the surface force and moment ramped from the last
        exchange's to their extrapolation at the step's end (module docstring)."""
        t0 = time.perf_counter()
        con = self.body.constraint
        F0, M0 = self.F.copy(), (self.M.copy() if self.free3d else self.M)
        if self._end is not None:
            (F1, M1), self._end = self._end, None
        elif self.dt_prev > 0:
            F1 = F0 + (dt / self.dt_prev) * (F0 - self.F_last)
            M1 = M0 + (dt / self.dt_prev) * (M0 - self.M_last)
        else:
            F1, M1 = F0.copy(), (M0.copy() if self.free3d else M0)
        self.F_last, self.M_last, self.dt_prev = F0, M0, dt
        if self.free3d:
            self._advance_free(dt, F0, F1, M0, M1)
            self.seconds += time.perf_counter() - t0
            return
        c_start, theta_start = self.c.copy(), self.theta
        n = 1
        if self.omega_n > 0:
            n = max(1, math.ceil(dt * self.omega_n / RIGID_PHASE_PER_SUBSTEP * (1.0 - 1e-12)))
        h = dt / n
        self._accelerations(F0, M0)
        for k in range(n):
            ramp = (k + 1.0) / n
            F, M = F0 + ramp * (F1 - F0), M0 + ramp * (M1 - M0)
            if isinstance(con, Hinge):
                self.omega += 0.5 * h * self.alpha
                self.theta += h * self.omega
                self.c = self.p + self._rotation(self.theta) @ (self.c0 - self.p)
                self._accelerations(F, M)
                self.omega += 0.5 * h * self.alpha
                r = self.c - self.p
                self.V = self.omega * self._turn(r)
            elif con != "fixed":
                self.V += 0.5 * h * self.A
                self.omega += 0.5 * h * self.alpha
                self.c = self.c + h * self.V
                self.theta += h * self.omega
                self._accelerations(F, M)
                self.V += 0.5 * h * self.A
                self.omega += 0.5 * h * self.alpha
        # work of the surface forces: the ramp's mean force and moment on the step's motion
        self.work += float(0.5 * (F0 + F1) @ (self.c - c_start)) + 0.5 * (M0 + M1) * (self.theta - theta_start)
        self.substeps += n
        self.outer_steps += 1
        self.seconds += time.perf_counter() - t0

    def _advance_free(self, dt: float, F0: FloatArray, F1: FloatArray, M0: FloatArray, M1: FloatArray) -> None:
        """A free 3D body over ``dt`` (s): velocity Verlet for the centre and the kick–rotate–kick
        splitting for the rotation (module docstring), the load ramped from ``F0, M0`` to
        ``F1, M1`` (N, N m, world frame)."""
        m, g = self.body.mass, self.g
        spin = math.sqrt(float(self.omega @ self.omega))
        n = max(1, math.ceil(dt * spin / RIGID_PHASE_PER_SUBSTEP * (1.0 - 1e-12)))
        h = dt / n
        c_start = self.c.copy()
        self.A = F0 / m + g
        M_start, rotational_work = M0, 0.0
        for k in range(n):
            ramp = (k + 1.0) / n
            F, M = F0 + ramp * (F1 - F0), M0 + ramp * (M1 - M0)
            omega_start = self.omega
            self.V = self.V + 0.5 * h * self.A
            self.L = self.L + 0.5 * h * M_start
            self.c = self.c + h * self.V
            self.q = free_rotation(self.q, self.L, self.axes, self.moments, h)
            self.A = F / m + g
            self.V = self.V + 0.5 * h * self.A
            self.L = self.L + 0.5 * h * M
            self._spin(M)
            rotational_work += 0.25 * h * float((M_start + M) @ (omega_start + self.omega))
            M_start = M
        self.work += float(0.5 * (F0 + F1) @ (self.c - c_start)) + rotational_work
        self.substeps += n
        self.outer_steps += 1

    def surface(self) -> Surface:
        if self.free3d:
            r = self.nodes() - self.c
            v = self.V + np.cross(self.omega, r)
            a = self.A + np.cross(self.alpha, r) + np.cross(self.omega, np.cross(self.omega, r))
            return Surface(self.body.name, self.c + r, v, self.body.surface.facets, None, a)
        r = self.nodes() - self.c
        perp = self._turn(r)
        e = self._axis_d()
        v = self.V + self.omega * perp
        a = self.A + self.alpha * perp - self.omega**2 * (r - np.outer(r @ e, e))
        return Surface(self.body.name, self.c + r, v, self.body.surface.facets, None, a)

    def step_end_load(self) -> tuple[FloatArray, float | FloatArray]:
        """The resultant and moment of the surface forces added since the last clear (the moment
        a world (3,) vector for a free 3D body)."""
        return self.F.copy(), (self.M.copy() if self.free3d else self.M)

    def set_step_end_load(self, load: tuple[FloatArray, float | FloatArray]) -> None:
        """Use ``load`` (resultant, moment) at the end of the next step instead of the extrapolation."""
        M = np.array(load[1], dtype=float) if self.free3d else float(load[1])
        self._end = (np.asarray(load[0], dtype=float).copy(), M)

    def add_forces(self, forces: FloatArray) -> None:
        r = self.nodes() - self.c
        self.F = self.F + forces.sum(axis=0)
        if self.free3d:
            self.M = self.M + np.cross(r, forces).sum(axis=0)
        else:
            self.M += float(np.sum(self._torque(r, forces)))

    def clear_forces(self) -> None:
        self.F = np.zeros(self.dim)
        self.M = np.zeros(3) if self.free3d else 0.0

    def kinetic_energy(self) -> float:
        """``½ m V² + ½ ω·L`` (J, per unit depth in 2D; ``½ I_p ω²`` on a hinge)."""
        b = self.body
        if isinstance(b.constraint, Hinge):
            return 0.5 * self.I * self.omega**2
        if self.free3d:
            return 0.5 * b.mass * float(self.V @ self.V) + 0.5 * float(self.omega @ self.L)
        return 0.5 * b.mass * float(self.V @ self.V) + 0.5 * self.I * self.omega**2

    def angle(self) -> float:
        """The angle turned from rest (rad): ``θ`` about the axis, or a free 3D body's rotation
        angle ``2 atan2(|q_xyz|, |q_w|)`` in ``[0, π]``."""
        if self.free3d:
            return 2.0 * math.atan2(math.sqrt(float(self.q[1:] @ self.q[1:])), abs(float(self.q[0])))
        return self.theta

    def energies(self) -> dict[str, float]:
        b = self.body
        con = b.constraint
        spring = 0.5 * con.stiffness * self.theta**2 if isinstance(con, Hinge) else 0.0
        return {"kinetic_energy": self.kinetic_energy(), "spring_energy": spring,
                "weight_potential": -b.mass * float(self.g @ (self.c - self.c0)), "surface_work": self.work}

    def observables(self) -> dict[str, float]:
        """Energies, the centre's displacement ``x|y|z`` (m), velocity ``vx|vy|vz`` (m/s), the
        surface load ``force_x|y|z`` (N); ``angle``, ``omega``, ``moment`` about the axis, or for a
        free 3D body ``angle`` (of its rotation from rest) and the world vectors ``omega_x|y|z``
        (rad/s), ``moment_x|y|z`` (N m about the centre) and ``angular_momentum_x|y|z``
        (kg m²/s)."""
        row = self.energies()
        d = self.c - self.c0
        for k in range(self.dim):
            a = "xyz"[k]
            row[a], row[f"v{a}"], row[f"force_{a}"] = float(d[k]), float(self.V[k]), float(self.F[k])
        if self.free3d:
            row["angle"] = self.angle()
            for k, a in enumerate("xyz"):
                row[f"omega_{a}"], row[f"moment_{a}"] = float(self.omega[k]), float(self.M[k])
                row[f"angular_momentum_{a}"] = float(self.L[k])
            return row
        row.update({"angle": self.theta, "omega": self.omega, "moment": self.M})
        return row

    def frame(self) -> tuple[FloatArray, dict[str, FloatArray]]:
        x = self.nodes()
        return x, {"displacement": x - self.X, "velocity": self.surface().velocities}

    @property
    def n_frame_points(self) -> int:
        """Points of :meth:`frame`: the surface nodes."""
        return self.n_surface

    def frame_cells(self) -> tuple[str, NDArray[np.int64]]:
        """The surface facets on :meth:`frame`'s points (the surface nodes): segments in 2D,
        triangles in 3D."""
        return ("line" if self.dim == 2 else "triangle"), self.body.surface.facets.astype(np.int64)

    def finite(self) -> bool:
        if self.free3d:
            return bool(all(np.all(np.isfinite(x)) for x in (self.c, self.V, self.q, self.L)))
        return bool(np.all(np.isfinite(self.c)) and math.isfinite(self.theta) and math.isfinite(self.omega))

    def checkpoint(self) -> dict[str, FloatArray]:
        if self.free3d:
            return {"c": self.c.copy(), "V": self.V.copy(), "A": self.A.copy(), "F": self.F.copy(),
                    "F_last": self.F_last.copy(), "q": self.q.copy(), "L": self.L.copy(), "omega": self.omega.copy(),
                    "alpha": self.alpha.copy(), "M": self.M.copy(), "M_last": self.M_last.copy(),
                    "counters": np.array([self.work, self.dt_prev, self.substeps, self.outer_steps], dtype=float)}
        return {"c": self.c.copy(), "V": self.V.copy(), "A": self.A.copy(), "F": self.F.copy(),
                "F_last": self.F_last.copy(),
                "scalars": np.array([self.theta, self.omega, self.alpha, self.M, self.M_last, self.work, self.dt_prev,
                                     self.substeps, self.outer_steps], dtype=float)}

    def restore(self, arrays: dict[str, FloatArray]) -> None:
        self.c, self.V, self.A, self.F, self.F_last = (arrays[k].copy() for k in ("c", "V", "A", "F", "F_last"))
        if self.free3d:
            self.q, self.L, self.omega, self.alpha, self.M, self.M_last = (
                np.array(arrays[k], dtype=float) for k in ("q", "L", "omega", "alpha", "M", "M_last"))
            work, dt_prev, sub, outer = arrays["counters"]
            self.work, self.dt_prev, self.substeps, self.outer_steps = float(work), float(dt_prev), int(sub), int(outer)
            return
        th, om, al, M, M_last, work, dt_prev, sub, outer = arrays["scalars"]
        self.theta, self.omega, self.alpha, self.M, self.M_last = float(th), float(om), float(al), float(M), float(M_last)
        self.work, self.dt_prev = float(work), float(dt_prev)
        self.substeps, self.outer_steps = int(sub), int(outer)

    def summary(self) -> dict[str, Any]:
        b = self.body
        con = b.constraint
        inertia = np.asarray(self.I).tolist() if self.free3d or np.ndim(self.I) else self.I
        principal = {"principal_inertia_kg_m2": self.moments.tolist()} if self.free3d else {}
        return {"kind": "rigid", "constraint": repr(con) if isinstance(con, Hinge) else con, "mass_kg": b.mass,
                "inertia_kg_m2": inertia, **principal, "natural_period_s": b.natural_period() if isinstance(con, Hinge) else None,
                "outer_steps": self.outer_steps, "substeps": self.substeps, "time_s": self.seconds,
                **{f"end_{k}_J": v for k, v in self.energies().items()}}
