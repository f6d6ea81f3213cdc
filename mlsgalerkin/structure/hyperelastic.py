r"""Geometrically nonlinear (total-Lagrangian) internal force of elastic bodies on scikit-fem: 2D
plane strain and 3D.

The body is the reference configuration :math:`\Omega_0` of an
:class:`~mlsgalerkin.structure.elastic.ElasticBody` (a scikit-fem mesh with a vector element: Q1,
9-node Q2 or P1 in 2D; Hex1, 27-node Hex2 or tetrahedral P1 in 3D), with displacement
:math:`\mathbf u(\mathbf X) = \sum_a N_a(\mathbf X)\,\mathbf u_a`. Everything is measured on the
reference configuration:

.. math::

    \mathbf F = \mathbf I + \nabla_{\mathbf X}\mathbf u
              = \mathbf I + \sum_a \mathbf u_a \otimes \nabla_{\mathbf X} N_a, \qquad
    J = \det\mathbf F, \qquad \mathbf C = \mathbf F^T\mathbf F, \qquad
    \mathbf E = \tfrac12(\mathbf C - \mathbf I),

and the internal force is the weak form of the first Piola–Kirchhoff stress :math:`\mathbf P`,

.. math::

    f_i = \int_{\Omega_0} \mathbf P(\mathbf F) : \nabla_{\mathbf X}\boldsymbol\phi_i \, d\Omega_0
        = \frac{\partial}{\partial u_i} \int_{\Omega_0} W(\mathbf F)\, d\Omega_0 ,

:math:`\boldsymbol\phi_i = N_a \mathbf e_c` the vector shape function of degree of freedom
:math:`i = d\,a + c` in dimension :math:`d` (scikit-fem's interleaved numbering: ``2a + c`` in 2D,
``3a + c`` in 3D). The models (:data:`MODELS`), both hyperelastic with the Lamé parameters
:math:`\lambda, \mu` and both reducing to small-strain linear elasticity
:math:`\boldsymbol\sigma = \lambda\,\mathrm{tr}\,\boldsymbol\varepsilon\,\mathbf I +
2\mu\boldsymbol\varepsilon` for small displacements:

* ``"stvenant_kirchhoff"`` (St Venant–Kirchhoff):

  .. math:: \mathbf S = \lambda\,\mathrm{tr}(\mathbf E)\,\mathbf I + 2\mu\mathbf E, \qquad
            \mathbf P = \mathbf F\mathbf S, \qquad
            W = \tfrac12\lambda(\mathrm{tr}\,\mathbf E)^2 + \mu\,\mathbf E:\mathbf E;

* ``"neo_hookean"`` (compressible neo-Hookean):

  .. math:: \mathbf P = \mu(\mathbf F - \mathbf F^{-T}) + \lambda \ln J\,\mathbf F^{-T}, \qquad
            W = \tfrac12\mu(\mathrm{tr}\,\mathbf C - d - 2\ln J) + \tfrac12\lambda(\ln J)^2 ,

  :math:`d` = 2 or 3 the dimension.

In 3D, :math:`\mathbf F` is 3 × 3 and the numba kernel writes it out: the cofactor matrix
:math:`\mathrm{cof}\,\mathbf F = J\mathbf F^{-T}` (:math:`(\mathrm{cof}\,\mathbf F)_{ij} =
\tfrac12\epsilon_{ikl}\epsilon_{jmn}F_{km}F_{ln}`), :math:`J = \sum_j F_{0j}(\mathrm{cof}\,
\mathbf F)_{0j}`, so that the neo-Hookean :math:`\mathbf P = \mu\mathbf F + (\lambda\ln J -
\mu)\,\mathrm{cof}\,\mathbf F / J` needs no inverse; the Lamé parameters are the material's 3D ones
(``ElasticMaterial.lame(3)``, :func:`lame_for_dimension`).

In 2D both models are plane strain (:math:`F_{33} = 1`; the 2D neo-Hookean :math:`W` is the 3D one
with :math:`\mathrm{tr}\,\mathbf C_{3D} = \mathrm{tr}\,\mathbf C + 1`). Plane stress would need the
out-of-plane stretch from :math:`S_{33} = 0` at every quadrature point and is refused
(:func:`plane_strain_lame`). An inverted element (:math:`J \le 0` at a quadrature point) raises
:class:`InvertedElementError` naming the element, for both models and in both dimensions: the
neo-Hookean energy is not defined there, and a St Venant–Kirchhoff body that folds an element is
no longer a physical state.

Units: :math:`\lambda, \mu, \mathbf P, \mathbf S` in Pa, lengths and displacements in m, forces
``f`` in N and energies in J (in 2D per unit depth, out of plane; in 3D total).

Arrays: ``u`` and ``f`` have shape ``(N,)`` = ``(basis.N,)`` (vector degree of freedom
``d s + c`` of scalar node ``s``, component ``c``); :class:`QuadratureData` holds, for the
``n_elements`` elements with ``n_local_nodes`` nodes and ``n_qp`` quadrature points each,
``dofs (n_elements, n_local_nodes)``, ``grads (n_elements, n_qp, n_local_nodes, d)`` (the
reference-configuration :math:`\partial N_a / \partial X_k`) and ``weights (n_elements, n_qp)``
(quadrature weight × det of the element map, scikit-fem's ``basis.dx``), all taken from the
scikit-fem basis once.

:func:`internal_force` and :func:`strain_energy` are numba kernels over these flat arrays (a
``prange`` over elements into element-local forces, then a serial scatter: no write races; one
kernel for 2D and one for 3D, chosen by the last axis of ``grads``);
:func:`internal_force_reference`, :func:`strain_energy_reference` and
:func:`tangent_stiffness_reference` are the same quantities written the scikit-fem way
(``LinearForm`` / ``Functional`` / ``BilinearForm`` with ``skfem.helpers``, dimension-generic),
after scikit-fem's hyperelasticity example (``docs/examples/ex43.py``, "Hyperelasticity":
neo-Hookean ``LinearForm`` and ``BilinearForm``). Formulas: J. Bonet, R. D. Wood, *Nonlinear
Continuum Mechanics for Finite Element Analysis*, 2nd ed., Cambridge University Press (2008), the
hyperelasticity chapter (St Venant–Kirchhoff and compressible neo-Hookean materials, there in
:math:`\mathbf S`, with :math:`\mathbf P = \mathbf F\mathbf S`); the tangent is the linearisation
:math:`\Delta\mathbf P = \partial\mathbf P/\partial\mathbf F : \Delta\mathbf F` (their chapter on
the linearised equilibrium equations).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numba
import numpy as np
import scipy.sparse as sp
from numba import prange
from numpy.typing import NDArray
from skfem import BilinearForm, ElementVector, Functional, LinearForm, asm
from skfem.assembly.basis import AbstractBasis
from skfem.helpers import ddot, det, grad, identity, inv, mul, trace, transpose

if TYPE_CHECKING:   # a leaf module: elastic.py may import this one without a cycle
    from mlsgalerkin.structure.elastic import ElasticMaterial

__all__ = [
    "MODELS",
    "InvertedElementError",
    "QuadratureData",
    "internal_force",
    "internal_force_reference",
    "lame_for_dimension",
    "plane_strain_lame",
    "strain_energy",
    "strain_energy_reference",
    "tangent_stiffness_reference",
]

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.int64]

#: The hyperelastic models, by name; the numba kernels take the position in this tuple.
MODELS = ("stvenant_kirchhoff", "neo_hookean")
_SVK = MODELS.index("stvenant_kirchhoff")


class InvertedElementError(ValueError):
    """An element of the deformed body is inverted: :math:`J = \\det\\mathbf F \\le 0` at one of
    its quadrature points. ``elements`` are the mesh element indices (``mesh.t[:, e]``) found
    inverted, ``j_min`` their smallest :math:`J`."""

    def __init__(self, message: str, elements: IntArray, j_min: FloatArray) -> None:
        super().__init__(message)
        self.elements = elements
        self.j_min = j_min


def _model_code(model: str) -> int:
    if model not in MODELS:
        raise ValueError(f"hyperelastic model must be one of {MODELS}, got {model!r}")
    return MODELS.index(model)


def _check_lame(lam: float, mu: float) -> tuple[float, float]:
    lam, mu = float(lam), float(mu)
    if not (math.isfinite(lam) and math.isfinite(mu) and mu > 0.0):
        raise ValueError(f"hyperelastic: Lamé parameters must be finite with mu > 0, got lam={lam!r}, mu={mu!r}")
    return lam, mu


def plane_strain_lame(material: ElasticMaterial) -> tuple[float, float]:
    """``(λ, μ)`` in Pa of ``material`` for the nonlinear models, which are plane strain only.

    Raises ``ValueError`` for ``material.plane == "stress"``: the plane-stress Lamé parameter of
    :meth:`ElasticMaterial.lame` is a small-strain device; a plane-stress hyperelastic body needs
    the out-of-plane stretch solved from :math:`S_{33} = 0` at every quadrature point, which this
    module does not do."""
    if material.plane != "strain":
        raise ValueError(
            "hyperelastic (geometrically nonlinear) models are plane strain only, got an ElasticMaterial with "
            f"plane={material.plane!r}: plane stress of a finite-strain material needs the out-of-plane stretch "
            "solved from S33 = 0 at every quadrature point, which is not implemented (the plane-stress lambda of "
            "ElasticMaterial.lame() is only valid for small strains). Build the material with plane='strain' "
            "(for a slender beam with poisson=0 the two coincide; otherwise plane strain is stiffer by "
            "1/(1 - poisson**2) in bending), or keep the small-strain ElasticBody for plane stress.")
    return material.lame(2)


def lame_for_dimension(material: ElasticMaterial, dim: int) -> tuple[float, float]:
    """``(λ, μ)`` in Pa of ``material`` for the nonlinear models of a ``dim``-dimensional body:
    :func:`plane_strain_lame` in 2D (plane stress refused), the 3D Lamé parameters
    ``material.lame(3)`` in 3D (``material.plane`` does not apply)."""
    if dim == 2:
        return plane_strain_lame(material)
    if dim == 3:
        return material.lame(3)
    raise ValueError(f"hyperelastic: a body is 2D or 3D, got dim={dim!r}")


# ---------------------------------------------------------------------------- quadrature data
@dataclass(frozen=True, eq=False)
class QuadratureData:
    """The flat, contiguous arrays the numba kernels run over, taken once from a 2D or 3D vector
    scikit-fem basis (:meth:`from_basis`); ``d`` = :attr:`dim` is 2 or 3.

    ``dofs`` int64 ``(n_elements, n_local_nodes)``: scalar node of each local shape function
    (vector degrees of freedom ``d * dofs + c``); ``grads`` float64 ``(n_elements, n_qp,
    n_local_nodes, d)``: :math:`\\partial N_a/\\partial X_k` (1/m) in the reference configuration;
    ``weights`` float64 ``(n_elements, n_qp)``: quadrature weight × det of the element map (m² in
    2D, m³ in 3D, scikit-fem's ``basis.dx``); ``elements`` int64 ``(n_elements,)``: the mesh
    element of each row (``basis.tind``, all elements by default); ``n_dofs``: length ``N`` of
    ``u`` and ``f``."""

    dofs: IntArray
    grads: FloatArray
    weights: FloatArray
    elements: IntArray
    n_dofs: int

    @classmethod
    def from_basis(cls, basis: AbstractBasis) -> QuadratureData:
        """From ``basis = Basis(mesh, ElementVector(scalar_element))`` on a 2D or 3D mesh
        (dimension ``d``): the scalar gradients are the first component row of the vector basis
        functions ``d a`` (scikit-fem's ``ElementVector`` puts ``N_a`` in component ``i % d`` of
        basis function ``i``), the weights ``basis.dx``, the nodes
        ``basis.element_dofs[0::d] // d``."""
        elem = basis.elem
        d = basis.mesh.dim()
        if not isinstance(elem, ElementVector) or d not in (2, 3) or elem.dim != d:
            raise ValueError("QuadratureData.from_basis: needs a 2D or 3D mesh with an ElementVector basis of as many "
                             f"components, got {type(elem).__name__} (dim {getattr(elem, 'dim', None)}) on a "
                             f"{d}D mesh")
        edofs = np.asarray(basis.element_dofs, dtype=np.int64)            # (d n_local, n_elements)
        first = edofs[0::d]
        if np.any(first % d != 0) or any(np.any(edofs[c::d] != first + c) for c in range(1, d)):
            raise ValueError("QuadratureData.from_basis: the basis does not number vector degrees of freedom "
                             f"interleaved ({d} * node + component), which the kernels assume")
        n_local = first.shape[0]
        grads = np.stack([basis.basis[d * a][0].grad[0] for a in range(n_local)])  # (n_local, d, ne, nq)
        grads = np.ascontiguousarray(grads.transpose(2, 3, 0, 1), dtype=np.float64)
        tind = basis.tind if basis.tind is not None else np.arange(basis.mesh.t.shape[1])
        return cls(dofs=np.ascontiguousarray((first // d).T), grads=grads,
                   weights=np.ascontiguousarray(basis.dx, dtype=np.float64),
                   elements=np.asarray(tind, dtype=np.int64), n_dofs=int(basis.N))

    @property
    def n_elements(self) -> int:
        return self.dofs.shape[0]

    @property
    def dim(self) -> int:
        """The dimension ``d`` of the body (2 or 3): the last axis of ``grads``."""
        return self.grads.shape[3]


# ---------------------------------------------------------------------------- numba kernels
@numba.njit(cache=True, inline="always")
def _piola(F00, F01, F10, F11, lam, mu, model):
    """First Piola–Kirchhoff stress ``(P00, P01, P10, P11)``, energy density ``W`` and ``J``."""
    J = F00 * F11 - F01 * F10
    if model == _SVK:   # St Venant–Kirchhoff
        E00 = 0.5 * (F00 * F00 + F10 * F10 - 1.0)
        E01 = 0.5 * (F00 * F01 + F10 * F11)
        E11 = 0.5 * (F01 * F01 + F11 * F11 - 1.0)
        tr = E00 + E11
        S00 = lam * tr + 2.0 * mu * E00
        S01 = 2.0 * mu * E01
        S11 = lam * tr + 2.0 * mu * E11
        W = 0.5 * lam * tr * tr + mu * (E00 * E00 + 2.0 * E01 * E01 + E11 * E11)
        return (F00 * S00 + F01 * S01, F00 * S01 + F01 * S11,
                F10 * S00 + F11 * S01, F10 * S01 + F11 * S11, W, J)
    # compressible neo-Hookean
    if J <= 0.0:
        return 0.0, 0.0, 0.0, 0.0, 0.0, J
    lnJ = math.log(J)
    c = (lam * lnJ - mu) / J       # coefficient of F^-T = (1/J) [[F11, -F10], [-F01, F00]]
    W = 0.5 * mu * (F00 * F00 + F01 * F01 + F10 * F10 + F11 * F11 - 2.0 - 2.0 * lnJ) + 0.5 * lam * lnJ * lnJ
    return mu * F00 + c * F11, mu * F01 - c * F10, mu * F10 - c * F01, mu * F11 + c * F00, W, J


@numba.njit(cache=True, parallel=True)
def _element_forces(dofs, grads, weights, u, lam, mu, model):
    """Element-local forces ``(n_elements, n_local, 2)``, element energies and smallest ``J``."""
    ne, nq, na, _ = grads.shape
    fe = np.zeros((ne, na, 2))
    energy = np.zeros(ne)
    jmin = np.empty(ne)
    for e in prange(ne):
        jm = np.inf
        for q in range(nq):
            H00 = 0.0
            H01 = 0.0
            H10 = 0.0
            H11 = 0.0
            for a in range(na):
                s = dofs[e, a]
                ux = u[2 * s]
                uy = u[2 * s + 1]
                gx = grads[e, q, a, 0]
                gy = grads[e, q, a, 1]
                H00 += ux * gx
                H01 += ux * gy
                H10 += uy * gx
                H11 += uy * gy
            P00, P01, P10, P11, W, J = _piola(1.0 + H00, H01, H10, 1.0 + H11, lam, mu, model)
            jm = min(jm, J)
            w = weights[e, q]
            energy[e] += w * W
            for a in range(na):
                gx = grads[e, q, a, 0]
                gy = grads[e, q, a, 1]
                fe[e, a, 0] += w * (P00 * gx + P01 * gy)
                fe[e, a, 1] += w * (P10 * gx + P11 * gy)
        jmin[e] = jm
    return fe, energy, jmin


@numba.njit(cache=True)
def _scatter(dofs, fe, n):
    """Element-local forces ``fe (n_elements, n_local, d)`` summed into the global ``(n,)``
    vector of interleaved degrees of freedom ``d s + c`` (serial: no write races)."""
    f = np.zeros(n)
    ne, na = dofs.shape
    d = fe.shape[2]
    for e in range(ne):
        for a in range(na):
            s = dofs[e, a]
            for c in range(d):
                f[d * s + c] += fe[e, a, c]
    return f


@numba.njit(cache=True, inline="always")
def _piola_3d(F00, F01, F02, F10, F11, F12, F20, F21, F22, lam, mu, model):
    """3D first Piola–Kirchhoff stress ``(P00, P01, P02, P10, ..., P22)`` (row-major), energy
    density ``W`` and ``J``, written out for a 3 × 3 ``F``: ``J`` from the cofactor matrix
    ``cof F = J F^-T`` (expansion along the first row), no inverse."""
    C00 = F11 * F22 - F12 * F21
    C01 = F12 * F20 - F10 * F22
    C02 = F10 * F21 - F11 * F20
    J = F00 * C00 + F01 * C01 + F02 * C02
    if model == _SVK:   # St Venant–Kirchhoff: E = (F^T F - I)/2, S = lam tr(E) I + 2 mu E, P = F S
        E00 = 0.5 * (F00 * F00 + F10 * F10 + F20 * F20 - 1.0)
        E11 = 0.5 * (F01 * F01 + F11 * F11 + F21 * F21 - 1.0)
        E22 = 0.5 * (F02 * F02 + F12 * F12 + F22 * F22 - 1.0)
        E01 = 0.5 * (F00 * F01 + F10 * F11 + F20 * F21)
        E02 = 0.5 * (F00 * F02 + F10 * F12 + F20 * F22)
        E12 = 0.5 * (F01 * F02 + F11 * F12 + F21 * F22)
        tr = E00 + E11 + E22
        S00 = lam * tr + 2.0 * mu * E00
        S11 = lam * tr + 2.0 * mu * E11
        S22 = lam * tr + 2.0 * mu * E22
        S01 = 2.0 * mu * E01
        S02 = 2.0 * mu * E02
        S12 = 2.0 * mu * E12
        W = 0.5 * lam * tr * tr + mu * (E00 * E00 + E11 * E11 + E22 * E22
                                        + 2.0 * (E01 * E01 + E02 * E02 + E12 * E12))
        return (F00 * S00 + F01 * S01 + F02 * S02, F00 * S01 + F01 * S11 + F02 * S12,
                F00 * S02 + F01 * S12 + F02 * S22,
                F10 * S00 + F11 * S01 + F12 * S02, F10 * S01 + F11 * S11 + F12 * S12,
                F10 * S02 + F11 * S12 + F12 * S22,
                F20 * S00 + F21 * S01 + F22 * S02, F20 * S01 + F21 * S11 + F22 * S12,
                F20 * S02 + F21 * S12 + F22 * S22, W, J)
    # compressible neo-Hookean: P = mu F + (lam ln J - mu) F^-T, F^-T = cof(F) / J
    if J <= 0.0:
        return 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, J
    C10 = F02 * F21 - F01 * F22
    C11 = F00 * F22 - F02 * F20
    C12 = F01 * F20 - F00 * F21
    C20 = F01 * F12 - F02 * F11
    C21 = F02 * F10 - F00 * F12
    C22 = F00 * F11 - F01 * F10
    lnJ = math.log(J)
    c = (lam * lnJ - mu) / J
    trC = (F00 * F00 + F01 * F01 + F02 * F02 + F10 * F10 + F11 * F11 + F12 * F12
           + F20 * F20 + F21 * F21 + F22 * F22)
    W = 0.5 * mu * (trC - 3.0 - 2.0 * lnJ) + 0.5 * lam * lnJ * lnJ
    return (mu * F00 + c * C00, mu * F01 + c * C01, mu * F02 + c * C02,
            mu * F10 + c * C10, mu * F11 + c * C11, mu * F12 + c * C12,
            mu * F20 + c * C20, mu * F21 + c * C21, mu * F22 + c * C22, W, J)


@numba.njit(cache=True, parallel=True)
def _element_forces_3d(dofs, grads, weights, u, lam, mu, model):
    """3D element-local forces ``(n_elements, n_local, 3)``, element energies and smallest ``J``
    (the element's nodal displacements gathered once into ``(n_local, 3)``)."""
    ne, nq, na, _ = grads.shape
    fe = np.zeros((ne, na, 3))
    energy = np.zeros(ne)
    jmin = np.empty(ne)
    for e in prange(ne):
        ue = np.empty((na, 3))
        for a in range(na):
            s = dofs[e, a]
            ue[a, 0] = u[3 * s]
            ue[a, 1] = u[3 * s + 1]
            ue[a, 2] = u[3 * s + 2]
        jm = np.inf
        for q in range(nq):
            H00 = 0.0
            H01 = 0.0
            H02 = 0.0
            H10 = 0.0
            H11 = 0.0
            H12 = 0.0
            H20 = 0.0
            H21 = 0.0
            H22 = 0.0
            for a in range(na):
                ux = ue[a, 0]
                uy = ue[a, 1]
                uz = ue[a, 2]
                gx = grads[e, q, a, 0]
                gy = grads[e, q, a, 1]
                gz = grads[e, q, a, 2]
                H00 += ux * gx
                H01 += ux * gy
                H02 += ux * gz
                H10 += uy * gx
                H11 += uy * gy
                H12 += uy * gz
                H20 += uz * gx
                H21 += uz * gy
                H22 += uz * gz
            P00, P01, P02, P10, P11, P12, P20, P21, P22, W, J = _piola_3d(
                1.0 + H00, H01, H02, H10, 1.0 + H11, H12, H20, H21, 1.0 + H22, lam, mu, model)
            jm = min(jm, J)
            w = weights[e, q]
            energy[e] += w * W
            for a in range(na):
                gx = grads[e, q, a, 0]
                gy = grads[e, q, a, 1]
                gz = grads[e, q, a, 2]
                fe[e, a, 0] += w * (P00 * gx + P01 * gy + P02 * gz)
                fe[e, a, 1] += w * (P10 * gx + P11 * gy + P12 * gz)
                fe[e, a, 2] += w * (P20 * gx + P21 * gy + P22 * gz)
        jmin[e] = jm
    return fe, energy, jmin


def _inverted(where: str, model: str, elements: IntArray, jmin: FloatArray) -> InvertedElementError:
    bad = np.flatnonzero(jmin <= 0.0)
    worst = bad[np.argmin(jmin[bad])]
    mesh_elements = elements[bad]
    return InvertedElementError(
        f"{where} ({model}): {bad.size} inverted element(s), J = det F <= 0 at a quadrature point; the worst is "
        f"mesh element {int(elements[worst])} (mesh.t[:, {int(elements[worst])}]) with J = {float(jmin[worst]):.6g}"
        + (f"; all: {mesh_elements[:20].tolist()}{' ...' if bad.size > 20 else ''}" if bad.size > 1 else "")
        + ". The displacement folds the element over: a time step or load increment too large, or a mesh too "
          "coarse for this deformation.", mesh_elements, jmin[bad])


def _run(data: QuadratureData, u: FloatArray, lam: float, mu: float, model: str, where: str):
    code = _model_code(model)
    lam, mu = _check_lame(lam, mu)
    u = np.ascontiguousarray(u, dtype=np.float64)
    if u.shape != (data.n_dofs,):
        raise ValueError(f"{where}: u must have shape ({data.n_dofs},), got {u.shape}")
    if not np.all(np.isfinite(u)):
        raise ValueError(f"{where}: u has {int(np.sum(~np.isfinite(u)))} non-finite entries")
    kernel = _element_forces_3d if data.dim == 3 else _element_forces
    fe, energy, jmin = kernel(data.dofs, data.grads, data.weights, u, lam, mu, code)
    if np.any(jmin <= 0.0):
        raise _inverted(where, model, data.elements, jmin)
    return fe, energy


def internal_force(data: QuadratureData, u: FloatArray, lam: float, mu: float, model: str) -> FloatArray:
    """Internal force ``f (N,)`` in N (per unit depth in 2D), :math:`f_i = \\int \\mathbf
    P(\\mathbf F) : \\nabla_X\\boldsymbol\\phi_i\\,d\\Omega_0`, of the displacement ``u (N,)`` (m)
    with Lamé parameters ``lam``, ``mu`` (Pa) and model ``model`` (one of :data:`MODELS`); numba
    over ``data``, the 2D or the 3D kernel by ``data.dim``. Raises :class:`InvertedElementError`
    if an element has :math:`J \\le 0`."""
    fe, _ = _run(data, u, lam, mu, model, "internal_force")
    return _scatter(data.dofs, fe, data.n_dofs)


def strain_energy(data: QuadratureData, u: FloatArray, lam: float, mu: float, model: str) -> float:
    """Strain energy :math:`\\int W(\\mathbf F)\\,d\\Omega_0` in J (per unit depth in 2D; numba,
    2D or 3D by ``data.dim``)."""
    _, energy = _run(data, u, lam, mu, model, "strain_energy")
    return float(energy.sum())


# ---------------------------------------------------------------------------- scikit-fem reference
def _piola_reference(F, lam: float, mu: float, model: str):
    """``(P, W)`` on scikit-fem's ``(d, d, n_elements, n_qp)`` arrays with ``skfem.helpers``
    (``d`` = 2 or 3; the neo-Hookean :math:`W` has :math:`\\mathrm{tr}\\,\\mathbf C - d`)."""
    if model == "stvenant_kirchhoff":
        I = identity(F)
        E = 0.5 * (mul(transpose(F), F) - I)
        S = lam * trace(E) * I + 2.0 * mu * E
        return mul(F, S), 0.5 * lam * trace(E) ** 2 + mu * ddot(E, E)
    lnJ = np.log(det(F))
    iFT = transpose(inv(F))
    return (mu * (F - iFT) + lam * lnJ * iFT,
            0.5 * mu * (ddot(F, F) - float(F.shape[0]) - 2.0 * lnJ) + 0.5 * lam * lnJ ** 2)


def _deformation_gradient(w):
    """``F = I + grad(u)``, ``(d, d, n_elements, n_qp)``."""
    H = grad(w["u"])
    return H + identity(H)


def _interpolate_checked(basis: AbstractBasis, u: FloatArray, model: str, where: str):
    _model_code(model)
    u = np.asarray(u, dtype=np.float64)
    if u.shape != (basis.N,):
        raise ValueError(f"{where}: u must have shape ({basis.N},), got {u.shape}")
    uh = basis.interpolate(u)
    H = uh.grad
    J = det(H + identity(H))                                       # (n_elements, n_qp)
    jmin = J.min(axis=1)
    if np.any(jmin <= 0.0):
        tind = basis.tind if basis.tind is not None else np.arange(basis.mesh.t.shape[1])
        raise _inverted(where, model, np.asarray(tind, dtype=np.int64), jmin)
    return uh


def internal_force_reference(basis: AbstractBasis, u: FloatArray, lam: float, mu: float, model: str) -> FloatArray:
    """:func:`internal_force` written the scikit-fem way: ``asm`` of the ``LinearForm``
    :math:`\\mathbf P(\\mathbf F) : \\nabla\\mathbf v` with ``F = I + grad(u)`` from
    ``basis.interpolate(u)`` (slow: numpy over ``(d, d, n_elements, n_qp)`` arrays; 2D or 3D)."""
    lam, mu = _check_lame(lam, mu)
    uh = _interpolate_checked(basis, u, model, "internal_force_reference")

    @LinearForm
    def residual(v, w):
        P, _ = _piola_reference(_deformation_gradient(w), lam, mu, model)
        return ddot(P, grad(v))

    return asm(residual, basis, u=uh)


def strain_energy_reference(basis: AbstractBasis, u: FloatArray, lam: float, mu: float, model: str) -> float:
    """:func:`strain_energy` as a scikit-fem ``Functional`` of :math:`W(\\mathbf F)`."""
    lam, mu = _check_lame(lam, mu)
    uh = _interpolate_checked(basis, u, model, "strain_energy_reference")

    @Functional
    def energy(w):
        return _piola_reference(_deformation_gradient(w), lam, mu, model)[1]

    return float(asm(energy, basis, u=uh))


def tangent_stiffness_reference(basis: AbstractBasis, u: FloatArray, lam: float, mu: float,
                                model: str) -> sp.csr_matrix:
    """Tangent stiffness ``K (N, N)`` in N/m (per unit depth in 2D), :math:`K_{ij} = \\partial f_i /
    \\partial u_j = \\int (\\partial\\mathbf P/\\partial\\mathbf F : \\nabla\\boldsymbol\\phi_j) :
    \\nabla\\boldsymbol\\phi_i\\,d\\Omega_0`, a scikit-fem ``BilinearForm`` (symmetric):

    * St Venant–Kirchhoff: :math:`\\Delta\\mathbf P = \\Delta\\mathbf F\\,\\mathbf S + \\mathbf F
      (\\lambda\\,\\mathrm{tr}\\,\\Delta\\mathbf E\\,\\mathbf I + 2\\mu\\Delta\\mathbf E)`,
      :math:`\\Delta\\mathbf E = \\tfrac12(\\mathbf F^T\\Delta\\mathbf F + \\Delta\\mathbf F^T\\mathbf F)`;
    * neo-Hookean: :math:`\\Delta\\mathbf P = \\mu\\Delta\\mathbf F + (\\mu - \\lambda\\ln J)
      \\mathbf F^{-T}\\Delta\\mathbf F^T\\mathbf F^{-T} + \\lambda(\\mathbf F^{-T}:\\Delta\\mathbf F)
      \\mathbf F^{-T}` (scikit-fem's example 43).

    For an implicit (Newton / Newmark) step; at ``u = 0`` it is the linear-elastic stiffness."""
    lam, mu = _check_lame(lam, mu)
    uh = _interpolate_checked(basis, u, model, "tangent_stiffness_reference")

    @BilinearForm
    def tangent(du, v, w):
        F = _deformation_gradient(w)
        DF, dF = grad(du), grad(v)
        if model == "stvenant_kirchhoff":
            I = identity(F)
            E = 0.5 * (mul(transpose(F), F) - I)
            S = lam * trace(E) * I + 2.0 * mu * E
            DE = 0.5 * (mul(transpose(F), DF) + mul(transpose(DF), F))
            DP = mul(DF, S) + mul(F, lam * trace(DE) * I + 2.0 * mu * DE)
        else:
            lnJ = np.log(det(F))
            iFT = transpose(inv(F))
            DP = (mu * DF + (mu - lam * lnJ) * mul(mul(iFT, transpose(DF)), iFT)
                  + lam * ddot(iFT, DF) * iFT)
        return ddot(DP, dF)

    return asm(tangent, basis, u=uh).tocsr()


if __name__ == "__main__":   # timing: numba kernel vs the scikit-fem LinearForm, 4 x 40 Q2 mesh
    import time

    from skfem import Basis, ElementQuad2, MeshQuad

    mesh = MeshQuad.init_tensor(np.linspace(0.0, 1.0, 41), np.linspace(0.0, 0.1, 5))
    basis = Basis(mesh, ElementVector(ElementQuad2()))
    lam_, mu_ = 1.0e6, 0.5e6
    rng = np.random.default_rng(0)
    x, y = basis.doflocs
    u_ = np.where(np.arange(basis.N) % 2 == 0, 0.05 * x * y, 0.1 * x**2) + 1e-5 * rng.standard_normal(basis.N)
    t0 = time.perf_counter()
    data_ = QuadratureData.from_basis(basis)
    t_data = time.perf_counter() - t0
    for name in MODELS:
        internal_force(data_, u_, lam_, mu_, name)      # compile / load the cache
        n = 200
        t0 = time.perf_counter()
        for _ in range(n):
            internal_force(data_, u_, lam_, mu_, name)
        t_numba = (time.perf_counter() - t0) / n
        t0 = time.perf_counter()
        for _ in range(5):
            internal_force_reference(basis, u_, lam_, mu_, name)
        t_ref = (time.perf_counter() - t0) / 5
        print(f"{name}: {basis.N} dofs, {mesh.t.shape[1]} elements x {data_.grads.shape[1]} points: "
              f"internal_force {t_numba * 1e6:.1f} us, internal_force_reference {t_ref * 1e3:.2f} ms, "
              f"ratio {t_ref / t_numba:.0f} (QuadratureData.from_basis {t_data * 1e3:.2f} ms, once)")
