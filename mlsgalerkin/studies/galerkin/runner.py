r"""One measured Galerkin solve: discretise, assemble, solve, measure the error, time each phase.

A :class:`SolveSpec` names everything that defines one point of the study (problem, rule,
polynomial basis, kernel, support radius over spacing, spacing, node layout, boundary
condition). :func:`measure` runs it and returns one CSV row with the errors and the wall time
split into

``wall_shape_s``
    building the shape functions the solve needs: the nodal rule (clipped Voronoi cells, shape
    functions at the nodes, SCNI edge smoothing or the VCI correction) and the boundary
    quadratures (their Voronoi cells and shape functions);
``wall_assembly_s``
    stiffness, load vector, Nitsche/penalty and traction terms, and their sum;
``wall_solve_s``
    sparse LU factorisation and solve (SuperLU, ``permc_spec="MMD_ATA"``, the fastest of
    SuperLU's orderings on these matrices).

``wall_s`` is their sum. The error evaluation (shape functions on the background Gauss grid) is
timed separately (``wall_error_s``) and not part of the cost of a solution.

Rules
-----
``"dni"``   direct nodal integration (Voronoi volumes, direct gradients);
``"scni"``  stabilised conforming nodal integration (smoothed gradients);
``"vci"``   DNI trial functions with variationally consistent test gradients
            (:mod:`.vci`, Petrov–Galerkin, unsymmetric stiffness).

Essential conditions use symmetric Nitsche (``β = 100``, modulus ``E`` for elasticity) or
penalty (``β = 1e4``) on the boundary Gauss points of the rule's Voronoi cell edges. The flux
in Nitsche's terms uses the *rule's* gradient at the nearest integration point
(``gradients="rule"`` of :func:`~mlsgalerkin.integration.boundary_basis`) for every rule; see
:data:`BOUNDARY_GRADIENTS` for why.
"""

from __future__ import annotations

import logging
import math
import time
from dataclasses import asdict, dataclass
from typing import Any

import numpy as np

from mlsgalerkin.analysis import ErrorNorms, rectangle_quadrature
from mlsgalerkin.basis import MeshfreeBasis
from mlsgalerkin.integration import BoundaryBasis, boundary_basis, meshfree_basis
from mlsgalerkin.kernels import get_kernel
from mlsgalerkin.models import (
    elasticity,
    neumann_load,
    nitsche,
    nitsche_inverse_constant,
    penalty,
    poisson,
)
from mlsgalerkin.studies.galerkin.problems import Problem, get_problem, node_grid
from mlsgalerkin.integration.vci import vci_test_basis

__all__ = [
    "SolveSpec",
    "Discretisation",
    "discretise",
    "measure",
    "spectrum",
    "RULES",
    "RULE_LABELS",
    "BASES",
    "BCS",
    "NITSCHE_BETA",
    "PENALTY_BETA",
    "BOUNDARY_GRADIENTS",
]

logger = logging.getLogger(__name__)

RULES = ("dni", "scni", "vci")
#: How the rules are named in tables and figures.
RULE_LABELS = {"dni": "DNI", "scni": "SCNI", "vci": "VCI",
               "vci_constant": "VCI (constant profile)"}
#: Extra rule names a spec accepts: VCI with the constant correction profile (ablation).
EXTRA_RULES = ("vci_constant",)
BASES = ("linear", "quadratic")
BCS = ("nitsche", "penalty")
NITSCHE_BETA = 100.0
PENALTY_BETA = 1e4
#: Gradient used in Nitsche's flux terms. "rule" (the rule's gradient at the nearest
#: integration point) keeps the inverse constant C_I of every rule O(1) whatever the support
#: radius, so β = 100 stays coercive (the h-sweep records C_I); with exact ("direct")
#: boundary gradients C_I grows with the support radius and exceeds β/2 on quadratic bases.
BOUNDARY_GRADIENTS = "rule"
#: Profile of the VCI gradient correction (see :mod:`.vci`).
VCI_CORRECTION = "shape"
#: Background Gauss points per direction in each error-quadrature cell (one cell per spacing).
ERROR_GAUSS = 4


@dataclass(frozen=True)
class SolveSpec:
    """One point of the study.

    ``support_ratio`` is the support radius over the nodal spacing, ``κ h / Δx`` (``κ`` the
    kernel's support in units of ``h``), so that kernels are compared at equal support radius.
    """

    problem: str
    rule: str
    basis: str
    kernel: str
    support_ratio: float
    spacing: float
    nodes: str = "regular"
    bc: str = "nitsche"
    seed: int = 0

    def __post_init__(self) -> None:
        if self.rule not in RULES + EXTRA_RULES:
            raise ValueError(f"unknown rule {self.rule!r}; choose one of "
                             f"{', '.join(RULES + EXTRA_RULES)}")
        if self.basis not in BASES:
            raise ValueError(f"unknown basis {self.basis!r}; choose one of {', '.join(BASES)}")
        if self.bc not in BCS:
            raise ValueError(f"unknown bc {self.bc!r}; choose one of {', '.join(BCS)}")
        get_kernel(self.kernel)
        if not (self.support_ratio > 0 and self.spacing > 0):
            raise ValueError("support_ratio and spacing must be positive")

    @property
    def dilation(self) -> float:
        """``h`` in units of the spacing, ``support_ratio / κ``."""
        return self.support_ratio / get_kernel(self.kernel).support

    @property
    def h(self) -> float:
        return self.dilation * self.spacing


@dataclass
class Discretisation:
    """Trial and test bases of one rule, and the boundary quadratures of the problem.

    ``test is trial`` except for VCI. ``dirichlet`` / ``neumann`` are None when the problem has
    no such edges.
    """

    trial: MeshfreeBasis
    test: MeshfreeBasis
    dirichlet: BoundaryBasis | None
    neumann: BoundaryBasis | None

    @property
    def symmetric(self) -> bool:
        return self.test is self.trial


def discretise(problem: Problem, nodes: np.ndarray, spec: SolveSpec) -> Discretisation:
    """Build the rule's bases and the boundary quadratures (the "shape" phase)."""
    dom = problem.domain
    # fallbacks to a lower order are counted from the tables (n_fallback column) instead of
    # being logged and warned at every one of the many tables a sweep builds
    kw = dict(kernel=spec.kernel, basis=spec.basis, on_fallback="ignore")
    vci = spec.rule.startswith("vci")
    base_rule = "dni" if vci else spec.rule
    trial = meshfree_basis(nodes, spec.h, rule=base_rule, domain=dom,
                           n_components=problem.n_components, **kw)
    correction = "constant" if spec.rule == "vci_constant" else VCI_CORRECTION
    test = vci_test_basis(trial, dom, correction=correction) if vci else trial
    bd = (boundary_basis(trial, dom, edges=problem.dirichlet_edges,
                         gradients=BOUNDARY_GRADIENTS) if problem.dirichlet_edges else None)
    bn = (boundary_basis(trial, dom, edges=problem.neumann_edges, gradients="direct")
          if problem.neumann_edges else None)
    return Discretisation(trial, test, bd, bn)


def _stiffness(problem: Problem, d: Discretisation):
    test = None if d.symmetric else d.test
    if problem.is_vector:
        lam, mu = problem.lame
        return elasticity.linear_elasticity(lam, mu).assemble(d.trial, test)
    return poisson.laplace.assemble(d.trial, test)


def _flux(problem: Problem):
    if problem.is_vector:
        return elasticity.stress(*problem.lame)
    return poisson.flux


def assemble(problem: Problem, d: Discretisation, bc: str):
    """System matrix (CSC) and right-hand side (the "assembly" phase)."""
    K = _stiffness(problem, d)
    f = np.zeros(d.trial.n_dofs)
    if problem.source is not None:
        load = (elasticity.body_force(problem.source) if problem.is_vector
                else poisson.source(problem.source))
        f += load.assemble(d.test)
    if d.dirichlet is not None:
        if bc == "nitsche":
            Kb, fb = nitsche(d.dirichlet, problem.exact, flux=_flux(problem),
                             modulus=problem.modulus, beta=NITSCHE_BETA)
        else:
            Kb, fb = penalty(d.dirichlet, problem.exact, modulus=problem.modulus,
                             beta=PENALTY_BETA)
        K = K + Kb
        f += fb
    if d.neumann is not None:
        bn = d.neumann
        f += neumann_load(bn, problem.boundary_flux(bn.points.T, bn.normals.T))
    return K.tocsc(), f


def solve(A, f) -> np.ndarray:
    """Sparse LU solve (the "solve" phase)."""
    from scipy.sparse.linalg import splu

    return splu(A, permc_spec="MMD_ATA").solve(f)


def _once(problem: Problem, nodes: np.ndarray, spec: SolveSpec):
    t0 = time.perf_counter()
    d = discretise(problem, nodes, spec)
    t1 = time.perf_counter()
    A, f = assemble(problem, d, spec.bc)
    t2 = time.perf_counter()
    u = solve(A, f)
    t3 = time.perf_counter()
    return d, u, (t1 - t0, t2 - t1, t3 - t2)


def _rule_gradient_error(problem: Problem, d: Discretisation, u: np.ndarray) -> float:
    """Relative error of the gradient the rule itself uses (smoothed for SCNI, direct for DNI and
    VCI's trial functions) at its integration points, weighted by its weights:
    ``sqrt(Σ_L w_L |∇̃u_h(x_L) − ∇u(x_L)|² / Σ_L w_L |∇u(x_L)|²)``."""
    g = d.trial.interpolate(u).grad
    ge = problem.grad_exact(d.trial.points.T)
    w = d.trial.weights
    num = np.sum(w * ((g - ge) ** 2).reshape(-1, w.size).sum(axis=0))
    den = np.sum(w * (ge**2).reshape(-1, w.size).sum(axis=0))
    return float(np.sqrt(num / den))


def measure(spec: SolveSpec, *, min_time: float = 0.3, max_repeats: int = 3) -> dict[str, Any]:
    """Run ``spec`` and return its CSV row (errors, sizes, diagnostics and the wall-time split).

    Runs shorter than ``min_time`` seconds are repeated (up to ``max_repeats`` in all) and each
    phase keeps its fastest time, which removes most scheduling noise from the small problems.
    """
    problem = get_problem(spec.problem)
    rng = np.random.default_rng(spec.seed)
    nodes = node_grid(problem, spec.spacing, spec.nodes, rng)
    best = None
    total = 0.0
    for _ in range(max(1, max_repeats)):
        d, u, times = _once(problem, nodes, spec)
        best = times if best is None else tuple(min(a, b) for a, b in zip(best, times))
        total += sum(times)
        if total >= min_time:
            break
    t0 = time.perf_counter()
    cells = np.rint(problem.size / spec.spacing).astype(int)
    quad = rectangle_quadrature(problem.lower, problem.upper, tuple(int(c) for c in cells),
                                ERROR_GAUSS)
    norms = ErrorNorms(d.trial, quad)
    err_l2 = norms.l2(u, problem.exact, relative=True)
    err_h1 = norms.h1_seminorm(u, problem.grad_exact, relative=True)
    if problem.is_vector:
        err_en = norms.energy(u, problem.grad_exact, *problem.lame, relative=True)
    else:
        err_en = err_h1  # Poisson: the energy norm is the H1 seminorm
    err_rule = _rule_gradient_error(problem, d, u)
    t_err = time.perf_counter() - t0
    table = d.trial.table
    row = asdict(spec)
    row.pop("seed")
    row.update(
        dilation=spec.dilation,
        n_nodes=d.trial.n_nodes,
        n_dofs=d.trial.n_dofs,
        error_l2=err_l2,
        error_h1=err_h1,
        error_energy=err_en,
        error_h1_rule=err_rule,
        wall_shape_s=best[0],
        wall_assembly_s=best[1],
        wall_solve_s=best[2],
        wall_s=float(sum(best)),
        wall_error_s=t_err,
        neighbors_mean=float(table.n_neighbors.mean()),
        n_fallback=int(table.n_fallback + norms.table.n_fallback),
        finite=bool(np.isfinite(u).all()),
    )
    if not row["finite"]:
        logger.warning("%s: the solution is not finite", spec)
    return row


def reference_stiffness(problem: Problem, d: Discretisation, spacing: float):
    """Stiffness of the trial functions integrated accurately: direct gradients on the
    background Gauss grid of the error norms (sparse algebra ``Bᵀ D W B``), ``(n_dofs, n_dofs)``."""
    from scipy.sparse import csr_array, diags_array, kron, vstack

    cells = np.rint(problem.size / spacing).astype(int)
    quad = rectangle_quadrature(problem.lower, problem.upper, tuple(int(c) for c in cells),
                                ERROR_GAUSS)
    G0, G1 = d.trial.shape_functions_at(quad.points).gradient_matrices()
    W = diags_array(quad.weights)
    if not problem.is_vector:
        return csr_array(G0.T @ W @ G0 + G1.T @ W @ G1)
    n = d.trial.n_nodes

    def place(A, comp):  # columns of displacement component ``comp`` (node-major DOFs)
        A = A.tocoo()
        return csr_array((A.data, (A.row, 2 * A.col + comp)), shape=(A.shape[0], 2 * n))

    B = vstack([place(G0, 0), place(G1, 1), place(G1, 0) + place(G0, 1)]).tocsr()
    lam, mu = problem.lame
    D = np.array([[lam + 2 * mu, lam, 0.0], [lam, lam + 2 * mu, 0.0], [0.0, 0.0, mu]])
    return csr_array(B.T @ kron(csr_array(D), W) @ B)


def spectrum(spec: SolveSpec, *, tol: float = 1e-10, soft: float = 10.0,
             with_inverse_constant: bool = True) -> tuple[dict[str, Any], np.ndarray]:
    """Zero-energy modes of the stiffness **without** boundary conditions (dense; small problems).

    Symmetric rules: eigenvalues (``eigvalsh``); VCI (unsymmetric): singular values, which
    count the same null space. Values are divided by the largest. A mode is "zero" when its value
    is below ``tol``; the rigid modes (1 for Poisson, 3 for 2D elasticity) are subtracted to
    give the spurious ones. ``eig_below`` is the largest value under ``tol`` (after the rigid
    ones: the largest spurious one, else the largest rigid one), ``eig_above`` the smallest over
    it, ``eig_gap = eig_above / eig_below`` (how clearly the threshold separates them), and
    ``eig_first`` the smallest non-rigid value whatever ``tol``.

    Beyond exact zeros (symmetric rules only): the energy of every non-rigid nodal vector under
    the rule is compared with its energy under the same shape functions integrated accurately
    (direct gradients on the background Gauss grid of the error norms), through the
    generalised eigenvalues ``μ`` of ``K_ref v = μ K_rule v`` on the complement of the rigid
    modes. ``energy_ratio_max = max μ`` is the worst underestimate of the energy by the rule,
    ``n_soft_modes`` the number of modes with ``μ > soft`` (energy underestimated more than
    ``soft``-fold; infinite if the rule has an extra zero mode).

    With ``with_inverse_constant`` the Nitsche inverse constant ``C_I`` of the problem's
    Dirichlet boundary is measured as well (symmetric rules; NaN for VCI).

    Returns the row and the normalised values (ascending).
    """
    import scipy.linalg

    problem = get_problem(spec.problem)
    rng = np.random.default_rng(spec.seed)
    nodes = node_grid(problem, spec.spacing, spec.nodes, rng)
    d = discretise(problem, nodes, spec)
    K = _stiffness(problem, d)
    Kd = K.toarray()
    if d.symmetric:
        vals = np.abs(scipy.linalg.eigvalsh(0.5 * (Kd + Kd.T)))
    else:
        vals = scipy.linalg.svdvals(Kd)
    vals = np.sort(vals) / vals.max()
    n_rigid = 3 if problem.is_vector else 1
    n_zero = int(np.count_nonzero(vals < tol))
    below = vals[n_zero - 1] if n_zero else math.nan
    above = vals[n_zero] if n_zero < vals.size else math.nan
    ci = mu_max = math.nan
    n_soft = -1
    if d.symmetric:
        Kref = reference_stiffness(problem, d, spec.spacing).toarray()
        _, V = scipy.linalg.eigh(0.5 * (Kref + Kref.T))
        Q = V[:, n_rigid:]  # complement of the rigid modes (shared by both stiffnesses)
        A, B = Q.T @ Kref @ Q, Q.T @ Kd @ Q
        try:
            mu = scipy.linalg.eigh(0.5 * (A + A.T), 0.5 * (B + B.T), eigvals_only=True)
            mu_max, n_soft = float(mu.max()), int(np.count_nonzero(mu > soft))
        except np.linalg.LinAlgError:  # the rule's stiffness is singular there: a zero mode
            mu_max, n_soft = math.inf, int(np.count_nonzero(vals[n_rigid:] < tol))
        if with_inverse_constant and d.dirichlet is not None:
            ci = nitsche_inverse_constant(d.dirichlet, K, flux=_flux(problem),
                                          modulus=problem.modulus)
    row = asdict(spec)
    row.pop("seed")
    row.update(
        dilation=spec.dilation,
        n_nodes=d.trial.n_nodes,
        n_dofs=d.trial.n_dofs,
        n_rigid=n_rigid,
        n_zero_modes=n_zero,
        n_spurious_modes=n_zero - n_rigid,
        eig_below=float(below),
        eig_above=float(above),
        eig_gap=float(above / below) if n_zero and n_zero < vals.size else math.nan,
        eig_first=float(vals[n_rigid]) if vals.size > n_rigid else math.nan,
        energy_ratio_max=mu_max,
        n_soft_modes=n_soft if n_soft >= 0 else None,
        nitsche_ci=float(ci),
        eig_tol=tol,
        spectrum="eigvalsh" if d.symmetric else "svdvals",
    )
    return row, vals
