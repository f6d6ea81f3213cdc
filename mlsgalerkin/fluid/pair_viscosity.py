r"""Monaghan's pair artificial viscosity (Monaghan 1992) and the :class:`MonaghanViscosity` effect.

For particles ``i``, ``j`` with :math:`\mathbf x_{ij} = \mathbf x_i - \mathbf x_j`,
:math:`\mathbf v_{ij} = \mathbf v_i - \mathbf v_j` and arithmetic means
:math:`\bar c_{ij}, \bar\rho_{ij}, h_{ij}`:

.. math::
    \phi_{ij} = \frac{h_{ij}\,\mathbf v_{ij}\cdot\mathbf x_{ij}}
                     {|\mathbf x_{ij}|^2 + 0.01 h_{ij}^2},
    \qquad
    \Pi_{ij} = \begin{cases}
        (-\alpha\,\bar c_{ij}\,\phi_{ij} + \beta\,\phi_{ij}^2) / \bar\rho_{ij},
            & \mathbf v_{ij}\cdot\mathbf x_{ij} < 0 \\
        0, & \text{otherwise,}
    \end{cases}

.. math::
    \mathbf f_i = -\sum_{j \ne i} M_i M_j\, \Pi_{ij}\, \nabla_i W(r_{ij}, h_{ij}),
    \qquad \nabla_i W = \frac{\partial W}{\partial r}\,\frac{\mathbf x_{ij}}{r_{ij}},

with the normalised kernel :math:`W(r, h) = \alpha_d h^{-d} f(r/h)`
(:mod:`mlsgalerkin.kernels`). Units (SI, 3D): ``φ`` m/s, ``Π`` m⁵ kg⁻¹ s⁻² (like
:math:`p/\rho^2`), ``f`` N. In 2D the masses are per unit depth and ``f`` is N/m.

Properties (tested): the pair term is antisymmetric, :math:`\mathbf f_{ij} = -\mathbf f_{ji}`
(bit for bit: every mean is a commutative sum), and central (parallel to
:math:`\mathbf x_{ij}`), so linear and angular momentum are conserved to round-off; it vanishes
for rigid translation and for separating pairs (expansion); and for a kernel with
``dW/dr <= 0`` it dissipates, :math:`\sum_i \mathbf f_i\cdot\mathbf v_i \le 0`.

The compiled loop is the *gather* form: with a symmetric table (``find_neighbors(x, x, R)``
with one scalar radius ``R >= support * max h``) particle ``i`` sums over its own row, so the
parallel loop writes only row ``i`` — no scatter, no race. With an unsymmetric table (per-point
radii) a pair present in only one row acts on one particle only and momentum is not conserved.

Example
-------
>>> import numpy as np
>>> from mlsgalerkin.neighbors import find_neighbors
>>> x = np.array([[0.0, 0.0], [0.01, 0.0]])
>>> v = np.array([[1.0, 0.0], [-1.0, 0.0]])       # approaching head-on
>>> table = find_neighbors(x, x, radius=0.03)
>>> f, max_phi = monaghan_viscosity_force(x, v, np.full(2, 1000.0), np.full(2, 20.0),
...                                       np.full(2, 0.1), np.full(2, 0.012), table, alpha=0.1)
>>> bool(f[0, 0] < 0 < f[1, 0]), float(abs(f.sum()))  # decelerates both, conserves momentum
(True, 0.0)
"""

from __future__ import annotations

import math
import warnings
from typing import Any

import numba
import numpy as np
from numba import prange
from numpy.typing import ArrayLike, NDArray

from mlsgalerkin.fluid.effect import Effect, EffectContext, check_nonnegative
from mlsgalerkin.fluid.state import FluidState
from mlsgalerkin.fluid.time_step import pair_viscosity_limit
from mlsgalerkin.kernels import Kernel, get_kernel, kernel_f_df
from mlsgalerkin.neighbors import NeighborTable, as_coordinates
from mlsgalerkin.pairs import pair_offset
from mlsgalerkin.periodic import as_period, minimum_image

__all__ = [
    "MonaghanViscosity",
    "monaghan_viscosity_force",
    "monaghan_viscosity_force_reference",
]

FloatArray = NDArray[np.float64]

#: ``φ² = 0.01 h²`` regulariser of the denominator (Monaghan 1992: ``η = 0.1 h``).
ETA_SQUARED = 0.01


# --------------------------------------------------------------------------------------
# validation
# --------------------------------------------------------------------------------------


def _per_particle(name: str, a: ArrayLike, n: int, positive: bool = True) -> FloatArray:
    a = np.asarray(a, dtype=np.float64)
    if a.ndim == 0:
        a = np.full(n, float(a))
    if a.shape != (n,):
        raise ValueError(
            f"{name} must be a scalar or have shape ({n},) (one per particle), got {a.shape}"
        )
    bad = ~np.isfinite(a) | ((a <= 0) if positive else False)
    if np.any(bad):
        k = int(np.flatnonzero(bad)[0])
        need = "positive and finite" if positive else "finite"
        raise ValueError(f"{name} must be {need}; particle {k} has {float(a[k])}")
    return np.ascontiguousarray(a)


def _prepare(
    positions, velocity, density, sound_speed, masses, h, neighbors, kernel, alpha, beta, active
):
    x = as_coordinates("positions", positions)
    n, dim = x.shape
    v = np.asarray(velocity, dtype=np.float64)
    if v.shape != (n, dim):
        raise ValueError(f"velocity must have shape ({n}, {dim}) like positions, got {v.shape}")
    if not np.isfinite(v).all():
        k = int(np.flatnonzero(~np.isfinite(v).all(axis=1))[0])
        raise ValueError(f"velocity is not finite at particle {k}")
    rho = _per_particle("density", density, n)
    c = _per_particle("sound_speed", sound_speed, n)
    m = _per_particle("masses", masses, n)
    hh = _per_particle("h", h, n)
    if not isinstance(neighbors, NeighborTable):
        raise ValueError(f"neighbors must be a NeighborTable, got {type(neighbors).__name__}")
    if neighbors.n_points != n or neighbors.n_nodes != n:
        raise ValueError(
            f"neighbors must be the table of the particles against themselves: expected {n} "
            f"points and {n} nodes, got {neighbors.n_points} and {neighbors.n_nodes}"
        )
    k = get_kernel(kernel)
    alpha, beta = float(alpha), float(beta)
    if not (math.isfinite(alpha) and alpha >= 0 and math.isfinite(beta) and beta >= 0):
        raise ValueError(f"alpha and beta must be non-negative and finite, got {alpha}, {beta}")
    if active is None:
        act = np.ones(n, dtype=np.bool_)
    else:
        act = np.asarray(active)
        if act.shape != (n,) or act.dtype != np.bool_:
            raise ValueError(
                f"active must be a boolean mask of shape ({n},), got {act.dtype} {act.shape}"
            )
        act = np.ascontiguousarray(act)
    return (
        x, np.ascontiguousarray(v), rho, c, m, hh,
        np.ascontiguousarray(neighbors.indptr, dtype=np.int64),
        np.ascontiguousarray(neighbors.indices, dtype=np.int32),
        k, alpha, beta, act,
    )


# --------------------------------------------------------------------------------------
# compiled gather loop
# --------------------------------------------------------------------------------------


@numba.njit(parallel=True, cache=True)
def _monaghan_kernel(
    x, v, rho, c, m, h, indptr, indices, kid, support, norm_d, alpha, beta, active, L, use_l, period
):
    n, dim = x.shape
    force = np.zeros((n, dim))
    row_max_phi = np.zeros(n)
    # loop over the active rows only: with fluid first and walls last, a prange over all rows
    # gave one thread the fluid and the other mostly idle wall rows (no speed-up on 2 threads)
    rows = np.nonzero(active)[0]
    for k in prange(rows.shape[0]):
        i = rows[k]
        fx = 0.0
        fy = 0.0
        fz = 0.0
        phimax = 0.0
        for p in range(indptr[i], indptr[i + 1]):
            j = indices[p]
            if j == i:
                continue
            dx, dy, dz, r2 = pair_offset(x, i, j, period)   # x_ji; x_ij is its negation (exact)
            dx, dy, dz = -dx, -dy, -dz
            vx = (v[i, 0] - v[j, 0]) * dx
            if dim > 1:
                vx += (v[i, 1] - v[j, 1]) * dy
            if dim > 2:
                vx += (v[i, 2] - v[j, 2]) * dz
            if r2 <= 0.0:
                continue
            hij = 0.5 * (h[i] + h[j])
            r = math.sqrt(r2)
            q = r / hij
            if q >= support:
                continue
            if use_l:  # remove the linear part: w_ij = v_ij − ½(L_i + L_j) x_ij, vx = w_ij · x_ij
                for a in range(dim):
                    da = dx if a == 0 else (dy if a == 1 else dz)
                    for b in range(dim):
                        db = dx if b == 0 else (dy if b == 1 else dz)
                        vx -= 0.5 * (L[i, a, b] + L[j, a, b]) * db * da
            phi = hij * vx / (r2 + ETA_SQUARED * hij * hij)
            if abs(phi) > phimax:
                phimax = abs(phi)
            if vx >= 0.0:
                continue
            c_bar = 0.5 * (c[i] + c[j])
            rho_bar = 0.5 * (rho[i] + rho[j])
            pi_ij = (-alpha * c_bar * phi + beta * phi * phi) / rho_bar
            _, dfdq = kernel_f_df(kid, q, support, dim)
            dwdr = norm_d / hij ** (dim + 1) * dfdq
            s = -(m[i] * m[j]) * pi_ij * dwdr / r
            fx += s * dx
            fy += s * dy
            fz += s * dz
        force[i, 0] = fx
        if dim > 1:
            force[i, 1] = fy
        if dim > 2:
            force[i, 2] = fz
        row_max_phi[i] = phimax
    return force, row_max_phi


def monaghan_viscosity_force(
    positions: ArrayLike,
    velocity: ArrayLike,
    density: ArrayLike,
    sound_speed: ArrayLike,
    masses: ArrayLike,
    h: ArrayLike,
    neighbors: NeighborTable,
    kernel: str | Kernel = "cubic_spline",
    alpha: float = 0.05,
    beta: float = 0.0,
    active: ArrayLike | None = None,
    gradient: ArrayLike | None = None,
    period: ArrayLike | None = None,
) -> tuple[FloatArray, float]:
    """Artificial-viscosity force ``f_i = −Σ_j M_i M_j Π_ij ∇_i W_ij`` and ``max |φ_ij|``.

    Parameters
    ----------
    positions, velocity : (n, d) in m and m/s, ``d`` = 1, 2 or 3.
    density : (n,) kg/m^d; sound_speed : (n,) m/s; masses : (n,) kg; h : (n,) smoothing
        length in m (scalars are broadcast).
    neighbors : symmetric table of the particles against themselves, radius at least
        ``kernel.support * max(h)`` (pairs beyond the kernel support are skipped; the pair
        ``(i, i)`` and coincident particles contribute nothing).
    kernel : kernel name or :class:`~mlsgalerkin.kernels.Kernel` for ``W``.
    alpha, beta : Monaghan's linear and quadratic coefficients (water: α ≈ 0.01–0.1, β = 0;
        shocks: α ≈ β ≈ 1).
    active : optional (n,) bool; only these particles receive force (others, e.g. fixed wall
        particles, still act as partners ``j``); inactive rows are zero.
    gradient : optional (n, d, d) velocity gradient ``L`` (1/s): the pair velocity difference is
        replaced by its deviation from the linear field, ``w_ij = v_ij − ½(L_i + L_j) x_ij``
        (:class:`MonaghanViscosity` with ``residual=True``).
    period : optional (3,) periods (m) of the periodic axes, 0 for the others
        (:mod:`mlsgalerkin.periodic`); pair offsets are then minimum images.

    Returns
    -------
    force : (n, d) in N (N/m in 2D).
    max_phi : ``max |φ_ij|`` in m/s over the pairs inside the kernel support in the rows of
        active particles (approaching *and* separating pairs: the conservative choice for
        :func:`~mlsgalerkin.fluid.time_step.pair_viscosity_limit`); 0 without pairs.
    """
    x, v, rho, c, m, hh, indptr, indices, k, alpha, beta, act = _prepare(
        positions, velocity, density, sound_speed, masses, h, neighbors, kernel, alpha, beta, active
    )
    dim = x.shape[1]
    use_l = gradient is not None
    L = np.ascontiguousarray(gradient, dtype=float) if use_l else np.zeros((1, dim, dim))
    force, row_phi = _monaghan_kernel(
        x, v, rho, c, m, hh, indptr, indices, k.kernel_id, float(k.support),
        float(k.normalisation(dim)), alpha, beta, act, L, use_l, as_period(period),
    )
    return force, float(row_phi.max()) if row_phi.size else 0.0


def monaghan_viscosity_force_reference(
    positions: ArrayLike,
    velocity: ArrayLike,
    density: ArrayLike,
    sound_speed: ArrayLike,
    masses: ArrayLike,
    h: ArrayLike,
    neighbors: NeighborTable,
    kernel: str | Kernel = "cubic_spline",
    alpha: float = 0.05,
    beta: float = 0.0,
    active: ArrayLike | None = None,
    gradient: ArrayLike | None = None,
    period: ArrayLike | None = None,
) -> tuple[FloatArray, float]:
    """numpy reference of :func:`monaghan_viscosity_force` (vectorised over pairs)."""
    x, v, rho, c, m, hh, indptr, indices, k, alpha, beta, act = _prepare(
        positions, velocity, density, sound_speed, masses, h, neighbors, kernel, alpha, beta, active
    )
    n, dim = x.shape
    rows = np.repeat(np.arange(n), np.diff(indptr))
    cols = indices.astype(np.int64)
    dx = -minimum_image(x[cols] - x[rows], as_period(period))
    dv = v[rows] - v[cols]
    if gradient is not None:
        Lg = np.asarray(gradient, dtype=float)
        dv = dv - 0.5 * np.einsum("pab,pb->pa", Lg[rows] + Lg[cols], dx)
    r2 = np.einsum("pd,pd->p", dx, dx)
    vx = np.einsum("pd,pd->p", dv, dx)
    hij = 0.5 * (hh[rows] + hh[cols])
    r = np.sqrt(r2)
    keep = act[rows] & (cols != rows) & (r2 > 0) & (r < k.support * hij)
    rows, cols, dx, r2, vx, hij, r = (a[keep] for a in (rows, cols, dx, r2, vx, hij, r))
    phi = hij * vx / (r2 + ETA_SQUARED * hij**2)
    c_bar = 0.5 * (c[rows] + c[cols])
    rho_bar = 0.5 * (rho[rows] + rho[cols])
    pi_ij = np.where(vx < 0, (-alpha * c_bar * phi + beta * phi**2) / rho_bar, 0.0)
    dwdr = k.derivative(r, hij, dim)
    s = -(m[rows] * m[cols]) * pi_ij * dwdr / r
    force = np.stack([np.bincount(rows, s * dx[:, a], minlength=n) for a in range(dim)], axis=1)
    return force, float(np.abs(phi).max()) if phi.size else 0.0


# --------------------------------------------------------------------------------------
# the effect
# --------------------------------------------------------------------------------------


#: Below this Reynolds number of the artificial viscosity (flow speed × length / ν_num) a run
#: warns: measured on the gravity current, the head speed error passes 10 % below about 100
#: (``docs/theory/stabilisation.md``).
REYNOLDS_THRESHOLD = 100.0


class NumericalViscosityWarning(UserWarning):
    """The artificial viscosity sets a flow's Reynolds number below :data:`REYNOLDS_THRESHOLD`."""


def numerical_viscosity(alpha: float, h: float, c0: float, dim: int) -> float:
    """Kinematic viscosity (m²/s) of Monaghan's artificial viscosity in the continuum limit,
    ``ν = α h c0 / (2(d + 2))`` (Monaghan 2005): ``α h c0/8`` in 2D, ``α h c0/10`` in 3D."""
    return alpha * h * c0 / (2.0 * (dim + 2))


class MonaghanViscosity(Effect):
    r"""Monaghan's pair artificial viscosity (Monaghan 1992), a pair force
    ``f_i = −Σ_j M_i M_j Π_ij ∇_i W_ij`` on the fluid particles (module docstring): momentum-
    conserving and able to damp the velocity modes that nodal integration cannot see.
    ``alpha`` 0.01–0.1 for water, ``beta`` 0. It acts as a kinematic viscosity of about
    ``α h c0 / 8`` in 2D (:func:`numerical_viscosity`; ``docs/theory/galerkin_fluid.md``),
    reported in the run's summary. Given ``flow=(U, L)`` (the flow's speed, m/s, and length,
    m) it also reports the Reynolds number ``U L / ν`` this viscosity implies and warns
    (:class:`NumericalViscosityWarning`) when it is below ``min_reynolds`` (default
    :data:`REYNOLDS_THRESHOLD`). Time-step limit
    ``0.4 h/(c + 0.6(α c + β max φ))``
    (:func:`~mlsgalerkin.fluid.time_step.pair_viscosity_limit`).
    """

    name = "monaghan_viscosity"
    stabilising = True
    stages = ("force",)
    reads = ("velocity", "density", "sound_speed", "neighbors")

    def __init__(self, alpha: float = 0.05, beta: float = 0.0, *, residual: bool = False,
                 flow: tuple[float, float] | None = None, min_reynolds: float = REYNOLDS_THRESHOLD) -> None:
        self.alpha, self.beta = alpha, beta
        self.residual = residual
        self.flow, self.min_reynolds = flow, min_reynolds
        self.max_phi = 0.0
        self.nu = math.nan
        self.reynolds = math.nan

    def __repr__(self) -> str:
        extra = ", residual=True" if self.residual else ""
        extra += "" if self.flow is None else f", flow={tuple(self.flow)!r}"
        return f"MonaghanViscosity(alpha={self.alpha:g}, beta={self.beta:g}{extra})"

    def check(self, ctx: EffectContext) -> list[str]:
        problems: list[str] = []
        check_nonnegative("MonaghanViscosity", "alpha", self.alpha, problems)
        check_nonnegative("MonaghanViscosity", "beta", self.beta, problems)
        if self.flow is not None:
            ok = len(tuple(self.flow)) == 2 and all(math.isfinite(v) and v > 0 for v in self.flow)
            if not ok:
                problems.append(f"MonaghanViscosity: flow must be (speed m/s, length m), both positive, got "
                                f"{self.flow!r}")
        return problems

    def setup(self, state: FluidState, ctx: EffectContext) -> None:
        self._kernel = get_kernel(ctx.approximation.kernel)
        self._active = np.zeros(state.n, dtype=bool)
        self._active[state.fluid] = True
        self._no_gradient = np.zeros((1, state.dim, state.dim))
        c0 = state.c0  # NaN without a pressure model that has one
        h = float(np.mean(state.h[state.fluid])) if state.n_fluid else math.nan
        self.nu = numerical_viscosity(self.alpha, h, c0, state.dim)
        if self.flow is not None and not self.residual:
            U, L = (float(v) for v in self.flow)
            self.reynolds = U * L / self.nu if self.nu > 0 else math.inf
            if self.reynolds < self.min_reynolds:
                warnings.warn(
                    f"MonaghanViscosity(alpha={self.alpha:g}) acts as a viscosity of {self.nu:.3g} m²/s "
                    f"(alpha h c0 / {2 * (state.dim + 2)}, h = {h:.3g} m, c0 = {c0:.3g} m/s): with the flow's speed "
                    f"{U:.3g} m/s and length {L:.3g} m its Reynolds number is {self.reynolds:.3g}, below "
                    f"{self.min_reynolds:g}, so the artificial viscosity, not the physics, sets the flow. Lower alpha "
                    f"(list DensityDiffusion and ParticleShifting to keep the run stable), refine dx, or lower c0",
                    NumericalViscosityWarning, stacklevel=2)

    def summary(self) -> dict[str, Any]:
        out: dict[str, Any] = {"alpha": self.alpha, "beta": self.beta, "residual": self.residual,
                               "numerical_viscosity_m2_per_s": self.nu}
        if self.flow is not None:
            out["flow_speed_m_per_s"], out["flow_length_m"] = (float(v) for v in self.flow)
            out["numerical_reynolds_number"] = self.reynolds
        return out

    def force(self, s: FluidState) -> None:
        # the solver's own arrays are valid by construction: call the compiled kernel directly
        # (monaghan_viscosity_force re-validates every input, ~2.6 ms per call at 1.6e5 particles)
        k = self._kernel
        L = s.L if self.residual else self._no_gradient
        f, row_phi = _monaghan_kernel(
            s.x, s.v, s.rho, s.c, s.M, s.h, s.neighbors.indptr, s.neighbors.indices, k.kernel_id,
            float(k.support), float(k.normalisation(s.dim)), float(self.alpha), float(self.beta), self._active,
            L, self.residual, s.period,
        )
        self.max_phi = float(row_phi.max()) if row_phi.size else 0.0
        s.force[s.fluid] += f[s.fluid]

    def time_step_limit(self, s: FluidState) -> float:
        f = s.fluid
        return pair_viscosity_limit(s.h[f], s.c[f], self.alpha, self.beta, self.max_phi)

    def state_dict(self) -> dict[str, Any]:
        return {"max_phi": self.max_phi}

    def load_state_dict(self, d: dict[str, Any]) -> None:
        self.max_phi = d["max_phi"]
