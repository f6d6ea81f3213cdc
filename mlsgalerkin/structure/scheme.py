"""The structure solver's numerical settings: :class:`StructureScheme`.

Each body carries its own integrator choice (``ElasticBody(integrator=...)``); what the solver
as a whole needs is the outer step of a scene of structures alone (with a fluid, the fluid and
the interactions set it, and an explicit body sub-cycles inside it).

>>> StructureScheme(dt_max=1e-4).problems()
[]
>>> StructureScheme(dt_max=-1.0).problems()
['StructureScheme: dt_max must be positive (s), got -1.0']
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, ClassVar

from mlsgalerkin.dynamics import Scheme

__all__ = ["StructureScheme"]


@dataclass
class StructureScheme(Scheme):
    """Settings of the structure solver.

    Parameters
    ----------
    dt_max : float, optional
        Largest outer time step (s); required for a scene of structures alone.
    """

    solver: ClassVar[str] = "mlsgalerkin.structure.solver:StructureSolver"

    dt_max: float | None = None

    def problems(self) -> list[str]:
        if self.dt_max is not None and not (isinstance(self.dt_max, (int, float)) and math.isfinite(self.dt_max)
                                            and self.dt_max > 0):
            return [f"StructureScheme: dt_max must be positive (s), got {self.dt_max!r}"]
        return []

    def identity(self) -> dict[str, Any]:
        return {} if self.dt_max is None else {"structure_dt_max": self.dt_max}
