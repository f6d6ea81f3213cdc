r"""Test problems of the Galerkin study: exact solutions, loads, boundary data and node sets.

Four problems on axis-aligned rectangles (edges numbered as
:func:`~mlsgalerkin.integration.rectangle`: 0 bottom, 1 right, 2 top, 3 left):

``poisson_patch``
    ``-Δu = 0`` on the unit square, ``u = 1 + 2x - 3y`` (linear), Dirichlet on all edges.
``elastic_patch``
    Linear elasticity (plane strain, ``E = 1000``, ``ν = 0.3``, no body force) on the unit
    square, linear displacement ``u = c + A x``, Dirichlet on all edges.
``poisson_mms``
    Manufactured ``u = sin(πx) cos(πy) + x y²`` on the unit square (non-zero boundary data on
    every edge), ``f = -Δu = 2π² sin(πx) cos(πy) - 2x``, Dirichlet on all edges.
``timoshenko``
    Cantilever of Timoshenko & Goodier (1970, §21), **plane stress**: ``L = 48``, ``D = 12``,
    ``E = 3e7``, ``ν = 0.3``, ``P = 1000`` (consistent units), domain ``[0, L] x [-D/2, D/2]``,
    exact displacement on ``x = 0`` (edge 3), parabolic shear traction on ``x = L`` (edge 1),
    traction-free top and bottom. With ``I = D³/12``:

    .. math::

        u_x &= -\frac{P y}{6EI}\Big[(6L - 3x)x + (2 + ν)\big(y^2 - \tfrac{D^2}{4}\big)\Big],\\
        u_y &= \frac{P}{6EI}\Big[3ν y^2 (L - x) + (4 + 5ν)\frac{D^2 x}{4} + (3L - x)x^2\Big],\\
        σ_{xx} &= -\frac{P (L - x) y}{I},\quad σ_{yy} = 0,\quad
        σ_{xy} = \frac{P}{2I}\Big(\frac{D^2}{4} - y^2\Big).

    The traction on ``x = L`` is ``(0, σ_xy)``; it integrates to ``+P`` (upward with this sign
    convention, so the tip deflects upward: ``u_y(L, 0) = P L³/(3EI) + (4 + 5ν) P D² L/(24 EI)``).

Callables follow the forms' convention: ``x`` has shape ``(2, n)``; scalars return ``(n,)``,
vectors ``(2, n)``, gradients ``(2, n)`` or ``(2, 2, n)`` with ``[a, b] = ∂u_a/∂x_b``.

>>> p = timoshenko()
>>> import numpy as np
>>> x = np.array([[48.0], [0.0]])
>>> round(float(p.exact(x)[1, 0]), 6)   # tip deflection
0.0089
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Callable

import numpy as np
from numpy.typing import NDArray

from mlsgalerkin.integration import rectangle
from mlsgalerkin.models.elasticity import lame_parameters

__all__ = [
    "Problem",
    "PROBLEMS",
    "get_problem",
    "poisson_patch",
    "elastic_patch",
    "poisson_mms",
    "timoshenko",
    "node_grid",
    "NODE_LAYOUTS",
]

FloatArray = NDArray[np.float64]
NODE_LAYOUTS = ("regular", "perturbed")
#: Interior nodes of the "perturbed" layout move by up to this fraction of the spacing.
JITTER = 0.3


@dataclass(frozen=True)
class Problem:
    """A boundary-value problem with a closed-form solution on a rectangle.

    Attributes
    ----------
    name : str
    kind : ``"poisson"`` or ``"elasticity"``
    lower, upper : (2,) corners of the rectangle (length)
    exact, grad_exact : callables ``x (2, n)`` -> values / gradients (see module docstring)
    source : callable ``x -> (n,)`` (Poisson ``f``) or ``(2, n)`` (body force), or None
    dirichlet_edges : rectangle edges with the exact solution imposed weakly
    neumann_edges : edges with the exact flux / traction prescribed (others: free, zero flux)
    E, nu, plane_stress : elasticity material (ignored for Poisson)
    description : one line for reports
    """

    name: str
    kind: str
    lower: tuple[float, float]
    upper: tuple[float, float]
    exact: Callable[[FloatArray], FloatArray]
    grad_exact: Callable[[FloatArray], FloatArray]
    source: Callable[[FloatArray], FloatArray] | None
    dirichlet_edges: tuple[int, ...] = (0, 1, 2, 3)
    neumann_edges: tuple[int, ...] = ()
    E: float = 1.0
    nu: float = 0.3
    plane_stress: bool = False
    linear: bool = False
    description: str = ""
    meta: dict = field(default_factory=dict, compare=False)

    @property
    def is_vector(self) -> bool:
        return self.kind == "elasticity"

    @property
    def n_components(self) -> int:
        return 2 if self.is_vector else 1

    @property
    def domain(self) -> FloatArray:
        """Counter-clockwise corners ``(4, 2)``."""
        return rectangle(self.lower, self.upper)

    @property
    def size(self) -> FloatArray:
        return np.asarray(self.upper, float) - np.asarray(self.lower, float)

    @property
    def lame(self) -> tuple[float, float]:
        """``(λ, μ)`` (plane-stress ``λ*`` when ``plane_stress``)."""
        return lame_parameters(self.E, self.nu, plane_stress=self.plane_stress)

    @property
    def modulus(self) -> float:
        """Material scale ``M`` of the Nitsche/penalty parameter ``βM/h``."""
        return self.E if self.is_vector else 1.0

    def flux_exact(self, x: FloatArray) -> FloatArray:
        """``∇u`` ``(2, n)`` (Poisson) or ``σ(u)`` ``(2, 2, n)`` (elasticity)."""
        g = self.grad_exact(x)
        if not self.is_vector:
            return g
        lam, mu = self.lame
        eps = 0.5 * (g + np.swapaxes(g, 0, 1))
        tr = eps[0, 0] + eps[1, 1]
        return 2.0 * mu * eps + lam * tr * np.eye(2)[:, :, None]

    def boundary_flux(self, x: FloatArray, normals: FloatArray) -> FloatArray:
        """``∇u·n`` ``(n,)`` or traction ``σn`` ``(2, n)`` at ``x (2, n)``, normals ``(2, n)``."""
        F = self.flux_exact(x)
        if not self.is_vector:
            return np.einsum("dn,dn->n", F, normals)
        return np.einsum("abn,bn->an", F, normals)


# --------------------------------------------------------------------------------------
# node sets
# --------------------------------------------------------------------------------------


def node_grid(problem: Problem, spacing: float, layout: str = "regular",
              rng: np.random.Generator | None = None) -> FloatArray:
    """Nodes ``(n, 2)`` on the problem's rectangle with (about) the given ``spacing``.

    ``layout="regular"``: a tensor grid with ``round(size / spacing) + 1`` nodes per side
    (the spacing must divide the sides). ``"perturbed"``: the same grid with every interior node
    moved by a uniform random offset of up to ``±0.3`` spacing per coordinate (``rng``; boundary
    nodes stay on the boundary, at their grid positions).
    """
    if layout not in NODE_LAYOUTS:
        raise ValueError(f"unknown node layout {layout!r}; choose one of {', '.join(NODE_LAYOUTS)}")
    size = problem.size
    counts = np.rint(size / spacing).astype(int)
    if (counts < 1).any() or not np.allclose(counts * spacing, size, rtol=1e-9):
        raise ValueError(f"spacing {spacing} does not divide the domain {size.tolist()}")
    axes = [np.linspace(problem.lower[d], problem.upper[d], counts[d] + 1) for d in range(2)]
    g = np.stack(np.meshgrid(*axes, indexing="ij"), -1).reshape(-1, 2)
    if layout == "perturbed":
        if rng is None:
            raise ValueError("layout='perturbed' needs an rng (numpy.random.Generator)")
        tol = 1e-9 * float(size.max())
        lo, hi = np.asarray(problem.lower), np.asarray(problem.upper)
        inner = ((g > lo + tol) & (g < hi - tol)).all(axis=1)
        g[inner] += rng.uniform(-JITTER, JITTER, (int(inner.sum()), 2)) * spacing
    return g


# --------------------------------------------------------------------------------------
# the problems
# --------------------------------------------------------------------------------------


def poisson_patch() -> Problem:
    """Linear Poisson patch test ``u = 1 + 2x - 3y`` on the unit square."""

    def exact(x):
        return 1.0 + 2.0 * x[0] - 3.0 * x[1]

    def grad_exact(x):
        n = x.shape[1]
        return np.stack([np.full(n, 2.0), np.full(n, -3.0)])

    return Problem("poisson_patch", "poisson", (0.0, 0.0), (1.0, 1.0), exact, grad_exact,
                   None, linear=True, description="Poisson, u = 1 + 2x − 3y, unit square")


_A_PATCH = np.array([[0.01, 0.02], [-0.015, 0.005]])
_C_PATCH = np.array([0.003, -0.002])


def elastic_patch() -> Problem:
    """Linear elasticity patch test ``u = c + A x`` (plane strain, E = 1000, ν = 0.3)."""

    def exact(x):
        return _C_PATCH[:, None] + _A_PATCH @ x

    def grad_exact(x):
        return np.repeat(_A_PATCH[:, :, None], x.shape[1], axis=2)

    return Problem("elastic_patch", "elasticity", (0.0, 0.0), (1.0, 1.0), exact, grad_exact,
                   None, E=1000.0, nu=0.3, plane_stress=False, linear=True,
                   description="plane-strain elasticity, u = c + A x, unit square")


def poisson_mms() -> Problem:
    """Manufactured Poisson solution ``u = sin(πx) cos(πy) + x y²`` on the unit square."""
    pi = np.pi

    def exact(x):
        return np.sin(pi * x[0]) * np.cos(pi * x[1]) + x[0] * x[1] ** 2

    def grad_exact(x):
        return np.stack([pi * np.cos(pi * x[0]) * np.cos(pi * x[1]) + x[1] ** 2,
                         -pi * np.sin(pi * x[0]) * np.sin(pi * x[1]) + 2.0 * x[0] * x[1]])

    def source(x):
        return 2.0 * pi**2 * np.sin(pi * x[0]) * np.cos(pi * x[1]) - 2.0 * x[0]

    return Problem("poisson_mms", "poisson", (0.0, 0.0), (1.0, 1.0), exact, grad_exact, source,
                   description="Poisson MMS, u = sin(πx)cos(πy) + xy², unit square, "
                               "Nitsche on all edges")


def timoshenko(L: float = 48.0, D: float = 12.0, E: float = 3e7, nu: float = 0.3,
               P: float = 1000.0) -> Problem:
    """Timoshenko & Goodier cantilever (plane stress), classic data by default."""
    inertia = D**3 / 12.0
    c = P / (6.0 * E * inertia)

    def exact(x):
        X, Y = x[0], x[1]
        ux = -c * Y * ((6.0 * L - 3.0 * X) * X + (2.0 + nu) * (Y**2 - D**2 / 4.0))
        uy = c * (3.0 * nu * Y**2 * (L - X) + (4.0 + 5.0 * nu) * D**2 * X / 4.0
                  + (3.0 * L - X) * X**2)
        return np.stack([ux, uy])

    def grad_exact(x):
        X, Y = x[0], x[1]
        dux_dx = -c * Y * (6.0 * L - 6.0 * X)
        dux_dy = -c * ((6.0 * L - 3.0 * X) * X + (2.0 + nu) * (3.0 * Y**2 - D**2 / 4.0))
        duy_dx = c * (-3.0 * nu * Y**2 + (4.0 + 5.0 * nu) * D**2 / 4.0 + 6.0 * L * X - 3.0 * X**2)
        duy_dy = c * 6.0 * nu * Y * (L - X)
        return np.stack([np.stack([dux_dx, dux_dy]), np.stack([duy_dx, duy_dy])])

    def stress(x):
        X, Y = x[0], x[1]
        sxx = -P * (L - X) * Y / inertia
        sxy = P / (2.0 * inertia) * (D**2 / 4.0 - Y**2)
        return np.stack([np.stack([sxx, sxy]), np.stack([sxy, 0.0 * X])])

    return Problem("timoshenko", "elasticity", (0.0, -D / 2.0), (L, D / 2.0), exact, grad_exact,
                   None, dirichlet_edges=(3,), neumann_edges=(1,), E=E, nu=nu, plane_stress=True,
                   description=f"Timoshenko cantilever, plane stress, L = {L:g}, D = {D:g}, "
                               f"E = {E:g}, ν = {nu:g}, P = {P:g}",
                   meta={"L": L, "D": D, "P": P, "I": inertia, "stress": stress})


#: Problem factories by name.
PROBLEMS: dict[str, Callable[[], Problem]] = {
    "poisson_patch": poisson_patch,
    "elastic_patch": elastic_patch,
    "poisson_mms": poisson_mms,
    "timoshenko": timoshenko,
}


def get_problem(name: str) -> Problem:
    """The problem called ``name`` (one of :data:`PROBLEMS`)."""
    try:
        return PROBLEMS[name]()
    except KeyError:
        raise ValueError(f"unknown problem {name!r}; choose one of {', '.join(PROBLEMS)}") from None
