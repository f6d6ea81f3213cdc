r"""Node-to-surface penalty contact: the force on each slave node and its reaction on the master.

Slave nodes ``s`` (particles: positions :math:`\mathbf x_s`, velocities, masses :math:`m_s`)
meet a master :class:`~mlsgalerkin.contact.surface.ContactSurface` (nodes :math:`\mathbf x_a`,
velocities, masses :math:`m_a`, or a rigid master of infinite mass). This is the penalty form
of the node-to-surface contact of explicit codes (Hallquist, *LS-DYNA Theory Manual*; the
master–slave treatment of particles against finite-element surfaces of Attaway et al. 1994
and Johnson 1994).

**Contacts of a slave.** Among the candidate facets of the broad phase
(:mod:`mlsgalerkin.contact.search`) the slave's closest points
:math:`\mathbf x_c = \sum_a N_a\mathbf x_a` are found (:mod:`mlsgalerkin.contact.geometry`).

1. *Primary contact*: the nearest facet (smallest :math:`|\mathbf x_s - \mathbf x_c|`; the
   lowest facet index on a tie). If its closest point is inside the facet, the normal is the
   facet's outward normal and the signed distance :math:`d = (\mathbf x_s-\mathbf x_c)\cdot\mathbf n`
   (negative behind the facet). If the closest point is on the facet's border (a node, or an
   edge in 3D), the slave is past the end of the facet: if it is in front of the facet's plane
   the normal is the direction :math:`\mathbf n = (\mathbf x_s-\mathbf x_c)/|\mathbf x_s-\mathbf x_c|`
   and :math:`d = |\mathbf x_s - \mathbf x_c|` (an *outside corner* or an open end is rounded
   with radius :math:`g_0`); if it is behind the plane there is no primary contact (the slave is
   beyond an open end, on the far side).
2. *Secondary contacts* (inside corners): any other candidate facet whose closest point is
   inside it, with the slave in front of it (:math:`d \ge 0`) and within the thickness, whose
   normal makes more than ``feature_angle`` (default 30°) with the normal of every contact taken
   so far, nearest first, up to ``d`` contacts per slave. In the inside corner of a tank a
   particle near both the floor and the side wall is held by both; at an outside corner the
   second facet's closest point is the shared node (not inside the facet), so nothing is counted
   twice; facets closer than ``feature_angle`` to each other (a finely discretised curve) act as
   one smooth surface through the nearest alone.

**Gap and force** of each contact (units: m, kg, s; forces in N, per unit depth in 2D):

.. math::

    g = d - g_0, \qquad \text{active if } -r < g < 0,

    f_n = \max\big(-k\,g - c\,\dot g,\; 0\big), \qquad \mathbf f_s = f_n\,\mathbf n,
    \qquad \mathbf f_a = -N_a\,\mathbf f_s,

    \dot g = (\mathbf v_s - \textstyle\sum_a N_a\mathbf v_a)\cdot\mathbf n,\qquad
    k = \alpha\,\frac{m^*}{\Delta t_{ref}^2}, \qquad c = 2\zeta\sqrt{k\,m^*},\qquad
    m^* = \frac{m_s\,m_m}{m_s+m_m},\ m_m = \textstyle\sum_a N_a m_a\ (m^* = m_s \text{ for a rigid master}),

with the contact thickness :math:`g_0` (m; half the particle spacing for particles, so that a
particle's "radius" does not enter the surface), the reach :math:`r` (m; how deep behind the
surface a slave is still pushed out — one-sided, so a slave on the far side of a thin plate is
not pulled through), the stiffness factor :math:`\alpha` (–), the damping ratio :math:`\zeta`
(fraction of critical, –) and the reference time step :math:`\Delta t_{ref}` (s). This is the
mass-and-time-step soft constraint of LS-DYNA (``SOFT = 1``): the contact spring of a slave has
the frequency :math:`\omega = \sqrt{k/m^*}`, so :math:`\omega\Delta t_{ref} = \sqrt\alpha`
whatever the masses. The normal force is never attractive (clamped at 0). The reactions
:math:`\mathbf f_a` spread the force to the facet's nodes with the facet shape functions, so
:math:`\mathbf f_s + \sum_a\mathbf f_a = 0` (linear momentum) and, since
:math:`\mathbf x_s - \mathbf x_c \parallel \mathbf n`, :math:`\mathbf x_s\times\mathbf f_s +
\sum_a \mathbf x_a\times\mathbf f_a = (\mathbf x_s - \mathbf x_c)\times\mathbf f_s = 0`
(angular momentum).

**Stable time step.** A contact adds a spring to the slave and the master nodes; by
Gershgorin's theorem on :math:`\mathbf M^{-1}\mathbf K` the largest frequency is bounded by
:math:`\omega^2 \le \max\big(\kappa\sum k / m_s,\ 2\sum_s N_a k_s / m_a\big)` (:math:`\kappa = 1`
for a rigid master, 2 otherwise). Leapfrog with damping ratio :math:`\zeta` is stable for
:math:`\omega\Delta t \le 2(\sqrt{1+\zeta^2}-\zeta)`; the limit returned is
:math:`\Delta t \le C\cdot 2(\sqrt{1+\zeta^2}-\zeta)/\omega` with :math:`C` =
:data:`STABILITY_FACTOR` = 0.5 (a margin for the fluid's own stiffness on the same particles and
a lumped mass below the particle mass). For a rigid master and at most ``d`` contacts per slave
it is a constant, :func:`rigid_time_step` :math:`= C\cdot 2(\sqrt{1+\zeta^2}-\zeta)\,
\Delta t_{ref}/\sqrt{d\,\alpha}` (2.2 :math:`\Delta t_{ref}` in 2D with the defaults): it binds
only if the step grows to twice the reference step.

:func:`penalty_forces` is the numba kernel: the broad phase, then the narrow phase over the
slaves that have candidate facets only (parallel over them: in a fluid most particles are far
from every wall), then the reactions, gathered serially in slave order so that the totals are
bit-reproducible. The active contacts come back as flat per-pair arrays
(:class:`PenaltyResult`). :func:`penalty_forces_reference` is a numpy version for the tests.
Measured (``benchmarks/bench_contact.py``, one thread): 3–5×10⁶ candidate pairs/s in 2D,
7–8×10⁶ in 3D, from 10⁴ to 10⁶ slaves.
"""

from __future__ import annotations

import math
import numbers
from dataclasses import dataclass

import numba
import numpy as np
from numba import prange
from numpy.typing import ArrayLike, NDArray

from mlsgalerkin.contact.geometry import INTERIOR, closest_on_facet, facet_normals, facet_normals_reference
from mlsgalerkin.contact.search import candidate_pairs, candidate_pairs_reference
from mlsgalerkin.kernel_arrays import kernel_array

__all__ = [
    "DEFAULT_ALPHA", "DEFAULT_DAMPING", "DEFAULT_FEATURE_ANGLE", "STABILITY_FACTOR", "PenaltyResult",
    "check_penalty_parameters", "penalty_forces", "penalty_forces_reference", "penalty_stiffness",
    "rigid_time_step", "search_margin",
]

#: Stiffness factor α = (ω Δt_ref)² of the mass-and-time-step penalty (–): 0.1, the upper end of
#: LS-DYNA's soft-constraint scale; see ``docs/theory/contact.md`` for the measurements.
DEFAULT_ALPHA = 0.1
#: Damping ratio ζ of the contact spring, a fraction of critical (–).
DEFAULT_DAMPING = 0.03
#: Facets whose normals differ by less than this (degrees) act as one smooth surface.
DEFAULT_FEATURE_ANGLE = 30.0
#: Fraction C of the leapfrog stability limit the contact allows (–).
STABILITY_FACTOR = 0.5


def penalty_stiffness(alpha: float, mass: ArrayLike, dt_ref: float) -> NDArray[np.float64]:
    """``k = α m*/Δt_ref²`` (N/m, per unit depth in 2D) for effective masses ``m*`` (kg)."""
    return alpha * np.asarray(mass, dtype=float) / dt_ref**2


def rigid_time_step(alpha: float, damping: float, dt_ref: float, contacts: int = 2) -> float:
    """Stable step (s) of slaves against a rigid master with up to ``contacts`` contacts each:
    ``C · 2(√(1+ζ²) − ζ) Δt_ref / √(contacts · α)`` (module docstring)."""
    return STABILITY_FACTOR * 2.0 * (math.sqrt(1.0 + damping**2) - damping) * dt_ref / math.sqrt(contacts * alpha)


def search_margin(thickness: float, reach: float) -> float:
    """Broad-phase margin ``max(g0, r − g0)`` (m): the farthest a touching slave can be from a facet."""
    return max(thickness, reach - thickness)


def check_penalty_parameters(owner: str, alpha: float, damping: float, thickness: float | None,
                             reach: float | None, feature_angle: float, dt_ref: float | None) -> list[str]:
    """Problems with penalty parameters (empty if none); ``None`` thickness/reach/dt_ref mean
    "chosen later" and are accepted."""
    out = []
    ok = lambda v: isinstance(v, numbers.Real) and not isinstance(v, bool) and math.isfinite(v)  # noqa: E731
    if not (ok(alpha) and alpha > 0):
        out.append(f"{owner}: alpha (the stiffness factor (ω Δt_ref)², k = α m*/Δt_ref²) must be positive, "
                   f"got {alpha!r}; 0.01–0.2 is usual, default {DEFAULT_ALPHA}")
    elif alpha > 1.0:
        out.append(f"{owner}: alpha = {alpha!r} makes the contact spring stiffer than the reference step "
                   "resolves (ω Δt_ref = √α > 1); keep alpha <= 1")
    if not (ok(damping) and 0 <= damping < 1):
        out.append(f"{owner}: damping (ζ, a fraction of critical damping) must be in [0, 1), got {damping!r}")
    if thickness is not None and not (ok(thickness) and thickness >= 0):
        out.append(f"{owner}: thickness (the contact thickness g0, m) must be >= 0, got {thickness!r}")
    if reach is not None:
        if not (ok(reach) and reach > 0):
            out.append(f"{owner}: reach (how deep behind the surface a slave is still pushed out, m) must be "
                       f"positive, got {reach!r}")
        elif thickness is not None and ok(thickness) and reach <= thickness:
            out.append(f"{owner}: reach ({reach!r} m) must exceed the thickness ({thickness!r} m), or a slave "
                       "behind the surface is never pushed out; the default is twice the thickness")
    if not (ok(feature_angle) and 0 < feature_angle <= 90):
        out.append(f"{owner}: feature_angle must be in (0, 90] degrees, got {feature_angle!r}")
    if dt_ref is not None and not (ok(dt_ref) and dt_ref > 0):
        out.append(f"{owner}: dt_ref (the reference time step of the stiffness, s) must be positive, got {dt_ref!r}")
    return out


@dataclass
class PenaltyResult:
    """What :func:`penalty_forces` returns (forces in N, per unit depth in 2D).

    Attributes
    ----------
    slave_forces : (n, d)
        Force on each slave node.
    master_forces : (m, d)
        Reaction on each master node (``−Σ N_a f_s``).
    gaps : (n,)
        Signed gap ``g`` of each slave's primary contact (m; negative = penetration),
        ``inf`` without one.
    contacts : int
        Active contact pairs (``−r < g < 0``).
    active_slaves : int
        Slaves with at least one active contact.
    max_penetration : float
        Deepest ``−g`` over the active contacts (m; 0 without any).
    total_force : (d,)
        Total force on the master (``−Σ f_s``).
    moment : float (2D) or (3,) (3D)
        Moment of the reactions on the master about ``centre`` (N·m, per unit depth in 2D).
    stable_dt : float
        Stable time step of the active contacts (s; ``inf`` without any).
    pair_slave, pair_facet : (P,) int
        The ``P`` active contacts as flat arrays, in slave order (a slave's contacts in the order
        they were taken: the primary first): the slave and the facet of each, with
        :attr:`pair_weights` ``(P, d)`` (facet coordinates ``N_a`` of the contact point),
        :attr:`pair_normal` ``(P, d)`` (the contact normal, toward the slave), :attr:`pair_gap`
        ``(P,)`` (m), :attr:`pair_force` ``(P,)`` (the normal force ``f_n ≥ 0``, N) and
        :attr:`pair_stiffness` ``(P,)`` (``k = α m*/Δt_ref²``, N/m).
    """

    slave_forces: NDArray[np.float64]
    master_forces: NDArray[np.float64]
    gaps: NDArray[np.float64]
    contacts: int
    active_slaves: int
    max_penetration: float
    total_force: NDArray[np.float64]
    moment: float | NDArray[np.float64]
    stable_dt: float
    pair_slave: NDArray[np.int64]
    pair_facet: NDArray[np.int64]
    pair_weights: NDArray[np.float64]
    pair_normal: NDArray[np.float64]
    pair_gap: NDArray[np.float64]
    pair_force: NDArray[np.float64]
    pair_stiffness: NDArray[np.float64]

    @property
    def stored_energy(self) -> float:
        """Elastic energy of the active contact springs, ``½ Σ_p k_p g_p²`` (J, per unit depth in
        2D): the potential of the penalty force ``−k g`` (its damping part dissipates)."""
        return float(0.5 * np.sum(self.pair_stiffness * self.pair_gap ** 2))

    def contact_points(self, master_x: NDArray[np.float64], facets: NDArray[np.int64]
                       ) -> tuple[NDArray[np.int64], NDArray[np.float64], NDArray[np.float64]]:
        """The active contacts: slave index ``(P,)``, contact point ``x_c = Σ N_a x_a (P, d)`` on
        the master (m) and force on the slave ``f_n n (P, d)`` (N), in slave order."""
        xc = np.einsum("pa,pad->pd", self.pair_weights, np.asarray(master_x)[np.asarray(facets)[self.pair_facet]])
        return self.pair_slave, xc, self.pair_force[:, None] * self.pair_normal


# ---------------------------------------------------------------------------------- numba
@numba.njit(cache=True)
def _store(s, c, j, w0, w1, w2, n0, n1, n2, g, vs, ms, vm, mm, rigid, facets, alpha_dt2, zeta,
           pf, pw, pn, pg, pk, pfn):
    """Record contact ``c`` of slave ``s`` with facet ``j`` and compute its normal force
    (``pw, pn (n, maxc, d)``)."""
    dim = vs.shape[1]
    a = facets[j, 0]
    b = facets[j, 1]
    m_s = ms[s]
    if rigid:
        m_eff = m_s
    else:
        m_m = w0 * mm[a] + w1 * mm[b]
        if dim == 3:
            m_m += w2 * mm[facets[j, 2]]
        m_eff = m_s * m_m / (m_s + m_m)
    k = alpha_dt2 * m_eff
    gdot = 0.0
    for q in range(dim):
        vc = w0 * vm[a, q] + w1 * vm[b, q]
        if dim == 3:
            vc += w2 * vm[facets[j, 2], q]
        gdot += (vs[s, q] - vc) * (n0 if q == 0 else (n1 if q == 1 else n2))
    fn = -k * g - 2.0 * zeta * math.sqrt(k * m_eff) * gdot
    if fn < 0.0:
        fn = 0.0
    pf[s, c] = j
    pw[s, c, 0] = w0
    pw[s, c, 1] = w1
    pn[s, c, 0] = n0
    pn[s, c, 1] = n1
    if dim == 3:
        pw[s, c, 2] = w2
        pn[s, c, 2] = n2
    pg[s, c] = g
    pk[s, c] = k
    pfn[s, c] = fn


@numba.njit(cache=True, inline="always")
def _point(w0, w1, w2, xm, facets, j, q, dim):
    v = w0 * xm[facets[j, 0], q] + w1 * xm[facets[j, 1], q]
    if dim == 3:
        v += w2 * xm[facets[j, 2], q]
    return v


@numba.njit(parallel=True, cache=True)
def _contacts(xs, vs, ms, xm, vm, mm, rigid, facets, normals, indptr, indices, g0, reach, cos_feature,
              alpha_dt2, zeta, pf, pw, pn, pg, pk, pfn, gap, slave_f):
    n_s, dim = xs.shape
    maxc = pf.shape[1]
    for s in prange(n_s):
        for c in range(maxc):
            pf[s, c] = -1
        gap[s] = np.inf
        for q in range(dim):
            slave_f[s, q] = 0.0
        lo = indptr[s]
        hi = indptr[s + 1]
        if lo == hi:
            continue
        best = -1
        best_r2 = np.inf
        for p in range(lo, hi):
            j = indices[p]
            w0, w1, w2, reg = closest_on_facet(xs, s, xm, facets, j)
            r2 = 0.0
            for q in range(dim):
                e = xs[s, q] - _point(w0, w1, w2, xm, facets, j, q, dim)
                r2 += e * e
            if r2 < best_r2:
                best_r2 = r2
                best = j
        nc = 0
        # primary contact: the nearest facet
        j = best
        w0, w1, w2, reg = closest_on_facet(xs, s, xm, facets, j)
        dot = 0.0
        for q in range(dim):
            dot += (xs[s, q] - _point(w0, w1, w2, xm, facets, j, q, dim)) * normals[j, q]
        have = True
        d = dot
        n0 = normals[j, 0]
        n1 = normals[j, 1]
        n2 = normals[j, 2] if dim == 3 else 0.0
        if reg != INTERIOR:
            r = math.sqrt(best_r2)
            if dot < 0.0:
                have = False  # beyond an open end, behind the facet's plane
            elif r > 0.0:  # past the facet's border, in front: the direction from the closest point
                d = r
                n0 = (xs[s, 0] - _point(w0, w1, w2, xm, facets, j, 0, dim)) / r
                n1 = (xs[s, 1] - _point(w0, w1, w2, xm, facets, j, 1, dim)) / r
                if dim == 3:
                    n2 = (xs[s, 2] - _point(w0, w1, w2, xm, facets, j, 2, dim)) / r
            else:
                d = 0.0
        if have:
            g = d - g0
            gap[s] = g
            if g < 0.0 and g > -reach:
                _store(s, nc, j, w0, w1, w2, n0, n1, n2, g, vs, ms, vm, mm, rigid, facets, alpha_dt2, zeta,
                       pf, pw, pn, pg, pk, pfn)
                nc += 1
        # secondary contacts: inside corners
        while nc < maxc:
            pick = -1
            pick_r2 = np.inf
            for p in range(lo, hi):
                j = indices[p]
                if j == best:
                    continue
                taken = False
                for c in range(nc):
                    if pf[s, c] == j:
                        taken = True
                if taken:
                    continue
                w0, w1, w2, reg = closest_on_facet(xs, s, xm, facets, j)
                if reg != INTERIOR:
                    continue
                dot = 0.0
                for q in range(dim):
                    dot += (xs[s, q] - _point(w0, w1, w2, xm, facets, j, q, dim)) * normals[j, q]
                if dot < 0.0 or dot - g0 >= 0.0:
                    continue
                distinct = True
                for c in range(nc):
                    cosine = 0.0
                    for q in range(dim):
                        cosine += normals[j, q] * pn[s, c, q]
                    if cosine >= cos_feature:
                        distinct = False
                if not distinct:
                    continue
                if dot * dot < pick_r2:
                    pick_r2 = dot * dot
                    pick = j
            if pick < 0:
                break
            j = pick
            w0, w1, w2, reg = closest_on_facet(xs, s, xm, facets, j)
            dot = 0.0
            for q in range(dim):
                dot += (xs[s, q] - _point(w0, w1, w2, xm, facets, j, q, dim)) * normals[j, q]
            _store(s, nc, j, w0, w1, w2, normals[j, 0], normals[j, 1], normals[j, 2] if dim == 3 else 0.0,
                   dot - g0, vs, ms, vm, mm, rigid, facets, alpha_dt2, zeta, pf, pw, pn, pg, pk, pfn)
            nc += 1
        for c in range(nc):
            for q in range(dim):
                slave_f[s, q] += pfn[s, c] * pn[s, c, q]


@numba.njit(cache=True)
def _gather(pf, pw, pn, pg, pk, pfn, xm, facets, centre, master_f, total, moment, slave_k, node_k,
            out_slave, out_facet, out_w, out_n, out_g, out_f, out_k, rows):
    """Serial, in slave order: reactions on the master nodes, totals, stiffness row sums, and
    the active contacts as flat arrays (``rows[s]``: the slave's index among all slaves)."""
    n_s, maxc = pf.shape
    dim = xm.shape[1]
    nv = facets.shape[1]
    contacts = 0
    slaves = 0
    deepest = 0.0
    for s in range(n_s):
        if pf[s, 0] < 0:  # contacts are stored from slot 0 on
            continue
        slaves += 1
        for c in range(maxc):
            j = pf[s, c]
            if j < 0:
                continue
            p = contacts
            contacts += 1
            out_slave[p] = rows[s]
            out_facet[p] = j
            out_g[p] = pg[s, c]
            out_f[p] = pfn[s, c]
            out_k[p] = pk[s, c]
            for q in range(dim):
                out_w[p, q] = pw[s, c, q]
                out_n[p, q] = pn[s, c, q]
            if -pg[s, c] > deepest:
                deepest = -pg[s, c]
            slave_k[s] += pk[s, c]
            fm0 = -pfn[s, c] * pn[s, c, 0]
            fm1 = -pfn[s, c] * pn[s, c, 1]
            fm2 = -pfn[s, c] * pn[s, c, 2] if dim == 3 else 0.0
            x0 = 0.0
            x1 = 0.0
            x2 = 0.0
            for v in range(nv):
                a = facets[j, v]
                w = pw[s, c, v]
                master_f[a, 0] += w * fm0
                master_f[a, 1] += w * fm1
                if dim == 3:
                    master_f[a, 2] += w * fm2
                node_k[a] += w * pk[s, c]
                x0 += w * xm[a, 0]
                x1 += w * xm[a, 1]
                if dim == 3:
                    x2 += w * xm[a, 2]
            total[0] += fm0
            total[1] += fm1
            r0 = x0 - centre[0]
            r1 = x1 - centre[1]
            if dim == 2:
                moment[0] += r0 * fm1 - r1 * fm0
            else:
                total[2] += fm2
                r2 = x2 - centre[2]
                moment[0] += r1 * fm2 - r2 * fm1
                moment[1] += r2 * fm0 - r0 * fm2
                moment[2] += r0 * fm1 - r1 * fm0
    return contacts, slaves, deepest


# ---------------------------------------------------------------------------------- API
def _prepare(slave_x, slave_v, slave_m, master_x, master_v, master_m, facets):
    xs = kernel_array(slave_x, np.float64)
    if xs.ndim != 2 or xs.shape[1] not in (2, 3):
        raise ValueError(f"penalty_forces: slave positions must be an (n, 2) or (n, 3) array, got shape {xs.shape}")
    n, d = xs.shape
    vs = kernel_array(slave_v, np.float64)
    ms = kernel_array(slave_m, np.float64, (n,))
    xm = kernel_array(master_x, np.float64)
    vm = np.zeros_like(xm) if master_v is None else kernel_array(master_v, np.float64, xm.shape)
    rigid = master_m is None
    mm = np.zeros(xm.shape[0]) if rigid else kernel_array(master_m, np.float64, (xm.shape[0],))
    f = kernel_array(facets, np.int64)
    if vs.shape != (n, d) or xm.ndim != 2 or xm.shape[1] != d or f.ndim != 2 or f.shape[1] != d:
        raise ValueError(f"penalty_forces: slave positions {xs.shape}, velocities {vs.shape}, master nodes "
                         f"{xm.shape} and facets {f.shape} must share one dimension d (2 or 3): (n, d), (n, d), "
                         "(m, d), (k, d)")
    if f.size and (f.min() < 0 or f.max() >= xm.shape[0]):
        raise ValueError(f"penalty_forces: facet node indices must lie in [0, {xm.shape[0]}), got {int(f.min())} to "
                         f"{int(f.max())}")
    if not np.all(ms > 0) or (not rigid and not np.all(mm > 0)):
        raise ValueError("penalty_forces: slave and master masses must be positive (kg; master_m=None for a rigid "
                         "master), the stiffness k = alpha m*/dt_ref^2 needs them")
    return xs, vs, ms, xm, vm, mm, rigid, f


def _check_scalars(alpha, damping, thickness, reach, feature_angle, dt_ref) -> None:
    """Raise ``ValueError`` listing every bad scalar parameter of :func:`penalty_forces`."""
    problems = check_penalty_parameters("penalty_forces", alpha, damping, thickness, reach, feature_angle, dt_ref)
    for name, value in (("thickness", thickness), ("reach", reach), ("dt_ref", dt_ref)):
        if value is None:
            problems.append(f"penalty_forces: {name} is required")
    if problems:
        raise ValueError("; ".join(problems))


def _stable_dt(slave_k, node_k, ms, mm, rigid, damping):
    """``C · 2(√(1+ζ²) − ζ)/ω`` with the Gershgorin bound of ω (module docstring)."""
    kappa = 1.0 if rigid else 2.0
    w2 = float(np.max(kappa * slave_k / ms, initial=0.0))
    if not rigid:
        touched = node_k > 0
        if touched.any():
            w2 = max(w2, float(np.max(2.0 * node_k[touched] / mm[touched])))
    if w2 <= 0:
        return math.inf
    return STABILITY_FACTOR * 2.0 * (math.sqrt(1.0 + damping**2) - damping) / math.sqrt(w2)


def penalty_forces(
    slave_x: NDArray[np.float64], slave_v: NDArray[np.float64], slave_m: ArrayLike,
    master_x: NDArray[np.float64], master_v: NDArray[np.float64] | None, master_m: ArrayLike | None,
    facets: NDArray[np.int64], *, dt_ref: float, thickness: float, reach: float,
    alpha: float = DEFAULT_ALPHA, damping: float = DEFAULT_DAMPING, feature_angle: float = DEFAULT_FEATURE_ANGLE,
    centre: ArrayLike | None = None, candidates: tuple[NDArray[np.int64], NDArray[np.int64]] | None = None,
) -> PenaltyResult:
    """Penalty forces between slave nodes and a master surface (module docstring; numba).

    Parameters
    ----------
    slave_x, slave_v : (n, d) float arrays
        Slave positions (m) and velocities (m/s).
    slave_m : (n,) or scalar
        Slave masses (kg, per unit depth in 2D).
    master_x : (m, d) float array
        Master node positions (m).
    master_v : (m, d) or (d,) float array, optional
        Master node velocities (m/s); zero if ``None``.
    master_m : (m,) or scalar, optional
        Master nodal masses (kg); ``None`` for a rigid master (``m* = m_s``).
    facets : (k, d) int array
        Master facets, oriented as in :class:`~mlsgalerkin.contact.surface.ContactSurface`.
    dt_ref : float
        Reference time step of the stiffness ``k = α m*/Δt_ref²`` (s).
    thickness, reach : float
        Contact thickness ``g0`` and reach ``r`` (m).
    alpha, damping, feature_angle : float
        Stiffness factor α (–), damping ratio ζ (–), feature angle (degrees).
    centre : (d,) array, optional
        Point about which :attr:`PenaltyResult.moment` is taken (default the origin).
    candidates : (indptr, indices), optional
        Broad-phase pairs (:func:`~mlsgalerkin.contact.search.candidate_pairs` with
        :func:`search_margin`); computed if not given.
    """
    _check_scalars(alpha, damping, thickness, reach, feature_angle, dt_ref)
    xs, vs, ms, xm, vm, mm, rigid, f = _prepare(slave_x, slave_v, slave_m, master_x, master_v, master_m, facets)
    n, d = xs.shape
    if candidates is None:
        candidates = candidate_pairs(xs, xm, f, search_margin(thickness, reach))
    indptr, indices = candidates
    # the narrow phase runs over the slaves that have candidates only (near the surface)
    counts = np.diff(indptr)
    rows = np.flatnonzero(counts)
    t = rows.size
    if t < n:
        sub_ptr = np.zeros(t + 1, dtype=np.int64)
        np.cumsum(counts[rows], out=sub_ptr[1:])
        xs_t, vs_t, ms_t = xs[rows], vs[rows], ms[rows]
    else:
        sub_ptr, xs_t, vs_t, ms_t = kernel_array(indptr, np.int64), xs, vs, ms
    normals = facet_normals(xm, f)
    maxc = d
    pf = np.empty((t, maxc), dtype=np.int64)
    pw, pn = np.empty((t, maxc, d)), np.empty((t, maxc, d))
    pg, pk, pfn = np.empty((t, maxc)), np.empty((t, maxc)), np.empty((t, maxc))
    gap_t, force_t = np.empty(t), np.empty((t, d))
    cos_feature = math.cos(math.radians(feature_angle))
    _contacts(xs_t, vs_t, ms_t, xm, vm, mm, rigid, f, normals, sub_ptr, kernel_array(indices, np.int64),
              float(thickness), float(reach), cos_feature, alpha / dt_ref**2, float(damping), pf, pw, pn, pg, pk, pfn,
              gap_t, force_t)
    master_f = np.zeros_like(xm)
    total = np.zeros(d)
    moment = np.zeros(1 if d == 2 else 3)
    slave_k = np.zeros(t)
    node_k = np.zeros(xm.shape[0])
    c = np.zeros(d) if centre is None else kernel_array(centre, np.float64)
    most = int(np.count_nonzero(pf >= 0))
    out_slave, out_facet = np.empty(most, dtype=np.int64), np.empty(most, dtype=np.int64)
    out_w, out_n, out_g, out_f = np.empty((most, d)), np.empty((most, d)), np.empty(most), np.empty(most)
    out_k = np.empty(most)
    contacts, slaves, deepest = _gather(pf, pw, pn, pg, pk, pfn, xm, f, c, master_f, total, moment, slave_k, node_k,
                                        out_slave, out_facet, out_w, out_n, out_g, out_f, out_k, rows)
    slave_f = np.zeros((n, d))
    slave_f[rows] = force_t
    gaps = np.full(n, np.inf)
    gaps[rows] = gap_t
    return PenaltyResult(
        slave_forces=slave_f, master_forces=master_f, gaps=gaps, contacts=int(contacts), active_slaves=int(slaves),
        max_penetration=float(deepest), total_force=total, moment=float(moment[0]) if d == 2 else moment,
        stable_dt=_stable_dt(slave_k, node_k, ms_t, mm, rigid, damping), pair_slave=out_slave, pair_facet=out_facet,
        pair_weights=out_w, pair_normal=out_n, pair_gap=out_g, pair_force=out_f, pair_stiffness=out_k,
    )


def penalty_forces_reference(
    slave_x, slave_v, slave_m, master_x, master_v, master_m, facets, *, dt_ref, thickness, reach,
    alpha=DEFAULT_ALPHA, damping=DEFAULT_DAMPING, feature_angle=DEFAULT_FEATURE_ANGLE, centre=None,
) -> PenaltyResult:
    """Numpy version of :func:`penalty_forces` (a loop over slaves; tests only)."""
    from mlsgalerkin.contact.geometry import closest_points_reference

    _check_scalars(alpha, damping, thickness, reach, feature_angle, dt_ref)
    xs, vs, ms, xm, vm, mm, rigid, f = _prepare(slave_x, slave_v, slave_m, master_x, master_v, master_m, facets)
    n, d = xs.shape
    indptr, indices = candidate_pairs_reference(xs, xm, f, search_margin(thickness, reach))
    normals = facet_normals_reference(xm, f)
    cos_feature = math.cos(math.radians(feature_angle))
    slave_f, master_f = np.zeros((n, d)), np.zeros_like(xm)
    gaps = np.full(n, np.inf)
    pairs = []  # (slave, facet, weights, normal, gap, force, stiffness)
    total, moment = np.zeros(d), np.zeros(1 if d == 2 else 3)
    slave_k, node_k = np.zeros(n), np.zeros(xm.shape[0])
    c0 = np.zeros(d) if centre is None else np.asarray(centre, dtype=float)
    contacts = slaves = 0
    deepest = 0.0
    for s in range(n):
        cand = indices[indptr[s]:indptr[s + 1]]
        if cand.size == 0:
            continue
        cp = closest_points_reference(np.repeat(xs[s:s + 1], cand.size, axis=0), xm, f, cand)
        r = np.linalg.norm(xs[s] - cp.points, axis=1)
        first = int(np.argmin(r))
        chosen = []  # (facet, weights, normal, gap)
        e = xs[s] - cp.points[first]
        if cp.region[first] == INTERIOR:
            nrm, dist = cp.normals[first], cp.distance[first]
        elif cp.distance[first] >= 0:
            nrm, dist = (e / r[first], r[first]) if r[first] > 0 else (cp.normals[first], 0.0)
        else:
            nrm = None
        if nrm is not None:
            gaps[s] = dist - thickness
            if -reach < gaps[s] < 0:
                chosen.append((cand[first], cp.weights[first], nrm, gaps[s]))
        order = np.argsort(np.abs(cp.distance), kind="stable")
        for q in order:
            if len(chosen) >= d:
                break
            if q == first or cp.region[q] != INTERIOR or cp.distance[q] < 0 or cp.distance[q] - thickness >= 0:
                continue
            if any(cp.normals[q] @ ch[2] >= cos_feature for ch in chosen):
                continue
            chosen.append((cand[q], cp.weights[q], cp.normals[q], cp.distance[q] - thickness))
        if chosen:
            slaves += 1
        for c, (j, w, nrm, g) in enumerate(chosen):
            m_eff = ms[s] if rigid else ms[s] * (w @ mm[f[j]]) / (ms[s] + w @ mm[f[j]])
            k = alpha * m_eff / dt_ref**2
            gdot = (vs[s] - w @ vm[f[j]]) @ nrm
            fn = max(-k * g - 2 * damping * math.sqrt(k * m_eff) * gdot, 0.0)
            slave_f[s] += fn * nrm
            np.add.at(master_f, f[j], -np.outer(w, fn * nrm))
            total -= fn * nrm
            arm = w @ xm[f[j]] - c0
            moment += np.cross(arm, -fn * nrm) if d == 3 else arm[0] * (-fn * nrm[1]) - arm[1] * (-fn * nrm[0])
            slave_k[s] += k
            np.add.at(node_k, f[j], w * k)
            pairs.append((s, j, w, nrm, g, fn, k))
            contacts += 1
            deepest = max(deepest, -g)
    return PenaltyResult(
        slave_forces=slave_f, master_forces=master_f, gaps=gaps, contacts=contacts, active_slaves=slaves,
        max_penetration=deepest, total_force=total, moment=float(moment[0]) if d == 2 else moment,
        stable_dt=_stable_dt(slave_k, node_k, ms, mm, rigid, damping),
        pair_slave=np.array([q[0] for q in pairs], dtype=np.int64), pair_facet=np.array([q[1] for q in pairs], dtype=np.int64),
        pair_weights=np.array([q[2] for q in pairs]).reshape(-1, d), pair_normal=np.array([q[3] for q in pairs]).reshape(-1, d),
        pair_gap=np.array([q[4] for q in pairs], dtype=float), pair_force=np.array([q[5] for q in pairs], dtype=float),
        pair_stiffness=np.array([q[6] for q in pairs], dtype=float),
    )
