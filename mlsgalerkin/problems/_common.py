"""Shared machinery of the problem modules: parameter parsing, hydrostatic start, running.

A problem module defines a ``Parameters`` dataclass (named parameters with defaults and
units in the field docstrings), ``make_scene(params) -> Scene``, ``analyse(result, params) ->
dict`` (the problem's results: errors against references, measured speeds) and ``SMOKE``
(overrides for a seconds-long smoke run used by the tests).
"""

from __future__ import annotations

import dataclasses
import logging
from typing import Any

import numpy as np


__all__ = ["parse_overrides", "hydrostatic_density", "kth_smallest"]

logger = logging.getLogger(__name__)


def parse_overrides(params_cls, overrides: dict[str, Any]):
    """``params_cls(**overrides)`` with strings converted to each field's type.

    Unknown names raise a ``ValueError`` listing the valid ones.
    """
    fields = {f.name: f for f in dataclasses.fields(params_cls)}
    unknown = sorted(set(overrides) - set(fields))
    if unknown:
        valid = ", ".join(sorted(fields))
        raise ValueError(f"unknown parameter(s) {unknown} for {params_cls.__module__}; valid: {valid}")
    kwargs = {}
    defaults = params_cls()
    for name, value in overrides.items():
        current = getattr(defaults, name)
        if isinstance(value, str):
            try:
                if isinstance(current, bool):
                    value = value.lower() in ("1", "true", "yes", "on")
                elif isinstance(current, int):
                    value = int(value)
                elif isinstance(current, float) or current is None:
                    value = float(value)
                elif isinstance(current, tuple):
                    value = tuple(float(v) for v in value.strip("()").split(","))
            except ValueError:
                raise ValueError(f"parameter {name}: cannot read {value!r} as {type(current).__name__}") from None
        kwargs[name] = value
    return params_cls(**kwargs)


def hydrostatic_density(eos_c0: float, rho0: np.ndarray, depth_below_surface: np.ndarray, g: float,
                        overburden: np.ndarray | float = 0.0, gamma: float = 7.0) -> np.ndarray:
    """Tait density at hydrostatic pressure ``p = overburden + ρ0 g depth`` (per particle ``ρ0``)."""
    p = overburden + rho0 * g * depth_below_surface
    B = rho0 * eos_c0**2 / gamma
    return rho0 * (1.0 + p / B) ** (1.0 / gamma)


def kth_smallest(a: np.ndarray, k: int) -> float:
    """The ``k``-th smallest value (0-based) — a front position robust to ``k`` stray particles."""
    if a.size == 0:
        return float("nan")
    k = min(k, a.size - 1)
    return float(np.partition(a, k)[k])
