r"""Rigid bodies in a run: what their steppers share (:class:`RigidStepper`), and velocity Verlet
in the constrained coordinates of a body on a hinge, a vertical guide, fixed, or free in 2D
(:class:`RigidMotion`).

:class:`RigidMotion` advances the centre :math:`\mathbf c` and the angle :math:`\theta` about the
constraint's axis by velocity Verlet, sub-cycled so that :math:`\omega_n\,\delta t \le 0.05` on
a hinge spring (:data:`RIGID_PHASE_PER_SUBSTEP`), with the surface force and moment ramped over
the outer step (:mod:`~mlsgalerkin.structure.steppers.base`). A free 3D body turns about any axis:
:class:`~mlsgalerkin.structure.steppers.free_rigid_motion.FreeRigidMotion`.
"""

from __future__ import annotations

import math
from abc import abstractmethod
from typing import Any

import numpy as np
from numpy.typing import NDArray

from mlsgalerkin.dynamics import Surface
from mlsgalerkin.structure.rigid import Hinge, RigidBody
from mlsgalerkin.structure.steppers.base import Stepper

__all__ = ["RIGID_PHASE_PER_SUBSTEP", "RigidMotion", "RigidStepper"]

FloatArray = NDArray[np.float64]

#: Largest ``ω δt`` of a rigid body's sub-steps on its hinge spring, and of a free 3D body's
#: spin ``|ω| δt`` (rad).
RIGID_PHASE_PER_SUBSTEP = 0.05


def _cross(r: FloatArray, f: FloatArray) -> FloatArray:
    """``r × f`` (z-component) of ``(n, 2)`` rows."""
    return r[..., 0] * f[..., 1] - r[..., 1] * f[..., 0]


class RigidStepper(Stepper):
    """What the steppers of a :class:`RigidBody` share: the surface nodes at rest ``X`` ``(m, d)``
    (m), the centre at rest ``c0`` and now ``c``, its velocity ``V`` and acceleration ``A``, the
    resultant of the surface forces of the last exchange ``F`` and of the one before ``F_last``
    (N), and the body's gravity ``g``; the moment ``M`` and the rotation belong to the method."""

    kind = "rigid"

    def __init__(self, body: RigidBody) -> None:
        super().__init__(body)
        self.body: RigidBody = body
        self.X = body.surface.nodes.copy()
        self.c0 = body.centre.copy()
        self.c = body.centre.copy()
        self.theta = 0.0
        self.V = body.velocity.copy()
        d = body.dim
        self.dim = d
        self.A = np.zeros(d)          # acceleration of the centre under the body's own forces (m/s²)
        self.F = np.zeros(d)          # resultant of the surface forces of the last exchange (N)
        self.F_last = np.zeros(d)     # resultant and moment of the exchange before, for the extrapolation
        self.g = np.zeros(d) if body.gravity is None else body.gravity

    @property
    def n_surface(self) -> int:
        return self.X.shape[0]

    @abstractmethod
    def rotation(self) -> FloatArray:
        """The body's rotation from rest now: (2, 2) or (3, 3)."""

    def nodes(self) -> FloatArray:
        """Surface node positions ``(m, d)`` now (m)."""
        return self.c + (self.X - self.c0) @ self.rotation().T

    @abstractmethod
    def kinetic_energy(self) -> float:
        """The kinetic energy (J, per unit depth in 2D)."""

    def energies(self) -> dict[str, float]:
        b = self.body
        con = b.constraint
        spring = 0.5 * con.stiffness * self.theta**2 if isinstance(con, Hinge) else 0.0
        return {"kinetic_energy": self.kinetic_energy(), "spring_energy": spring,
                "weight_potential": -b.mass * float(self.g @ (self.c - self.c0)), "surface_work": self.work}

    def observables(self) -> dict[str, float]:
        """Energies, the centre's displacement ``x|y|z`` (m), velocity ``vx|vy|vz`` (m/s) and the
        surface load ``force_x|y|z`` (N); the rotation's columns come from the method."""
        row = self.energies()
        d = self.c - self.c0
        for k in range(self.dim):
            a = "xyz"[k]
            row[a], row[f"v{a}"], row[f"force_{a}"] = float(d[k]), float(self.V[k]), float(self.F[k])
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

    def _summary(self, inertia: Any, **extra: Any) -> dict[str, Any]:
        """The body's ``summary.json`` entry with its ``inertia`` and the method's ``extra`` entries."""
        b = self.body
        con = b.constraint
        return {"kind": "rigid", "constraint": repr(con) if isinstance(con, Hinge) else con, "mass_kg": b.mass,
                "inertia_kg_m2": inertia, **extra,
                "natural_period_s": b.natural_period() if isinstance(con, Hinge) else None,
                "outer_steps": self.outer_steps, "substeps": self.substeps, "time_s": self.seconds,
                **{f"end_{k}_J": v for k, v in self.energies().items()}}


class RigidMotion(RigidStepper):
    """Velocity Verlet of a :class:`RigidBody` turning about one axis (module docstring): on a
    hinge, a vertical guide, fixed, or free in 2D. The angle ``theta`` (rad), the rate ``omega``
    (rad/s), the angular acceleration ``alpha`` (rad/s²) and the moment of the surface forces
    ``M`` about the centre (N m) are scalars about the axis."""

    def __init__(self, body: RigidBody) -> None:
        if body.free_rotation:
            raise TypeError(f"rigid body {body.name!r} is free in 3D: it turns about any axis and moves with "
                            "FreeRigidMotion (stepper_for(body) picks the stepper of a body)")
        super().__init__(body)
        d = self.dim
        self.omega = float(body.angular_velocity)
        self.alpha = 0.0          # angular acceleration about the axis (rad/s²)
        self.M = 0.0              # moment of the surface forces about the centre of mass, about the axis (N m)
        self.M_last = 0.0
        con = body.constraint
        self.axis = con.unit_axis(d) if isinstance(con, Hinge) else np.array([0.0, 0.0, 1.0])
        if isinstance(con, Hinge):
            self.p = np.asarray(con.point, dtype=float)
            self.I = body.hinge_inertia()
            self.omega_n = math.sqrt(max(body.natural_frequency_squared(), 0.0))
        else:
            self.p = None
            self.I = body.axis_inertia(self.axis)
            self.omega_n = 0.0

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
        return self._rotation(self.theta)

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
        F0, M0 = self.F.copy(), self.M
        F1, M1 = self._ramp_end((F0, M0), (self.F_last, self.M_last), dt)
        self.F_last, self.M_last = F0, M0
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

    def surface(self) -> Surface:
        r = self.nodes() - self.c
        perp = self._turn(r)
        e = self._axis_d()
        v = self.V + self.omega * perp
        a = self.A + self.alpha * perp - self.omega**2 * (r - np.outer(r @ e, e))
        return Surface(self.body.name, self.c + r, v, self.body.surface.facets, None, a)

    def step_end_load(self) -> tuple[FloatArray, float]:
        """The resultant and the moment about the axis of the surface forces added since the last
        clear."""
        return self.F.copy(), self.M

    def set_step_end_load(self, load: tuple[FloatArray, float]) -> None:
        """Use ``load`` (resultant, moment) at the end of the next step instead of the extrapolation."""
        self._end = (np.asarray(load[0], dtype=float).copy(), float(load[1]))

    def add_forces(self, forces: FloatArray) -> None:
        r = self.nodes() - self.c
        self.F = self.F + forces.sum(axis=0)
        self.M += float(np.sum(self._torque(r, forces)))

    def clear_forces(self) -> None:
        self.F = np.zeros(self.dim)
        self.M = 0.0

    def kinetic_energy(self) -> float:
        """``½ m V² + ½ I ω²`` (J, per unit depth in 2D; ``½ I_p ω²`` on a hinge)."""
        b = self.body
        if isinstance(b.constraint, Hinge):
            return 0.5 * self.I * self.omega**2
        return 0.5 * b.mass * float(self.V @ self.V) + 0.5 * self.I * self.omega**2

    def angle(self) -> float:
        """The angle ``θ`` turned from rest about the axis (rad)."""
        return self.theta

    def observables(self) -> dict[str, float]:
        """:meth:`RigidStepper.observables` and the ``angle``, ``omega`` and ``moment`` about the
        axis."""
        row = super().observables()
        row.update({"angle": self.theta, "omega": self.omega, "moment": self.M})
        return row

    def finite(self) -> bool:
        return bool(np.all(np.isfinite(self.c)) and math.isfinite(self.theta) and math.isfinite(self.omega))

    def checkpoint(self) -> dict[str, FloatArray]:
        return {"c": self.c.copy(), "V": self.V.copy(), "A": self.A.copy(), "F": self.F.copy(),
                "F_last": self.F_last.copy(),
                "scalars": np.array([self.theta, self.omega, self.alpha, self.M, self.M_last, self.work, self.dt_prev,
                                     self.substeps, self.outer_steps], dtype=float)}

    def restore(self, arrays: dict[str, FloatArray]) -> None:
        self.c, self.V, self.A, self.F, self.F_last = (arrays[k].copy() for k in ("c", "V", "A", "F", "F_last"))
        th, om, al, M, M_last, work, dt_prev, sub, outer = arrays["scalars"]
        self.theta, self.omega, self.alpha, self.M, self.M_last = float(th), float(om), float(al), float(M), float(M_last)
        self.work, self.dt_prev = float(work), float(dt_prev)
        self.substeps, self.outer_steps = int(sub), int(outer)

    def summary(self) -> dict[str, Any]:
        return self._summary(np.asarray(self.I).tolist() if np.ndim(self.I) else self.I)
