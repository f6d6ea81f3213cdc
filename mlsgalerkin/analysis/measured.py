"""Honest results: a quantity a run did not measure is ``None`` with a reason, never NaN.

A problem's analysis reports a number only when the run covered the event the number needs (a
peak that has passed, a window that has closed, a period with enough cycles). Otherwise the
result is ``None`` (JSON ``null``), a ``"<key>_not_measured"`` entry says why and how long the
run must be, and the headline says ``"not measured: <why>, run to t ≥ <time>"``.

>>> out = {}
>>> not_measured(out, "period_s", "fewer than 2 cycles after the load", run_to=0.9)
'not measured: fewer than 2 cycles after the load, run to t ≥ 0.9 s'
>>> out
{'period_s': None, 'period_s_not_measured': 'fewer than 2 cycles after the load, run to t ≥ 0.9 s'}
>>> unexplained_values(out), unexplained_values({"x": float("nan")})
([], ['x = nan has no x_not_measured reason'])
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Mapping
from typing import Any

__all__ = ["NOT_MEASURED_SUFFIX", "not_measured", "reason", "unexplained_values"]

#: The suffix of the key that holds the reason a result is ``None``.
NOT_MEASURED_SUFFIX = "_not_measured"


def reason(why: str, run_to: float | None = None, unit: str = "s") -> str:
    """``"<why>, run to t ≥ <run_to> <unit>"`` (or ``why`` alone without ``run_to``)."""
    return why if run_to is None else f"{why}, run to t ≥ {run_to:.4g} {unit}"


def not_measured(results: dict[str, Any], keys: str | Iterable[str], why: str, run_to: float | None = None,
                 unit: str = "s") -> str:
    """Set every key of ``keys`` in ``results`` to ``None`` with the reason
    ``results[key + "_not_measured"]``; return the headline text ``"not measured: <reason>"``.

    ``run_to`` is the end time (in ``unit``, seconds unless the problem's analysis speaks in its own
    time scale) the run must reach for the quantity to be measured; ``None`` when no longer run
    helps (a finer spacing or another setting is needed, and ``why`` says which).
    """
    text = reason(why, run_to, unit)
    for key in [keys] if isinstance(keys, str) else keys:
        results[key] = None
        results[key + NOT_MEASURED_SUFFIX] = text
    return f"not measured: {text}"


def _floats(value: Any, path: str) -> Iterable[tuple[str, float]]:
    if isinstance(value, float):
        yield path, value
    elif isinstance(value, Mapping):
        for k, v in value.items():
            yield from _floats(v, f"{path}.{k}" if path else str(k))
    elif isinstance(value, (list, tuple)):
        for i, v in enumerate(value):
            yield from _floats(v, f"{path}[{i}]")


def unexplained_values(results: Mapping[str, Any]) -> list[str]:
    """What breaks the rule in a results dict: every float (at any depth) that is NaN or infinite,
    and every top-level ``None`` without its ``"<key>_not_measured"`` reason. Empty when honest."""
    out = [f"{path} = {value!r} has no {path}{NOT_MEASURED_SUFFIX} reason" if "." not in path and "[" not in path
           else f"{path} = {value!r}" for path, value in _floats(dict(results), "") if not math.isfinite(value)]
    out += [f"{key} is None without a {key}{NOT_MEASURED_SUFFIX} reason" for key, value in results.items()
            if value is None and not results.get(key + NOT_MEASURED_SUFFIX)]
    return out
