r"""Input sanity for structure bodies, before any work: pure functions over arrays that return the
problems they find as one-line messages (an empty list: nothing wrong), each saying what is wrong
and how to fix it.

**Materials** (:func:`material_problems`). Young's modulus :math:`E` and the density
:math:`\rho_s` positive and finite; Poisson's ratio inside :data:`POISSON_LIMITS` =
``[-0.99, 0.499]``, a margin inside the theoretical ``(-1, 0.5)``. The margin keeps the explicit
step sane and the stiffness usable: the dilatational wave speed, which sets the explicit step
``Δt ∝ h/c_d``, grows as

.. math:: c_d^2 = \frac{\lambda + 2\mu}{\rho_s} = \frac{E}{\rho_s}\,\frac{1-\nu}{(1+\nu)(1-2\nu)},

which is 167 ``E/ρ_s`` at ``ν = 0.499`` (the step 13 times shorter than at ``ν = 0``) and
without bound as ``ν → 0.5`` (``ν = 0.49999999``: 1700 times shorter, hours instead of
seconds); the shear modulus :math:`\mu = E/(2(1+\nu))` grows without bound as ``ν → -1``
(50 ``E`` at ``ν = -0.99``, the step 7 times shorter). Beyond the margin displacement elements
also lock (the bulk-to-shear ratio :math:`K/\mu = 2(1+\nu)/(3(1-2\nu))` is 500 at ``ν = 0.499``).

**Run length** (:func:`explicit_step_estimate`, :func:`substep_problems`). The explicit
(central-difference) step of an elastic body is estimated from its material and its smallest
node spacing :math:`h` (the shortest edge of an element, halved for the quadratic Q2 and Hex2):

.. math:: \omega_{\max} \approx \kappa\,\frac{c_d}{h},\qquad \Delta t_{\rm stable} = \frac{2}{\omega_{\max}},

with :data:`KAPPA` = 3: ``ω_max h/c_d`` measured with ``eigsh`` lies in 2.0–3.3 for Q1, Q2 and
P1 in 2D and Hex1, Hex2 and P1 in 3D, ``ν`` from 0 to 0.499. A run sub-cycles at about half that
step (:data:`SUBSTEP_FRACTION`: the safety factor times the reduction by the damping of the
highest mode), so it takes about ``t_end/(0.5 Δt_stable)`` sub-steps; above
:data:`MAX_STRUCTURE_SUBSTEPS` (10⁷, about ten times the longest shipped run) the run is refused
with the fix named. A hinged rigid body sub-cycles at ``ω_n δt = 0.05``, a spinning free body at
``|ω| δt = 0.05``: ``t_end ω/0.05`` sub-steps.

**Mesh size** (:func:`element_limit`, :func:`mesh_size_problems`). A mesh of more elements than
the current limit (``mlsgalerkin run --max-elements``, default
:data:`mlsgalerkin.problem.DEFAULT_MAX_ELEMENTS`) is refused
before scikit-fem assembles it (a 2D Q2 element costs about 10 kB and 2 ms to assemble, a 3D
Hex2 element about 160 kB). Shipped problems estimate their element count from their parameters in
``check(params)``, before the mesh is built.

**Elements** (:func:`element_problems`). A node with a NaN or infinite coordinate; an element
whose Jacobian determinant :math:`\det J` is zero (below :data:`JACOBIAN_TOLERANCE` times its
longest edge to the power ``d``) at a vertex or a quadrature point (degenerate: zero area or
volume); an element whose :math:`\det J` changes sign inside it (folded, a bow-tie); an element
that lies on the same side of a facet as its neighbour across that facet (inverted: turned inside
out through its neighbours, the mesh overlapping itself). The sign of :math:`\det J` alone is not
the criterion: scikit-fem's own meshes order half their triangles and tetrahedra clockwise, and
integrate with :math:`|\det J|`. The geometry checked is the vertices' (the linear map of the
element).

**Placement** (:func:`placement_problems`, :func:`inside_surface`). The tank is the bounding box
of the scene's fixed and moving wall particles (not those riding on a structure), open above. A
body with less than :data:`INSIDE_FRACTION` of its bounding box inside the tank's box is outside
the tank (or under the floor, if its centre is below the tank's bottom): a body partly inside a
wall (a beam that closes the tank) is not; a closed body surface with fluid
particles inside it overlaps the fluid (its mass would count twice).

**Rotation** (:func:`rotation_operator`). Small-strain (linear) elasticity holds for rotations
well below one radian: at a rotation :math:`\theta` a rigid turn already strains the body by
about :math:`\theta^2/2` (0.5 % at 0.1 rad) and the error grows from there. The structure solver
warns once when a linear body's largest element rotation
:math:`\theta = \tfrac12|\nabla\times\mathbf u|` exceeds :data:`LINEAR_ROTATION_LIMIT` = 0.1 rad.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any

import numpy as np
import scipy.sparse as sp
from numpy.typing import NDArray
from skfem import ElementHex1, ElementQuad1, ElementTetP1, ElementTriP1

from mlsgalerkin.limits import current_element_limit, element_limit

__all__ = [
    "BYTES_PER_ELEMENT", "INSIDE_FRACTION", "JACOBIAN_TOLERANCE", "KAPPA", "LINEAR_ROTATION_LIMIT",
    "MAX_STRUCTURE_SUBSTEPS", "POISSON_LIMITS", "SUBSTEP_FRACTION", "LargeRotationWarning", "dilatational_speed",
    "element_limit", "element_problems", "explicit_step_estimate", "explicit_substep_problems", "inside_surface",
    "material_problems", "mesh_size_problems", "node_spacing", "placement_problems", "poisson_problems",
    "rotation_operator", "rotation_warning", "structure_scene_problems", "substep_estimate", "substep_problems",
]

FloatArray = NDArray[np.float64]

#: Poisson's ratio allowed (closed interval), a margin inside ``(-1, 0.5)`` (module docstring).
POISSON_LIMITS = (-0.99, 0.499)
#: Bytes per element while scikit-fem assembles the stiffness and mass (COO triplets of the
#: element matrices, 24 bytes per entry, twice), by element name (P1: the tetrahedron's).
BYTES_PER_ELEMENT = {"Q1": 4_000, "Q2": 16_000, "P1": 7_000, "Hex1": 28_000, "Hex2": 320_000}
#: ``ω_max h / c_d`` of the explicit step estimate (measured 2.0–3.3; module docstring).
KAPPA = 3.0
#: The sub-step a run takes as a fraction of ``2/ω_max`` (0.9 safety × 0.62 from the default
#: damping of the highest mode).
SUBSTEP_FRACTION = 0.5
#: The most structure sub-steps a run may take to ``t_end`` (one body).
MAX_STRUCTURE_SUBSTEPS = 10_000_000
#: ``ω δt`` of a rigid body's sub-steps (the integrator's rule, rad).
RIGID_PHASE = 0.05
#: ``|det J|`` below this times (longest edge)^d is a degenerate element.
JACOBIAN_TOLERANCE = 1e-10
#: A body with less than this share of its bounding box inside the tank's box is outside it.
INSIDE_FRACTION = 0.1
#: Largest element rotation (rad) of a linear elastic body before the solver warns.
LINEAR_ROTATION_LIMIT = 0.1

#: The geometric (vertex) element of a mesh by (dimension, vertices per element).
_GEOMETRY = {(2, 3): ElementTriP1, (2, 4): ElementQuad1, (3, 4): ElementTetP1, (3, 8): ElementHex1}


class LargeRotationWarning(UserWarning):
    """A linear (small-strain) elastic body turned through more than :data:`LINEAR_ROTATION_LIMIT`."""


# ------------------------------------------------------------------ materials
def material_problems(young: float, poisson: float, density: float, owner: str = "ElasticMaterial") -> list[str]:
    """Problems with an elastic material: ``young`` (Pa) and ``density`` (kg/m³) positive and
    finite, ``poisson`` (–) within :data:`POISSON_LIMITS` (module docstring: why the margin)."""
    out = []
    for what, value, unit in (("young", young, "Pa"), ("density", density, "kg/m³")):
        if not (_real(value) and math.isfinite(value) and value > 0):
            out.append(f"{owner}: {what} must be a positive, finite number ({unit}), got {value!r}")
    return out + poisson_problems(poisson, owner)


def poisson_problems(poisson: float, owner: str = "ElasticMaterial") -> list[str]:
    """``[message]`` if Poisson's ratio ``poisson`` (–) lies outside :data:`POISSON_LIMITS`."""
    lo, hi = POISSON_LIMITS
    if _real(poisson) and lo <= poisson <= hi:
        return []
    return [f"{owner}: poisson must be in [{lo}, {hi}], got {poisson!r}; closer to 0.5 (or -1) the explicit step "
            f"shrinks without bound and displacement elements lock (nearly incompressible rubber: use {hi})"]


def _real(value: Any) -> bool:
    return isinstance(value, (int, float, np.integer, np.floating)) and not isinstance(value, bool)


def dilatational_speed(young: float, poisson: float, density: float, *, dim: int = 2, plane: str = "strain") -> float:
    """``c_d = sqrt((λ + 2μ)/ρ)`` (m/s), with the plane-stress ``λ* = 2λμ/(λ + 2μ)`` for a 2D
    body in plane stress."""
    mu = young / (2.0 * (1.0 + poisson))
    lam = young * poisson / ((1.0 + poisson) * (1.0 - 2.0 * poisson))
    if dim == 2 and plane == "stress":
        lam = 2.0 * lam * mu / (lam + 2.0 * mu)
    return math.sqrt((lam + 2.0 * mu) / density)


# ------------------------------------------------------------------ run length
def explicit_step_estimate(young: float, poisson: float, density: float, spacing: float, *, dim: int = 2,
                           plane: str = "strain") -> float:
    """The central-difference stability limit ``2/ω_max`` (s) estimated as
    ``2 h/(κ c_d)`` for the smallest node spacing ``spacing`` = ``h`` (m) (module docstring)."""
    return 2.0 * spacing / (KAPPA * dilatational_speed(young, poisson, density, dim=dim, plane=plane))


def substep_problems(owner: str, t_end: float, substep: float, fix: str) -> list[str]:
    """``[message]`` if ``t_end/substep`` sub-steps (``substep`` in s) exceed
    :data:`MAX_STRUCTURE_SUBSTEPS`; ``fix`` names the way out."""
    if not (substep > 0 and math.isfinite(t_end)):
        return []
    n = t_end / substep
    if n <= MAX_STRUCTURE_SUBSTEPS:
        return []
    return [f"{owner}: its stable step is about {substep:.3g} s, so {t_end:g} s of simulated time take about {n:.3g} "
            f"structure sub-steps, above the limit of {MAX_STRUCTURE_SUBSTEPS:.0e} (hours to days of work): {fix}"]


def explicit_substep_problems(owner: str, young: float, poisson: float, density: float, spacing: float,
                              t_end: float, *, dim: int = 2, plane: str = "strain") -> list[str]:
    """:func:`substep_problems` of an explicit elastic body from its material and smallest node
    spacing ``spacing`` (m) (for a problem's ``check``, before the mesh is built)."""
    if material_problems(young, poisson, density) or not spacing > 0:
        return []
    step = SUBSTEP_FRACTION * explicit_step_estimate(young, poisson, density, spacing, dim=dim, plane=plane)
    return substep_problems(owner, t_end, step, "lower young, raise density or the element size (fewer elements), "
                                                "shorten t_end, or use integrator='newmark' (linear model)")


# ------------------------------------------------------------------ mesh size
def mesh_size_problems(n_elements: float, what: str, limit: int | None = None) -> list[str]:
    """``[message]`` if a mesh of ``n_elements`` elements exceeds ``limit`` (default: the current
    :func:`element_limit`); ``what`` names the mesh."""
    limit = current_element_limit() if limit is None else limit
    if limit is None or n_elements <= limit:
        return []
    return [f"{what} would have {n_elements:,.0f} elements, above the limit of {limit:,}; use fewer elements, or "
            "raise the limit (--max-elements) if the machine has the memory and the time"]


def node_spacing(p: FloatArray, t: NDArray[np.int64], quadratic: bool = False) -> float:
    """The smallest distance (m) between two vertices of one element, halved for a quadratic
    element (Q2, Hex2: a mid-side node between); ``p (d, n)`` nodes, ``t (m, k)`` elements."""
    m = t.shape[0]
    h = math.inf
    for i in range(m):
        for j in range(i + 1, m):
            h = min(h, float(np.linalg.norm(p[:, t[i]] - p[:, t[j]], axis=0).min()))
    return 0.5 * h if quadratic else h


# ------------------------------------------------------------------ elements
def element_problems(p: FloatArray, t: NDArray[np.int64], facets: NDArray[np.int64] | None = None,
                     f2t: NDArray[np.int64] | None = None, owner: str = "mesh") -> list[str]:
    """Non-finite nodes and degenerate, folded or inverted elements of the mesh with nodes
    ``p (d, n)`` (m) and elements ``t (m, k)`` (the first vertices of each column used), with its
    facets ``facets (d or 4, f)`` and their elements ``f2t (2, f)`` (``-1``: a boundary facet;
    scikit-fem's ``mesh.facets``, ``mesh.f2t``) for the inversion test (module docstring). Names
    the first element (or node) at fault and how many there are."""
    d = p.shape[0]
    bad_nodes = np.flatnonzero(~np.isfinite(p).all(axis=0))
    if bad_nodes.size:
        k = int(bad_nodes[0])
        users = np.flatnonzero((t == k).any(axis=0))
        used = f", used by element {int(users[0])}" if users.size else ""
        return [f"{owner}: node {k} has a NaN or infinite coordinate {p[:, k].tolist()}{used} "
                f"({bad_nodes.size} such node{'s' if bad_nodes.size > 1 else ''}); give finite positions (m)"]
    geometry = _GEOMETRY.get((d, min(t.shape[0], 8 if d == 3 else 4)))
    if geometry is None:
        return []
    nv = 3 if geometry is ElementTriP1 else 4 if geometry in (ElementQuad1, ElementTetP1) else 8
    t = t[:nv]
    chunks = [_jacobians(p, t[:, s:s + 20_000], geometry()) for s in range(0, t.shape[1], 20_000)]
    det, size = np.concatenate([c[0] for c in chunks]), np.concatenate([c[1] for c in chunks])
    tol = JACOBIAN_TOLERANCE * size ** d
    folded = np.flatnonzero((det > tol[:, None]).any(axis=1) & (det < -tol[:, None]).any(axis=1))
    if folded.size:
        e = int(folded[0])
        return [f"{owner}: element {e} is folded (its Jacobian determinant changes sign inside it: a bow-tie or a "
                f"vertex pushed through an edge; vertices {t[:, e].tolist()}); {folded.size} such element"
                f"{'s' if folded.size > 1 else ''}: order each element's vertices around it, or re-mesh"]
    degenerate = np.flatnonzero((np.abs(det) <= tol[:, None]).any(axis=1))
    if degenerate.size:
        e = int(degenerate[0])
        return [f"{owner}: element {e} is degenerate (zero {'area' if d == 2 else 'volume'}: its Jacobian determinant "
                f"is {np.abs(det[e]).min():.3g} at a vertex or quadrature point; vertices {t[:, e].tolist()} at "
                f"{np.round(p[:, t[:, e]].T, 9).tolist()}); {degenerate.size} such element"
                f"{'s' if degenerate.size > 1 else ''}: remove repeated or collinear nodes, or re-mesh"]
    if facets is None or f2t is None:
        return []
    inner = np.flatnonzero(f2t[1] >= 0)
    if inner.size == 0:
        return []
    a, b = f2t[0, inner], f2t[1, inner]
    x0 = p[:, facets[0, inner]]
    if d == 2:
        tangent = p[:, facets[1, inner]] - x0
        normal = np.stack([tangent[1], -tangent[0]])
    else:
        normal = np.cross(p[:, facets[1, inner]] - x0, p[:, facets[2, inner]] - x0, axis=0)
    centre = p[:, t].mean(axis=1)                                        # (d, k)
    side_a = np.einsum("dk,dk->k", normal, centre[:, a] - x0)
    side_b = np.einsum("dk,dk->k", normal, centre[:, b] - x0)
    wrong = side_a * side_b >= 0
    if not wrong.any():
        return []
    count = np.bincount(np.concatenate([a[wrong], b[wrong]]), minlength=t.shape[1])
    e = int(np.argmax(count))
    return [f"{owner}: element {e} is inverted (it lies on the same side of {int(count[e])} of its facets as the "
            f"neighbour across it: the mesh overlaps itself there; vertices {t[:, e].tolist()}); "
            f"{int(np.count_nonzero(count))} elements touch such facets: move its nodes back or re-mesh"]


def _jacobians(p: FloatArray, t: NDArray[np.int64], element: Any) -> tuple[FloatArray, FloatArray]:
    """``det J`` ``(k, q)`` of the vertex map of each element at its vertices and the points of a
    degree-4 Gauss rule, and each element's longest vertex–vertex distance ``(k,)`` (m)."""
    from skfem.quadrature import get_quadrature

    X = np.concatenate([np.asarray(element.doflocs, dtype=float).T, get_quadrature(element.refdom, 4)[0]], axis=1)
    d, nv = p.shape[0], t.shape[0]
    J = np.zeros((t.shape[1], X.shape[1], d, d))
    for i in range(nv):
        grad = element.lbasis(X, i)[1]                                    # (d, q) reference gradient
        J += np.einsum("ak,bq->kqab", p[:, t[i]], grad)
    size = np.zeros(t.shape[1])
    for i in range(nv):
        for j in range(i + 1, nv):
            size = np.maximum(size, np.linalg.norm(p[:, t[i]] - p[:, t[j]], axis=0))
    return np.linalg.det(J), size


# ------------------------------------------------------------------ placement
def placement_problems(owner: str, nodes: FloatArray, tank: tuple[FloatArray, FloatArray]) -> list[str]:
    """``[message]`` if less than :data:`INSIDE_FRACTION` of the bounding box of ``nodes (n, d)``
    (m) lies inside the box ``tank = (lower, upper)`` (m) open above (the last axis is up: a body
    above the walls' top, dropped from a height, is in the tank); "under the floor" if the body's
    centre is below the tank's bottom."""
    lo, hi = nodes.min(axis=0), nodes.max(axis=0)
    t_lo, t_hi = tank
    t_hi = np.append(t_hi[:-1], math.inf)
    extent = hi - lo
    overlap = np.clip(np.minimum(hi, t_hi) - np.maximum(lo, t_lo), 0.0, None)
    # a flat (zero-extent) direction counts as inside when it lies within the tank's range
    share = np.where(extent > 0, overlap / np.where(extent > 0, extent, 1.0), (lo >= t_lo) & (hi <= t_hi))
    inside = float(np.prod(share))
    if inside >= INSIDE_FRACTION:
        return []
    box = f"[{_fmt(lo)} .. {_fmt(hi)}] m"
    tank_box = f"[{_fmt(t_lo)} .. {_fmt(tank[1])}] m, open above"
    if 0.5 * (lo[-1] + hi[-1]) < t_lo[-1]:
        return [f"{owner} lies under the floor: its box {box} is below the tank's bottom at {t_lo[-1]:g} m (the tank's "
                f"walls span {tank_box}); move it up into the tank"]
    return [f"{owner} lies outside the tank: only {100 * inside:.0f} % of its box {box} is inside the box of the "
            f"tank's walls {tank_box}; move it into the tank (check its position and size parameters and units)"]


def _fmt(x: FloatArray) -> str:
    return ", ".join(f"{v:.4g}" for v in x)


def inside_surface(points: FloatArray, nodes: FloatArray, facets: NDArray[np.int64],
                   chunk: int = 500_000) -> NDArray[np.bool_]:
    """Which ``points (n, d)`` lie inside the closed surface of ``nodes (m, d)`` and ``facets
    (k, d)`` (2D segments, 3D triangles), by the winding number ``w = Σ θ/2π`` (2D: the angle
    each segment subtends) or ``w = Σ Ω/4π`` (3D: the solid angle of each triangle, Van
    Oosterom & Strackee 1983): inside where ``|w| > 1/2`` (either orientation)."""
    out = np.zeros(points.shape[0], dtype=bool)
    if points.shape[0] == 0:
        return out
    lo, hi = nodes.min(axis=0), nodes.max(axis=0)
    candidates = np.flatnonzero(np.all((points >= lo) & (points <= hi), axis=1))
    d = nodes.shape[1]
    step = max(1, chunk // max(1, facets.shape[0]))
    for s in range(0, candidates.size, step):
        idx = candidates[s:s + step]
        r = nodes[facets][None, :, :, :] - points[idx][:, None, None, :]        # (c, k, d, d)
        if d == 2:
            a, b = r[:, :, 0], r[:, :, 1]
            angle = np.arctan2(a[..., 0] * b[..., 1] - a[..., 1] * b[..., 0], np.einsum("ckd,ckd->ck", a, b))
            w = angle.sum(axis=1) / (2.0 * math.pi)
        else:
            a, b, c = r[:, :, 0], r[:, :, 1], r[:, :, 2]
            la, lb, lc = (np.linalg.norm(v, axis=-1) for v in (a, b, c))
            triple = np.einsum("ckd,ckd->ck", a, np.cross(b, c))
            den = (la * lb * lc + np.einsum("ckd,ckd->ck", a, b) * lc + np.einsum("ckd,ckd->ck", a, c) * lb
                   + np.einsum("ckd,ckd->ck", b, c) * la)
            w = (2.0 * np.arctan2(triple, den)).sum(axis=1) / (4.0 * math.pi)
        out[idx] = np.abs(w) > 0.5
    return out


def _closed(facets: NDArray[np.int64]) -> bool:
    """Every node (2D) or edge (3D) of the facets is shared by exactly two facets."""
    if facets.shape[1] == 2:
        counts = np.bincount(facets.ravel())
        return bool(np.all(counts[counts > 0] == 2))
    edges = np.sort(np.concatenate([facets[:, [0, 1]], facets[:, [1, 2]], facets[:, [2, 0]]]), axis=1)
    _, counts = np.unique(edges, axis=0, return_counts=True)
    return bool(np.all(counts == 2))


def overlap_problems(owner: str, nodes: FloatArray, facets: NDArray[np.int64], particles: FloatArray,
                     fluid: str) -> list[str]:
    """``[message]`` if particles ``(n, d)`` of the fluid body ``fluid`` lie inside the closed
    surface (``nodes``, ``facets``) of a structure (nothing to say for an open surface)."""
    if not _closed(facets):
        return []
    inside = np.flatnonzero(inside_surface(particles, nodes, facets))
    if inside.size == 0:
        return []
    first = particles[inside[0]]
    many = "s" if inside.size > 1 else ""
    return [f"{owner} overlaps the fluid: {inside.size} particle{many} of {fluid!r} lie inside "
            f"it (the first at [{_fmt(first)}] m), so their mass would count twice; leave the structure's space out "
            "of the fluid block, or move the structure"]


# ------------------------------------------------------------------ rotation
def rotation_operator(basis: Any) -> sp.csr_matrix:
    """The sparse operator ``R`` (``(k, N)`` in 2D, ``(3k, N)`` in 3D) that maps the
    displacement ``u`` of the vector scikit-fem ``basis`` to each element's mean rotation
    ``½ ∇×u`` (rad, small rotations; 3D: the three components of element ``e`` at rows ``e``,
    ``k + e``, ``2k + e``): the element integral of the curl against a piecewise-constant test
    function, divided by the element's area or volume."""
    from skfem import BilinearForm, CellBasis, asm
    from skfem.element import ElementHex0, ElementQuad0, ElementTetP0, ElementTriP0

    mesh = basis.mesh
    d = mesh.p.shape[0]
    zero = {(2, 3): ElementTriP0, (2, 4): ElementQuad0, (3, 4): ElementTetP0, (3, 8): ElementHex0}[(d, mesh.t.shape[0])]
    cells = CellBasis(mesh, zero(), quadrature=basis.quadrature)

    @BilinearForm
    def volume(u, v, w):
        return u * v

    area = np.asarray(asm(volume, cells, cells).diagonal()).ravel()

    def curl(i: int, j: int) -> Any:
        @BilinearForm
        def form(u, v, w):
            return 0.5 * (u.grad[j][i] - u.grad[i][j]) * v
        return form

    pairs = [(0, 1)] if d == 2 else [(1, 2), (2, 0), (0, 1)]
    rows = [sp.diags(1.0 / area) @ asm(curl(i, j), basis, cells) for i, j in pairs]
    return sp.vstack(rows).tocsr()


def rotation_warning(owner: str, operator: sp.spmatrix, u: FloatArray, dim: int, t: float) -> str | None:
    """The warning for a linear body whose largest element rotation ``|R u|`` (rad; 3D: the norm
    of the three components; ``operator`` from :func:`rotation_operator`) exceeds
    :data:`LINEAR_ROTATION_LIMIT` at time ``t`` (s), else ``None``."""
    r = operator @ u
    theta = float(np.abs(r).max()) if dim == 2 else float(np.linalg.norm(r.reshape(3, -1), axis=0).max())
    if not theta > LINEAR_ROTATION_LIMIT:
        return None
    return (f"{owner}: an element has turned {theta:.3g} rad at t = {t:.4g} s, beyond {LINEAR_ROTATION_LIMIT:g} rad, "
            "where small-strain (linear) elasticity is wrong (a rigid turn alone strains it by θ²/2); use "
            "model='neo_hookean' or 'stvenant_kirchhoff' (explicit integrator) for large rotations")


# ------------------------------------------------------------------ a scene's structures
def _is_fluid(body: Any) -> bool:
    return hasattr(body, "phases") and getattr(body, "positions", None) is not None


def _is_tank_wall(body: Any) -> bool:
    """Wall particles that stand still or move by a prescribed motion (not riding on a structure)."""
    return (not hasattr(body, "phases") and getattr(body, "positions", None) is not None
            and hasattr(body, "normals") and getattr(body, "follows", None) is None)


def structure_scene_problems(bodies: Sequence[Any], others: Sequence[Any], t_end: float | None = None) -> list[str]:
    """Problems of the structure ``bodies`` (``ElasticBody``, ``RigidBody``) in a scene whose
    other bodies are ``others``: outside the tank or under its floor, overlapping a fluid body's
    particles, and (with ``t_end``, s) more sub-steps than :data:`MAX_STRUCTURE_SUBSTEPS`
    (module docstring)."""
    walls = [np.asarray(b.positions, dtype=float) for b in others if _is_tank_wall(b) and len(b.positions)]
    fluids = [(b.name, np.asarray(b.positions, dtype=float)) for b in others if _is_fluid(b)]
    tank = None
    if walls:
        x = np.concatenate(walls)
        tank = (x.min(axis=0), x.max(axis=0))
    out: list[str] = []
    for body in bodies:
        owner = f"{type(body).__name__} {body.name!r}"
        outline = _outline(body)
        if outline is None:
            continue
        nodes, facets = outline
        if tank is not None and tank[0].shape == nodes.shape[1:]:
            out += placement_problems(owner, nodes, tank)
        for name, x in fluids:
            if x.ndim == 2 and x.shape[1] == nodes.shape[1]:
                out += overlap_problems(owner, nodes, facets, x, name)
        if _real(t_end) and math.isfinite(t_end) and t_end > 0:
            out += _run_length_problems(owner, body, float(t_end))
    return out


def _outline(body: Any) -> tuple[FloatArray, NDArray[np.int64]] | None:
    """The nodes ``(n, d)`` and oriented boundary facets of a structure body at rest (an elastic
    body's whole boundary, a rigid body's surface)."""
    surface = body.surface() if callable(getattr(body, "surface", None)) else getattr(body, "surface", None)
    if surface is None or not hasattr(surface, "nodes"):
        return None
    return np.asarray(surface.nodes, dtype=float), np.asarray(surface.facets, dtype=np.int64)


def substep_estimate(body: Any) -> float | None:
    """The sub-step (s) a run of the structure ``body`` is estimated to take (module docstring):
    ``SUBSTEP_FRACTION · 2h/(κ c_d)`` for an explicit elastic body, ``0.05/ω`` for a hinged
    (``ω_n``) or spinning (``|ω|``) rigid body; ``None`` where the step is the outer one (Newmark,
    a rigid body at rest without a spring)."""
    mesh = getattr(body, "mesh", None)
    if mesh is not None:
        if getattr(body, "integrator", "explicit") != "explicit":
            return None
        m = body.material
        spacing = node_spacing(mesh.p, mesh.t, quadratic=body.element in ("Q2", "Hex2"))
        if not spacing > 0:
            return None
        return SUBSTEP_FRACTION * explicit_step_estimate(m.young, m.poisson, m.density, spacing,
                                                         dim=mesh.p.shape[0], plane=m.plane)
    omega = 0.0
    if hasattr(getattr(body, "constraint", None), "stiffness"):               # a Hinge
        omega = math.sqrt(max(body.natural_frequency_squared(), 0.0))
    spin = float(np.linalg.norm(np.atleast_1d(getattr(body, "angular_velocity", 0.0))))
    omega = max(omega, spin)
    return RIGID_PHASE / omega if omega > 0 else None


def _run_length_problems(owner: str, body: Any, t_end: float) -> list[str]:
    step = substep_estimate(body)
    if step is None:
        return []
    if getattr(body, "mesh", None) is not None:
        fix = ("lower young, raise the element size (fewer elements), shorten t_end, or use integrator='newmark' "
               "(linear model)")
    else:
        fix = "lower the hinge stiffness or the spin, or raise the inertia (check the units: N m/rad, kg m², rad/s)"
    return substep_problems(owner, t_end, step, fix)
