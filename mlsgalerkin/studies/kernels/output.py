"""CSV cells of the kernel study's rows and fits (the study's number formats)."""

from __future__ import annotations

from typing import Any, Iterator

from mlsgalerkin.io.files import format_cell

__all__ = ["csv_cells"]

#: Columns written to 4 significant digits (errors, ratios, spacings, fit results).
_FOUR_DIGITS = {
    "error_abs",
    "error_rel",
    "error_grad",
    "error_grad_rel",
    "n_neighbors",
    "error_grad_max",
    "cond_max",
    "exponent",
    "coefficient",
    "r2",
    "h_over_dx",
    "spacing",
}
#: Columns written to 3 significant digits (wall times).
_THREE_DIGITS = {"wall_s"}


def csv_cells(rows: list[dict[str, Any]], columns: list[str]) -> Iterator[list[str]]:
    """Formatted cells of each row: errors, ratios and spacings to 4 significant digits,
    ``wall_s`` to 3, other floats to 6; ``None`` and NaN empty."""
    for r in rows:
        yield [
            format_cell(r.get(c), digits=3 if c in _THREE_DIGITS else 4 if c in _FOUR_DIGITS else 6,
                        nan="")
            for c in columns
        ]
