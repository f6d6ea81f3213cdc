"""How a particle solver approximates its fields: kernel, smoothing length, basis, method."""

from __future__ import annotations

from dataclasses import dataclass

__all__ = ["Approximation"]


@dataclass(frozen=True)
class Approximation:
    """Kernel, ``h = h_factor · Δx``, polynomial basis, method, neighbour skin, condition limit.

    Parameters
    ----------
    kernel : str
        A non-negative kernel of :data:`mlsgalerkin.kernels.KERNELS` (the MLS weight).
    h_factor : float
        Smoothing length over particle spacing, ``h/Δx`` (0.5–4).
    basis : str
        ``"constant"``, ``"linear"`` or ``"quadratic"``.
    method : str
        ``"mls"``, ``"rkpm"``, ``"shepard"`` or ``"orthogonal"``.
    skin : float
        Pads the neighbour search radius by ``skin · Δx`` so the list is rebuilt only when some
        particle has moved more than ``skin/2`` spacings.
    condition_limit : float
        A particle whose scaled moment matrix has a 1-norm condition number above this uses a
        lower order (down to Shepard). The particle solvers' default, 100, is far stricter than
        the library's 1e8: a splashing particle's large linear-MLS gradients make a stiff mode
        that the ``h/c`` time step does not resolve (measurements in
        ``docs/theory/galerkin_fluid.md``, "Hard cases").
    """

    kernel: str = "cubic_spline"
    h_factor: float = 1.3
    basis: str = "linear"
    method: str = "mls"
    skin: float = 0.15
    condition_limit: float = 100.0

    @property
    def order(self) -> int:
        """Polynomial order the approximation aims for (0 for Shepard)."""
        if self.method == "shepard":
            return 0
        return {"constant": 0, "linear": 1, "quadratic": 2}.get(self.basis, 1)

    def problems(self) -> list[str]:
        """Every problem with these settings (empty if none)."""
        from mlsgalerkin.kernels import KERNELS

        out: list[str] = []
        if self.kernel not in KERNELS:
            out.append(f"unknown kernel {self.kernel!r}; choose from {sorted(KERNELS)}")
        elif not KERNELS[self.kernel].nonnegative:
            out.append(f"kernel {self.kernel!r} changes sign and cannot be an MLS weight")
        if self.method not in ("mls", "rkpm", "shepard", "orthogonal"):
            out.append(f"approximation method must be mls, rkpm, shepard or orthogonal, got {self.method!r}")
        if self.basis not in ("constant", "linear", "quadratic"):
            out.append(f"approximation basis must be constant, linear or quadratic, got {self.basis!r}")
        if not (0.5 <= self.h_factor <= 4):
            out.append(f"h_factor = h/Δx must be in [0.5, 4], got {self.h_factor!r}")
        if not (0 <= self.skin <= 1):
            out.append(f"skin must be in [0, 1] (units of Δx), got {self.skin!r}")
        if not self.condition_limit > 1:
            out.append(f"condition_limit must be > 1, got {self.condition_limit!r}")
        return out
