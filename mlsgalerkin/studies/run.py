"""What a run of a shipped study returns: where it wrote, its rows, provenance, engine result."""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from mlsgalerkin.studies.engine.result import StudyResult

__all__ = ["StudyRun"]


@dataclass
class StudyRun:
    """Common part of :class:`~mlsgalerkin.studies.kernels.KernelStudyResult` and
    :class:`~mlsgalerkin.studies.galerkin.GalerkinStudyResult`.

    ``config`` is the study's configuration (with a ``quick`` flag), ``rows`` the engine's
    records (the CSV columns and more), ``provenance`` the dict written to ``provenance_path``,
    ``study`` the engine's result (scheduler, workers, timing policy) and ``wall_s`` the seconds
    the whole run took.
    """

    out: Path
    config: Any = field(repr=False)
    csv_path: Path
    provenance_path: Path
    plots: list[Path]
    rows: list[dict[str, Any]] = field(repr=False)
    provenance: dict[str, Any] = field(repr=False)
    study: StudyResult = field(repr=False)
    wall_s: float

    @property
    def quick(self) -> bool:
        """Whether this was the quick configuration."""
        return bool(self.config.quick)

    def files_lines(self, extra: dict[str, Path]) -> list[str]:
        """The first lines of a console report: what was written where, on which scheduler."""
        return [
            f"  table     : {self.csv_path} ({len(self.rows)} rows)",
            *(f"  {name:<10}: {path}" for name, path in extra.items()),
            f"  provenance: {self.provenance_path} (commit {self.provenance['git_commit']})",
            "  plots     : " + ", ".join(p.name for p in self.plots),
        ]
