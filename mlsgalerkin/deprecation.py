"""Names that moved keep working for one release: one helper for every module that forwards them.

A module whose public names moved defines its ``__getattr__`` with :func:`moved_names`; each old
name is looked up in its new home when first read, with a ``DeprecationWarning`` that says what
to write instead. A module that moved as a whole is an alias made by :func:`moved_module`. The new home is imported by name when the old name is read (never at import
time), so a forward may point up the layers without an import edge.

>>> import warnings
>>> __getattr__ = moved_names("pkg.old", {"sqrt": "math", "tau_value": "math:tau"})
>>> with warnings.catch_warnings(record=True) as caught:
...     warnings.simplefilter("always")
...     round(__getattr__("tau_value"), 4)
6.2832
>>> str(caught[0].message)
"pkg.old.tau_value has moved: write 'from math import tau'; the old name goes in the next release"
"""

from __future__ import annotations

import importlib
import sys
import warnings
from typing import Any, Callable, Mapping

__all__ = ["moved_module", "moved_names"]


def moved_names(module: str, moved: Mapping[str, str], note: str = "") -> Callable[[str], Any]:
    """A module ``__getattr__`` for the old names of ``module``: ``moved`` maps each old name to its
    new home, ``"package.module"`` (same name) or ``"package.module:NewName"``; ``note`` is added to
    the warning (e.g. how a call changed). The value is cached in ``module`` after the first read,
    so each old name warns once per process (``from m import x`` looks ``x`` up twice)."""

    def __getattr__(name: str) -> Any:
        target = moved.get(name)
        if target is None:
            raise AttributeError(f"module {module!r} has no attribute {name!r}")
        where, _, new = target.partition(":")
        new = new or name
        warnings.warn(f"{module}.{name} has moved: write 'from {where} import {new}'{note}; the old name goes in "
                      "the next release", DeprecationWarning, stacklevel=2)
        value = getattr(importlib.import_module(where), new)
        if module in sys.modules:
            setattr(sys.modules[module], name, value)
        return value

    return __getattr__


def moved_module(old: str, new: str) -> tuple[Callable[[str], Any], Callable[[], list[str]]]:
    """``(__getattr__, __dir__)`` of module ``old``, now an alias of module ``new``: importing
    ``old`` warns once (``DeprecationWarning``, naming ``new``), and every attribute is ``new``'s."""
    warnings.warn(f"{old} has moved to {new}: import it from there; the old module goes in the next release",
                  DeprecationWarning, stacklevel=3)
    target = importlib.import_module(new)

    def __getattr__(name: str) -> Any:
        return getattr(target, name)

    def __dir__() -> list[str]:
        return dir(target)

    return __getattr__, __dir__
