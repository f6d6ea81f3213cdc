"""Reference data shipped with the package (digitised experiments and converged solutions).

Every file carries its source, normalisation and digitisation notes in its ``#`` header lines;
``mlsgalerkin/data/README.md`` lists them. They are package data, so a problem's analysis
works from any installation:

>>> sorted(reference_columns("martin_moyce_1952.csv"))
['T', 'Z', 'column_width_in']
"""

from __future__ import annotations

from importlib import resources
from pathlib import Path

import numpy as np

__all__ = ["reference_columns", "reference_files", "reference_path"]


def reference_files() -> list[str]:
    """Names of the shipped reference files."""
    return sorted(p.name for p in resources.files(__name__).iterdir() if p.name.endswith(".csv"))


def reference_path(name: str) -> Path:
    """Path of the shipped reference file ``name`` (clear error listing the files if unknown)."""
    path = Path(str(resources.files(__name__).joinpath(name)))
    if not path.is_file():
        raise FileNotFoundError(f"no reference data {name!r}; the package ships {reference_files()}")
    return path


def reference_columns(name: str) -> dict[str, np.ndarray]:
    """The columns of a shipped CSV file (``#`` lines are comments; the first other line is the
    header), as float arrays; a column that is not numeric (a sensor name, say) as strings."""
    import csv

    lines = [ln for ln in reference_path(name).read_text().splitlines() if ln.strip() and not ln.startswith("#")]
    rows = list(csv.reader(lines))
    header, body = rows[0], rows[1:]
    out = {}
    for j, h in enumerate(header):
        column = [r[j].strip() for r in body]
        try:
            out[h] = np.array([float(v) for v in column])
        except ValueError:
            out[h] = np.array(column)
    return out
