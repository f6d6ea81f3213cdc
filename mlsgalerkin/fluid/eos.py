r"""Tait equation of state for a weakly compressible liquid (seed digest §7.9).

.. math:: p = B\left[\left(\frac{\rho}{\rho_0}\right)^{\gamma} - 1\right],
          \qquad B = \frac{\rho_0 c_0^2}{\gamma},\qquad \gamma = 7,

so that ``p = 0`` at the reference density (no spurious free-surface pressure) and the sound
speed at ``ρ0`` is ``c0``. ``c0`` is chosen from the largest expected flow speed so that the
Mach number ``U_max / c0`` stays at most 0.1 (density fluctuations about 1 %).

>>> eos = TaitEOS.from_max_velocity(rho0=1000.0, u_max=2.0)
>>> eos.c0, round(eos.B)
(20.0, 57143)
>>> float(eos.pressure(1000.0)), round(float(eos.density(eos.pressure(1010.0))), 9)
(0.0, 1010.0)
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

__all__ = ["MachNumberWarning", "TaitEOS"]


class MachNumberWarning(UserWarning):
    """The sound speed is too low for the expected flow speed (Mach number above the limit)."""


@dataclass(frozen=True)
class TaitEOS:
    """Tait EOS with reference density ``rho0`` (kg/m^d), sound speed ``c0`` (m/s), ``gamma``."""

    rho0: float
    c0: float
    gamma: float = 7.0

    def __post_init__(self) -> None:
        for name in ("rho0", "c0"):
            v = getattr(self, name)
            if not (np.isfinite(v) and v > 0):
                raise ValueError(f"TaitEOS: {name} must be positive and finite, got {v!r}")
        if not (np.isfinite(self.gamma) and self.gamma >= 1.0):
            raise ValueError(f"TaitEOS: gamma must be >= 1, got {self.gamma!r}")

    @classmethod
    def from_max_velocity(
        cls, rho0: float, u_max: float, mach: float = 0.1, gamma: float = 7.0
    ) -> "TaitEOS":
        """``c0 = u_max / mach``: the sound speed that keeps the Mach number at ``mach``.

        For a dam break of height ``H`` use ``u_max = sqrt(2 g H)``.
        """
        if not (u_max > 0 and 0 < mach <= 1):
            raise ValueError(f"need u_max > 0 and 0 < mach <= 1, got u_max={u_max}, mach={mach}")
        return cls(rho0=rho0, c0=u_max / mach, gamma=gamma)

    @property
    def B(self) -> float:
        """Stiffness ``B = rho0 c0^2 / gamma`` in Pa."""
        return self.rho0 * self.c0**2 / self.gamma

    def pressure(self, rho: ArrayLike) -> NDArray[np.float64]:
        """``p(ρ)`` in Pa."""
        return self.B * ((np.asarray(rho, dtype=float) / self.rho0) ** self.gamma - 1.0)

    def density(self, p: ArrayLike) -> NDArray[np.float64]:
        """Inverse ``ρ(p) = rho0 (1 + p/B)^(1/gamma)`` (hydrostatic initialisation)."""
        x = 1.0 + np.asarray(p, dtype=float) / self.B
        if np.any(x <= 0):
            raise ValueError(f"pressure below the Tait cavitation limit -B = {-self.B:.6g} Pa")
        return self.rho0 * x ** (1.0 / self.gamma)

    def sound_speed(self, rho: ArrayLike) -> NDArray[np.float64]:
        """Local ``c = sqrt(dp/dρ) = c0 (ρ/rho0)^((gamma-1)/2)`` in m/s."""
        return self.c0 * (np.asarray(rho, dtype=float) / self.rho0) ** (0.5 * (self.gamma - 1.0))

    def check_mach(self, u_max: float, limit: float = 0.1) -> float:
        """Mach number ``u_max / c0``; warns with :class:`MachNumberWarning` above ``limit``."""
        mach = float(u_max) / self.c0
        if mach > limit:
            warnings.warn(
                f"Mach number {mach:.3g} exceeds {limit:g} (u_max = {u_max:g} m/s, c0 = "
                f"{self.c0:g} m/s): density errors grow like Ma^2; raise c0 to at least "
                f"{u_max / limit:g} m/s",
                MachNumberWarning,
                stacklevel=2,
            )
        return mach
