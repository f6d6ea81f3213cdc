"""The size limit of a scene under construction: builders refuse, before allocating anything, to
make more points than the current limit allows.

``mlsgalerkin run`` sets the limit from ``--max-particles`` around a problem's ``make_scene``;
lattice and wall builders (and any body builder of a user's) call :func:`check_size` with the
number of points they are about to make. The limit lives in a :class:`~contextvars.ContextVar`,
so threads and nested runs each see their own.

>>> with particle_limit(100):
...     check_size(50, "a lattice (box [0.5, 0.5] m", 0.1)
>>> with particle_limit(10):
...     check_size(50, "a lattice (box [0.5, 0.5] m", 0.1)
Traceback (most recent call last):
...
mlsgalerkin.limits.ParticleLimitError: a lattice (box [0.5, 0.5] m at spacing 0.1 m) would hold 50 particles, ...
"""

from __future__ import annotations

import contextlib
from collections.abc import Iterator
from contextvars import ContextVar

__all__ = ["ParticleLimitError", "check_size", "current_element_limit", "element_limit", "particle_limit"]

#: The largest number of points one builder call may make in the current context (``None``: no limit).
_LIMIT: ContextVar[int | None] = ContextVar("particle_limit", default=None)


class ParticleLimitError(ValueError):
    """A builder would make more points than the current :func:`particle_limit` allows."""


def check_size(count: float, what: str, spacing: float) -> None:
    """Raise :class:`ParticleLimitError` if ``count`` points exceed the current limit; ``what`` names
    the thing being built and ends with an open parenthesis the message closes after ``spacing`` (m)."""
    limit = _LIMIT.get()
    if limit is not None and count > limit:
        raise ParticleLimitError(
            f"{what} at spacing {spacing:g} m) would hold {count:.3g} particles, which exceeds the limit of "
            f"{limit:.3g}; coarsen the spacing, or raise the limit (--max-particles) if the machine has the memory "
            "and the time")


@contextlib.contextmanager
def particle_limit(n: int | None) -> Iterator[None]:
    """Within the block, builders refuse (before allocating anything) to make more than ``n``
    points in one call; ``mlsgalerkin run`` sets it from ``--max-particles``."""
    token = _LIMIT.set(n)
    try:
        yield
    finally:
        _LIMIT.reset(token)


#: The largest number of elements one structure mesh may have in the current context.
_ELEMENT_LIMIT: ContextVar[int | None] = ContextVar("element_limit", default=None)


@contextlib.contextmanager
def element_limit(n: int | None) -> Iterator[None]:
    """Within the block, structure meshes of more than ``n`` elements are refused before they are
    built or assembled (``None``: no limit); ``mlsgalerkin run`` sets it from ``--max-elements``."""
    token = _ELEMENT_LIMIT.set(n)
    try:
        yield
    finally:
        _ELEMENT_LIMIT.reset(token)


def current_element_limit() -> int | None:
    """The element limit of the current context (``None``: no limit)."""
    return _ELEMENT_LIMIT.get()
