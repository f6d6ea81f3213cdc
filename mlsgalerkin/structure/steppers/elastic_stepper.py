r"""What the steppers of an elastic body share: its displacement, velocity and acceleration, the
surface load on its wet surface, energies, frames and checkpoints.

The state of an :class:`~mlsgalerkin.structure.elastic.ElasticBody` with :math:`N` degrees of
freedom is :math:`\mathbf u, \mathbf v, \mathbf a` (m, m/s, m/s², (N,)); its own forces are the
weight :math:`\mathbf f_g`, the internal force :math:`\mathbf f_{int}(\mathbf u)` (:math:`K\mathbf u`
for the linear model) and Rayleigh damping :math:`C = a_0M + a_1K`:

.. math:: \mathbf a = M^{-1}\bigl(\mathbf f_g - \mathbf f_{int}(\mathbf u) - a_1K\mathbf v\bigr) - a_0\mathbf v,

with the clamped degrees of freedom held at zero. The methods differ only in how they advance
over a step (:mod:`~mlsgalerkin.structure.steppers.central_difference`,
:mod:`~mlsgalerkin.structure.steppers.newmark`).
"""

from __future__ import annotations

import math
from abc import abstractmethod
from typing import Any, Protocol

import numpy as np
from numpy.typing import NDArray

from mlsgalerkin.dynamics import Surface
from mlsgalerkin.structure.elastic import ElasticBody
from mlsgalerkin.structure.steppers.base import Stepper

__all__ = ["ElasticStepper", "InternalForce", "central_difference_limit"]

FloatArray = NDArray[np.float64]


class InternalForce(Protocol):
    """A nonlinear internal force of an elastic body's displacement and its strain energy."""

    def __call__(self, u: FloatArray) -> FloatArray: ...

    def strain_energy(self, u: FloatArray) -> float: ...


def central_difference_limit(omega_max: float, a0: float, a1: float, safety: float) -> float:
    """``safety · (2/ω_max)(sqrt(1 + ξ²) − ξ)`` (s), ``ξ = a1 ω_max/2 + a0/(2ω_max)``: the stable
    step of central differences with Rayleigh damping ``a0`` (1/s), ``a1`` (s) at the highest
    frequency ``omega_max`` (rad/s), times ``safety``."""
    xi = 0.5 * (a1 * omega_max + a0 / omega_max)
    return safety * 2.0 / omega_max * (math.sqrt(1.0 + xi * xi) - xi)


class ElasticStepper(Stepper):
    """The state of one :class:`ElasticBody` in a run (module docstring): ``u``, ``v``, ``a``
    (N,), the surface load ``f`` of the last exchange and ``f_last`` of the one before (N per
    degree of freedom), and what the methods share. Subclasses advance it."""

    kind = "elastic"

    def __init__(self, body: ElasticBody) -> None:
        super().__init__(body)
        self.body: ElasticBody = body
        n = body.n_dofs
        self.K = body.stiffness.tocsr()
        self.K.sort_indices()
        self.inv_m = 1.0 / body.lumped_mass
        self.fixed = np.zeros(n, dtype=np.bool_)
        self.fixed[body.clamped_dofs] = True
        self.a0, self.a1 = body.damping
        self.omega_max = body.highest_frequency()
        self.a1_high = 0.0            # stiffness-proportional damping added for the highest mode (s)
        self.nonlinear: InternalForce | None = None
        self.u = np.zeros(n)
        self.v = np.zeros(n)
        self.a = np.zeros(n)
        self.f = np.zeros(n)          # surface forces of the last exchange (N)
        self.f_last = np.zeros(n)     # the surface forces of the exchange before (N), for the extrapolation
        self.max_substeps = 0
        #: The sub-step of central differences on this body (s), set by the method.
        self.substep_limit = math.nan

    # ------------------------------------------------------------------ forces
    def internal_force(self, u: FloatArray) -> FloatArray:
        """``K u`` (linear) or the nonlinear internal force (N)."""
        if self.nonlinear is None:
            return self.K @ u
        return self.nonlinear(u)

    def acceleration(self) -> FloatArray:
        """``M⁻¹(f_g − f_int(u) − a1 K v) − a0 v``, the body's own forces, with the clamped degrees of
        freedom at zero."""
        f = self.body.weight - self.internal_force(self.u)
        if self.a1:
            f = f - self.a1 * (self.K @ self.v)
        a = f * self.inv_m - self.a0 * self.v
        a[self.fixed] = 0.0
        return a

    def step_end_load(self) -> FloatArray:
        """The surface forces added since the last clear (N per degree of freedom)."""
        return self.f.copy()

    def set_step_end_load(self, load: FloatArray) -> None:
        self._end = (np.asarray(load, dtype=float).copy(),)

    def load_ramp(self, dt: float) -> tuple[FloatArray, FloatArray]:
        """The surface forces at the start of the outer step ``dt`` (s) (those of the last exchange)
        and at its end (:mod:`~mlsgalerkin.structure.steppers.base`), zero on the clamped degrees of
        freedom."""
        f0 = self.f.copy()
        f0[self.fixed] = 0.0
        (f1,) = self._ramp_end((f0,), (self.f_last,), dt)
        f1[self.fixed] = 0.0
        self.f_last[:] = f0
        return f0, f1

    def start(self) -> None:
        self.a = self.acceleration()

    # ------------------------------------------------------------------ stepping
    def _advance(self, dt: float) -> int:
        f0, f1 = self.load_ramp(dt)
        wet = self.body.wet.dofs
        u_start = self.u[wet].copy()
        self.a = self.acceleration() + f0 * self.inv_m       # equilibrium at the step's start
        n = self._integrate(dt, f0, f1)
        self.work += 0.5 * float(np.sum((f0[wet] + f1[wet]) * (self.u[wet] - u_start)))
        self.max_substeps = max(self.max_substeps, n)
        return n

    @abstractmethod
    def _integrate(self, dt: float, f0: FloatArray, f1: FloatArray) -> int:
        """``u, v, a`` over ``dt`` (s) with the surface forces ramped from ``f0`` to ``f1`` (N), ``a``
        at the step's start given; return the sub-steps taken."""

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
        kinetic = 0.5 * float(np.dot(self.v / self.inv_m, self.v))
        if self.nonlinear is None:
            strain = 0.5 * float(self.u @ (self.K @ self.u))
        else:
            strain = float(self.nonlinear.strain_energy(self.u))
        return {"kinetic_energy": kinetic, "strain_energy": strain,
                "weight_potential": -float(self.body.weight @ self.u), "surface_work": self.work}

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

    def _method_counters(self) -> tuple[float, int]:
        """The method's own counters in the checkpoint (Newmark: the step its factorisation was
        made for, and the number of factorisations)."""
        return 0.0, 0

    def _restore_method_counters(self, counters: tuple[float, float]) -> None:
        """Continue from :meth:`_method_counters` as stored."""

    def checkpoint(self) -> dict[str, FloatArray]:
        return {"u": self.u.copy(), "v": self.v.copy(), "a": self.a.copy(), "f": self.f.copy(),
                "f_last": self.f_last.copy(),
                "counters": np.array([self.work, self.substeps, self.outer_steps, self.max_substeps, self.dt_prev,
                                      *self._method_counters()])}

    def restore(self, arrays: dict[str, FloatArray]) -> None:
        self.u, self.v, self.a, self.f, self.f_last = (arrays[k].copy() for k in ("u", "v", "a", "f", "f_last"))
        work, sub, outer, mx, dt_prev, *method = arrays["counters"]
        self.work, self.substeps, self.outer_steps, self.max_substeps = float(work), int(sub), int(outer), int(mx)
        self.dt_prev = float(dt_prev)
        self._restore_method_counters(tuple(method))

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
                **self._method_summary(),
                "time_s": self.seconds, **{f"end_{k}_J": v for k, v in self.energies().items()}}

    def _method_summary(self) -> dict[str, Any]:
        """The method's own entries in :meth:`summary`."""
        return {"newmark_factorisations": None}
