r"""The Tait equation of state of a weakly compressible liquid, and the :class:`TaitPressure` effect.

.. math:: p = B\left[r^{\gamma} - 1\right],\qquad r = \frac{\rho}{\rho_0},\qquad
          B = \frac{\rho_0 c_0^2}{\gamma},\qquad \gamma = 7,

so that ``p = 0`` at the reference density (no spurious free-surface pressure) and the sound
speed at ``ρ0`` is ``c0``; the local sound speed is ``c = c0 r^{(γ−1)/2}``, the inverse
``ρ(p) = ρ0 (1 + p/B)^{1/γ}`` and the energy stored per unit mass (the work of compression
from ``ρ0``) ``e(r) = (B/ρ0)[(r^{γ−1} − 1)/(γ−1) + 1/r − 1] ≥ 0`` (Monaghan 1994). ``c0`` is
chosen from the largest expected flow speed so that the Mach number ``U_max / c0`` stays at most
0.1 (density fluctuations about 1 %). Every Tait expression of the package is in this module.

>>> eos = TaitEOS.from_max_velocity(rho0=1000.0, u_max=2.0)
>>> eos.c0, round(eos.B)
(20.0, 57143)
>>> float(eos.pressure(1000.0)), round(float(eos.density(eos.pressure(1010.0))), 9)
(0.0, 1010.0)
"""

from __future__ import annotations

import math
import warnings
from dataclasses import dataclass
from typing import Any

import numba
import numpy as np
from numpy.typing import ArrayLike, NDArray

from mlsgalerkin.fluid.effect import Effect, EffectContext, check_positive
from mlsgalerkin.fluid.state import FluidState
from mlsgalerkin.fluid.time_step import acoustic_limit

__all__ = [
    "VOID_STRAIN",
    "MachNumberWarning",
    "TaitEOS",
    "TaitPressure",
    "hydrostatic_density",
    "hydrostatic_pressure",
    "remember_void",
    "remember_void_reference",
    "tait_density",
    "tait_energy",
    "tait_pressure",
    "tait_sound_speed",
    "tait_stored_energy",
]

FloatArray = NDArray[np.float64]


#: The state's ``extra`` array of the void strain a cavitated particle remembers (–,
#: ``TaitPressure(void_memory=...)``).
VOID_STRAIN = "void_strain"


@numba.njit(cache=True)
def remember_void(rho, rho0, eps, eps_max):
    """The cavitation floor with a void memory, in place over ``rho``, ``rho0``, ``eps`` ``(n,)``:
    ``ρ < ρ0`` adds ``min(ln(ρ0/ρ), ε_max − ε)`` to ``ε`` and sets ``ρ = ρ0``; ``ρ > ρ0`` with
    ``ε > 0`` closes ``c = min(ε, ln(ρ/ρ0))`` and sets ``ρ = ρ0 e^{ln(ρ/ρ0) − c}``; other rows
    are left bit for bit. Returns how many rows were floored."""
    floored = 0
    for i in range(rho.shape[0]):
        if rho[i] < rho0[i]:
            eps[i] = min(eps[i] + math.log(rho0[i] / rho[i]), eps_max)
            rho[i] = rho0[i]
            floored += 1
        elif eps[i] > 0.0 and rho[i] > rho0[i]:
            strain = math.log(rho[i] / rho0[i])
            close = min(eps[i], strain)
            eps[i] -= close
            rho[i] = rho0[i] * math.exp(strain - close)
    return floored


def remember_void_reference(rho, rho0, eps, eps_max):
    """numpy reference of :func:`remember_void`."""
    below = rho < rho0
    closing = (~below) & (eps > 0.0) & (rho > rho0)
    strain = np.log(rho / rho0)
    close = np.where(closing, np.minimum(eps, strain), 0.0)
    eps[:] = np.where(below, np.minimum(eps - strain, eps_max), eps - close)
    rho[:] = np.where(below, rho0, np.where(closing, rho0 * np.exp(strain - close), rho))
    return int(np.count_nonzero(below))


#: What :class:`TaitPressure` does with negative pressures (see its docstring).
NEGATIVE_PRESSURE_MODES = ("allow", "clamp", "cavitate", "free_surface")


class MachNumberWarning(UserWarning):
    """The sound speed is too low for the expected flow speed (Mach number above the limit)."""


# --------------------------------------------------------------------------------------
# the equation (functions of the density ratio r = rho/rho0; rho0 scalar or per particle)
# --------------------------------------------------------------------------------------


def tait_pressure(ratio: FloatArray, rho0: ArrayLike, c0: float, gamma: float = 7.0) -> FloatArray:
    """``p = B (r^γ − 1)`` (Pa) with ``B = (c0²/γ) ρ0`` per particle (``ρ0`` kg/m³, ``c0`` m/s)."""
    return (c0**2 / gamma * np.asarray(rho0)) * (ratio**gamma - 1.0)


def tait_energy(ratio: FloatArray, rho0: ArrayLike, c0: float, gamma: float = 7.0) -> FloatArray:
    """Specific compression energy ``e(ρ) = ∫_{ρ0}^{ρ} p/ρ'² dρ' = (B/ρ0)[(r^{γ−1} − 1)/(γ − 1) +
    1/r − 1]`` (J/kg), ``r = ρ/ρ0``, ``B = ρ0 c0²/γ``: the work stored by compressing a unit mass
    from ``ρ0`` (the tension's work below it), so that ``Σ M e`` closes the fluid's energy balance."""
    r = np.asarray(ratio, dtype=float)
    return (c0**2 / gamma) * ((r ** (gamma - 1.0) - 1.0) / (gamma - 1.0) + 1.0 / r - 1.0)


def tait_sound_speed(ratio: FloatArray, c0: float, gamma: float = 7.0) -> FloatArray:
    """Local sound speed ``c = sqrt(dp/dρ) = c0 r^{(γ−1)/2}`` (m/s)."""
    return c0 * ratio ** (0.5 * (gamma - 1.0))


def tait_density(p: ArrayLike, rho0: ArrayLike, c0: float, gamma: float = 7.0) -> FloatArray:
    """Inverse ``ρ(p) = ρ0 (1 + p/B)^{1/γ}`` (kg/m³), ``B = ρ0 c0²/γ``; raises below the
    cavitation limit ``p = −B``."""
    rho0 = np.asarray(rho0, dtype=float)
    B = rho0 * c0**2 / gamma
    if not np.all(B > 0):
        raise ValueError(f"the Tait stiffness B = rho0 c0²/gamma must be positive (rho0 and c0 positive), got "
                         f"c0 = {c0!r}, rho0 between {np.min(rho0)!r} and {np.max(rho0)!r}")
    x = 1.0 + np.asarray(p, dtype=float) / B
    if np.any(x <= 0):
        raise ValueError(f"pressure below the Tait cavitation limit -B = {-float(np.min(B)):.6g} Pa")
    return rho0 * x ** (1.0 / gamma)


def hydrostatic_pressure(rho0: ArrayLike, depth: ArrayLike, g: float, c0: float, overburden: ArrayLike = 0.0,
                         gamma: float = 7.0, compressible: bool = False) -> FloatArray:
    r"""Hydrostatic pressure (Pa) at ``depth`` (m) below a level at pressure ``overburden`` (Pa)
    in a Tait fluid of reference density ``rho0`` (kg/m³, per particle).

    ``compressible=False``: ``p = overburden + ρ0 g d`` (the weight of an incompressible
    fluid). ``compressible=True``: the exact equilibrium ``dp/dd = ρ(p) g`` of the Tait fluid,
    whose density grows with depth,

    .. math:: p = B\Big[\Big(u_s^{m} + m\,\frac{\rho_0 g d}{B}\Big)^{1/m} - 1\Big],\qquad
              m = \frac{\gamma - 1}{\gamma},\quad u_s = 1 + \frac{p_s}{B},\quad B = \frac{\rho_0 c_0^2}{\gamma}.

    The two differ by about ``(ρ0 g d)² / (2 γ B)``: at ``c0 = 10 sqrt(g D)`` the bottom
    pressure of the compressible column is 0.7 % higher, which matters where pressure
    differences of a per cent of ``ρ0 g D`` are the signal (stratified fluids).
    """
    rho0 = np.asarray(rho0, dtype=float)
    d = np.asarray(depth, dtype=float)
    if not compressible:
        return overburden + rho0 * g * d
    B = rho0 * c0**2 / gamma
    m = (gamma - 1.0) / gamma
    u_s = 1.0 + np.asarray(overburden, dtype=float) / B
    return B * ((u_s**m + m * rho0 * g * d / B) ** (1.0 / m) - 1.0)


def hydrostatic_density(rho0: ArrayLike, depth: ArrayLike, g: float, c0: float, overburden: ArrayLike = 0.0,
                        gamma: float = 7.0, compressible: bool = False) -> FloatArray:
    """Tait density at the hydrostatic pressure of :func:`hydrostatic_pressure` (per particle
    ``ρ0``, kg/m³; ``depth`` below the level at ``overburden`` Pa, m; ``g`` m/s²): the start of
    a fluid at rest. With ``compressible=True`` the particles' weight is exactly in balance
    with the pressure they start at."""
    p = hydrostatic_pressure(rho0, depth, g, c0, overburden, gamma, compressible)
    return tait_density(p, rho0, c0, gamma)


def tait_stored_energy(M: FloatArray, ratio: FloatArray, c0: float, gamma: float = 7.0) -> FloatArray:
    """Energy stored in each particle by compression, ``M (B/ρ0)[(r^{γ−1} − 1)/(γ−1) + 1/r − 1]``
    (J, per unit depth in 2D; ``M`` kg): zero at ``r = 1`` and positive otherwise."""
    return M * (c0**2 / gamma) * ((ratio ** (gamma - 1) - 1) / (gamma - 1) + 1 / ratio - 1)


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
    def from_max_velocity(cls, rho0: float, u_max: float, mach: float = 0.1, gamma: float = 7.0) -> "TaitEOS":
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

    def pressure(self, rho: ArrayLike) -> FloatArray:
        """``p(ρ)`` in Pa."""
        return tait_pressure(np.asarray(rho, dtype=float) / self.rho0, self.rho0, self.c0, self.gamma)

    def density(self, p: ArrayLike) -> FloatArray:
        """Inverse ``ρ(p) = rho0 (1 + p/B)^(1/gamma)`` (hydrostatic initialisation)."""
        return tait_density(p, self.rho0, self.c0, self.gamma)

    def sound_speed(self, rho: ArrayLike) -> FloatArray:
        """Local ``c = sqrt(dp/dρ) = c0 (ρ/rho0)^((gamma-1)/2)`` in m/s."""
        return tait_sound_speed(np.asarray(rho, dtype=float) / self.rho0, self.c0, self.gamma)

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


# --------------------------------------------------------------------------------------
# the effect
# --------------------------------------------------------------------------------------


class TaitPressure(Effect):
    r"""Tait equation of state per phase, ``p = B_φ[(ρ/ρ0_φ)^γ − 1]``, ``B_φ = ρ0_φ c0²/γ``.

    Give ``c0`` (m/s) or ``u_max`` (the expected largest speed; then ``c0 = u_max/mach``).
    A :class:`MachNumberWarning` is raised when ``u_max/c0 > 0.1``.
    ``negative_pressure``: ``"allow"`` (default; a tensile-instability diagnostic counts the
    fluid particles with ``p < 0``), ``"clamp"`` (``p = max(p, 0)``; the density may still
    drift below ``ρ0``) or ``"cavitate"`` (a liquid that cannot carry tension: the density is
    floored at ``ρ0``, so ``p ≥ 0`` and a splashing particle's volume never exceeds ``M/ρ0``;
    the floorings are counted) or ``"free_surface"`` (the same floor on the particles that
    :class:`~mlsgalerkin.fluid.free_surface.FreeSurfaceDetection` flags as free surface — a
    surface in contact with air carries no tension — while the bulk keeps negative pressures;
    needs ``FreeSurfaceDetection`` listed). With ``"cavitate"``, ``void_memory`` ``ε_max > 0`` keeps
    up to that much of the floored expansion as a void strain per particle, ``extra["void_strain"]``
    (``ε``, –): a density ``ρ < ρ0`` from the continuity equation adds ``ln(ρ0/ρ)`` to ``ε``
    (capped at ``ε_max``) and is floored at ``ρ0``; a later compression ``ln(ρ/ρ0) > 0`` first
    closes ``ε``, and only the rest raises ``ρ``. A splash that lands must close the space it
    opened before it carries pressure again, so the settled water does not keep a loose layer; the
    cap keeps particles from meeting without pressure (``void_memory = 0``, the default: the plain
    floor; ``docs/theory/stabilisation.md`` §3). Provides ``pressure`` and ``sound_speed``. Time-step limit: the
    acoustic CFL ``cfl · h/(c + |v|)`` (:func:`~mlsgalerkin.fluid.time_step.acoustic_limit`).
    """

    name = "tait_pressure"
    stages = ("pressure",)
    reads = ("density",)
    provides = ("pressure", "sound_speed")
    role = "pressure"

    def __init__(self, c0: float | None = None, *, u_max: float | None = None, mach: float = 0.1,
                 gamma: float = 7.0, cfl: float = 0.4, negative_pressure: str = "allow",
                 void_memory: float = 0.0) -> None:
        self.c0_arg, self.u_max, self.mach, self.gamma, self.cfl = c0, u_max, mach, gamma, cfl
        self.negative_pressure = negative_pressure
        self.void_memory = void_memory
        self.c0 = float(c0) if c0 is not None else (u_max / mach if u_max else float("nan"))
        self.min_pressure = math.inf
        self.max_negative_fraction = 0.0
        self.steps_with_negative = 0
        self.cavitated = 0

    def __repr__(self) -> str:
        memory = f", void_memory={self.void_memory:g}" if self.void_memory else ""
        return f"TaitPressure(c0={self.c0:g}, gamma={self.gamma:g}{memory})"

    def check(self, ctx: EffectContext) -> list[str]:
        problems: list[str] = []
        if self.c0_arg is None and self.u_max is None:
            problems.append("TaitPressure: give c0 (sound speed) or u_max (expected largest speed)")
        else:
            check_positive("TaitPressure", "c0", self.c0, problems)
        check_positive("TaitPressure", "cfl", self.cfl, problems)
        if not self.gamma >= 1:
            problems.append(f"TaitPressure: gamma must be >= 1, got {self.gamma}")
        if self.negative_pressure not in NEGATIVE_PRESSURE_MODES:
            problems.append(f"TaitPressure: negative_pressure must be one of {NEGATIVE_PRESSURE_MODES}, got "
                            f"{self.negative_pressure!r}")
        if not (isinstance(self.void_memory, (int, float)) and 0.0 <= self.void_memory < math.inf):
            problems.append(f"TaitPressure: void_memory must be a finite number >= 0, got {self.void_memory!r}")
        elif self.void_memory > 0 and self.negative_pressure != "cavitate":
            problems.append(f"TaitPressure: void_memory acts with negative_pressure='cavitate' only, got "
                            f"{self.negative_pressure!r}; set void_memory=0 or negative_pressure='cavitate'")
        if self.negative_pressure == "free_surface" and not ctx.provides("free_surface"):
            problems.append("TaitPressure(negative_pressure='free_surface') floors the density of the free-surface "
                            "particles: list FreeSurfaceDetection(), which flags them")
        if not problems and self.u_max is not None:
            TaitEOS(1.0, self.c0, self.gamma).check_mach(self.u_max)
        return problems

    def setup(self, state: FluidState, ctx: EffectContext) -> None:
        state.c0, state.gamma = float(self.c0), float(self.gamma)
        state.c = np.full(state.n, self.c0)
        if self._remembers_void() and VOID_STRAIN not in state.extra:
            state.extra[VOID_STRAIN] = np.zeros(state.n)

    def _remembers_void(self) -> bool:
        return self.negative_pressure == "cavitate" and self.void_memory > 0

    def pressure(self, s: FluidState) -> None:
        f = s.fluid
        if self._remembers_void():
            self.cavitated += remember_void(s.rho[: s.n_fluid], s.rho0[: s.n_fluid],
                                            s.extra[VOID_STRAIN][: s.n_fluid], float(self.void_memory))
        elif self.negative_pressure == "cavitate":
            below = s.rho[f] < s.rho0[f]
            self.cavitated += int(np.count_nonzero(below))
            np.maximum(s.rho[f], s.rho0[f], out=s.rho[f])
        elif self.negative_pressure == "free_surface":
            below = (s.rho[f] < s.rho0[f]) & s.extra["free_surface"][f]
            self.cavitated += int(np.count_nonzero(below))
            s.rho[f][below] = s.rho0[f][below]
        ratio = s.rho[f] / s.rho0[f]
        power = ratio**self.gamma          # shared by the pressure and the compression energy
        p = (self.c0**2 / self.gamma * s.rho0[f]) * (power - 1.0)   # tait_pressure, term for term
        negative = p < 0.0
        n_neg = int(np.count_nonzero(negative))
        if n_neg:
            self.min_pressure = min(self.min_pressure, float(p.min()))
            self.steps_with_negative += 1
            self.max_negative_fraction = max(self.max_negative_fraction, n_neg / max(p.size, 1))
            if self.negative_pressure == "clamp":
                np.maximum(p, 0.0, out=p)
        s.p[f] = p
        s.c[f] = tait_sound_speed(ratio, self.c0, self.gamma)
        # Σ M e(ρ) (tait_energy) with r^{γ−1} = r^γ / r: a diagnostic, so no second power
        g = self.gamma
        e = (self.c0**2 / g) * ((power / ratio - 1.0) / (g - 1.0) + 1.0 / ratio - 1.0)
        s.sensors["compression_energy"] = float(np.dot(s.M[f], e))

    def time_step_limit(self, s: FluidState) -> float:
        f = s.fluid
        return acoustic_limit(s.h[f], s.c[f], s.v[f], self.cfl)

    def summary(self) -> dict[str, Any]:
        return {
            "c0": self.c0, "gamma": self.gamma,
            "tensile_instability": {
                "min_pressure_Pa": None if math.isinf(self.min_pressure) else self.min_pressure,
                "max_fraction_negative": self.max_negative_fraction,
                "steps_with_negative_pressure": self.steps_with_negative,
                "mode": self.negative_pressure,
                "cavitation_floorings": self.cavitated,
            },
        }

    def state_dict(self) -> dict[str, Any]:
        return {"min_pressure": self.min_pressure, "max_negative_fraction": self.max_negative_fraction,
                "steps_with_negative": self.steps_with_negative, "cavitated": self.cavitated}

    def load_state_dict(self, d: dict[str, Any]) -> None:
        self.min_pressure = d["min_pressure"]
        self.max_negative_fraction = d["max_negative_fraction"]
        self.steps_with_negative = d["steps_with_negative"]
        self.cavitated = d.get("cavitated", 0)
