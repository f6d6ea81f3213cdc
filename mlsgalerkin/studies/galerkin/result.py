"""What a Galerkin-study run returns: its files, rows, orders and a console report."""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from mlsgalerkin.studies.galerkin.runner import RULE_LABELS
from mlsgalerkin.studies.galerkin.sweeps import energy_quantity
from mlsgalerkin.studies.run import StudyRun

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
class GalerkinStudyResult(StudyRun):
    """A Galerkin-study run (:class:`~mlsgalerkin.studies.run.StudyRun`) with its observed
    orders."""

    orders_path: Path = field(kw_only=True)
    orders: list[dict[str, Any]] = field(kw_only=True, repr=False)

    def report(self) -> str:
        """Text for the terminal: files, where it ran, patch tests and observed orders."""
        lines = [f"Galerkin study ({'quick' if self.quick else 'default'}) written to {self.out} "
                 f"in {self.wall_s:.1f} s on {self.study.scheduler}",
                 *self.files_lines({"orders": self.orders_path}), "",
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
