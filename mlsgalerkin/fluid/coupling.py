"""Moved: :class:`StructureCoupling` (with ``riding_kinematics``, ``AITKEN_RANGE``) is in
:mod:`mlsgalerkin.interactions.structure_coupling`.

This module path keeps working for one release; each name read from it gives a
``DeprecationWarning`` naming the new one.
"""

from __future__ import annotations

import warnings
from typing import Any

__all__: list[str] = []

#: Old name -> the module that holds it now.
MOVED = {name: "mlsgalerkin.interactions.structure_coupling"
         for name in ("AITKEN_RANGE", "StructureCoupling", "riding_kinematics")}


def __getattr__(name: str) -> Any:
    if name in MOVED:
        warnings.warn(f"mlsgalerkin.fluid.coupling.{name} has moved: write 'from mlsgalerkin.interactions import "
                      f"{name}' ({MOVED[name]}); the old path goes in the next release", DeprecationWarning,
                      stacklevel=2)
        from mlsgalerkin.interactions import structure_coupling

        globals()[name] = getattr(structure_coupling, name)  # one warning per name (``from ... import`` looks it up twice)
        return globals()[name]
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
