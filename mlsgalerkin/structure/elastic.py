r"""Elastic bodies on scikit-fem: stiffness, lumped mass, clamped facets, the wet surface, and the
body's options in a run (model, integrator, weight, damping, named points).

The body is a scikit-fem mesh with a vector element: Q1, 9-node Q2 or P1 in 2D; Hex1, 27-node Hex2
or P1 (tetrahedra) in 3D, with the same API. scikit-fem
assembles everything once:

.. math:: K = \int_\Omega \boldsymbol\varepsilon(\mathbf v) : \mathbb C : \boldsymbol\varepsilon(\mathbf u)\,d\Omega,
          \qquad m_i = \sum_j \int_\Omega \rho_s\,\phi_i\cdot\phi_j\,d\Omega,
          \qquad \mathbf f_g = \int_\Omega \rho_s\,\mathbf g\cdot\phi_i\,d\Omega

(``skfem.models.elasticity.linear_elasticity`` with the Lamé parameters; the row-sum lumped mass,
positive for Q1, 9-node Q2, P1, Hex1, 27-node Hex2 and tetrahedral P1, not for serendipity
elements; the weight ``f_g`` if the body
has ``gravity``). In plane stress the first Lamé parameter is replaced by
:math:`2\lambda\mu/(\lambda + 2\mu)`. Clamped degrees of freedom come from a facet predicate
(``basis.get_dofs``). Units: m, kg, s, N (per unit depth in 2D), Pa.

A run advances the body with the :class:`~mlsgalerkin.structure.solver.StructureSolver`:
explicit central differences sub-cycled inside the fluid's step (linear or a total-Lagrangian
nonlinear model, :mod:`mlsgalerkin.structure.hyperelastic`), or implicit Newmark (linear). The
fluid touches the body on its *wet surface*: the boundary facets chosen by ``wet``, as straight
segments between the facet's nodes (vertices, and the mid-side node of a Q2 facet) in 2D, as
triangles on the facet's vertices in 3D (a quadrilateral facet split in two), oriented from the
owning element (scikit-fem sorts facet nodes) so that the normal points out of the body.

>>> from skfem import MeshQuad
>>> mesh = MeshQuad.init_tensor(np.linspace(0, 0.3, 7), np.linspace(0, 0.006, 2))
>>> beam = ElasticBody("beam", mesh, ElasticMaterial(0.2e9, 0.3, 7860.0, plane="stress"),
...                    clamped=lambda x: np.isclose(x[0], 0.0), wet=lambda x: np.isclose(x[1], 0.006))
>>> beam.wet.n_nodes, beam.wet.segments.shape   # 7 vertices and 6 mid-side nodes on the top
(13, (12, 2))
"""

from __future__ import annotations

import inspect
import math
import warnings
from collections.abc import Callable
from dataclasses import dataclass
from typing import ClassVar

import numpy as np
import scipy.sparse as sp
from numpy.typing import ArrayLike, NDArray
from scipy.sparse.linalg import eigsh
from skfem import (
    Basis,
    BilinearForm,
    ElementHex1,
    ElementHex2,
    ElementQuad1,
    ElementQuad2,
    ElementTetP1,
    ElementTriP1,
    ElementVector,
    FacetBasis,
    LinearForm,
    Mesh,
    asm,
    condense,
    solve,
)
from skfem.helpers import dot
from skfem.models.elasticity import linear_elasticity
from threadpoolctl import threadpool_limits

from mlsgalerkin.contact import ContactSurface
from mlsgalerkin.dynamics import Body
from mlsgalerkin.structure.checks import BYTES_PER_ELEMENT, element_problems, mesh_size_problems, substep_estimate
from mlsgalerkin.structure.material import ElasticMaterial

__all__ = ["ARPACK_SEED", "ELEMENTS", "ELEMENTS_3D", "INTEGRATORS", "MODELS", "STRUCTURE_SOLVER", "ElasticBody",
           "ElasticMaterial", "WetSurface", "arpack_eigenvalue"]

FloatArray = NDArray[np.float64]
Predicate = Callable[[FloatArray], FloatArray]

#: The solver of structure bodies (a string: the body module does not import its solver).
STRUCTURE_SOLVER = "mlsgalerkin.structure.solver:StructureSolver"
#: The 2D elements with a positive row-sum lumped mass, by name.
ELEMENTS = {"Q1": ElementQuad1, "Q2": ElementQuad2, "P1": ElementTriP1}
#: The 3D elements with a positive row-sum lumped mass, by name.
ELEMENTS_3D = {"Hex1": ElementHex1, "Hex2": ElementHex2, "P1": ElementTetP1}
#: Material models: small-strain linear elasticity and two total-Lagrangian hyperelastic models.
MODELS = ("linear", "stvenant_kirchhoff", "neo_hookean")
#: Time integrators: explicit central differences (sub-cycled) and implicit Newmark (linear only).
INTEGRATORS = ("explicit", "newmark")
#: Seed of ARPACK's start vector in :func:`arpack_eigenvalue`.
ARPACK_SEED = 0
_EIGSH_TAKES_RNG = "rng" in inspect.signature(eigsh).parameters


def arpack_eigenvalue(A: sp.spmatrix, **options: object) -> float:
    """The eigenvalue of the symmetric ``A`` that scipy's ``eigsh(A, k=1, **options)`` finds, the
    same in every process: ARPACK starts from a fixed pseudo-random vector (seed
    :data:`ARPACK_SEED`) and draws any restart vector from the same seeded generator, on one BLAS
    thread. Without ``v0`` scipy (≥ 1.15) draws the start from the operating system's entropy, so
    the eigenvalue differed at round-off between runs (and, through the sub-step and the
    high-mode damping, every number of an explicit elastic run)."""
    rng = np.random.default_rng(ARPACK_SEED)
    v0 = rng.uniform(-1.0, 1.0, A.shape[0])
    seeded = {"rng": rng} if _EIGSH_TAKES_RNG else {}
    with threadpool_limits(limits=1, user_api="blas"):
        return float(eigsh(A, k=1, v0=v0, return_eigenvectors=False, **seeded, **options)[0])


@dataclass(frozen=True, eq=False)
class WetSurface:
    """The wet surface of an elastic body in the reference configuration.

    Attributes
    ----------
    dofs : (m, d) int array
        The ``d`` vector degrees of freedom of each surface node.
    reference : (m, d) float array
        Node positions at rest (m).
    segments : (k, d) int array
        Surface node indices of each facet — 2D segments, 3D triangles — ordered so that the
        normal (2D: the segment direction turned clockwise; 3D: counter-clockwise seen from
        outside) points out of the body.
    """

    dofs: NDArray[np.int64]
    reference: FloatArray
    segments: NDArray[np.int64]

    @property
    def n_nodes(self) -> int:
        return self.dofs.shape[0]

    def contact_surface(self, u: FloatArray | None = None) -> ContactSurface:
        """The surface as a :class:`~mlsgalerkin.contact.ContactSurface`, displaced by ``u (N,)``."""
        x = self.reference if u is None else self.reference + u[self.dofs]
        return ContactSurface(x, self.segments)


def wet_surface(basis: Basis, facets: NDArray[np.int64]) -> WetSurface:
    """The oriented facets of the boundary ``facets`` of a vector ``basis``: 2D segments (vertices,
    and the mid-side node of a quadratic facet), 3D triangles on the vertices (see
    :class:`WetSurface`)."""
    if basis.mesh.p.shape[0] == 3:
        return _wet_surface_3d(basis, facets)
    mesh = basis.mesh
    ends = mesh.facets[:, facets].T.copy()                       # (k, 2) sorted vertex pairs
    owner = mesh.f2t[0, facets]
    centre = mesh.p[:, mesh.t[:, owner]].mean(axis=1).T          # (k, 2) owning element centroids
    a, b = mesh.p[:, ends[:, 0]].T, mesh.p[:, ends[:, 1]].T
    t = b - a
    normal = np.stack([t[:, 1], -t[:, 0]], axis=1)
    flip = np.einsum("kd,kd->k", normal, 0.5 * (a + b) - centre) < 0
    ends[flip] = ends[flip][:, ::-1]
    first = basis.nodal_dofs[:, ends[:, 0]].T                     # (k, 2) dofs of the start vertex
    last = basis.nodal_dofs[:, ends[:, 1]].T
    if basis.facet_dofs.shape[1]:                                 # quadratic: split at the mid-side node
        mid = basis.facet_dofs[:2, facets].T
        chain = np.stack([first, mid, last], axis=1)              # (k, 3, 2)
        pairs = np.concatenate([chain[:, [0, 1]], chain[:, [1, 2]]], axis=0)
    else:
        pairs = np.stack([first, last], axis=1)                   # (k, 2, 2)
    node_dof = pairs[:, :, 0].ravel()
    unique, local = np.unique(node_dof, return_inverse=True)
    dofs = np.stack([unique, unique + 1], axis=1)   # scikit-fem interleaves ElementVector's components
    reference = basis.doflocs[:, unique].T.copy()
    return WetSurface(dofs.astype(np.int64), reference, local.reshape(-1, 2).astype(np.int64))


def _wet_surface_3d(basis: Basis, facets: NDArray[np.int64]) -> WetSurface:
    """Triangles on the vertices of 3D boundary facets, counter-clockwise seen from outside."""
    mesh = basis.mesh
    verts = mesh.facets[:, facets].T                              # (k, 3 or 4) sorted vertex indices
    owner = mesh.f2t[0, facets]
    centre = mesh.p[:, mesh.t[:, owner]].mean(axis=1).T           # (k, 3) owning element centroids
    tris = []
    for f in range(verts.shape[0]):
        v = verts[f]
        x = mesh.p[:, v].T
        c = x.mean(axis=0)
        if v.size == 4:                                           # order the quadrilateral around its centre
            n0 = np.cross(x[1] - x[0], x[2] - x[0])
            if np.linalg.norm(n0) < 1e-14 * np.ptp(x):
                n0 = np.cross(x[1] - x[0], x[3] - x[0])
            e1 = (x[0] - c) / np.linalg.norm(x[0] - c)
            e2 = np.cross(n0 / np.linalg.norm(n0), e1)
            order = np.argsort(np.arctan2((x - c) @ e2, (x - c) @ e1))
            v, x = v[order], x[order]
            pieces = [[v[0], v[1], v[2]], [v[0], v[2], v[3]]]
        else:
            pieces = [list(v)]
        normal = np.cross(x[1] - x[0], x[2] - x[0])
        flip = float(normal @ (c - centre[f])) < 0
        tris += [[p[0], p[2], p[1]] if flip else p for p in pieces]
    tris = np.array(tris, dtype=np.int64)
    vertices, local = np.unique(tris, return_inverse=True)
    first = basis.nodal_dofs[0, vertices]
    dofs = np.stack([basis.nodal_dofs[c, vertices] for c in range(3)], axis=1)
    reference = basis.doflocs[:, first].T.copy()
    return WetSurface(dofs.astype(np.int64), reference, local.reshape(-1, 3).astype(np.int64))


class ElasticBody(Body):
    """An elastic body on the scikit-fem ``mesh`` with element ``element``: ``"Q1"``, ``"Q2"`` or
    ``"P1"`` in 2D, ``"Hex1"``, ``"Hex2"`` or ``"P1"`` in 3D.

    Parameters
    ----------
    name : str
    mesh : skfem.Mesh
        A 2D mesh (``MeshQuad`` for Q1/Q2, ``MeshTri`` for P1) or a 3D one (``MeshHex`` for
        Hex1/Hex2, ``MeshTet`` for P1), in m, at rest. In 3D the material's ``plane`` does not
        apply: the linear and the nonlinear models use the 3D Lamé parameters (``lame(3)``).
    material : ElasticMaterial
    element : str
    clamped : callable, optional
        ``clamped(x) -> bool array`` on facet midpoints ``x (d, n)``: the boundary facets whose
        degrees of freedom are held at zero.
    wet : callable, optional
        The boundary facets the fluid may touch (same form); default all boundary facets.
    model : str
        ``"linear"`` (small strain), ``"stvenant_kirchhoff"`` or ``"neo_hookean"`` (total
        Lagrangian, large rotations, :mod:`~mlsgalerkin.structure.hyperelastic`; 2D plane strain
        or 3D, explicit only).
    integrator : str
        ``"explicit"`` (central differences, sub-cycled inside the outer step) or ``"newmark"``
        (implicit average acceleration, linear model only; one step per outer step).
    gravity : (d,) array, optional
        Acceleration of gravity on the body (m/s²), e.g. ``(0, -9.81)``; none by default.
    damping : (float, float)
        Rayleigh damping ``C = a0 M + a1 K`` (1/s, s); none by default.
    high_mode_damping : float
        Explicit integrator: stiffness-proportional damping added so that the highest mode has
        this damping ratio (``a1 = 2ξ/ω_max``; default 0.5). It keeps the stiff modes a coupled
        run cannot resolve from ringing at the wet surface (measured necessary on the plate under
        water); its damping ratio at the first mode, ``ξ ω₁/ω_max``, is in ``summary.json``.
    points : dict of str to (d,) point, optional
        Named material points (m, at rest) whose displacement is recorded every step as the
        time-series columns ``<name>_<point>_ux`` and ``_uy``.
    """

    solver: ClassVar[str] = STRUCTURE_SOLVER

    def __init__(self, name: str, mesh: Mesh, material: ElasticMaterial, element: str = "Q2",
                 clamped: Predicate | None = None, wet: Predicate | None = None, *, model: str = "linear",
                 integrator: str = "explicit", gravity: ArrayLike | None = None,
                 damping: tuple[float, float] = (0.0, 0.0), high_mode_damping: float = 0.5,
                 points: dict[str, ArrayLike] | None = None) -> None:
        owner = f"ElasticBody {name!r}"
        if not isinstance(mesh, Mesh) or mesh.p.shape[0] not in (2, 3):
            raise ValueError(f"{owner}: mesh must be a 2D or 3D scikit-fem mesh (MeshQuad, MeshTri, MeshHex, MeshTet), "
                             f"got {type(mesh).__name__}")
        d = mesh.p.shape[0]
        # before scikit-fem sees the mesh: its size, non-finite nodes, degenerate, folded or inverted elements
        problems = mesh_size_problems(mesh.t.shape[1], f"{owner}: the mesh") or element_problems(
            mesh.p, mesh.t, mesh.facets, mesh.f2t, owner=f"{owner}: the mesh")
        if problems:
            raise ValueError(problems[0])
        table = ELEMENTS if d == 2 else ELEMENTS_3D
        if element not in table:
            raise ValueError(f"{owner}: element must be one of {sorted(table)} for a {d}D mesh, got {element!r}")
        if table[element].refdom is not type(mesh).elem.refdom:
            fits = sorted(k for k, e in table.items() if e.refdom is type(mesh).elem.refdom)
            raise ValueError(f"{owner}: element {element!r} does not fit a {type(mesh).__name__} (its cells are "
                             f"{type(mesh).elem.refdom.__name__[3:].lower()}s); use {' or '.join(fits)}")
        if not isinstance(material, ElasticMaterial):
            raise TypeError(f"{owner}: material must be an ElasticMaterial, got {type(material).__name__}")
        if model not in MODELS:
            raise ValueError(f"{owner}: model must be one of {MODELS}, got {model!r}")
        if integrator not in INTEGRATORS:
            raise ValueError(f"{owner}: integrator must be one of {INTEGRATORS}, got {integrator!r}")
        if model != "linear" and integrator != "explicit":
            raise ValueError(f"{owner}: the nonlinear model {model!r} runs with the explicit integrator only; "
                             "use integrator='explicit' (or model='linear' for Newmark)")
        if model != "linear" and d == 2 and material.plane != "strain":
            raise ValueError(f"{owner}: the nonlinear model {model!r} is plane strain; use ElasticMaterial(..., "
                             "plane='strain') (plane stress needs the thickness change, which it does not model)")
        if not (isinstance(high_mode_damping, (int, float)) and 0.0 <= high_mode_damping <= 1.0):
            raise ValueError(f"{owner}: high_mode_damping is a damping ratio at the highest mode, in [0, 1]; got "
                             f"{high_mode_damping!r}")
        self.high_mode_damping = float(high_mode_damping)
        a0, a1 = (float(c) for c in damping)
        if not (math.isfinite(a0) and math.isfinite(a1) and a0 >= 0 and a1 >= 0):
            raise ValueError(f"{owner}: Rayleigh damping (a0, a1) must be finite and >= 0, got {damping!r}")
        self.name, self.mesh, self.material, self.element = name, mesh, material, element
        self.model, self.integrator, self.damping = model, integrator, (a0, a1)
        self.gravity = None if gravity is None else np.asarray(gravity, dtype=float)
        if self.gravity is not None and self.gravity.shape != (d,):
            raise ValueError(f"{owner}: gravity must be a ({d},) vector (m/s²), got shape {self.gravity.shape}")
        self.basis = Basis(mesh, ElementVector(table[element]()))
        lam, mu = material.lame(d)
        self.stiffness = asm(linear_elasticity(lam, mu), self.basis).tocsr()
        rho = material.density

        @BilinearForm
        def mass(u, v, w):
            return rho * dot(u, v)

        self.lumped_mass = np.asarray(asm(mass, self.basis).sum(axis=1)).ravel()
        if np.any(self.lumped_mass <= 0):
            raise ValueError(f"{owner}: the row-sum lumped mass is not positive for element {element!r}")
        n = self.basis.N
        self.clamped_dofs = (self.basis.get_dofs(clamped).all() if clamped is not None
                             else np.empty(0, dtype=np.int64))
        self.free = np.setdiff1d(np.arange(n), self.clamped_dofs)
        chosen = (mesh.boundary_facets() if wet is None
                  else mesh.facets_satisfying(wet, boundaries_only=True))
        if len(chosen) == 0:
            raise ValueError(f"{owner}: the wet predicate selects no boundary facet; it is called with facet "
                             "midpoints x of shape (2, n) and must be true on the facets the fluid may touch")
        self.wet = wet_surface(self.basis, np.asarray(chosen, dtype=np.int64))
        self.weight = np.zeros(n)
        if self.gravity is not None:
            g = self.gravity

            @LinearForm
            def body_force(v, w):
                return rho * sum(g[c] * v[c] for c in range(d))

            self.weight = asm(body_force, self.basis)
        self.points: dict[str, FloatArray] = {}
        for key, p in (points or {}).items():
            q = np.asarray(p, dtype=float)
            if q.shape != (d,) or not np.all(np.isfinite(q)):
                raise ValueError(f"{owner}: point {key!r} must be a finite ({d},) position, got {p!r}")
            self.points[key] = q
        self._probes = None
        if self.points:
            try:
                self._probes = self.basis.probes(np.array(list(self.points.values())).T)
            except Exception as exc:
                raise ValueError(f"{owner}: a named point lies outside the mesh ({exc}); give points inside the "
                                 "body at rest") from exc

    @property
    def dim(self) -> int:
        return int(self.mesh.p.shape[0])

    @property
    def n_dofs(self) -> int:
        return self.basis.N

    @property
    def n_elements(self) -> int:
        """Elements of the mesh."""
        return int(self.mesh.t.shape[1])

    def memory_estimate(self) -> float:
        """Bytes a run of this body holds (stiffness, mass, state), from its element count
        (:data:`~mlsgalerkin.structure.checks.BYTES_PER_ELEMENT`): for ``mlsgalerkin run --check``."""
        return float(self.n_elements * BYTES_PER_ELEMENT.get(self.element, 16_000))

    def substep_estimate(self) -> float | None:
        """The explicit sub-step (s) a run takes, estimated before any assembly
        (:func:`~mlsgalerkin.structure.checks.substep_estimate`); ``None`` for Newmark."""
        return substep_estimate(self)

    def __repr__(self) -> str:
        m = self.material
        return (f"ElasticBody(name={self.name!r}, nodes={self.mesh.p.shape[1]}, elements={self.mesh.t.shape[1]}, "
                f"element={self.element!r}, young={m.young!r}, poisson={m.poisson!r}, density={m.density!r}, "
                f"plane={m.plane!r}, model={self.model!r}, integrator={self.integrator!r}, "
                f"clamped_dofs={self.clamped_dofs.size}, wet_nodes={self.wet.n_nodes}, "
                f"gravity={None if self.gravity is None else self.gravity.tolist()}, damping={self.damping!r}, "
                f"high_mode_damping={self.high_mode_damping!r})")

    # ------------------------------------------------------------------ loads
    def edge_traction(self, facets: Predicate, traction: tuple[float, ...]) -> FloatArray:
        """Nodal forces ``(N,)`` of a uniform traction ``traction`` (Pa) on the boundary facets
        where ``facets(x)`` is true: ``f_i = ∫ t · φ_i ds``."""
        fb = FacetBasis(self.mesh, self.basis.elem, facets=self.mesh.facets_satisfying(facets, boundaries_only=True))
        t = np.asarray(traction, dtype=float)

        @LinearForm
        def load(v, w):
            return sum(t[c] * v[c] for c in range(t.size))

        return asm(load, fb)

    # ------------------------------------------------------------------ solves and probes
    def static(self, f: FloatArray) -> FloatArray:
        """The displacement ``(N,)`` (m) of ``K u = f`` with the clamped degrees of freedom at zero."""
        return solve(*condense(self.stiffness, f, D=self.clamped_dofs))

    def equilibrium(self, f: FloatArray, increments: int = 10, tolerance: float = 1e-10,
                    max_iterations: int = 30) -> FloatArray:
        """The static displacement ``(N,)`` (m) of the body's own model under the dead load ``f``
        (N): ``f_int(u) = f`` with the clamped degrees of freedom at zero.

        For the linear model this is :meth:`static`. For a total-Lagrangian model, Newton's method
        on the scikit-fem reference forms of :mod:`mlsgalerkin.structure.hyperelastic` (internal
        force and tangent stiffness), with the load applied in ``increments`` equal parts; each
        increment converges when the largest Newton correction is below ``tolerance`` times the
        largest displacement (raises ``RuntimeError`` after ``max_iterations``). For checks and
        quasi-static comparisons, not a run's step."""
        if self.model == "linear":
            return self.static(f)
        from mlsgalerkin.structure import hyperelastic

        lam, mu = self.material.lame(self.dim)     # plane strain in 2D: the constructor refuses plane stress
        f = np.asarray(f, dtype=float)
        u = np.zeros(self.n_dofs)
        for k in range(1, int(increments) + 1):
            load = f * (k / increments)
            for _ in range(max_iterations):
                r = load - hyperelastic.internal_force_reference(self.basis, u, lam, mu, self.model)
                K = hyperelastic.tangent_stiffness_reference(self.basis, u, lam, mu, self.model)
                du = solve(*condense(K, r, D=self.clamped_dofs))
                u += du
                if np.abs(du).max() <= tolerance * max(np.abs(u).max(), 1e-300):
                    break
            else:
                raise RuntimeError(f"ElasticBody {self.name!r}: Newton did not converge in {max_iterations} "
                                   f"iterations at load increment {k}/{increments}; use more increments")
        return u

    def displacement_at(self, points: FloatArray, u: FloatArray | None = None) -> FloatArray:
        """Displacement ``(n, d)`` at ``points (d, n)`` (m) of the displacement ``u (N,)``,
        interpolated with the element's shape functions."""
        P = self.basis.probes(np.asarray(points, dtype=float))
        return (P @ self._displacement(u)).reshape(self.dim, -1).T

    def point_displacements(self, u: FloatArray) -> dict[str, FloatArray]:
        """Displacement ``(d,)`` (m) of each named point."""
        if self._probes is None:
            return {}
        d = (self._probes @ u).reshape(self.dim, -1)
        return {k: d[:, i] for i, k in enumerate(self.points)}

    def vertex_displacement(self, vertices: NDArray[np.int64], u: FloatArray | None = None) -> FloatArray:
        """Displacement ``(k, d)`` (m) of the mesh vertices ``vertices`` (their nodal degrees of
        freedom) of the displacement ``u (N,)``."""
        return self._displacement(u)[self.basis.nodal_dofs[:, vertices]].T

    def surface(self, facets: Predicate | None = None, u: FloatArray | None = None) -> ContactSurface:
        """The boundary facets where ``facets(x)`` is true (all if ``None``) in the configuration
        displaced by ``u (N,)`` (at rest if ``None``), as an oriented
        :class:`~mlsgalerkin.contact.ContactSurface` (normals out of the body)."""
        mesh = self.mesh
        chosen = mesh.boundary_facets() if facets is None else mesh.facets_satisfying(facets, boundaries_only=True)
        return wet_surface(self.basis, np.asarray(chosen, dtype=np.int64)).contact_surface(self._displacement(u))

    def internal_force(self, u: FloatArray | None = None) -> FloatArray:
        """``K u`` ``(N,)`` in N (per unit depth) of the displacement ``u (N,)``, zero on the clamped
        degrees of freedom."""
        f = self.stiffness @ self._displacement(u)
        f[self.clamped_dofs] = 0.0
        return f

    def kinetic_energy(self, v: FloatArray) -> float:
        """``½ vᵀ M v`` (J per unit depth) of the velocity ``v (N,)`` (m/s)."""
        return 0.5 * float(np.dot(self.lumped_mass * v, v))

    def strain_energy(self, u: FloatArray) -> float:
        """``½ uᵀ K u`` (J per unit depth) of the displacement ``u (N,)`` (m), small strain."""
        return 0.5 * float(u @ (self.stiffness @ u))

    def highest_frequency(self) -> float:
        """``ω_max`` (rad/s): the square root of the largest eigenvalue of ``M⁻¹K`` over the free
        degrees of freedom (scipy ``eigsh`` from a fixed start vector: the same in every process)."""
        free = self.free
        s = 1.0 / np.sqrt(self.lumped_mass[free])
        A = sp.diags(s) @ self.stiffness[free][:, free] @ sp.diags(s)
        return float(np.sqrt(arpack_eigenvalue(A, which="LA", tol=1e-6)))

    def lowest_frequency(self) -> float:
        """``ω₁`` (rad/s) of the clamped body: the smallest eigenvalue of ``M⁻¹K`` over the free
        degrees of freedom (``eigsh`` in shift-invert mode, from a fixed start vector)."""
        free = self.free
        K = self.stiffness[free][:, free]
        M = sp.diags(self.lumped_mass[free])
        return float(np.sqrt(arpack_eigenvalue(K, M=M, sigma=0.0, which="LM")))

    def stable_time_step(self) -> float:
        """``2/ω_max`` (s), the stability limit of undamped central differences."""
        return 2.0 / self.highest_frequency()

    # ------------------------------------------------------------------ deprecated live state
    # A body is a spec: its displacement and velocity in a run belong to its stepper
    # (state.systems["structure"].body(name)); a script keeps its own arrays and passes them.
    _STATELESS = ("ElasticBody.{} is deprecated: a body holds no displacement or velocity. Keep them as arrays "
                  "(n_dofs,) and pass them: displacement_at(points, u), surface(facets, u), internal_force(u), "
                  "kinetic_energy(v), strain_energy(u), mlsgalerkin.structure.explicit.leapfrog_step(body, u, v, "
                  "dt, f_ext); in a run read state.systems['structure'].body(name).u")

    def _legacy_state(self, name: str) -> tuple[FloatArray, FloatArray]:
        """The displacement and velocity a script keeps on the body through the deprecated
        ``u``, ``v``, ``step`` and ``energies`` (made at first use, with a warning)."""
        warnings.warn(self._STATELESS.format(name), DeprecationWarning, stacklevel=3)
        if "_legacy_uv" not in self.__dict__:
            self.__dict__["_legacy_uv"] = (np.zeros(self.n_dofs), np.zeros(self.n_dofs))
        return self.__dict__["_legacy_uv"]

    def _displacement(self, u: FloatArray | None) -> FloatArray:
        """``u``, or without it the displacement a script set through the deprecated ``u`` (zero,
        the body at rest, if it never did)."""
        if u is not None:
            return u
        legacy = self.__dict__.get("_legacy_uv")
        return legacy[0] if legacy is not None else np.zeros(self.n_dofs)

    @property
    def u(self) -> FloatArray:
        """Deprecated: keep the displacement ``(N,)`` yourself and pass it."""
        return self._legacy_state("u")[0]

    @u.setter
    def u(self, value: FloatArray) -> None:
        self._legacy_state("u")[0][:] = value

    @property
    def v(self) -> FloatArray:
        """Deprecated: keep the velocity ``(N,)`` yourself and pass it."""
        return self._legacy_state("v")[1]

    @v.setter
    def v(self, value: FloatArray) -> None:
        self._legacy_state("v")[1][:] = value

    def step(self, dt: float, f_ext: FloatArray | None = None) -> None:
        """Deprecated: :func:`mlsgalerkin.structure.explicit.leapfrog_step` on arrays you keep."""
        from mlsgalerkin.structure.explicit import leapfrog_step

        u, v = self._legacy_state("step()")
        leapfrog_step(self, u, v, dt, f_ext)

    def energies(self, v_full: FloatArray | None = None) -> tuple[float, float]:
        """Deprecated: :meth:`kinetic_energy` and :meth:`strain_energy` of arrays you keep."""
        u, v = self._legacy_state("energies()")
        return self.kinetic_energy(v if v_full is None else v_full), self.strain_energy(u)
