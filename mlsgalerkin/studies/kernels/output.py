"""Files of the kernel study: CSV cells of the rows and fits, and its provenance record."""

from __future__ import annotations

from typing import Iterator


from mlsgalerkin.io.files import format_cell
from mlsgalerkin.io.provenance import provenance as common_provenance
from mlsgalerkin.studies.kernels.config import StudyConfig

__all__ = ["csv_cells", "provenance"]


_SHORT = {
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
_SHORTER = {"wall_s"}


def _fmt(v, short: bool | str = False) -> str:
    return format_cell(v, digits=3 if short == "3" else 4 if short else 6, nan="")


def csv_cells(rows: list[dict], columns: list[str]) -> Iterator[list[str]]:
    """Formatted cells of each row: errors, ratios and spacings to 4 significant digits,
    ``wall_s`` to 3, other floats to 6; ``None`` and NaN empty."""
    for r in rows:
        yield [_fmt(r.get(c), "3" if c in _SHORTER else c in _SHORT) for c in columns]


def provenance(cfg: StudyConfig, extra: dict | None = None) -> dict:
    """Command line, versions, git commit, UTC date and machine of this run."""
    return common_provenance(
        "kernel_study",
        mode="quick" if cfg.quick else "full",
        extra={"seed": cfg.seed, **(extra or {})},
    )
