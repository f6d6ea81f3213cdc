"""Moved: :class:`PenaltyContact` is in :mod:`mlsgalerkin.interactions.penalty_contact`.

This module path keeps working for one release; each name read from it gives a
``DeprecationWarning`` naming the new one.
"""

from __future__ import annotations

from mlsgalerkin.deprecation import moved_names

__all__: list[str] = []

__getattr__ = moved_names(__name__, {"PenaltyContact": "mlsgalerkin.interactions"})
