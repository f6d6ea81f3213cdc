"""Arrays as the numba kernels take them: one compiled specialisation per kernel.

numba compiles a kernel once per *type* of each argument, and an array's type holds its dtype,
number of dimensions, layout and write flag. A read-only view (what :func:`numpy.broadcast_to`
returns, a slice of a memory-mapped file, an array a user froze) is a different type from the
writable array of the same shape, and a large parallel kernel compiles for about a minute. A
public function whose caller's arrays reach a kernel (``penalty_forces``,
``extrapolate_wall_state``) passes them through :func:`kernel_array`, so every call reaches the
one specialisation already compiled (or cached on disk).

>>> import numpy as np
>>> frozen = np.broadcast_to(np.ones(3), (4, 3))
>>> a = kernel_array(frozen, np.float64)
>>> a.flags.c_contiguous and a.flags.writeable
True
>>> b = np.zeros(5)
>>> kernel_array(b, np.float64) is b     # already what a kernel takes: no copy
True
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, DTypeLike, NDArray

__all__ = ["kernel_array"]


def kernel_array(a: ArrayLike, dtype: DTypeLike, shape: tuple[int, ...] | None = None) -> NDArray:
    """``a`` as a C-contiguous, writable array of ``dtype``, broadcast to ``shape`` if given.

    A copy is made only when ``a`` is not already such an array (a read-only or strided view,
    another dtype, a scalar or a shorter array broadcast to ``shape``).
    """
    out = np.asarray(a, dtype=dtype)
    if shape is not None and out.shape != tuple(shape):
        out = np.broadcast_to(out, shape)
    return np.require(out, requirements=("C", "W"))
