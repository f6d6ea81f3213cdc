"""How the engine times a measurement: best of repeated ``time.perf_counter`` measurements.

Policy (:func:`best_time`): the function is called once and that call is timed; its result is
the one recorded. If ``repeats > 1``, or the first call took less than ``min_time`` seconds,
``repeats`` further groups of calls are timed, each group long enough to last about
``min_time`` (at most 200 calls); the time reported is the smallest time per call seen. The
minimum is the estimator least disturbed by other processes on a shared machine. With the
defaults (``repeats=1, min_time=0``) the function is called exactly once.

>>> result, seconds = best_time(lambda: sum(range(1000)), min_time=1e-3)
>>> result, seconds > 0
(499500, True)
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable
from dataclasses import dataclass
from typing import TypeVar

__all__ = ["TimingPolicy", "best_time"]

T = TypeVar("T")

#: Most calls in one timed group (bounds the cost of timing very fast functions).
MAX_CALLS_PER_GROUP = 200


@dataclass(frozen=True)
class TimingPolicy:
    """``repeats`` timed groups, each lasting at least ``min_time`` seconds (see module doc)."""

    repeats: int = 1
    min_time: float = 0.0

    def __post_init__(self) -> None:
        if not isinstance(self.repeats, int) or isinstance(self.repeats, bool) or self.repeats < 1:
            raise ValueError(f"repeats must be an integer >= 1, got {self.repeats!r}")
        if not (isinstance(self.min_time, (int, float)) and math.isfinite(self.min_time)
                and self.min_time >= 0):
            raise ValueError(
                f"min_time must be a finite number of seconds >= 0, got {self.min_time!r}"
            )


def best_time(fn: Callable[[], T], min_time: float = 0.0, repeats: int = 1) -> tuple[T, float]:
    """Call ``fn`` and return ``(result of the first call, best seconds per call)``.

    See the module docstring for the policy.
    """
    t0 = time.perf_counter()
    out = fn()
    best = time.perf_counter() - t0
    n = int(min(MAX_CALLS_PER_GROUP, max(1, math.ceil(min_time / max(best, 1e-7)))))
    for _ in range(repeats if (repeats > 1 or best < min_time) else 0):
        t0 = time.perf_counter()
        for _ in range(n):
            fn()
        best = min(best, (time.perf_counter() - t0) / n)
    return out, best
