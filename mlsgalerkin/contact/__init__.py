"""Node-to-surface penalty contact: slave nodes (particles) against master surfaces.

=========================================  ====================================================
module                                     contents
=========================================  ====================================================
:mod:`~mlsgalerkin.contact.surface`        :class:`ContactSurface`: nodes and oriented facets
                                           (2D segments, 3D triangles), ``polyline``, ``tank``
:mod:`~mlsgalerkin.contact.geometry`       closest points on segments and triangles, facet
                                           normals, signed distances (numba + numpy reference)
:mod:`~mlsgalerkin.contact.search`         cell-grid broad phase: candidate slave–facet pairs
:mod:`~mlsgalerkin.contact.penalty`        the penalty kernel: forces, reactions, gaps, totals,
                                           moment, stable time step
:mod:`~mlsgalerkin.contact.law`            :class:`PenaltyLaw`: the one wrapper of the kernel
                                           (parameters, the fixed reference step, stored energy)
=========================================  ====================================================

The interaction between two bodies of a scene, :class:`~mlsgalerkin.interactions.PenaltyContact`,
is in :mod:`mlsgalerkin.interactions` (``mlsgalerkin.contact.PenaltyContact`` works for one more
release, with a ``DeprecationWarning``). The fluid uses the same law against rigid walls through
the ``PenaltyWalls`` effect (:mod:`mlsgalerkin.fluid.penalty_walls`). The formulas, parameters and measured defaults are
in ``docs/theory/contact.md``.

>>> import numpy as np
>>> floor = ContactSurface.polyline([(1.0, 0.0), (-1.0, 0.0)])
>>> res = penalty_forces(np.array([[0.0, 0.004]]), np.zeros((1, 2)), 0.1, floor.nodes, None, None,
...                      floor.facets, dt_ref=1e-4, thickness=0.005, reach=0.01)
>>> res.contacts, res.gaps.round(9).tolist()     # 4 mm above the floor, thickness 5 mm
(1, [-0.001])
>>> res.slave_forces.round(6).tolist()       # k = 0.1 · 0.1 kg / (1e-4 s)² = 1e6 N/m, times 1 mm
[[0.0, 1000.0]]
"""

from mlsgalerkin.contact.geometry import (
    ClosestPoints,
    closest_points,
    closest_points_reference,
    facet_normals,
    facet_normals_reference,
)
from mlsgalerkin.contact.law import PenaltyLaw
from mlsgalerkin.contact.penalty import (
    DEFAULT_ALPHA,
    DEFAULT_DAMPING,
    DEFAULT_FEATURE_ANGLE,
    STABILITY_FACTOR,
    PenaltyResult,
    penalty_forces,
    penalty_forces_reference,
    penalty_stiffness,
    rigid_time_step,
    search_margin,
)
from mlsgalerkin.contact.search import candidate_pairs, candidate_pairs_reference
from mlsgalerkin.contact.surface import ContactSurface
from mlsgalerkin.deprecation import moved_names

__all__ = [
    "DEFAULT_ALPHA",
    "DEFAULT_DAMPING",
    "DEFAULT_FEATURE_ANGLE",
    "STABILITY_FACTOR",
    "ClosestPoints",
    "ContactSurface",
    "PenaltyLaw",
    "PenaltyResult",
    "candidate_pairs",
    "candidate_pairs_reference",
    "closest_points",
    "closest_points_reference",
    "facet_normals",
    "facet_normals_reference",
    "penalty_forces",
    "penalty_forces_reference",
    "penalty_stiffness",
    "rigid_time_step",
    "search_margin",
]


#: ``PenaltyContact`` moved to :mod:`mlsgalerkin.interactions`: read here for one more release, with a
#: ``DeprecationWarning``.
__getattr__ = moved_names(__name__, {"PenaltyContact": "mlsgalerkin.interactions"})
