"""Files of the study: atomic writes, CSV tables and provenance (command, version, commit, machine).

>>> print(csv_text([{"a": 1, "b": 0.5}, {"a": 2, "b": float("nan")}], ["a", "b"]), end="")
a,b
1,0.5
2,nan
"""

from __future__ import annotations

import csv
import io
import os
import platform
from datetime import datetime, timezone
from typing import Any

import numpy as np

from mlsgalerkin.io.files import atomic_write, format_cell, write_json
from mlsgalerkin.io.provenance import command_line, git_commit

__all__ = ["atomic_write", "csv_text", "write_json", "provenance", "command_line", "git_commit"]


def _fmt(v: Any) -> str:
    return format_cell(v, digits=6, nan="nan")


def csv_text(rows: list[dict], columns: list[str]) -> str:
    """CSV with the given columns (missing values empty, floats to 6 significant digits)."""
    buf = io.StringIO()
    w = csv.writer(buf, lineterminator="\n")
    w.writerow(columns)
    for r in rows:
        w.writerow([_fmt(r.get(c)) for c in columns])
    return buf.getvalue()






def provenance(study: str, quick: bool, extra: dict | None = None) -> dict:
    """Command line, versions, git commit, UTC date and machine of this run."""
    import numba
    import scipy

    import mlsgalerkin

    prov = {
        "study": study,
        "command": command_line(),
        "mode": "quick" if quick else "default",
        "mlsgalerkin_version": getattr(mlsgalerkin, "__version__", "unknown"),
        "git_commit": git_commit(),
        "date_utc": datetime.now(timezone.utc).isoformat(timespec="seconds"),
        "machine": {
            "platform": platform.platform(),
            "processor": platform.machine() or "unknown",
            "cpu_count": os.cpu_count(),
        },
        "python": platform.python_version(),
        "numpy": np.__version__,
        "scipy": scipy.__version__,
        "numba": numba.__version__,
    }
    prov.update(extra or {})
    return prov
