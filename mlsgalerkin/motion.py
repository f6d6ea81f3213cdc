r"""Prescribed rigid motion of a body as functions of time: translation and rotation about a point.

A point at ``x0`` (reference configuration, ``t = 0`` for a motion starting at rest) moves to

.. math::

    \mathbf x(t) = \mathbf c + \mathbf d(t) + \mathbf R(\theta(t))\,(\mathbf x_0 - \mathbf c),
    \qquad
    \dot{\mathbf x} = \dot{\mathbf d} + \dot\theta\,\mathbf J\mathbf r,
    \qquad
    \ddot{\mathbf x} = \ddot{\mathbf d} + \ddot\theta\,\mathbf J\mathbf r - \dot\theta^2\,\mathbf r,

with ``r = R(θ)(x0 − c)``, the centre of rotation ``c`` (carried along by the translation
``d``), the 2D rotation ``R(θ)`` and ``J = R(π/2)``. Rotation is 2D only; translation works
in 2D and 3D. A :class:`Motion` supplies ``d, ḋ, d̈`` and ``θ, θ̇, θ̈``;
:meth:`Motion.check` compares them with finite differences so that a mistyped derivative is
reported before a run starts.

>>> piston = Oscillation(stroke=0.1, period=2.0, direction=(1.0, 0.0))
>>> x0 = np.zeros((1, 2))
>>> piston.positions(x0, 0.5)          # a quarter period: half the stroke forward
array([[0.05, 0.  ]])
>>> piston.check(2)
[]
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

__all__ = ["Motion", "Oscillation", "PrescribedMotion"]

FloatArray = NDArray[np.float64]


class Motion:
    """Base class: override the translation and/or rotation functions of time (SI units)."""

    centre: FloatArray | None = None

    def displacement(self, t: float) -> FloatArray | None:
        """Translation ``d(t)`` (m), or ``None`` for none."""
        return None

    def velocity(self, t: float) -> FloatArray | None:
        """``ḋ(t)`` (m/s)."""
        return None

    def acceleration(self, t: float) -> FloatArray | None:
        """``d̈(t)`` (m/s²)."""
        return None

    def angle(self, t: float) -> float:
        """Rotation angle ``θ(t)`` (rad, counter-clockwise) about :attr:`centre`."""
        return 0.0

    def angular_velocity(self, t: float) -> float:
        """``θ̇(t)`` (rad/s)."""
        return 0.0

    def angular_acceleration(self, t: float) -> float:
        """``θ̈(t)`` (rad/s²)."""
        return 0.0

    @property
    def rotates(self) -> bool:
        return self.centre is not None

    # ------------------------------------------------------------------ kinematics
    def _arm(self, x0: FloatArray, t: float) -> tuple[FloatArray, FloatArray]:
        """``(c + d, r = R(θ)(x0 − c))`` for reference points ``x0 (n, 2)``."""
        c = np.asarray(self.centre, dtype=float)
        th = self.angle(t)
        cs, sn = math.cos(th), math.sin(th)
        rel = x0 - c
        r = np.column_stack([cs * rel[:, 0] - sn * rel[:, 1], sn * rel[:, 0] + cs * rel[:, 1]])
        d = self.displacement(t)
        return (c if d is None else c + d), r

    def positions(self, x0: FloatArray, t: float) -> FloatArray:
        """Positions ``(n, d)`` at ``t`` of the reference points ``x0 (n, d)``."""
        if self.rotates:
            origin, r = self._arm(x0, t)
            return origin + r
        d = self.displacement(t)
        return x0 + d if d is not None else x0.copy()

    def velocities(self, x0: FloatArray, t: float) -> FloatArray:
        """Velocities ``(n, d)`` (m/s) at ``t`` of the points with reference positions ``x0``."""
        v = self.velocity(t)
        out = np.zeros_like(x0) + (v if v is not None else 0.0)
        if self.rotates:
            _, r = self._arm(x0, t)
            w = self.angular_velocity(t)
            out[:, 0] -= w * r[:, 1]
            out[:, 1] += w * r[:, 0]
        return out

    def accelerations(self, x0: FloatArray, t: float) -> FloatArray:
        """Accelerations ``(n, d)`` (m/s²) at ``t``."""
        a = self.acceleration(t)
        out = np.zeros_like(x0) + (a if a is not None else 0.0)
        if self.rotates:
            _, r = self._arm(x0, t)
            w, al = self.angular_velocity(t), self.angular_acceleration(t)
            out[:, 0] += -al * r[:, 1] - w * w * r[:, 0]
            out[:, 1] += al * r[:, 0] - w * w * r[:, 1]
        return out

    def rotate(self, vectors: FloatArray, t: float) -> FloatArray:
        """Reference directions ``(n, d)`` (e.g. wall normals) turned with the body at ``t``."""
        if not self.rotates:
            return vectors
        th = self.angle(t)
        cs, sn = math.cos(th), math.sin(th)
        return np.column_stack([cs * vectors[:, 0] - sn * vectors[:, 1], sn * vectors[:, 0] + cs * vectors[:, 1]])

    # ------------------------------------------------------------------ validation
    def check(self, dim: int, times: ArrayLike | None = None, rtol: float = 1e-4) -> list[str]:
        """Problems with this motion in ``dim`` dimensions: shapes, finiteness, and derivatives
        that disagree with central differences (relative to the motion's scale) at ``times``."""
        problems: list[str] = []
        if self.rotates and dim != 2:
            problems.append(f"{self!r}: rotation is 2D only, the scene is {dim}D")
            return problems
        if self.rotates and np.shape(self.centre) != (2,):
            problems.append(f"{self!r}: centre must be a (2,) point, got {np.shape(self.centre)}")
            return problems
        ts = np.linspace(0.05, 1.0, 7) if times is None else np.asarray(times, dtype=float)
        pairs: list[tuple[str, Callable[[float], Any], Callable[[float], Any]]] = [
            ("velocity", self.displacement, self.velocity),
            ("acceleration", self.velocity, self.acceleration),
            ("angular_velocity", self.angle, self.angular_velocity),
            ("angular_acceleration", self.angular_velocity, self.angular_acceleration),
        ]
        for name, f, df in pairs:
            try:
                values = [f(t) for t in ts]
                if values[0] is None:
                    continue
                vals = np.array(values, dtype=float).reshape(len(ts), -1)
                if name in ("velocity", "acceleration") and vals.shape[1] != dim:
                    problems.append(f"{self!r}: the translation must be a ({dim},) vector, got {vals.shape[1]} components")
                    return problems
                if not np.all(np.isfinite(vals)):
                    problems.append(f"{self!r}: non-finite values feeding {name}")
                    continue
                scale = max(float(np.abs(vals).max()), 1e-12)
                for t in ts:
                    eps = 1e-6 * max(1.0, abs(t))
                    fd = (np.asarray(f(t + eps), dtype=float) - np.asarray(f(t - eps), dtype=float)) / (2 * eps)
                    exact = np.asarray(df(t), dtype=float)
                    if not np.allclose(exact, fd, rtol=rtol, atol=rtol * scale / max(ts.max(), 1e-12)):
                        problems.append(
                            f"{self!r}: {name} at t = {t:g} s is {np.round(exact, 9).tolist()} but the finite "
                            f"difference of the function it is the derivative of gives {np.round(fd, 9).tolist()}; "
                            "give consistent derivatives")
                        break
            except Exception as exc:  # a user's function failed: report it, do not crash validation
                problems.append(f"{self!r}: evaluating {name} failed ({type(exc).__name__}: {exc})")
        return problems


class PrescribedMotion(Motion):
    """Rigid motion from user functions of time (SI units; see the module docstring).

    Parameters
    ----------
    displacement, velocity, acceleration : callable ``t -> (d,)``, optional
        Translation ``d(t)`` and its first two derivatives (all three, or none).
    angle, angular_velocity, angular_acceleration : callable ``t -> float``, optional
        Rotation (2D) about ``centre`` and its derivatives (all three, or none).
    centre : (2,) array, optional
        Centre of rotation in the reference configuration (m); required with a rotation.
    """

    def __init__(
        self, displacement: Callable | None = None, velocity: Callable | None = None,
        acceleration: Callable | None = None, *, angle: Callable | None = None,
        angular_velocity: Callable | None = None, angular_acceleration: Callable | None = None,
        centre: ArrayLike | None = None,
    ) -> None:
        trans = (displacement, velocity, acceleration)
        rot = (angle, angular_velocity, angular_acceleration)
        if any(f is not None for f in trans) and any(f is None for f in trans):
            raise ValueError("PrescribedMotion: give displacement, velocity and acceleration together")
        if any(f is not None for f in rot) and any(f is None for f in rot):
            raise ValueError("PrescribedMotion: give angle, angular_velocity and angular_acceleration together")
        if rot[0] is not None and centre is None:
            raise ValueError("PrescribedMotion: a rotation needs its centre=(x, y)")
        self._d, self._v, self._a = trans
        self._th, self._w, self._al = rot
        self.centre = None if rot[0] is None else np.asarray(centre, dtype=float)

    def __repr__(self) -> str:
        parts = []
        if self._d is not None:
            parts.append("translation")
        if self._th is not None:
            parts.append(f"rotation about {self.centre.tolist()}")
        return f"PrescribedMotion({', '.join(parts) or 'at rest'})"

    def displacement(self, t: float) -> FloatArray | None:
        return None if self._d is None else np.asarray(self._d(t), dtype=float)

    def velocity(self, t: float) -> FloatArray | None:
        return None if self._v is None else np.asarray(self._v(t), dtype=float)

    def acceleration(self, t: float) -> FloatArray | None:
        return None if self._a is None else np.asarray(self._a(t), dtype=float)

    def angle(self, t: float) -> float:
        return 0.0 if self._th is None else float(self._th(t))

    def angular_velocity(self, t: float) -> float:
        return 0.0 if self._w is None else float(self._w(t))

    def angular_acceleration(self, t: float) -> float:
        return 0.0 if self._al is None else float(self._al(t))


class Oscillation(Motion):
    r"""Harmonic translation along ``direction`` with peak-to-peak ``stroke`` ``S`` and ``period`` ``T``:

    .. math:: \mathbf d(t) = r(t)\,\tfrac{S}{2}\sin(\omega t)\,\hat{\mathbf e},\qquad \omega = 2\pi/T,

    optionally switched on smoothly over ``ramp`` seconds, ``r(t) = ½(1 − cos(π t / t_r))`` for
    ``t < t_r`` (1 after), so that the velocity and acceleration start from zero. A piston
    wave maker is an ``Oscillation`` of the paddle wall along ``x``.
    """

    def __init__(self, stroke: float, period: float, direction: ArrayLike = (1.0, 0.0), ramp: float = 0.0) -> None:
        e = np.asarray(direction, dtype=float)
        norm = float(np.linalg.norm(e)) if e.ndim == 1 else 0.0
        if not (math.isfinite(stroke) and stroke >= 0):
            raise ValueError(f"Oscillation: stroke must be >= 0 (m), got {stroke!r}")
        if not (math.isfinite(period) and period > 0):
            raise ValueError(f"Oscillation: period must be positive (s), got {period!r}")
        if not (math.isfinite(ramp) and ramp >= 0):
            raise ValueError(f"Oscillation: ramp must be >= 0 (s), got {ramp!r}")
        if not (norm > 0 and math.isfinite(norm)):
            raise ValueError(f"Oscillation: direction must be a non-zero vector, got {direction!r}")
        self.stroke, self.period, self.ramp = float(stroke), float(period), float(ramp)
        self.direction = e / norm
        self.omega = 2.0 * math.pi / self.period

    def __repr__(self) -> str:
        return (f"Oscillation(stroke={self.stroke:g}, period={self.period:g}, "
                f"direction={self.direction.tolist()}, ramp={self.ramp:g})")

    def _ramp(self, t: float) -> tuple[float, float, float]:
        """``r, ṙ, r̈`` of the switch-on."""
        if self.ramp <= 0 or t >= self.ramp:
            return 1.0, 0.0, 0.0
        if t <= 0:
            return 0.0, 0.0, 0.0
        k = math.pi / self.ramp
        return 0.5 * (1 - math.cos(k * t)), 0.5 * k * math.sin(k * t), 0.5 * k * k * math.cos(k * t)

    def displacement(self, t: float) -> FloatArray:
        r, _, _ = self._ramp(t)
        return (r * 0.5 * self.stroke * math.sin(self.omega * t)) * self.direction

    def velocity(self, t: float) -> FloatArray:
        r, dr, _ = self._ramp(t)
        A, w = 0.5 * self.stroke, self.omega
        return (dr * A * math.sin(w * t) + r * A * w * math.cos(w * t)) * self.direction

    def acceleration(self, t: float) -> FloatArray:
        r, dr, ddr = self._ramp(t)
        A, w = 0.5 * self.stroke, self.omega
        s, c = math.sin(w * t), math.cos(w * t)
        return (ddr * A * s + 2 * dr * A * w * c - r * A * w * w * s) * self.direction
