r""":class:`PenaltyLaw`: the one place where penalty contact meets its kernel.

Both users of node-to-surface penalty contact — the interaction between two bodies
(:class:`~mlsgalerkin.interactions.PenaltyContact`, and through it the fluid–structure
coupling) and the fluid's rigid walls (:class:`~mlsgalerkin.fluid.penalty_walls.PenaltyWalls`)
— hold one :class:`PenaltyLaw`. It keeps the contact's parameters (thickness ``g0`` and reach
``r`` in m, stiffness factor ``α``, damping ratio ``ζ``, feature angle in degrees), fixes the
reference time step ``Δt_ref`` of the stiffness ``k = α m*/Δt_ref²`` once (given, or the
owner's rule at its first use; kept for the rest of the run and in its checkpoints), calls
:func:`~mlsgalerkin.contact.penalty.penalty_forces` with them, and sums the elastic energy
stored in the active springs, ``½ Σ k g²`` (J, per unit depth in 2D), over the surfaces of one
evaluation. The formulas are :mod:`mlsgalerkin.contact.penalty`'s.

>>> import numpy as np
>>> from mlsgalerkin.contact import ContactSurface
>>> law = PenaltyLaw(thickness=0.005, reach=0.01)
>>> floor = ContactSurface.polyline([(1.0, 0.0), (-1.0, 0.0)])
>>> law.fix_reference_step(lambda: 1e-4, lambda dt: f"no step ({dt})")
0.0001
>>> law.begin()
>>> res = law.forces(np.array([[0.0, 0.004]]), np.zeros((1, 2)), 0.1, floor.nodes, None, None, floor.facets)
>>> res.slave_forces.round(6).tolist(), round(law.energy, 9)    # k = 1e6 N/m, g = -1 mm
([[0.0, 1000.0]], 0.5)
"""

from __future__ import annotations

import math
from typing import Callable

import numpy as np
from numpy.typing import ArrayLike, NDArray

from mlsgalerkin.contact.penalty import (
    DEFAULT_ALPHA,
    DEFAULT_DAMPING,
    DEFAULT_FEATURE_ANGLE,
    PenaltyResult,
    penalty_forces,
    rigid_time_step,
)

__all__ = ["PenaltyLaw"]


class PenaltyLaw:
    """Parameters, the fixed reference step and the kernel calls of one penalty contact
    (module docstring).

    Parameters
    ----------
    thickness, reach : float
        Contact thickness ``g0`` and reach ``r`` (m), resolved (no defaults left open).
    alpha, damping, feature_angle : float
        Stiffness factor (–), damping ratio (–), feature angle (degrees).
    dt_ref : float, optional
        Reference time step of the stiffness (s); ``None``: fixed by :meth:`fix_reference_step`.
    """

    def __init__(self, *, thickness: float, reach: float, alpha: float = DEFAULT_ALPHA,
                 damping: float = DEFAULT_DAMPING, feature_angle: float = DEFAULT_FEATURE_ANGLE,
                 dt_ref: float | None = None) -> None:
        self.thickness, self.reach = thickness, reach
        self.alpha, self.damping, self.feature_angle = alpha, damping, feature_angle
        #: The reference time step (s) once fixed; part of the owner's checkpointed state.
        self.dt_ref: float | None = dt_ref
        #: Elastic energy of the active springs summed since :meth:`begin` (J, per m in 2D).
        self.energy = 0.0

    def fix_reference_step(self, candidate: Callable[[], float], refusal: Callable[[float], str]) -> float:
        """The reference step: fixed now as ``candidate()`` (s) if not yet fixed, then kept.
        ``refusal(dt)`` is the error message when the candidate is not a positive finite step."""
        if self.dt_ref is None:
            dt = candidate()
            if not (math.isfinite(dt) and dt > 0):
                raise ValueError(refusal(dt))
            self.dt_ref = float(dt)
        return self.dt_ref

    def begin(self) -> None:
        """Start an evaluation: the stored energy is summed afresh over its :meth:`forces` calls."""
        self.energy = 0.0

    def forces(self, slave_x: NDArray[np.float64], slave_v: NDArray[np.float64], slave_m: ArrayLike,
               master_x: NDArray[np.float64], master_v: NDArray[np.float64] | None, master_m: ArrayLike | None,
               facets: NDArray[np.int64], centre: ArrayLike | None = None) -> PenaltyResult:
        """The penalty forces of slave nodes ``(n, d)`` against one master surface with this law
        (:func:`~mlsgalerkin.contact.penalty.penalty_forces`: positions m, velocities m/s, masses
        kg; a ``None`` master mass is a rigid master); adds the stored energy to :attr:`energy`."""
        if self.dt_ref is None:
            raise RuntimeError("PenaltyLaw.forces before the reference step is fixed (fix_reference_step)")
        res = penalty_forces(slave_x, slave_v, slave_m, master_x, master_v, master_m, facets, dt_ref=self.dt_ref,
                             thickness=self.thickness, reach=self.reach, alpha=self.alpha, damping=self.damping,
                             feature_angle=self.feature_angle, centre=centre)
        self.energy += res.stored_energy
        return res

    def time_step_limit(self, contacts: int) -> float:
        """The constant stable step (s) for a slave with up to ``contacts`` springs
        (:func:`~mlsgalerkin.contact.penalty.rigid_time_step`); ``inf`` before the reference
        step is fixed."""
        if self.dt_ref is None:
            return math.inf
        return rigid_time_step(self.alpha, self.damping, self.dt_ref, contacts)

    def __repr__(self) -> str:
        return (f"PenaltyLaw(thickness={self.thickness!r}, reach={self.reach!r}, alpha={self.alpha!r}, "
                f"damping={self.damping!r}, feature_angle={self.feature_angle!r}, dt_ref={self.dt_ref!r})")
