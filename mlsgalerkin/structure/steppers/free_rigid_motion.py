r"""The free 3D rigid body: six degrees of freedom, the kick–rotate–kick splitting.

A free 3D body (six degrees of freedom) keeps its orientation as a unit quaternion :math:`q`
(:math:`\mathbf x_a = \mathbf c + R(q)(\mathbf X_a - \mathbf c_0)`) and its angular momentum
about the centre in the world frame :math:`\mathbf L` (kg m²/s, (3,)). A sub-step
:math:`\delta t` (s) is the kick–rotate–kick splitting of Dullweber, Leimkuhler & McLachlan
(1997), with the translation by velocity Verlet:

.. math:: \mathbf V \mathrel{+}= \tfrac{\delta t}2\mathbf A_k,\quad
          \mathbf L \mathrel{+}= \tfrac{\delta t}2\mathbf M_k,\quad
          \mathbf c \mathrel{+}= \delta t\,\mathbf V,\quad
          q \leftarrow \text{free rotation over } \delta t,\quad
          \mathbf V \mathrel{+}= \tfrac{\delta t}2\mathbf A_{k+1},\quad
          \mathbf L \mathrel{+}= \tfrac{\delta t}2\mathbf M_{k+1},

(:func:`~mlsgalerkin.structure.steppers.rotation.free_rotation`) with
:math:`\mathbf A = \mathbf F/m + \mathbf g` and :math:`\mathbf M` (N m, world frame, about the
centre) the ramped surface load at the sub-step's ends. It sub-cycles so that
:math:`|\boldsymbol\omega|\,\delta t \le 0.05` at the step's start. After the sub-step the world
angular velocity and acceleration (for the surface's velocities and accelerations) are

.. math:: \boldsymbol\omega = I_w^{-1}\mathbf L,\qquad
          \boldsymbol\alpha = I_w^{-1}(\mathbf M - \boldsymbol\omega\times\mathbf L),\qquad
          I_w = R\,I_c R^{\mathsf T},

and the rotational work of the surface load over a sub-step is
:math:`\tfrac12(\mathbf M_k + \mathbf M_{k+1})\cdot\tfrac12(\boldsymbol\omega_k + \boldsymbol\omega_{k+1})\,\delta t`.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from numpy.typing import NDArray

from mlsgalerkin.dynamics import Surface
from mlsgalerkin.structure.rigid import RigidBody
from mlsgalerkin.structure.steppers.rigid_motion import RIGID_PHASE_PER_SUBSTEP, RigidStepper
from mlsgalerkin.structure.steppers.rotation import free_rotation, quaternion_matrix

__all__ = ["FreeRigidMotion"]

FloatArray = NDArray[np.float64]


class FreeRigidMotion(RigidStepper):
    """A free 3D :class:`RigidBody` (``body.free_rotation``; module docstring). It keeps the
    orientation ``q`` (unit quaternion, (4,)), the world angular momentum about the centre ``L``
    (kg m²/s, (3,)), and ``omega``, ``alpha``, ``M`` as world (3,) vectors (rad/s, rad/s², N m); its
    ``theta`` stays 0 (the ``angle`` observable is the angle of ``q``)."""

    def __init__(self, body: RigidBody) -> None:
        if not body.free_rotation:
            raise TypeError(f"rigid body {body.name!r} turns about one axis: it moves with RigidMotion "
                            "(stepper_for(body) picks the stepper of a body)")
        super().__init__(body)
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
        self.I = tensor

    def rotation(self) -> FloatArray:
        """The body's rotation from rest now, ``R(q)`` (3, 3)."""
        return quaternion_matrix(self.q)

    def body_angular_velocity(self) -> FloatArray:
        """The angular velocity in the body's own frame (the rest frame turned with it),
        ``Rᵀω = I_c⁻¹ Rᵀ L`` (rad/s, (3,))."""
        principal = self.axes.T @ (quaternion_matrix(self.q).T @ self.L)
        return self.axes @ (principal / self.moments)

    def _spin(self, M: FloatArray) -> None:
        """The world ``ω = I_w⁻¹ L`` and ``α = I_w⁻¹(M − ω × L)`` under the moment ``M`` about the
        centre (module docstring), ``I_w = R I_c Rᵀ``."""
        P = quaternion_matrix(self.q) @ self.axes        # principal frame → world
        self.omega = P @ ((P.T @ self.L) / self.moments)
        self.alpha = P @ ((P.T @ (M - np.cross(self.omega, self.L))) / self.moments)

    def start(self) -> None:
        self.A = self.F / self.body.mass + self.g
        self._spin(self.M)

    def _advance(self, dt: float) -> int:
        """Over ``dt`` (s): velocity Verlet for the centre and the kick–rotate–kick splitting for
        the rotation (module docstring), the load ramped from the last exchange's to the step's
        end load (N, N m, world frame); the sub-steps taken."""
        F0, M0 = self.F.copy(), self.M.copy()
        F1, M1 = self._ramp_end((F0, M0), (self.F_last, self.M_last), dt)
        self.F_last, self.M_last = F0, M0
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
        return n

    def surface(self) -> Surface:
        r = self.nodes() - self.c
        v = self.V + np.cross(self.omega, r)
        a = self.A + np.cross(self.alpha, r) + np.cross(self.omega, np.cross(self.omega, r))
        return Surface(self.body.name, self.c + r, v, self.body.surface.facets, None, a)

    def step_end_load(self) -> tuple[FloatArray, FloatArray]:
        """The resultant and the world moment (3,) about the centre of the surface forces added
        since the last clear."""
        return self.F.copy(), self.M.copy()

    def set_step_end_load(self, load: tuple[FloatArray, FloatArray]) -> None:
        """Use ``load`` (resultant, moment) at the end of the next step instead of the extrapolation."""
        self._end = (np.asarray(load[0], dtype=float).copy(), np.array(load[1], dtype=float))

    def add_forces(self, forces: FloatArray) -> None:
        r = self.nodes() - self.c
        self.F = self.F + forces.sum(axis=0)
        self.M = self.M + np.cross(r, forces).sum(axis=0)

    def clear_forces(self) -> None:
        self.F = np.zeros(self.dim)
        self.M = np.zeros(3)

    def kinetic_energy(self) -> float:
        """``½ m V² + ½ ω·L`` (J)."""
        return 0.5 * self.body.mass * float(self.V @ self.V) + 0.5 * float(self.omega @ self.L)

    def angle(self) -> float:
        """The angle of the rotation from rest, ``2 atan2(|q_xyz|, |q_w|)`` in ``[0, π]`` (rad)."""
        return 2.0 * math.atan2(math.sqrt(float(self.q[1:] @ self.q[1:])), abs(float(self.q[0])))

    def observables(self) -> dict[str, float]:
        """:meth:`RigidStepper.observables`, the ``angle`` of the rotation from rest and the world
        vectors ``omega_x|y|z`` (rad/s), ``moment_x|y|z`` (N m about the centre) and
        ``angular_momentum_x|y|z`` (kg m²/s)."""
        row = super().observables()
        row["angle"] = self.angle()
        for k, a in enumerate("xyz"):
            row[f"omega_{a}"], row[f"moment_{a}"] = float(self.omega[k]), float(self.M[k])
            row[f"angular_momentum_{a}"] = float(self.L[k])
        return row

    def finite(self) -> bool:
        return bool(all(np.all(np.isfinite(x)) for x in (self.c, self.V, self.q, self.L)))

    def checkpoint(self) -> dict[str, FloatArray]:
        return {"c": self.c.copy(), "V": self.V.copy(), "A": self.A.copy(), "F": self.F.copy(),
                "F_last": self.F_last.copy(), "q": self.q.copy(), "L": self.L.copy(), "omega": self.omega.copy(),
                "alpha": self.alpha.copy(), "M": self.M.copy(), "M_last": self.M_last.copy(),
                "counters": np.array([self.work, self.dt_prev, self.substeps, self.outer_steps], dtype=float)}

    def restore(self, arrays: dict[str, FloatArray]) -> None:
        self.c, self.V, self.A, self.F, self.F_last = (arrays[k].copy() for k in ("c", "V", "A", "F", "F_last"))
        self.q, self.L, self.omega, self.alpha, self.M, self.M_last = (
            np.array(arrays[k], dtype=float) for k in ("q", "L", "omega", "alpha", "M", "M_last"))
        work, dt_prev, sub, outer = arrays["counters"]
        self.work, self.dt_prev, self.substeps, self.outer_steps = float(work), float(dt_prev), int(sub), int(outer)

    def summary(self) -> dict[str, Any]:
        return self._summary(np.asarray(self.I).tolist(), principal_inertia_kg_m2=self.moments.tolist())
