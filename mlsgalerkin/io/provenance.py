"""Where a result came from: the command, package version, git commit, date and machine.

Every study, validation and run records :func:`provenance` next to its numbers.
"""

from __future__ import annotations

import os
import platform
import subprocess
import sys
from datetime import datetime, timezone
from pathlib import Path

import numpy as np

__all__ = ["command_line", "git_commit", "provenance"]


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
    ``numba``, ``numba_threads`` (the compiled kernels' thread count: the parallel sums' order,
    so the round-off, depends on it; in a chaotic flow two thread counts give visibly different
    results, each bit-identical on repeat); then the items of ``extra`` (which may override any
    of them).
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
            "numba_threads": numba.get_num_threads(),
        }
    )
    prov.update(extra or {})
    return prov
