"""A study's parameter grid: the points at which a measurement is made.

A grid is an ordered sequence of *points*; a point is a dict of named parameter values that the
measurement receives as keyword arguments. :meth:`Grid.product` builds the Cartesian product of
named value lists (the last name varies fastest, as in :func:`itertools.product`),
:meth:`Grid.from_points` takes explicit points, and grids concatenate with ``+``. The position of
a point in the grid (its *index*) fixes the order of the study's records, whatever the order in
which workers finish.

>>> grid = Grid.product(kernel=["cubic_spline", "wendland_c2"], spacing=[0.1, 0.05])
>>> len(grid), grid[1]
(4, {'kernel': 'cubic_spline', 'spacing': 0.05})
>>> extra = Grid.from_points([{"kernel": "quintic_spline", "spacing": 0.1}])
>>> len(grid + extra), (grid + extra).names
(5, ('kernel', 'spacing'))
"""

from __future__ import annotations

import inspect
import itertools
from collections.abc import Callable, Iterable, Iterator, Mapping, Sequence
from dataclasses import dataclass
from typing import Any

__all__ = ["RESERVED_COLUMNS", "Grid", "GridError", "as_grid"]

#: Columns the engine adds to every record; no parameter or measure may use these names.
RESERVED_COLUMNS = ("wall_time_s", "worker")


class GridError(ValueError):
    """A grid that cannot be measured: empty, badly named, or not fitting the measurement."""


def _check_name(name: object, where: str) -> str:
    if not isinstance(name, str) or not name.isidentifier():
        raise GridError(
            f"{where}: parameter name {name!r} is not a Python identifier; the measurement "
            "receives parameters as keyword arguments, so use names like 'spacing' or 'kernel'"
        )
    if name in RESERVED_COLUMNS:
        raise GridError(
            f"{where}: parameter name {name!r} is reserved for the engine's own columns "
            f"{RESERVED_COLUMNS}; rename the parameter"
        )
    return name


@dataclass(frozen=True)
class Grid:
    """An ordered tuple of parameter points (dicts of name -> value); see the module docstring."""

    points: tuple[dict[str, Any], ...]

    def __post_init__(self) -> None:
        for i, point in enumerate(self.points):
            if not isinstance(point, Mapping):
                raise GridError(
                    f"grid point #{i} is a {type(point).__name__}, not a mapping of parameter "
                    "names to values; write points as dicts, e.g. {'spacing': 0.1}"
                )
            for name in point:
                _check_name(name, f"grid point #{i}")

    @classmethod
    def product(cls, **axes: Sequence[Any]) -> Grid:
        """The Cartesian product of named value sequences; the last name varies fastest.

        Raises :class:`GridError` for an empty or scalar axis (a string is a scalar here: write
        ``kernel=["cubic_spline"]``, not ``kernel="cubic_spline"``).
        """
        if not axes:
            raise GridError("Grid.product needs at least one named axis, e.g. spacing=[0.1, 0.05]")
        values = []
        for name, axis in axes.items():
            _check_name(name, "Grid.product")
            if isinstance(axis, (str, bytes)) or not isinstance(axis, Iterable):
                raise GridError(
                    f"Grid.product: axis {name!r} must be a sequence of values, got "
                    f"{axis!r}; write {name}=[{axis!r}] for a single value"
                )
            axis = list(axis)
            if not axis:
                raise GridError(f"Grid.product: axis {name!r} is empty; give it at least one value")
            values.append(axis)
        names = list(axes)
        return cls(tuple(dict(zip(names, combo)) for combo in itertools.product(*values)))

    @classmethod
    def from_points(cls, points: Iterable[Mapping[str, Any]]) -> Grid:
        """A grid of explicit points, in the given order (each point is copied into a dict)."""
        if isinstance(points, Mapping):
            raise GridError(
                "Grid.from_points takes a sequence of points (dicts); for the product of named "
                "value lists use Grid.product(**axes)"
            )
        out = []
        for i, p in enumerate(points):
            if not isinstance(p, Mapping):
                raise GridError(
                    f"grid point #{i} is a {type(p).__name__}, not a mapping of parameter names "
                    "to values; write points as dicts, e.g. {'spacing': 0.1}"
                )
            out.append(dict(p))
        return cls(tuple(out))

    @property
    def names(self) -> tuple[str, ...]:
        """Every parameter name, in order of first appearance."""
        return tuple(dict.fromkeys(name for point in self.points for name in point))

    def __len__(self) -> int:
        return len(self.points)

    def __iter__(self) -> Iterator[dict[str, Any]]:
        return iter(self.points)

    def __getitem__(self, index: int) -> dict[str, Any]:
        return self.points[index]

    def __add__(self, other: Grid) -> Grid:
        if not isinstance(other, Grid):
            return NotImplemented
        return Grid(self.points + other.points)

    def check_measure(self, measure: Callable[..., Any]) -> None:
        """Raise :class:`GridError` unless every point binds to ``measure``'s signature.

        Catches misspelt, missing and surplus parameters before any work starts. Callables
        without an inspectable signature are not checked.
        """
        if not self.points:
            raise GridError("the grid has no points; give at least one parameter point")
        try:
            signature = inspect.signature(measure)
        except (TypeError, ValueError):
            return
        problems = []
        for i, point in enumerate(self.points):
            try:
                signature.bind(**point)
            except TypeError as exc:
                problems.append(f"point #{i} {point}: {exc}")
        if problems:
            name = getattr(measure, "__name__", type(measure).__name__)
            shown = "\n  ".join(problems[:5])
            more = f"\n  ... and {len(problems) - 5} more" if len(problems) > 5 else ""
            raise GridError(
                f"{len(problems)} of {len(self.points)} grid points do not fit "
                f"{name}{signature}:\n  {shown}{more}\nName the grid's parameters exactly as "
                "the measurement's keyword arguments."
            )


def as_grid(grid: Grid | Mapping[str, Sequence[Any]] | Iterable[Mapping[str, Any]]) -> Grid:
    """``grid`` as a :class:`Grid`: a mapping is a product of axes, a sequence explicit points."""
    if isinstance(grid, Grid):
        return grid
    if isinstance(grid, Mapping):
        return Grid.product(**grid)
    if isinstance(grid, (str, bytes)) or not isinstance(grid, Iterable):
        raise GridError(
            f"a grid is a Grid, a mapping of parameter names to value lists, or a sequence of "
            f"points (dicts); got {type(grid).__name__}"
        )
    return Grid.from_points(grid)
