"""Study-independent helpers for the studies: atomic files, command line, git commit, provenance.

Every study writes its tables, figures and ``summary.md`` through :func:`atomic_write` (a reader
never sees a half-written file) and records where its numbers came from with
:func:`provenance`.

>>> print(csv_text(["a", "b"], [["1", "0.5"], ["2", ""]]), end="")
a,b
1,0.5
2,
"""

from __future__ import annotations

import csv
import io
import json
import math
import os
import platform
import subprocess
import sys
import tempfile
from datetime import datetime, timezone
from pathlib import Path
from typing import Iterable, Sequence

import numpy as np

__all__ = [
    "atomic_write",
    "atomic_write_bytes",
    "atomic_write_text",
    "command_line",
    "csv_text",
    "git_commit",
    "provenance",
    "to_jsonable",
    "write_csv_rows",
    "write_json",
]


def atomic_write(path: str | Path, data: bytes | str) -> Path:
    """Write ``data`` to ``path`` atomically and return the path.

    The data go to a temporary file in the same directory, which is then moved into place with
    ``os.replace``; ``str`` data are encoded as UTF-8. The file gets mode ``0o644``. On any error
    the temporary file is removed and the exception re-raised; ``path`` is then untouched.
    """
    path = Path(path)
    if isinstance(data, str):
        data = data.encode("utf-8")
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp", dir=path.parent)
    try:
        with os.fdopen(fd, "wb") as fh:
            fh.write(data)
        os.chmod(tmp, 0o644)
        os.replace(tmp, path)
    except BaseException:
        try:
            os.unlink(tmp)
        except OSError:
            pass
        raise
    return path


def atomic_write_bytes(path: str | Path, data: bytes) -> Path:
    """Write bytes atomically (see :func:`atomic_write`)."""
    return atomic_write(path, bytes(data))


def atomic_write_text(path: str | Path, text: str) -> Path:
    """Write text atomically as UTF-8 (see :func:`atomic_write`)."""
    return atomic_write(path, str(text))


def format_cell(value: object, digits: int = 6, nan: str = "") -> str:
    """One CSV cell: ``None`` empty, booleans and integers as such, floats to ``digits``
    significant digits (``nan`` for NaN, ``inf``/``-inf`` spelled out), anything else ``str``."""
    if value is None:
        return ""
    if isinstance(value, (bool, np.bool_)):
        return str(bool(value))
    if isinstance(value, (int, np.integer)):
        return str(int(value))
    if isinstance(value, (float, np.floating)):
        v = float(value)
        return nan if v != v else f"{v:.{digits}g}"
    return str(value)


def csv_text(header: Sequence[str], rows: Iterable[Sequence[object]]) -> str:
    """CSV text (``\\n`` line ends) of a header line and rows of already formatted cells."""
    buf = io.StringIO()
    w = csv.writer(buf, lineterminator="\n")
    w.writerow(header)
    for row in rows:
        w.writerow(row)
    return buf.getvalue()


def write_csv_rows(
    path: str | Path, header: Sequence[str], rows: Iterable[Sequence[object]]
) -> Path:
    """Write :func:`csv_text` of ``header`` and ``rows`` atomically; returns the path."""
    return atomic_write(path, csv_text(header, rows))


def git_commit(cwd: str | Path | None = None) -> str:
    """Short commit of the source tree (``+dirty`` with uncommitted changes), or "unknown"."""
    here = Path(cwd) if cwd is not None else Path(__file__).resolve().parent
    try:
        out = subprocess.run(["git", "rev-parse", "--short", "HEAD"], capture_output=True,
                             text=True, timeout=10, cwd=here)
        if out.returncode != 0 or not out.stdout.strip():
            return "unknown"
        commit = out.stdout.strip()
        # the committed study outputs are not source: regenerating them must not mark the
        # tree dirty for the next study
        st = subprocess.run(["git", "status", "--porcelain", "--untracked-files=no", "--",
                             ":(top)", ":(top,exclude)verification/results",
                             ":(top,exclude)benchmarks/results"],
                            capture_output=True, text=True, timeout=10, cwd=here)
        return commit + ("+dirty" if st.returncode == 0 and st.stdout.strip() else "")
    except (OSError, subprocess.SubprocessError):
        return "unknown"


def command_line() -> str:
    """The command that started this process, with the package's entry points spelled out."""
    argv = list(sys.argv) or ["python"]
    prog = argv[0].replace("\\", "/")
    if prog.endswith("mlsgalerkin/cli.py") or prog.endswith("mlsgalerkin/__main__.py"):
        head = "python -m mlsgalerkin.cli"
    elif prog.endswith("/mlsgalerkin") or prog == "mlsgalerkin":
        head = "mlsgalerkin"
    elif prog.endswith(".py") and "pytest" not in prog:
        try:
            prog = os.path.relpath(prog)
        except ValueError:
            pass
        head = f"python {prog}"
    else:
        head = Path(prog).name or "python"
    return " ".join([head] + argv[1:])


def provenance(study: str, mode: str | None = None, extra: dict | None = None) -> dict:
    """Where a run's numbers came from, as a JSON-ready dict.

    Keys, in order: ``study``, ``command`` (:func:`command_line`), ``mode`` (only when given),
    ``mlsgalerkin_version``, ``git_commit`` (:func:`git_commit`), ``date_utc`` (ISO 8601,
    seconds), ``machine`` (``platform``, ``processor``, ``cpu_count``), ``python``, ``numpy``,
    ``numba``; then the items of ``extra`` (which may override any of them).
    """
    import numba

    import mlsgalerkin

    prov: dict = {"study": study, "command": command_line()}
    if mode is not None:
        prov["mode"] = mode
    prov.update(
        {
            "mlsgalerkin_version": getattr(mlsgalerkin, "__version__", "unknown"),
            "git_commit": git_commit(),
            "date_utc": datetime.now(timezone.utc).isoformat(timespec="seconds"),
            "machine": {
                "platform": platform.platform(),
                "processor": platform.machine(),
                "cpu_count": os.cpu_count(),
            },
            "python": platform.python_version(),
            "numpy": np.__version__,
            "numba": numba.__version__,
        }
    )
    prov.update(extra or {})
    return prov


def to_jsonable(v):
    """``v`` with numpy scalars/arrays and tuples converted for JSON; non-finite floats become
    ``None`` (JSON has no NaN) and unknown objects their ``repr``."""
    if isinstance(v, dict):
        return {str(k): to_jsonable(x) for k, x in v.items()}
    if isinstance(v, (list, tuple)):
        return [to_jsonable(x) for x in v]
    if isinstance(v, np.ndarray):
        return to_jsonable(v.tolist())
    if isinstance(v, (bool, np.bool_)):
        return bool(v)
    if isinstance(v, (int, np.integer)):
        return int(v)
    if isinstance(v, (float, np.floating)):
        v = float(v)
        return v if math.isfinite(v) else None
    if isinstance(v, str) or v is None:
        return v
    return repr(v)


def write_json(path: str | Path, data: dict) -> Path:
    """Atomic, indented JSON of :func:`to_jsonable` ``(data)``."""
    return atomic_write(path, json.dumps(to_jsonable(data), indent=2, ensure_ascii=False) + "\n")
