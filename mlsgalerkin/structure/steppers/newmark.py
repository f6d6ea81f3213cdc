r"""Implicit Newmark of a linear elastic body: one average-acceleration step per outer step.

With :math:`\beta = 1/4, \gamma = 1/2` (unconditionally stable, no numerical damping),

.. math:: (M + \gamma\Delta t\,C + \beta\Delta t^2K)\,\mathbf a^{n+1} = \mathbf f_g + \mathbf f^{n+1}
          - C(\mathbf v^n + (1-\gamma)\Delta t\,\mathbf a^n)
          - K(\mathbf u^n + \Delta t\,\mathbf v^n + (\tfrac12-\beta)\Delta t^2\mathbf a^n),

with :math:`\mathbf a^n` in equilibrium with the surface forces at :math:`t_n` and
:math:`\mathbf f^{n+1}` their value at the step's end (:mod:`~mlsgalerkin.structure.steppers.base`).
The factorisation (scipy ``splu`` over the free degrees of freedom) is kept while the step stays
within 1 % below the one it was made for (:data:`NEWMARK_REUSE`; ``β`` then lies in
``[1/4, 0.255]``).
"""

from __future__ import annotations

from typing import Any

import numpy as np
import scipy.sparse as sp
from numpy.typing import NDArray
from scipy.sparse.linalg import splu

from mlsgalerkin.structure.elastic import ElasticBody
from mlsgalerkin.structure.steppers.central_difference import SUBSTEP_SAFETY
from mlsgalerkin.structure.steppers.elastic_stepper import ElasticStepper, central_difference_limit

__all__ = ["NEWMARK_MARGIN", "NEWMARK_REUSE", "Newmark"]

FloatArray = NDArray[np.float64]

#: A Newmark factorisation made for ``Δt'`` is reused for steps in ``[Δt'/NEWMARK_REUSE, Δt']``,
#: and made for ``NEWMARK_MARGIN`` times the step that asks for a new one.
NEWMARK_REUSE = 1.01
NEWMARK_MARGIN = 1.005


class Newmark(ElasticStepper):
    """Average-acceleration Newmark of one linear :class:`ElasticBody` (module docstring)."""

    def __init__(self, body: ElasticBody) -> None:
        super().__init__(body)
        # reported beside the explicit method's: the sub-step central differences would need
        self.substep_limit = central_difference_limit(self.omega_max, self.a0, self.a1, SUBSTEP_SAFETY)
        self._lu: Any = None
        self._lu_dt = 0.0
        self.factorisations = 0

    def _integrate(self, dt: float, f0: FloatArray, f1: FloatArray) -> int:
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
        return 1

    def _method_counters(self) -> tuple[float, int]:
        return self._lu_dt, self.factorisations

    def _restore_method_counters(self, counters: tuple[float, float]) -> None:
        lu_dt, factorisations = counters
        self._lu_dt, self.factorisations = float(lu_dt), int(factorisations)
        self._lu = None

    def _method_summary(self) -> dict[str, Any]:
        return {"newmark_factorisations": self.factorisations}
