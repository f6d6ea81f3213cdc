r"""Rigid bodies: velocity Verlet in the constrained coordinates (hinge, vertical, fixed, free in
2D), and the kick–rotate–kick splitting of a free 3D body.

A body on a hinge, a vertical guide, fixed, or free in 2D advances by velocity Verlet in its
constrained coordinates, sub-cycled so that :math:`\omega_n\,\delta t \le 0.05` on a hinge spring
(:data:`RIGID_PHASE_PER_SUBSTEP`), with the surface force and moment ramped over the outer step
(:mod:`~mlsgalerkin.structure.steppers.base`).

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
from mlsgalerkin.structure.rigid import Hinge, RigidBody
from mlsgalerkin.structure.steppers.base import Stepper
from mlsgalerkin.structure.steppers.rotation import free_rotation, quaternion_matrix

__all__ = ["RIGID_PHASE_PER_SUBSTEP", "RigidMotion"]

FloatArray = NDArray[np.float64]

#: Largest ``ω δt`` of a rigid body's sub-steps on its hinge spring, and of a free 3D body's
#: spin ``|ω| δt`` (rad).
RIGID_PHASE_PER_SUBSTEP = 0.05


def _cross(r: FloatArray, f: FloatArray) -> FloatArray:
    """``r × f`` (z-component) of ``(n, 2)`` rows."""
    return r[..., 0] * f[..., 1] - r[..., 1] * f[..., 0]


class RigidMotion(Stepper):
    """State and integrator of one :class:`RigidBody` (module docstring).

    A free 3D body (``body.free_rotation``) keeps the orientation ``q`` (unit quaternion, (4,)),
    the world angular momentum about the centre ``L`` (kg m²/s, (3,)), and ``omega``, ``alpha``,
    ``M`` as world (3,) vectors (rad/s, rad/s², N m); its ``theta`` stays 0 (the ``angle``
    observable is the angle of ``q``). The other bodies keep scalars about their axis."""

    kind = "rigid"

    def __init__(self, body: RigidBody) -> None:
        super().__init__(body)
        self.body: RigidBody = body
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

    def _advance(self, dt: float) -> int:
        """Over the outer step ``dt`` (s), the surface force and moment ramped from the last
        exchange's to the step's end load (module docstring); the sub-steps taken."""
        con = self.body.constraint
        F0, M0 = self.F.copy(), (self.M.copy() if self.free3d else self.M)
        F1, M1 = self._ramp_end((F0, M0), (self.F_last, self.M_last), dt)
        self.F_last, self.M_last = F0, M0
        if self.free3d:
            return self._advance_free(dt, F0, F1, M0, M1)
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
        return n

    def _advance_free(self, dt: float, F0: FloatArray, F1: FloatArray, M0: FloatArray, M1: FloatArray) -> int:
        """A free 3D body over ``dt`` (s): velocity Verlet for the centre and the kick–rotate–kick
        splitting for the rotation (module docstring), the load ramped from ``F0, M0`` to
        ``F1, M1`` (N, N m, world frame); the sub-steps taken."""
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
