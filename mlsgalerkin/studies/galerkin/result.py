"""What a Galerkin-study run returns: its files, rows, orders and a console report."""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from mlsgalerkin.studies.engine.result import StudyResult
from mlsgalerkin.studies.galerkin.runner import RULE_LABELS
from mlsgalerkin.studies.galerkin.sweeps import GalerkinConfig, energy_quantity

__all__ = ["GalerkinStudyResult", "largest_patch_errors"]


def largest_patch_errors(rows: list[dict[str, Any]], bc: str = "nitsche"
                         ) -> dict[str, dict[str, float]]:
    """Largest relative L2 error of the patch tests with ``bc``, per rule and node layout."""
    out: dict[str, dict[str, float]] = {}
    for r in rows:
        if r["study"] == "patch" and r["bc"] == bc:
            worst = out.setdefault(r["rule"], {"regular": math.nan, "perturbed": math.nan})
            old = worst[r["nodes"]]
            worst[r["nodes"]] = r["error_l2"] if not old >= r["error_l2"] else old
    return out


@dataclass
class GalerkinStudyResult:
    """Paths, rows (the engine's records) and observed orders of one run.

    ``provenance`` is the dict written to ``provenance.json``; ``study`` the engine's result
    (scheduler, workers, timing policy).
    """

    out: Path
    config: GalerkinConfig = field(repr=False)
    csv_path: Path
    orders_path: Path
    provenance_path: Path
    plots: list[Path]
    rows: list[dict[str, Any]] = field(repr=False)
    orders: list[dict[str, Any]] = field(repr=False)
    provenance: dict[str, Any] = field(repr=False)
    study: StudyResult = field(repr=False)
    wall_s: float = math.nan

    @property
    def quick(self) -> bool:
        """Whether this was the quick configuration."""
        return self.config.quick

    def report(self) -> str:
        """Text for the terminal: files, where it ran, patch tests and observed orders."""
        lines = [f"Galerkin study ({'quick' if self.quick else 'default'}) written to {self.out} "
                 f"in {self.wall_s:.1f} s on {self.study.scheduler}",
                 f"  table     : {self.csv_path} ({len(self.rows)} rows)",
                 f"  orders    : {self.orders_path}",
                 f"  provenance: {self.provenance_path} (commit {self.provenance['git_commit']})",
                 "  plots     : " + ", ".join(p.name for p in self.plots), "",
                 "patch tests, largest relative L2 error (Nitsche):"]
        for rule, worst in largest_patch_errors(self.rows).items():
            lines.append(f"  {RULE_LABELS.get(rule, rule):<5} regular {worst['regular']:.1e}   "
                         f"perturbed {worst['perturbed']:.1e}")
        lines.append("observed orders (least squares over all levels, regular nodes): "
                     "L2 / H1 or energy")
        for o in self.orders:
            if o["nodes"] != "regular":
                continue
            key = energy_quantity(o["problem"])[0].removeprefix("error_")
            lines.append(f"  {o['problem']:<12} {RULE_LABELS.get(o['rule'], o['rule']):<5} "
                         f"{o['basis']:<9} {o['kernel']:<15} {o['order_l2']:5.2f} / "
                         f"{o[f'order_{key}']:5.2f}")
        return "\n".join(lines)
