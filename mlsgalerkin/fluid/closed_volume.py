r"""The volume balance of a fluid that fills a closed tank: :class:`ClosedVolume`.

In a tank closed on every side by fixed walls (a lid on top) the fluid's volume cannot change:
:math:`\frac{d}{dt}\int_\Omega dV = \oint_{\partial\Omega} \mathbf v\cdot\mathbf n\, dA = 0`.
The collocated continuity equation :math:`\dot\rho_i = -\rho_i\,\mathrm{tr}\,L_i` with nodal
integration does not keep the discrete form of it: :math:`\sum_i V_i\,\mathrm{tr}\,L_i` is a
small, persistent, one-signed sum of large terms of both signs once the flow moves (about 1 %
of the volume per second along the lid and the floor of a lock exchange; the measurements are
in ``verification/results/quiet_state/lid_clumping.md``). The fluid's mean density then falls
while the particles stay where they are, the pressure level under the lid runs out, and the
top row goes into tension and clumps.

:class:`ClosedVolume` removes the volume-weighted mean of the divergence over the fluid
particles before the continuity rate is formed,

.. math:: \mathrm{tr}\,L_i \leftarrow \mathrm{tr}\,L_i - \frac{\sum_k V_k\,\mathrm{tr}\,L_k}{\sum_k V_k},
          \qquad V_k = M_k/\rho_k,

so :math:`\frac{d}{dt}\sum_i M_i/\rho_i = \sum_i V_i\,\mathrm{tr}\,L_i = 0` as the exact flow
has it. It changes only the mean density (the closed tank's free pressure level), nothing local:
no dissipation, no smoothing. It is a statement about the scene, not a stabilisation: list it
only for a fluid that fills a tank closed by fixed walls (no free surface, no moving wall), as
``gravity_current`` and ``stratified_rest`` do under their lid.

>>> import numpy as np
>>> from mlsgalerkin.fluid.closed_volume import remove_mean_divergence
>>> div = np.array([1.0, 2.0, 3.0]); volumes = np.array([1.0, 1.0, 2.0])
>>> float(remove_mean_divergence(div, volumes)), div.tolist()
(2.25, [-1.25, -0.25, 0.75])
"""

from __future__ import annotations

from typing import Any

import numpy as np

from mlsgalerkin.fluid.bodies import WallBody
from mlsgalerkin.fluid.effect import Effect, EffectContext
from mlsgalerkin.fluid.state import FluidState

__all__ = ["ClosedVolume", "remove_mean_divergence"]


def remove_mean_divergence(div: np.ndarray, volumes: np.ndarray) -> float:
    """Subtract the ``volumes``-weighted mean from ``div`` (both ``(n,)``, 1/s and m³) in place;
    returns the mean removed (1/s)."""
    mean = float(np.dot(volumes, div) / volumes.sum())
    div -= mean
    return mean


class ClosedVolume(Effect):
    """The fluid's volume held by the continuity equation in a tank closed by fixed walls
    (module docstring). Reports the largest and the RMS mean divergence it removed (1/s)."""

    name = "closed_volume"
    stages = ("divergence",)
    reads = ("velocity_gradient", "volume")

    def __init__(self) -> None:
        self.largest_removed = 0.0
        self.sum_squares = 0.0
        self.evaluations = 0

    def __repr__(self) -> str:
        return "ClosedVolume()"

    def check(self, ctx: EffectContext) -> list[str]:
        from_walls = [w.name for w in ctx.bodies_of(WallBody) if getattr(w, "motion", None) is not None
                      or getattr(w, "follows", None) is not None]
        if from_walls:
            return [f"ClosedVolume holds the volume of a fluid closed in by fixed walls, but the wall bodies "
                    f"{from_walls} move: the volume then changes with their flux; leave ClosedVolume out"]
        return []

    def divergence(self, s: FluidState, div: np.ndarray) -> None:
        f = s.fluid
        removed = remove_mean_divergence(div[f], s.M[f] / s.rho[f]) if s.n_fluid else 0.0
        self.largest_removed = max(self.largest_removed, abs(removed))
        self.sum_squares += removed * removed
        self.evaluations += 1

    def summary(self) -> dict[str, Any]:
        rms = (self.sum_squares / self.evaluations) ** 0.5 if self.evaluations else 0.0
        return {"largest_mean_divergence_removed_per_s": self.largest_removed,
                "rms_mean_divergence_removed_per_s": rms, "evaluations": self.evaluations}

    def state_dict(self) -> dict[str, Any]:
        return {"largest_removed": self.largest_removed, "sum_squares": self.sum_squares,
                "evaluations": self.evaluations}

    def load_state_dict(self, d: dict[str, Any]) -> None:
        self.largest_removed = float(d.get("largest_removed", 0.0))
        self.sum_squares = float(d.get("sum_squares", 0.0))
        self.evaluations = int(d.get("evaluations", 0))
