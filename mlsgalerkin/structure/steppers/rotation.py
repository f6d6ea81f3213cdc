r"""Rotations of a free 3D rigid body: quaternions and the torque-free splitting.

A free 3D body keeps its orientation as a unit quaternion :math:`q` (:math:`R(q)` turns the body
from rest) and its angular momentum about the centre in the world frame :math:`\mathbf L`
(kg m²/s). With the inertia tensor at rest :math:`I_c = E\,\mathrm{diag}(I_1, I_2, I_3)E^{\mathsf T}`
(principal moments :math:`I_i` in kg m², ascending; principal axes :math:`\mathbf u_i = E\mathbf e_i`
in the rest frame, :math:`\det E = 1`), the torque-free motion over :math:`h` is the splitting of
Dullweber, Leimkuhler & McLachlan (1997, J. Chem. Phys. 107, 5840)

.. math:: q \leftarrow \Phi^{1}_{h/2}\circ\Phi^{2}_{h/2}\circ\Phi^{3}_{h}
          \circ\Phi^{2}_{h/2}\circ\Phi^{1}_{h/2}\,(q),

where :math:`\Phi^i_\tau` is the exact flow of :math:`T_i = \Pi_i^2/(2I_i)`, one part of the
kinetic energy of the free body :math:`T = \sum_i T_i`: a rotation about the principal axis
:math:`\mathbf u_i` by the angle :math:`\varphi = \tau\,\Pi_i/I_i`, :math:`\Pi_i = \mathbf u_i\cdot
R(q)^{\mathsf T}\mathbf L` (kg m²/s, the principal component in the body frame, constant along
:math:`\Phi^i`),

.. math:: q \leftarrow q\otimes\bigl(\cos\tfrac\varphi2,\ \sin\tfrac\varphi2\,\mathbf u_i\bigr),

which leaves :math:`\mathbf L` in the world frame unchanged; :math:`q` is renormalised after the
step. It is explicit, symplectic, time-reversible and second order; it keeps :math:`\mathbf L`
exactly (to round-off) and the kinetic energy within :math:`O(h^2)` without drift.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import NDArray

__all__ = ["FREE_ROTATION_SPLITTING", "free_rotation", "quaternion_matrix", "quaternion_product"]

FloatArray = NDArray[np.float64]

#: The free rotation's splitting ``Φ¹_{δt/2} Φ²_{δt/2} Φ³_{δt} Φ²_{δt/2} Φ¹_{δt/2}``: (principal
#: axis, fraction of the sub-step) in the order applied, principal moments ascending.
FREE_ROTATION_SPLITTING = ((0, 0.5), (1, 0.5), (2, 1.0), (1, 0.5), (0, 0.5))


def quaternion_matrix(q: FloatArray) -> FloatArray:
    """The rotation matrix (3, 3) of the unit quaternion ``q = (w, x, y, z)``."""
    w, x, y, z = q
    return np.array([[1.0 - 2.0 * (y * y + z * z), 2.0 * (x * y - w * z), 2.0 * (x * z + w * y)],
                     [2.0 * (x * y + w * z), 1.0 - 2.0 * (x * x + z * z), 2.0 * (y * z - w * x)],
                     [2.0 * (x * z - w * y), 2.0 * (y * z + w * x), 1.0 - 2.0 * (x * x + y * y)]])


def quaternion_product(a: FloatArray, b: FloatArray) -> FloatArray:
    """Hamilton's product ``a ⊗ b`` (the rotation ``R(a) R(b)``)."""
    aw, ax, ay, az = a
    bw, bx, by, bz = b
    return np.array([aw * bw - ax * bx - ay * by - az * bz, aw * bx + ax * bw + ay * bz - az * by,
                     aw * by - ax * bz + ay * bw + az * bx, aw * bz + ax * by - ay * bx + az * bw])


def free_rotation(q: FloatArray, L: FloatArray, axes: FloatArray, moments: FloatArray, h: float) -> FloatArray:
    """The orientation ``q`` (unit quaternion) after the torque-free motion over ``h`` (s) with the
    world angular momentum ``L`` (kg m²/s, unchanged), by the splitting of Dullweber, Leimkuhler
    & McLachlan (1997) (module docstring): exact rotations about the principal ``axes`` (columns
    of (3, 3), rest frame) with the principal ``moments`` (3,) (kg m²); renormalised."""
    for i, part in FREE_ROTATION_SPLITTING:
        u = axes[:, i]
        phi = part * h * float(u @ (quaternion_matrix(q).T @ L)) / moments[i]
        s = math.sin(0.5 * phi)
        q = quaternion_product(q, np.array([math.cos(0.5 * phi), s * u[0], s * u[1], s * u[2]]))
    return q / math.sqrt(float(q @ q))

