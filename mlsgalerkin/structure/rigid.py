r"""Rigid bodies in 2D and 3D: mass, inertia, a constraint, and a surface the fluid touches
(segments in 2D, triangles in 3D). A body moves freely, vertically, stays fixed, or turns on a
hinge about an axis, in 2D and in 3D (free rotation in 3D has three rotational degrees of
freedom and an inertia tensor).

A rigid body moves its surface nodes :math:`\mathbf X_a` (at rest) with the translation of its
centre of mass :math:`\mathbf c` and a rotation :math:`R` about it (by the angle :math:`\theta`
about the axis :math:`\mathbf e` in 2D, :math:`\mathbf e = \mathbf e_z`, and on a hinge; any
rotation for a free 3D body), :math:`\mathbf r_a = \mathbf x_a - \mathbf c`:

.. math:: \mathbf x_a = \mathbf c + R(\mathbf X_a - \mathbf c_0),\qquad
          \mathbf v_a = \mathbf V + \boldsymbol\omega\times\mathbf r_a,\qquad
          \mathbf a_a = \mathbf A + \boldsymbol\alpha\times\mathbf r_a
          + \boldsymbol\omega\times(\boldsymbol\omega\times\mathbf r_a),

with :math:`\boldsymbol\omega = \omega\mathbf e`, :math:`\boldsymbol\alpha = \dot\omega\mathbf e`
for a rotation about a fixed axis (the last term is then :math:`-\omega^2\mathbf r_{a\perp}`).

Forces :math:`\mathbf f_a` on the surface nodes (from contact and the fluid's wall particles)
give the resultant :math:`\mathbf F = \sum_a \mathbf f_a` and moment
:math:`\mathbf M = \sum_a (\mathbf x_a - \mathbf p)\times\mathbf f_a` about a point
:math:`\mathbf p` (its component :math:`M = \mathbf M\cdot\mathbf e` about a fixed axis).
The equations of motion by constraint (units: kg, kg m², N, N m, per unit depth in 2D):

- ``"free"`` in 2D: :math:`m\dot{\mathbf V} = \mathbf F + m\mathbf g`, :math:`I_c\dot\omega = M_c`;
- ``"free"`` in 3D (six degrees of freedom): :math:`m\dot{\mathbf V} = \mathbf F + m\mathbf g`
  and Euler's equations for the angular momentum about the centre,
  :math:`\dot{\mathbf L} = \mathbf M_c` in the world frame, :math:`\mathbf L = R\,I_c R^{\mathsf T}
  \boldsymbol\omega`, :math:`\dot R = \hat{\boldsymbol\omega} R`, with :math:`I_c` the (3, 3)
  inertia tensor about the centre of mass in the body's frame at rest (the world frame at
  :math:`t = 0`); in its principal frame, :math:`I_i\dot\Omega_i = (I_j - I_k)\Omega_j\Omega_k + M_i`
  (:math:`(i, j, k)` cyclic). The integrator is the symplectic splitting of Dullweber,
  Leimkuhler & McLachlan (1997), :mod:`mlsgalerkin.structure.steppers.rigid_motion`;
- ``"vertical"`` (heave only, the rigid wedge of Zhao, Faltinsen & Aarsnes 1996):
  :math:`m\dot V_y = F_y + m g_y`, no rotation, no horizontal motion;
- ``"fixed"``: the body does not move (a wall whose load is recorded);
- :class:`Hinge` (rotation about a fixed point :math:`\mathbf p` with a rotational spring
  :math:`K` and damper :math:`C`, the spring-supported beam of Sun 2016):
  :math:`I_p\ddot\theta = M_p + (\mathbf c - \mathbf p)\times m\mathbf g - K\theta - C\dot\theta`,
  :math:`I_p = \mathbf e^{\mathsf T} I_c\,\mathbf e + m|\mathbf r_\perp|^2`, :math:`\mathbf r_\perp` the
  centre's distance from the axis (:math:`I_p = I_c + m|\mathbf c_0 - \mathbf p|^2` in 2D).

For a uniform beam of length :math:`L` and mass :math:`m` standing on its hinge,
:math:`(\mathbf c - \mathbf p)\times m\mathbf g = \tfrac12 mgL\sin\theta`, and the dry natural
frequency is :math:`\omega_n^2 = (K - mgL/2)/I_p` (0.1879 s for :math:`L = 2` m,
:math:`m = 1` kg, :math:`K = 1500` N m/rad; Sun 2016).

>>> beam = RigidBody.beam("beam", base=(3.22, 0.0), length=2.0, mass=1.0, thickness=0.02,
...                       constraint=Hinge((3.22, 0.0), stiffness=1500.0), gravity=(0.0, -9.81))
>>> round(beam.natural_period(), 4)
0.1879
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import ClassVar

import numpy as np
from numpy.typing import ArrayLike, NDArray

from mlsgalerkin.contact import ContactSurface
from mlsgalerkin.dynamics import Body
from mlsgalerkin.structure.checks import substep_estimate
from mlsgalerkin.structure.elastic import STRUCTURE_SOLVER

__all__ = ["CONSTRAINTS", "Hinge", "RigidBody"]

FloatArray = NDArray[np.float64]

#: The named constraints of a rigid body (a :class:`Hinge` is the fourth kind).
CONSTRAINTS = ("free", "vertical", "fixed")


@dataclass(frozen=True)
class Hinge:
    """Rotation about the fixed ``point`` (m) with a rotational spring ``stiffness`` (N m/rad, per
    unit depth in 2D) and damper ``damping`` (N m s/rad); the angle is zero at rest. In 3D the
    rotation is about the line through ``point`` along ``axis`` (a unit vector; in 2D the axis is
    out of the plane)."""

    point: tuple[float, ...]
    stiffness: float = 0.0
    damping: float = 0.0
    axis: tuple[float, float, float] = (0.0, 0.0, 1.0)

    def __post_init__(self) -> None:
        p = np.asarray(self.point, dtype=float)
        if p.shape not in ((2,), (3,)) or not np.all(np.isfinite(p)):
            raise ValueError(f"Hinge: point must be a finite (2,) or (3,) position, got {self.point!r}")
        if not (math.isfinite(self.stiffness) and self.stiffness >= 0):
            raise ValueError(f"Hinge: stiffness must be finite and >= 0 (N m/rad), got {self.stiffness!r}")
        if not (math.isfinite(self.damping) and self.damping >= 0):
            raise ValueError(f"Hinge: damping must be finite and >= 0 (N m s/rad), got {self.damping!r}")
        a = np.asarray(self.axis, dtype=float)
        if a.shape != (3,) or not np.all(np.isfinite(a)) or abs(np.linalg.norm(a) - 1.0) > 1e-9:
            raise ValueError(f"Hinge: axis must be a unit (3,) vector, got {self.axis!r}")

    def unit_axis(self, dim: int) -> FloatArray:
        """The rotation axis as a 3-vector (``(0, 0, 1)`` in 2D)."""
        return np.array([0.0, 0.0, 1.0]) if dim == 2 else np.asarray(self.axis, dtype=float)


@dataclass
class RigidBody(Body):
    """A rigid body in 2D or 3D (module docstring), with the constraint ``"free"``,
    ``"vertical"`` (along the last axis), ``"fixed"`` or a :class:`Hinge` about an axis. A free
    3D body has six degrees of freedom: its centre translates and it turns about its centre under
    the moment of the surface forces, with its inertia tensor.

    Parameters
    ----------
    name : str
    surface : ContactSurface
        The surface the fluid may touch, at rest, normals out of the body.
    mass : float
        kg (per unit depth in 2D).
    inertia : float, (3,) or (3, 3)
        Inertia about the centre of mass (kg m², per unit depth in 2D). In 2D a positive scalar,
        about the axis out of the plane. In 3D, in the body's frame at rest (the world frame at
        ``t = 0``): a positive scalar (isotropic, ``I·1``), a (3,) positive diagonal (the
        principal moments about ``x, y, z``) or a symmetric positive-definite (3, 3) tensor; its
        principal moments must satisfy the triangle inequality ``I₁ + I₂ ≥ I₃`` that every mass
        distribution does. A 3D :class:`Hinge` uses ``eᵀ I e`` about its axis ``e`` through the
        centre. A tensor is stored as a (3, 3) array (symmetrised), a scalar as given.
    centre : (d,) point
        Centre of mass at rest (m).
    constraint : str or Hinge
        ``"free"``, ``"vertical"``, ``"fixed"`` or a :class:`Hinge`.
    velocity : (d,) m/s
        Initial velocity of the centre of mass.
    angular_velocity : float or (3,), rad/s
        Initial rate of rotation: a scalar in 2D and about a hinge's axis in 3D; a (3,) vector in
        the world frame for a free 3D body (a scalar ``0`` means at rest).
    gravity : (d,) m/s², optional
        Acceleration of gravity on the body; none by default.
    """

    solver: ClassVar[str] = STRUCTURE_SOLVER
    name: str
    surface: ContactSurface
    mass: float
    inertia: float | FloatArray
    centre: FloatArray
    constraint: str | Hinge = "free"
    velocity: FloatArray | None = None
    angular_velocity: float | FloatArray = 0.0
    gravity: FloatArray | None = None

    def __post_init__(self) -> None:
        owner = f"RigidBody {self.name!r}"
        if not isinstance(self.surface, ContactSurface):
            raise ValueError(f"{owner}: surface must be a mlsgalerkin.contact.ContactSurface (normals out of the "
                             f"body), got {type(self.surface).__name__}")
        if not (isinstance(self.mass, (int, float)) and math.isfinite(self.mass) and self.mass > 0):
            raise ValueError(f"{owner}: mass must be positive (kg per unit depth), got {self.mass!r}")
        if not (isinstance(self.constraint, Hinge) or self.constraint in CONSTRAINTS):
            raise ValueError(f"{owner}: constraint must be one of {CONSTRAINTS} or a Hinge(point, stiffness), got "
                             f"{self.constraint!r}")
        self.inertia = self._inertia(owner, self.inertia)
        self.centre = self._vector(owner, "centre", self.centre)
        if self.centre.shape != (self.surface.dim,):
            raise ValueError(f"{owner}: centre must be a ({self.surface.dim},) point like the surface's nodes")
        self.velocity = (np.zeros(self.surface.dim) if self.velocity is None
                         else self._vector(owner, "velocity", self.velocity))
        if self.free_rotation:
            w = np.asarray(self.angular_velocity, dtype=float)
            if w.shape == () and w == 0:
                w = np.zeros(3)
            if w.shape != (3,) or not np.all(np.isfinite(w)):
                raise ValueError(f"{owner}: a free 3D body takes angular_velocity as a finite (3,) vector (rad/s, "
                                 f"world frame), got {self.angular_velocity!r}")
            self.angular_velocity = w
        elif not (np.ndim(self.angular_velocity) == 0 and math.isfinite(self.angular_velocity)):
            raise ValueError(f"{owner}: angular_velocity must be a finite scalar (rad/s, about the axis of rotation) "
                             f"unless the body is free in 3D, got {self.angular_velocity!r}")
        if self.gravity is not None:
            self.gravity = self._vector(owner, "gravity", self.gravity)
        if isinstance(self.constraint, Hinge) and np.asarray(self.constraint.point).shape != (self.dim,):
            raise ValueError(f"{owner}: the hinge point must be a ({self.dim},) position")
        if self.constraint == "vertical" and np.any(self.velocity[:-1] != 0):
            raise ValueError(f"{owner}: a body constrained to vertical motion starts with no horizontal velocity")
        if self.constraint == "vertical" and self.angular_velocity != 0:
            raise ValueError(f"{owner}: a body constrained to vertical motion starts with no horizontal velocity "
                             "and no rotation")
        if self.constraint == "fixed" and (np.any(self.velocity != 0) or self.angular_velocity != 0):
            raise ValueError(f"{owner}: a fixed body has no initial velocity")
        if isinstance(self.constraint, Hinge) and np.any(self.velocity != 0):
            raise ValueError(f"{owner}: a hinged body starts with angular_velocity only (velocity must be zero)")
        if isinstance(self.constraint, Hinge) and self.natural_frequency_squared() <= 0 and self.constraint.stiffness > 0:
            raise ValueError(f"{owner}: the hinge spring ({self.constraint.stiffness:g} N m/rad) does not hold the body "
                             "up against gravity (K < m g |c - p|): stiffen the spring")

    def _inertia(self, owner: str, value: float | ArrayLike) -> float | FloatArray:
        """The inertia checked (class docstring): a positive scalar, or in 3D a symmetric
        positive-definite (3, 3) tensor (from a (3,) diagonal or a (3, 3) array)."""
        what = "kg m² about the centre of mass"
        if np.ndim(value) == 0 and not isinstance(value, (str, bytes)):
            real = isinstance(value, (int, float, np.integer, np.floating, np.ndarray)) and not isinstance(value, bool)
            if not (real and np.isreal(value) and math.isfinite(value) and value > 0):
                raise ValueError(f"{owner}: inertia must be positive ({what}), got {value!r}")
            return value if isinstance(value, (int, float)) else float(value)
        if self.surface.dim == 2:
            raise ValueError(f"{owner}: in 2D inertia is a positive scalar ({what}, about the axis out of the plane), "
                             f"got {value!r}")
        try:
            I = np.asarray(value, dtype=float)
        except (TypeError, ValueError):
            raise ValueError(f"{owner}: inertia must be a positive scalar, a (3,) principal diagonal or a symmetric "
                             f"positive-definite (3, 3) tensor ({what}), got {value!r}") from None
        if I.shape == (3,):
            if not (np.all(np.isfinite(I)) and np.all(I > 0)):
                raise ValueError(f"{owner}: the (3,) principal moments of inertia must be finite and positive ({what}), "
                                 f"got {value!r}")
            I = np.diag(I)
        elif I.shape == (3, 3):
            if not np.all(np.isfinite(I)):
                raise ValueError(f"{owner}: the inertia tensor must be finite ({what}), got {value!r}")
            scale = float(np.abs(I).max())
            if float(np.abs(I - I.T).max()) > 1e-12 * scale:
                raise ValueError(f"{owner}: the inertia tensor must be symmetric (I = Iᵀ within 1e-12 of its largest "
                                 f"entry), got {value!r}")
            I = 0.5 * (I + I.T)
        else:
            raise ValueError(f"{owner}: inertia must be a positive scalar, a (3,) principal diagonal or a symmetric "
                             f"positive-definite (3, 3) tensor ({what}), got shape {I.shape}")
        principal = np.linalg.eigvalsh(I)
        if not principal[0] > 0:
            raise ValueError(f"{owner}: the inertia tensor must be positive definite ({what}); its principal moments "
                             f"are {principal.tolist()}")
        if principal[0] + principal[1] < principal[2] * (1.0 - 1e-9):
            raise ValueError(f"{owner}: the principal moments of inertia {principal.tolist()} break the triangle "
                             "inequality I₁ + I₂ ≥ I₃ that every mass distribution satisfies (kg m² about the centre "
                             "of mass: check the units and the point they are taken about)")
        return I

    @staticmethod
    def _vector(owner: str, what: str, value: ArrayLike) -> FloatArray:
        v = np.asarray(value, dtype=float)
        if v.ndim != 1 or v.shape[0] not in (2, 3) or not np.all(np.isfinite(v)):
            raise ValueError(f"{owner}: {what} must be a finite (2,) or (3,) vector, got {value!r}")
        return v

    @property
    def dim(self) -> int:
        return self.surface.dim

    def substep_estimate(self) -> float | None:
        """The sub-step (s) a run takes for a hinge spring or a spin, ``None`` where the outer
        step is enough (:func:`~mlsgalerkin.structure.checks.substep_estimate`)."""
        return substep_estimate(self)

    @property
    def free_rotation(self) -> bool:
        """A free 3D body: six degrees of freedom, rotation with an inertia tensor."""
        return self.dim == 3 and self.constraint == "free"

    # ------------------------------------------------------------------ derived
    def inertia_tensor(self) -> FloatArray:
        """The (3, 3) inertia tensor about the centre of mass in the body's frame at rest (kg m²;
        3D only)."""
        if self.dim != 3:
            raise ValueError(f"RigidBody {self.name!r}: a 2D body has a scalar inertia, no tensor")
        if np.ndim(self.inertia) == 0:
            return float(self.inertia) * np.eye(3)
        return np.array(self.inertia, dtype=float)

    def axis_inertia(self, axis: FloatArray) -> float:
        """``eᵀ I_c e`` (kg m²) about the unit ``axis`` through the centre of mass (the scalar
        inertia itself in 2D or when it is given as a scalar)."""
        if np.ndim(self.inertia) == 0:
            return float(self.inertia)
        e = np.asarray(axis, dtype=float)
        return float(e @ self.inertia @ e)

    def _arm(self) -> FloatArray:
        """``r = c0 − p`` as a 3-vector, with the component along the hinge's axis removed."""
        r = np.zeros(3)
        r[: self.dim] = self.centre - np.asarray(self.constraint.point, dtype=float)
        a = self.constraint.unit_axis(self.dim)
        return r - (r @ a) * a

    def hinge_inertia(self) -> float:
        """``I_p = I_c + m |r⊥|²`` (kg m²) about the hinge's axis (a :class:`Hinge` body), ``r⊥``
        the centre's distance from the axis."""
        return self.axis_inertia(self.constraint.unit_axis(self.dim)) + self.mass * float(self._arm() @ self._arm())

    def natural_frequency_squared(self) -> float:
        """``ω² = (K + m g·r⊥)/I_p`` (rad²/s²) of small dry oscillations about a hinge (gravity
        pointing away from the centre lowers it for a body standing on its hinge)."""
        h = self.constraint
        g = np.zeros(3)
        if self.gravity is not None:
            g[: self.dim] = self.gravity
        return (h.stiffness + self.mass * float(g @ self._arm())) / self.hinge_inertia()

    def natural_period(self) -> float:
        """Dry natural period ``2π/ω_n`` (s) of a hinged body."""
        if not isinstance(self.constraint, Hinge):
            raise ValueError(f"RigidBody {self.name!r}: only a hinged body has a natural period")
        return 2.0 * math.pi / math.sqrt(self.natural_frequency_squared())

    # ------------------------------------------------------------------ builders
    @classmethod
    def beam(cls, name: str, base: ArrayLike, length: float, mass: float, thickness: float,
             constraint: str | Hinge = "free", gravity: ArrayLike | None = None, angle: float = 0.0) -> RigidBody:
        """A uniform rectangular beam standing on ``base`` (m) at ``angle`` from the vertical
        (rad, counter-clockwise), ``length × thickness`` (m); inertia ``m(L² + t²)/12`` about
        its centre; the surface is its outline (normals out of the beam)."""
        b = np.asarray(base, dtype=float)
        axis = np.array([-math.sin(angle), math.cos(angle)])
        side = np.array([axis[1], -axis[0]]) * 0.5 * thickness
        corners = [b - side, b + side, b + side + length * axis, b - side + length * axis]
        surface = ContactSurface(np.array(corners), np.array([[0, 1], [1, 2], [2, 3], [3, 0]]))
        return cls(name, surface, mass, mass * (length**2 + thickness**2) / 12.0, b + 0.5 * length * axis,
                   constraint=constraint, gravity=None if gravity is None else np.asarray(gravity, dtype=float))
