"""The material of an elastic body: :class:`ElasticMaterial`, and the one conversion of Young's
modulus and Poisson's ratio to the Lamé parameters.

A leaf module: the body (:mod:`mlsgalerkin.structure.elastic`) and the hyperelastic forces
(:mod:`mlsgalerkin.structure.hyperelastic`) both import it, neither imports the other for it.

>>> [round(v / 1e9, 3) for v in ElasticMaterial(70e9, 0.3, 2700.0).lame(3)]     # GPa
[40.385, 26.923]
"""

from __future__ import annotations

import math
import warnings
from dataclasses import dataclass

from skfem.models.elasticity import lame_parameters

from mlsgalerkin.structure.checks import material_problems

__all__ = ["ElasticMaterial"]


@dataclass(frozen=True)
class ElasticMaterial:
    """Young's modulus ``young`` (Pa), Poisson's ratio ``poisson`` (–), density ``density``
    (kg/m³) and the 2D assumption ``plane`` (``"strain"`` or ``"stress"``)."""

    young: float
    poisson: float
    density: float
    plane: str = "strain"

    def __post_init__(self) -> None:
        problems = material_problems(self.young, self.poisson, self.density)
        if problems:
            raise ValueError("; ".join(problems))
        if self.plane not in ("strain", "stress"):
            raise ValueError(f"ElasticMaterial: plane must be 'strain' or 'stress', got {self.plane!r}")

    def lame(self, dim: int = 2) -> tuple[float, float]:
        r"""``(λ, μ)`` in Pa of the material in a ``dim``-dimensional body: the one conversion from
        Young's modulus and Poisson's ratio,

        .. math:: \lambda = \frac{E\nu}{(1 + \nu)(1 - 2\nu)},\qquad \mu = \frac{E}{2(1 + \nu)}

        (``skfem.models.elasticity.lame_parameters``), in 3D and in 2D plane strain; in 2D plane
        stress ``λ`` becomes :math:`2\lambda\mu/(\lambda + 2\mu)` (``plane`` applies in 2D only)."""
        if dim not in (2, 3):
            raise ValueError(f"ElasticMaterial.lame: a body is 2D or 3D, got dim={dim!r}")
        lam, mu = lame_parameters(self.young, self.poisson)
        if dim == 2 and self.plane == "stress":
            lam = 2.0 * lam * mu / (lam + 2.0 * mu)
        return lam, mu

    def lame3d(self) -> tuple[float, float]:
        """Deprecated: ``lame(3)``."""
        warnings.warn("ElasticMaterial.lame3d() is deprecated; use ElasticMaterial.lame(3)", DeprecationWarning,
                      stacklevel=2)
        return self.lame(3)

    def wave_speed(self) -> float:
        """Dilatational wave speed ``sqrt((λ + 2μ)/ρ)`` (m/s) of the 2D model."""
        lam, mu = self.lame()
        return math.sqrt((lam + 2.0 * mu) / self.density)
