"""Moved: :class:`PenaltyContact` is in :mod:`mlsgalerkin.interactions.penalty_contact`.

This module path keeps working for one release; each name read from it gives a
``DeprecationWarning`` naming the new one.
"""

from __future__ import annotations

import warnings
from typing import Any

__all__: list[str] = []

#: Old name -> the module that holds it now.
MOVED = {"PenaltyContact": "mlsgalerkin.interactions.penalty_contact"}


def __getattr__(name: str) -> Any:
    if name in MOVED:
        warnings.warn(f"mlsgalerkin.contact.interaction.{name} has moved: write 'from mlsgalerkin.interactions import "
                      f"{name}' ({MOVED[name]}); the old path goes in the next release", DeprecationWarning,
                      stacklevel=2)
        from mlsgalerkin.interactions import penalty_contact

        globals()[name] = getattr(penalty_contact, name)  # one warning per name (``from ... import`` looks it up twice)
        return globals()[name]
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
