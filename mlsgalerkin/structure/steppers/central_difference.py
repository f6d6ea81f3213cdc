r"""Explicit central differences (velocity Verlet), sub-cycled inside the outer step, for a linear
or a total-Lagrangian elastic body.

The outer step :math:`\Delta t` is cut into :math:`n = \lceil\Delta t/\delta t_{max}\rceil`
sub-steps, with :math:`\delta t_{max}` = :data:`SUBSTEP_SAFETY` (0.8 for the nonlinear models,
whose tangent stiffens under stretch) times the central-difference limit with damping,

.. math:: \delta t_{max} = C\,\frac{2}{\omega_{max}}\bigl(\sqrt{1 + \xi^2} - \xi\bigr),\qquad
          \xi = \tfrac12 a_1\omega_{max} + \frac{a_0}{2\omega_{max}}

(:func:`~mlsgalerkin.structure.steppers.elastic_stepper.central_difference_limit`). The
stiffness-proportional damping :math:`a_1` includes the body's ``high_mode_damping`` ξ_h (a
damping ratio at :math:`\omega_{max}`, :math:`a_1 \mathrel{+}= 2\xi_h/\omega_{max}`), which keeps
the resolved but irrelevant stiff modes from ringing at the surface the fluid sees; the damping
ratio it implies at the first mode is reported. A linear body runs all sub-steps in one numba
call (:func:`~mlsgalerkin.structure.explicit.subcycle_linear`); a nonlinear one evaluates the
total-Lagrangian internal force of :mod:`mlsgalerkin.structure.hyperelastic`
(:class:`TotalLagrangianForce`) at each sub-step.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import NDArray
from skfem import Basis

from mlsgalerkin.structure import hyperelastic
from mlsgalerkin.structure.elastic import ElasticBody
from mlsgalerkin.structure.explicit import subcycle_linear
from mlsgalerkin.structure.steppers.elastic_stepper import ElasticStepper, central_difference_limit

__all__ = ["NONLINEAR_ORDER", "NONLINEAR_SUBSTEP_SAFETY", "SUBSTEP_SAFETY", "CentralDifference",
           "TotalLagrangianForce"]

FloatArray = NDArray[np.float64]

#: Fraction of the central-difference limit ``2/ω_max`` a sub-step takes (linear model).
SUBSTEP_SAFETY = 0.9
#: The same for the nonlinear models (their tangent stiffens under stretch).
NONLINEAR_SUBSTEP_SAFETY = 0.8
#: Quadrature order of the total-Lagrangian internal force (4: 3 × 3 Gauss points on a
#: quadrilateral, 6 on a triangle; 3 × 3 × 3 on a hexahedron, 11 on a tetrahedron).
NONLINEAR_ORDER = 4


class TotalLagrangianForce:
    """The total-Lagrangian internal force ``∫ P : ∇δu`` (N) of a nonlinear elastic body and its
    strain energy ``∫ W`` (J per unit depth), on :data:`NONLINEAR_ORDER` quadrature
    (:mod:`mlsgalerkin.structure.hyperelastic`)."""

    def __init__(self, body: ElasticBody) -> None:
        # 3 × 3 Gauss points per quadrilateral (scikit-fem's default for Q2 is 5 × 5, exact for the
        # mass): the usual full integration of the internal force, 2.8 times fewer points (3 × 3 × 3
        # per hexahedron against 7 × 7 × 7 for Hex2: 12.7 times fewer)
        self.quadrature = hyperelastic.QuadratureData.from_basis(Basis(body.mesh, body.basis.elem,
                                                                       intorder=NONLINEAR_ORDER))
        # plane strain in 2D (ElasticBody refuses plane stress for these models), 3D in 3D
        self.lame = body.material.lame(body.dim)
        self.model = body.model

    def __call__(self, u: FloatArray) -> FloatArray:
        return hyperelastic.internal_force(self.quadrature, u, *self.lame, self.model)

    def strain_energy(self, u: FloatArray) -> float:
        return float(hyperelastic.strain_energy(self.quadrature, u, *self.lame, self.model))


class CentralDifference(ElasticStepper):
    """Sub-cycled central differences of one :class:`ElasticBody` (module docstring)."""

    def __init__(self, body: ElasticBody) -> None:
        super().__init__(body)
        if body.high_mode_damping > 0:
            self.a1_high = 2.0 * body.high_mode_damping / self.omega_max
            self.a1 += self.a1_high
        if body.model != "linear":
            self.nonlinear = TotalLagrangianForce(body)
        safety = SUBSTEP_SAFETY if body.model == "linear" else NONLINEAR_SUBSTEP_SAFETY
        self.substep_limit = central_difference_limit(self.omega_max, self.a0, self.a1, safety)

    def _integrate(self, dt: float, f0: FloatArray, f1: FloatArray) -> int:
        n = max(1, math.ceil(dt / self.substep_limit * (1.0 - 1e-12)))
        h = dt / n
        if self.nonlinear is None:
            subcycle_linear(self.K, self.inv_m, self.fixed, self.body.weight + f0, f1 - f0, self.u, self.v, self.a,
                            h, n, self.a0, self.a1)
            return n
        for k in range(n):
            self.v += 0.5 * h * self.a
            self.u += h * self.v
            self.a = self.acceleration() + (f0 + (k + 1.0) / n * (f1 - f0)) * self.inv_m
            self.v += 0.5 * h * self.a
        return n
