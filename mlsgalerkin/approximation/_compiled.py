r"""numba kernels for MLS/RKPM/Shepard/orthogonal shape functions and their exact gradients.

All kernels fill per-pair arrays aligned with a CSR neighbour table (``indptr``, ``indices``):
``values[p] = N_j(x_i)`` and ``grads[p, k] = ∂N_j/∂x_k(x_i)`` for pair ``p`` of point ``i`` and
node ``j = indices[p]``, plus per-point ``order_out`` (order used; -1 if even the constant basis
failed) and ``cond_out`` (1-norm condition number of the scaled moment matrix at that order).

Formulas (exact derivatives with a "frozen centre" of the shifted basis): with weights ``w_j = f(r_j/h_j) / h_j^d [V_j]``,
scaled basis ``P_j = P((x_j - x)/s)``, ``M = Σ_j w_j P_j P_jᵀ``, ``γ = M⁻¹ P(0)``:

    N_j = (γ·P_j) w_j
    ∂_k γ = M⁻¹ (∂_k p − ∂_k M γ),  ∂_k p = ∂P/∂ξ_k(0) / s,  ∂_k M = Σ_j ∂_k w_j P_j P_jᵀ
    ∂_k N_j = (∂_k γ·P_j) w_j + (γ·P_j) ∂_k w_j

Kernel sum (on request, ``use_sum``): per point ``ksum[i] = Σ_j w_j sum_scale_j`` and
``ksum_grad[i] = Σ_j ∇w_j sum_scale_j`` (the zeroth moment ``M_00`` with per-node factors: with
``sum_scale_j = V_j`` on MLS weights, or ``V_j / vol_j`` on RKPM weights that carry ``vol_j``, it
is the Shepard sum ``Σ_j W(x − x_j, h_j) V_j``), accumulated in the same pass as the moment
matrix at no extra kernel evaluation.

Fallback: the requested order is tried first, then each lower order (the basis is ordered by
degree, so the lower-order moment matrix is the leading block); an order is accepted when its
Cholesky factorisation succeeds with every pivot above ``RELATIVE_PIVOT_TOL`` times its diagonal
entry, and ``cond_1(M) <= cond_limit``.

Two implementations: :func:`general_shape_kernel` (any order/dimension; optional Gram–Schmidt)
and :func:`linear2d_shape_kernel` (2D linear, closed-form 3x3 inverse, fused loops).

Periodic domains: every kernel takes ``period`` (three floats, m; ``0`` on the axes that are not
periodic) and uses the minimum image of each offset ``x_j − x`` along the periodic axes
(:func:`mlsgalerkin.pairs.image_component`), so a node across the seam enters the moment matrix
at its image; with all periods zero the offsets are the plain differences, bit for bit.
"""

from __future__ import annotations

import math

import numba
import numpy as np
from numba import prange

from mlsgalerkin.kernels import kernel_f_df
from mlsgalerkin.pairs import image_component
from mlsgalerkin.polynomials import evaluate_basis

_CHUNK = 64

#: A Cholesky pivot below this fraction of its diagonal entry is rounding noise: the moment
#: matrix is singular to working precision. (Matrices that pass the default condition limit
#: 1e8 have relative pivots of at least ~1/(m * 1e8) > 3e-10.) Without this check a
#: rank-deficient 3x3 matrix can pass, because its adjugate and determinant are both noise and
#: their ratio looks like a well-conditioned inverse.
RELATIVE_PIVOT_TOL = 1e-12


@numba.njit(cache=True, inline="always")
def _pair_weight(points, nodes, i, j, h, inv_hd, vol, use_vol, kid, support, dim, dw, period):
    """Weight ``w_j(x_i)``; fills ``dw[:dim]`` with ``∂w/∂x``. Returns ``(w, r)``."""
    r2 = 0.0
    for k in range(dim):
        d = image_component(points[i, k] - nodes[j, k], period[k])
        r2 += d * d
    r = math.sqrt(r2)
    hj = h[j]
    f, df = kernel_f_df(kid, r / hj, support, dim)
    scale = inv_hd[j] * (vol[j] if use_vol else 1.0)
    w = f * scale
    if r > 0.0:
        c = df * scale / (hj * r)
        for k in range(dim):
            dw[k] = c * image_component(points[i, k] - nodes[j, k], period[k])
    else:
        for k in range(dim):
            dw[k] = 0.0
    return w, r


@numba.njit(cache=True, inline="always")
def _cholesky(M, mo, L):
    """Lower Cholesky factor of ``M[:mo, :mo]`` into ``L``; False if not positive definite."""
    for k in range(mo):
        d = M[k, k]
        for l in range(k):
            d -= L[k, l] * L[k, l]
        if not d > RELATIVE_PIVOT_TOL * M[k, k]:
            return False
        L[k, k] = math.sqrt(d)
        for i in range(k + 1, mo):
            s = M[i, k]
            for l in range(k):
                s -= L[i, l] * L[k, l]
            L[i, k] = s / L[k, k]
    return True


@numba.njit(cache=True, inline="always")
def _inverse_from_cholesky(L, mo, T, Minv):
    """``Minv = L⁻ᵀ L⁻¹`` using ``T`` as scratch for ``L⁻¹``."""
    for c in range(mo):
        for i in range(mo):
            s = 1.0 if i == c else 0.0
            for l in range(i):
                s -= L[i, l] * T[l, c]
            T[i, c] = s / L[i, i] if i >= c else 0.0
    for a in range(mo):
        for b in range(a, mo):
            s = 0.0
            for l in range(b, mo):
                s += T[l, a] * T[l, b]
            Minv[a, b] = s
            Minv[b, a] = s


@numba.njit(cache=True, inline="always")
def _norm1(A, mo):
    best = 0.0
    for c in range(mo):
        s = 0.0
        for r in range(mo):
            s += abs(A[r, c])
        best = max(best, s)
    return best


@numba.njit(cache=True, inline="always")
def _gram_schmidt(Pn, w, n, mo, L, dvec, ok_tol):
    """Modified Gram–Schmidt of the columns ``Pn[:n, :mo]`` in ``<a, b> = Σ a b w``.

    Overwrites ``Pn[:, a]`` with ``q_a`` at the nodes and ``L`` (unit lower) with ``q = L P``;
    ``dvec[a] = <q_a, q_a>``. False when a column loses more than ``1 - ok_tol`` of its norm
    (linear dependence at this order).
    """
    for a in range(mo):
        for b in range(mo):
            L[a, b] = 1.0 if a == b else 0.0
        norm0 = 0.0
        for t in range(n):
            norm0 += Pn[t, a] * Pn[t, a] * w[t]
        for b in range(a):
            c = 0.0
            for t in range(n):
                c += Pn[t, a] * Pn[t, b] * w[t]
            c /= dvec[b]
            for t in range(n):
                Pn[t, a] -= c * Pn[t, b]
            for l in range(b + 1):
                L[a, l] -= c * L[b, l]
        d = 0.0
        for t in range(n):
            d += Pn[t, a] * Pn[t, a] * w[t]
        if not d > ok_tol * norm0:
            return False
        dvec[a] = d
    return True


@numba.njit(parallel=True, cache=True)
def general_shape_kernel(
    points, nodes, h, inv_hd, vol, use_vol, kid, support, indptr, indices, exps, sizes,
    order_req, cond_limit, orthogonal, values, grads, order_out, cond_out, period, use_sum, sum_scale, ksum,
    ksum_grad,
):
    """General path: any dimension, any order in ``sizes``; MLS/RKPM or Gram–Schmidt."""
    n_pts, dim = points.shape
    m = sizes[order_req]
    n_chunks = (n_pts + _CHUNK - 1) // _CHUNK
    for c in prange(n_chunks):
        i0 = c * _CHUNK
        i1 = min(i0 + _CHUNK, n_pts)
        max_nb = 1
        for i in range(i0, i1):
            max_nb = max(max_nb, indptr[i + 1] - indptr[i])
        M = np.empty((m, m))
        dM = np.empty((dim, m, m))
        L = np.empty((m, m))
        T = np.empty((m, m))
        Minv = np.empty((m, m))
        P = np.empty(m)
        xi = np.empty(dim)
        dw = np.empty(dim)
        gam = np.empty(m)
        dgam = np.empty((dim, m))
        tmp = np.empty(m)
        dvec = np.empty(m)
        Pn = np.empty((max_nb, m))
        wn = np.empty(max_nb)
        for i in range(i0, i1):
            p0 = indptr[i]
            p1 = indptr[i + 1]
            n = p1 - p0
            if n == 0:
                order_out[i] = -1
                cond_out[i] = np.inf
                continue
            s = 0.0
            for p in range(p0, p1):
                s += h[indices[p]]
            s /= n
            M[:, :] = 0.0
            dM[:, :, :] = 0.0
            for p in range(p0, p1):
                j = indices[p]
                w, r = _pair_weight(points, nodes, i, j, h, inv_hd, vol, use_vol, kid, support, dim, dw, period)
                values[p] = w
                for k in range(dim):
                    grads[p, k] = dw[k]
                    xi[k] = image_component(nodes[j, k] - points[i, k], period[k]) / s
                evaluate_basis(xi, exps, m, P)
                for a in range(m):
                    for b in range(a, m):
                        pp = P[a] * P[b]
                        M[a, b] += w * pp
                        for k in range(dim):
                            dM[k, a, b] += dw[k] * pp
                if orthogonal:
                    wn[p - p0] = w
            for a in range(m):
                for b in range(a):
                    M[a, b] = M[b, a]
                    for k in range(dim):
                        dM[k, a, b] = dM[k, b, a]
            if use_sum:
                acc = 0.0
                for k in range(dim):
                    xi[k] = 0.0
                for p in range(p0, p1):
                    sc = sum_scale[indices[p]]
                    acc += values[p] * sc
                    for k in range(dim):
                        xi[k] += grads[p, k] * sc
                ksum[i] = acc
                for k in range(dim):
                    ksum_grad[i, k] = xi[k]

            used = -1
            mo = 1
            for o in range(order_req, -1, -1):
                mo = sizes[o]
                if orthogonal:
                    for p in range(p0, p1):
                        j = indices[p]
                        for k in range(dim):
                            xi[k] = image_component(nodes[j, k] - points[i, k], period[k]) / s
                        evaluate_basis(xi, exps, mo, tmp)
                        for a in range(mo):
                            Pn[p - p0, a] = tmp[a]
                    if not _gram_schmidt(Pn, wn, n, mo, L, dvec, 1e-14):
                        continue
                    # M⁻¹ = Lᵀ D⁻¹ L  (q = L P has the diagonal moment matrix D)
                    for a in range(mo):
                        for b in range(mo):
                            acc = 0.0
                            for l in range(max(a, b), mo):
                                acc += L[l, a] * L[l, b] / dvec[l]
                            Minv[a, b] = acc
                else:
                    if not _cholesky(M, mo, L):
                        continue
                    _inverse_from_cholesky(L, mo, T, Minv)
                cond = _norm1(M, mo) * _norm1(Minv, mo)
                if cond <= cond_limit:
                    used = o
                    cond_out[i] = cond
                    break
            order_out[i] = used
            if used < 0:
                cond_out[i] = np.inf
                for p in range(p0, p1):
                    values[p] = 0.0
                    for k in range(dim):
                        grads[p, k] = 0.0
                continue

            # γ = M⁻¹ e₀ ; ∂_k γ = M⁻¹ (∂_k p − ∂_k M γ), ∂_k p = e_{1+k}/s for order ≥ 1
            for a in range(mo):
                gam[a] = Minv[a, 0]
            for k in range(dim):
                for a in range(mo):
                    acc = 0.0
                    for b in range(mo):
                        acc += dM[k, a, b] * gam[b]
                    tmp[a] = -acc
                if mo > 1:
                    tmp[1 + k] += 1.0 / s
                for a in range(mo):
                    acc = 0.0
                    for b in range(mo):
                        acc += Minv[a, b] * tmp[b]
                    dgam[k, a] = acc
            for p in range(p0, p1):
                j = indices[p]
                for k in range(dim):
                    xi[k] = image_component(nodes[j, k] - points[i, k], period[k]) / s
                evaluate_basis(xi, exps, mo, P)
                w = values[p]
                if orthogonal:
                    # N_j = w_j Σ_a q_a(x) q_a(x_j) / <q_a, q_a>, q_a(x) = L[a, 0] (P(0) = e₀)
                    cg = 0.0
                    for a in range(mo):
                        cg += L[a, 0] * Pn[p - p0, a] / dvec[a]
                else:
                    cg = 0.0
                    for a in range(mo):
                        cg += gam[a] * P[a]
                values[p] = cg * w
                for k in range(dim):
                    acc = 0.0
                    for a in range(mo):
                        acc += dgam[k, a] * P[a]
                    grads[p, k] = acc * w + cg * grads[p, k]


@numba.njit(parallel=True, cache=True)
def linear2d_shape_kernel(
    points, nodes, h, inv_hd, vol, use_vol, kid, support, indptr, indices, cond_limit,
    values, grads, order_out, cond_out, period, use_sum, sum_scale, ksum, ksum_grad,
):
    """Fused 2D linear MLS/RKPM: closed-form 3x3 inverse, Shepard inline as the fallback."""
    n_pts = points.shape[0]
    px = period[0]
    py = period[1]
    for i in prange(n_pts):
        p0 = indptr[i]
        p1 = indptr[i + 1]
        n = p1 - p0
        if n == 0:
            order_out[i] = -1
            cond_out[i] = np.inf
            continue
        xi_ = points[i, 0]
        yi_ = points[i, 1]
        s = 0.0
        for p in range(p0, p1):
            s += h[indices[p]]
        s /= n
        inv_s = 1.0 / s
        m00 = m01 = m02 = m11 = m12 = m22 = 0.0
        a00 = a01 = a02 = a11 = a12 = a22 = 0.0  # ∂M/∂x
        b00 = b01 = b02 = b11 = b12 = b22 = 0.0  # ∂M/∂y
        k0 = kx = ky = 0.0                        # kernel sum and its gradient
        for p in range(p0, p1):
            j = indices[p]
            dx = image_component(xi_ - nodes[j, 0], px)
            dy = image_component(yi_ - nodes[j, 1], py)
            r = math.sqrt(dx * dx + dy * dy)
            hj = h[j]
            f, df = kernel_f_df(kid, r / hj, support, 2)
            sc = inv_hd[j] * (vol[j] if use_vol else 1.0)
            w = f * sc
            c = df * sc / (hj * r) if r > 0.0 else 0.0
            wx = c * dx
            wy = c * dy
            values[p] = w
            grads[p, 0] = wx
            grads[p, 1] = wy
            ex = -dx * inv_s
            ey = -dy * inv_s
            exx = ex * ex
            exy = ex * ey
            eyy = ey * ey
            m00 += w
            m01 += w * ex
            m02 += w * ey
            m11 += w * exx
            m12 += w * exy
            m22 += w * eyy
            a00 += wx
            a01 += wx * ex
            a02 += wx * ey
            a11 += wx * exx
            a12 += wx * exy
            a22 += wx * eyy
            b00 += wy
            b01 += wy * ex
            b02 += wy * ey
            b11 += wy * exx
            b12 += wy * exy
            b22 += wy * eyy
            if use_sum:
                sc_j = sum_scale[j]
                k0 += w * sc_j
                kx += wx * sc_j
                ky += wy * sc_j
        if use_sum:
            ksum[i] = k0
            ksum_grad[i, 0] = kx
            ksum_grad[i, 1] = ky
        # adjugate inverse of the symmetric 3x3 moment matrix
        c00 = m11 * m22 - m12 * m12
        c01 = m02 * m12 - m01 * m22
        c02 = m01 * m12 - m02 * m11
        c11 = m00 * m22 - m02 * m02
        c12 = m01 * m02 - m00 * m12
        c22 = m00 * m11 - m01 * m01
        det = m00 * c00 + m01 * c01 + m02 * c02
        linear_ok = False
        cond = np.inf
        # Cholesky pivots m00, c22/m00, det/c22, each relative to its diagonal entry
        if (
            m00 > 0.0
            and c22 > RELATIVE_PIVOT_TOL * m00 * m11
            and det > RELATIVE_PIVOT_TOL * c22 * m22
        ):
            inv = 1.0 / det
            i00 = c00 * inv
            i01 = c01 * inv
            i02 = c02 * inv
            i11 = c11 * inv
            i12 = c12 * inv
            i22 = c22 * inv
            n_m = max(abs(m00) + abs(m01) + abs(m02),
                      max(abs(m01) + abs(m11) + abs(m12), abs(m02) + abs(m12) + abs(m22)))
            n_i = max(abs(i00) + abs(i01) + abs(i02),
                      max(abs(i01) + abs(i11) + abs(i12), abs(i02) + abs(i12) + abs(i22)))
            cond = n_m * n_i
            if cond <= cond_limit:
                linear_ok = True
        if linear_ok:
            order_out[i] = 1
            cond_out[i] = cond
            g0, g1, g2 = i00, i01, i02
            # ∂_x γ = M⁻¹ (e₁/s − ∂_x M γ)
            t0 = -(a00 * g0 + a01 * g1 + a02 * g2)
            t1 = -(a01 * g0 + a11 * g1 + a12 * g2) + inv_s
            t2 = -(a02 * g0 + a12 * g1 + a22 * g2)
            gx0 = i00 * t0 + i01 * t1 + i02 * t2
            gx1 = i01 * t0 + i11 * t1 + i12 * t2
            gx2 = i02 * t0 + i12 * t1 + i22 * t2
            t0 = -(b00 * g0 + b01 * g1 + b02 * g2)
            t1 = -(b01 * g0 + b11 * g1 + b12 * g2)
            t2 = -(b02 * g0 + b12 * g1 + b22 * g2) + inv_s
            gy0 = i00 * t0 + i01 * t1 + i02 * t2
            gy1 = i01 * t0 + i11 * t1 + i12 * t2
            gy2 = i02 * t0 + i12 * t1 + i22 * t2
            for p in range(p0, p1):
                j = indices[p]
                ex = image_component(nodes[j, 0] - xi_, px) * inv_s
                ey = image_component(nodes[j, 1] - yi_, py) * inv_s
                w = values[p]
                cg = g0 + g1 * ex + g2 * ey
                values[p] = cg * w
                grads[p, 0] = (gx0 + gx1 * ex + gx2 * ey) * w + cg * grads[p, 0]
                grads[p, 1] = (gy0 + gy1 * ex + gy2 * ey) * w + cg * grads[p, 1]
        elif m00 > 0.0:
            # Shepard: N_j = w_j / Σw,  ∇N_j = (∇w_j − N_j Σ∇w) / Σw
            order_out[i] = 0
            cond_out[i] = 1.0
            inv = 1.0 / m00
            for p in range(p0, p1):
                nj = values[p] * inv
                values[p] = nj
                grads[p, 0] = (grads[p, 0] - nj * a00) * inv
                grads[p, 1] = (grads[p, 1] - nj * b00) * inv
        else:
            order_out[i] = -1
            cond_out[i] = np.inf
            for p in range(p0, p1):
                values[p] = 0.0
                grads[p, 0] = 0.0
                grads[p, 1] = 0.0


@numba.njit(parallel=True, cache=True)
def singular_shepard_kernel(points, nodes, radius, indptr, indices, exponent, values, grads, order_out, period):
    r"""Interpolating Shepard with the Franke–Little weight ``w = ((R_j − r)/(R_j r))^α``.

    ``∂w/∂r = −α ((R_j − r)/(R_j r))^{α−1} / r²``. A point closer than ``1e-12 R_j`` to a node
    coincides with it: ``N = δ`` (shared equally among coincident duplicates), ``∇N = 0``.
    """
    n_pts, dim = points.shape
    for i in prange(n_pts):
        p0 = indptr[i]
        p1 = indptr[i + 1]
        if p1 == p0:
            order_out[i] = -1
            continue
        order_out[i] = 0
        n_coincident = 0
        for p in range(p0, p1):
            j = indices[p]
            r2 = 0.0
            for k in range(dim):
                d = image_component(points[i, k] - nodes[j, k], period[k])
                r2 += d * d
            if math.sqrt(r2) < 1e-12 * radius[j]:
                n_coincident += 1
        if n_coincident > 0:
            for p in range(p0, p1):
                j = indices[p]
                r2 = 0.0
                for k in range(dim):
                    d = image_component(points[i, k] - nodes[j, k], period[k])
                    r2 += d * d
                values[p] = 1.0 / n_coincident if math.sqrt(r2) < 1e-12 * radius[j] else 0.0
                for k in range(dim):
                    grads[p, k] = 0.0
            continue
        sw = 0.0
        sdw = np.zeros(dim)
        for p in range(p0, p1):
            j = indices[p]
            r2 = 0.0
            for k in range(dim):
                d = image_component(points[i, k] - nodes[j, k], period[k])
                r2 += d * d
            r = math.sqrt(r2)
            R = radius[j]
            u = (R - r) / (R * r)
            w = u**exponent
            dwdr = -exponent * u ** (exponent - 1.0) / r2
            values[p] = w
            sw += w
            for k in range(dim):
                g = dwdr * image_component(points[i, k] - nodes[j, k], period[k]) / r
                grads[p, k] = g
                sdw[k] += g
        if not sw > 0.0:
            order_out[i] = -1
            continue
        inv = 1.0 / sw
        for p in range(p0, p1):
            nj = values[p] * inv
            values[p] = nj
            for k in range(dim):
                grads[p, k] = (grads[p, k] - nj * sdw[k]) * inv
