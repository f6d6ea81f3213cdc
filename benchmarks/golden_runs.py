"""Golden runs: a fingerprint of every shipped problem's numbers, to show that a refactoring
changed none of them (bit for bit).

Each shipped problem runs at its ``SMOKE`` size, stretched to ``--steps-factor`` times its smoke
end time, on one numba thread. The fingerprint of a run is the SHA-256 of its
``timeseries.csv`` (every column is simulated, none is wall time) and of every array of its
last checkpoint; the analysis headline is kept beside it for reading.

    python benchmarks/golden_runs.py --out before.json            # on the old code
    python benchmarks/golden_runs.py --compare before.json        # on the new code: exit 1 on change

A changed fingerprint names the problem; compare the two run directories (``--keep DIR``) to see
which column moved first.
"""

from __future__ import annotations

import argparse
import hashlib
import json
import os
import sys
import tempfile
from pathlib import Path

os.environ.setdefault("NUMBA_NUM_THREADS", "1")
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import numpy as np  # noqa: E402


def fingerprint(run_dir: Path) -> dict[str, str]:
    """SHA-256 of the time series and of the last checkpoint's arrays of ``run_dir``."""
    out = {"timeseries": hashlib.sha256((run_dir / "timeseries.csv").read_bytes()).hexdigest()}
    checkpoints = sorted((run_dir / "checkpoints").glob("checkpoint_*.npz"))
    if checkpoints:
        h = hashlib.sha256()
        with np.load(checkpoints[-1]) as data:
            for key in sorted(data.files):
                if key.startswith("__meta"):  # metadata: wall-clock times, commit, paths
                    continue
                if key == "run__clock":  # the run's clock (t, dt, step), a copy of the metadata's, not state
                    continue
                h.update(key.encode())
                h.update(np.ascontiguousarray(data[key]).tobytes())
        out["checkpoint"] = h.hexdigest()
    return out


def run_all(names: list[str], factor: float, keep: Path | None) -> dict[str, dict]:
    from mlsgalerkin.problem import load_problem, run_problem

    results = {}
    for name in names:
        mod = load_problem(name)
        overrides = dict(getattr(mod, "SMOKE", {}))
        overrides["t_end"] = overrides.get("t_end", 0.02) * factor
        if "gif" in mod.Parameters.__dataclass_fields__:
            overrides["gif"] = False
        base = keep if keep is not None else Path(tempfile.mkdtemp(prefix="golden-"))
        out = base / name
        _, res = run_problem(name, overrides, out=out, progress=False, overwrite=True)
        results[name] = {**fingerprint(out), "headline": str(res.get("headline", ""))}
        print(f"{name:20s} {results[name]['timeseries'][:16]}  {results[name]['headline'][:90]}", flush=True)
    return results


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--out", type=Path, help="write the fingerprints here (JSON)")
    ap.add_argument("--compare", type=Path, help="compare with fingerprints written before; exit 1 on a change")
    ap.add_argument("--only", nargs="*", help="problem names (default: every shipped problem)")
    ap.add_argument("--steps-factor", type=float, default=3.0, help="end time as a multiple of the smoke end time")
    ap.add_argument("--keep", type=Path, help="keep the run directories under this folder")
    args = ap.parse_args(argv)
    from mlsgalerkin.problem import shipped_problems

    names = args.only or list(shipped_problems())
    if args.compare:
        before = json.loads(args.compare.read_text())
        factor = before.get("_steps_factor", args.steps_factor)
    else:
        before, factor = None, args.steps_factor
    now = run_all(names, factor, args.keep)
    if args.out:
        args.out.write_text(json.dumps({"_steps_factor": factor, **now}, indent=1) + "\n")
    if before is None:
        return 0
    changed = [n for n in names if n in before and {k: before[n].get(k) for k in ("timeseries", "checkpoint")}
               != {k: now[n].get(k) for k in ("timeseries", "checkpoint")}]
    missing = [n for n in names if n not in before]
    for n in changed:
        print(f"CHANGED {n}: before {before[n]['headline'][:80]!r}\n        now    {now[n]['headline'][:80]!r}")
    for n in missing:
        print(f"not in {args.compare}: {n}")
    print(f"{len(names) - len(changed) - len(missing)} of {len(names)} problems bit for bit")
    return 1 if changed else 0


if __name__ == "__main__":
    sys.exit(main())
