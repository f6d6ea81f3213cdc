r"""Small-strain elastic bodies on scikit-fem: stiffness, lumped mass, clamped facets, a static
solve and the explicit central-difference step.

The body is a scikit-fem mesh with a vector element (Q1, 9-node Q2 or P1 in 2D). scikit-fem
assembles everything once:

.. math:: K = \int_\Omega \boldsymbol\varepsilon(\mathbf v) : \mathbb C : \boldsymbol\varepsilon(\mathbf u)\,d\Omega,
          \qquad m_i = \sum_j \int_\Omega \rho_s\,\phi_i\cdot\phi_j\,d\Omega

(``skfem.models.elasticity.linear_elasticity`` with the Lamé parameters; the row-sum lumped mass,
positive for Q1, 9-node Q2 and P1, not for serendipity elements). In plane stress the first Lamé
parameter is replaced by :math:`2\lambda\mu/(\lambda + 2\mu)`. Clamped degrees of freedom come
from a facet predicate (``basis.get_dofs``). Explicit central differences,

.. math:: \mathbf v^{n+1/2} = \mathbf v^{n-1/2} + \Delta t\,M^{-1}(\mathbf f_{ext} - K\mathbf u^n),
          \qquad \mathbf u^{n+1} = \mathbf u^n + \Delta t\,\mathbf v^{n+1/2},

are stable for :math:`\Delta t < 2/\omega_{max}`, with :math:`\omega_{max}^2` the largest
eigenvalue of :math:`M^{-1}K` (:meth:`ElasticBody.stable_time_step`).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

import numpy as np
import scipy.sparse as sp
from numpy.typing import NDArray
from skfem import Basis, BilinearForm, ElementQuad1, ElementQuad2, ElementTriP1, ElementVector, FacetBasis, Mesh, asm
from skfem import LinearForm, condense, solve
from skfem.helpers import dot
from skfem.models.elasticity import lame_parameters, linear_elasticity

from mlsgalerkin.contact import ContactSurface

__all__ = ["ElasticMaterial", "ElasticBody", "ELEMENTS"]

FloatArray = NDArray[np.float64]

#: The 2D elements with a positive row-sum lumped mass, by name.
ELEMENTS = {"Q1": ElementQuad1, "Q2": ElementQuad2, "P1": ElementTriP1}


@dataclass(frozen=True)
class ElasticMaterial:
    """Young's modulus ``young`` (Pa), Poisson's ratio ``poisson`` (–), density ``density``
    (kg/m³) and the 2D assumption ``plane`` (``"strain"`` or ``"stress"``)."""

    young: float
    poisson: float
    density: float
    plane: str = "strain"

    def __post_init__(self) -> None:
        if not (self.young > 0 and self.density > 0):
            raise ValueError(f"ElasticMaterial: young and density must be positive, got {self.young!r}, "
                             f"{self.density!r}")
        if not (-1.0 < self.poisson < 0.5):
            raise ValueError(f"ElasticMaterial: poisson must be in (-1, 0.5), got {self.poisson!r}")
        if self.plane not in ("strain", "stress"):
            raise ValueError(f"ElasticMaterial: plane must be 'strain' or 'stress', got {self.plane!r}")

    def lame(self) -> tuple[float, float]:
        """``(λ, μ)`` in Pa, with the plane-stress ``λ`` when ``plane == "stress"``."""
        lam, mu = lame_parameters(self.young, self.poisson)
        if self.plane == "stress":
            lam = 2.0 * lam * mu / (lam + 2.0 * mu)
        return lam, mu


class ElasticBody:
    """A small-strain elastic body on the scikit-fem ``mesh`` (2D) with element ``element``
    (``"Q1"``, ``"Q2"`` or ``"P1"``), clamped where ``clamped(x)`` is true on the boundary
    facets (``x`` of shape ``(2, n)``)."""

    def __init__(self, name: str, mesh: Mesh, material: ElasticMaterial, element: str = "Q2",
                 clamped: Callable[[FloatArray], FloatArray] | None = None) -> None:
        if element not in ELEMENTS:
            raise ValueError(f"ElasticBody {name!r}: element must be one of {sorted(ELEMENTS)}, got {element!r}")
        self.name, self.mesh, self.material = name, mesh, material
        self.basis = Basis(mesh, ElementVector(ELEMENTS[element]()))
        lam, mu = material.lame()
        self.stiffness = asm(linear_elasticity(lam, mu), self.basis).tocsr()
        rho = material.density

        @BilinearForm
        def mass(u, v, w):
            return rho * dot(u, v)

        self.lumped_mass = np.asarray(asm(mass, self.basis).sum(axis=1)).ravel()
        if np.any(self.lumped_mass <= 0):
            raise ValueError(f"ElasticBody {name!r}: the row-sum lumped mass is not positive for element {element!r}")
        n = self.basis.N
        self.clamped_dofs = (self.basis.get_dofs(clamped).all() if clamped is not None
                             else np.empty(0, dtype=np.int64))
        self.free = np.setdiff1d(np.arange(n), self.clamped_dofs)
        self.u = np.zeros(n)
        self.v = np.zeros(n)   # at the half step (central differences)

    # ------------------------------------------------------------------ loads
    def edge_traction(self, facets: Callable[[FloatArray], FloatArray], traction: tuple[float, float]) -> FloatArray:
        """Nodal forces ``(N,)`` of a uniform traction ``traction`` (Pa) on the boundary facets
        where ``facets(x)`` is true: ``f_i = ∫ t · φ_i ds``."""
        fb = FacetBasis(self.mesh, self.basis.elem, facets=self.mesh.facets_satisfying(facets, boundaries_only=True))
        t = np.asarray(traction, dtype=float)

        @LinearForm
        def load(v, w):
            return t[0] * v[0] + t[1] * v[1]

        return asm(load, fb)

    # ------------------------------------------------------------------ solves
    def static(self, f: FloatArray) -> FloatArray:
        """The displacement ``(N,)`` (m) of ``K u = f`` with the clamped degrees of freedom at zero."""
        return solve(*condense(self.stiffness, f, D=self.clamped_dofs))

    def displacement_at(self, points: FloatArray, u: FloatArray | None = None) -> FloatArray:
        """Displacement ``(n, 2)`` at ``points (2, n)`` (m) interpolated with the element's shape functions."""
        u = self.u if u is None else u
        P = self.basis.probes(np.asarray(points, dtype=float))
        return (P @ u).reshape(2, -1).T

    def vertex_displacement(self, vertices: NDArray[np.int64], u: FloatArray | None = None) -> FloatArray:
        """Displacement ``(k, 2)`` (m) of the mesh vertices ``vertices`` (their nodal degrees of freedom)."""
        u = self.u if u is None else u
        return u[self.basis.nodal_dofs[:, vertices]].T

    def surface(self, facets: Callable[[FloatArray], FloatArray] | None = None,
                u: FloatArray | None = None) -> tuple[ContactSurface, NDArray[np.int64]]:
        """The wet surface in the current configuration: the boundary facets where ``facets(x)``
        is true (all boundary facets if ``None``) as a :class:`~mlsgalerkin.contact.ContactSurface`
        of straight segments between the facets' vertices, each oriented from its owning element
        (scikit-fem sorts facet nodes) so that the normal points out of the body; and the mesh
        vertex of each surface node ``(m,)``."""
        mesh = self.mesh
        chosen = mesh.boundary_facets() if facets is None else mesh.facets_satisfying(facets, boundaries_only=True)
        ends = mesh.facets[:, chosen].T.copy()                      # (k, 2) sorted vertex pairs
        owner = mesh.f2t[0, chosen]
        centre = mesh.p[:, mesh.t[:, owner]].mean(axis=1).T         # (k, 2) owning element centroids
        a, b = mesh.p[:, ends[:, 0]].T, mesh.p[:, ends[:, 1]].T
        t = b - a
        normal = np.stack([t[:, 1], -t[:, 0]], axis=1)
        flip = np.einsum("kd,kd->k", normal, 0.5 * (a + b) - centre) < 0
        ends[flip] = ends[flip][:, ::-1]
        vertices, local = np.unique(ends, return_inverse=True)
        nodes = mesh.p[:, vertices].T + self.vertex_displacement(vertices, u)
        return ContactSurface(nodes, local.reshape(-1, 2)), vertices

    def internal_force(self, u: FloatArray | None = None) -> FloatArray:
        """``K u`` ``(N,)`` in N (per unit depth), zero on the clamped degrees of freedom."""
        f = self.stiffness @ (self.u if u is None else u)
        f[self.clamped_dofs] = 0.0
        return f

    def stable_time_step(self) -> float:
        """``2/ω_max`` (s) of central differences, ``ω_max²`` the largest eigenvalue of
        ``M⁻¹K`` over the free degrees of freedom (scipy ``eigsh``)."""
        from scipy.sparse.linalg import eigsh

        free = self.free
        s = 1.0 / np.sqrt(self.lumped_mass[free])
        A = sp.diags(s) @ self.stiffness[free][:, free] @ sp.diags(s)
        lam = eigsh(A, k=1, which="LA", return_eigenvectors=False, tol=1e-6)[0]
        return 2.0 / float(np.sqrt(lam))

    def step(self, dt: float, f_ext: FloatArray | None = None) -> None:
        """One central-difference step of ``dt`` (s) under external nodal forces ``f_ext`` (N)."""
        f = -self.internal_force()
        if f_ext is not None:
            f = f + f_ext
        a = f / self.lumped_mass
        a[self.clamped_dofs] = 0.0
        self.v += dt * a
        self.u += dt * self.v

    def energies(self, v_full: FloatArray | None = None) -> tuple[float, float]:
        """``(kinetic, strain)`` energy in J per unit depth: ``½ vᵀ M v`` and ``½ uᵀ K u``."""
        v = self.v if v_full is None else v_full
        return 0.5 * float(np.dot(self.lumped_mass * v, v)), 0.5 * float(self.u @ (self.stiffness @ self.u))
