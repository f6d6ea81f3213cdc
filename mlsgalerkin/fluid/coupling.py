"""Moved: :class:`StructureCoupling` (with ``riding_kinematics``, ``AITKEN_RANGE``) is in
:mod:`mlsgalerkin.interactions.structure_coupling`.

This module path keeps working for one release; each name read from it gives a
``DeprecationWarning`` naming the new one.
"""

from __future__ import annotations

from mlsgalerkin.deprecation import moved_names

__all__: list[str] = []

__getattr__ = moved_names(__name__, {name: "mlsgalerkin.interactions"
                                     for name in ("AITKEN_RANGE", "StructureCoupling", "riding_kinematics")})
