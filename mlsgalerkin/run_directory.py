"""A run directory belongs to one run: its manifest, its files, its checkpoints, its identity.

A run with an output directory writes ``run.json`` (the manifest: the run's identity and
when it started) before its first step. The identity — scene name, problem (name, or file and
its SHA-256), every parameter, the physics settings (effects, approximation, integrator, mass,
interactions), the package version and a SHA-256 of the initial state — is stored in the
manifest and in every checkpoint, so that

* a **second run into the same directory** is refused (unless it replaces the old one,
  ``overwrite``), instead of mixing two runs' files;
* a **restart** takes the newest *valid* checkpoint *of this run* (damaged files and another
  run's checkpoints are skipped, with a note) and is refused, naming every difference, when the
  scene it continues with is not the one that wrote the checkpoint. Parameters that only change
  what is written (``RESTART_MAY_CHANGE``: the end time, frame and sampling intervals,
  pictures) may change; a longer ``t_end`` continues the run.
"""

from __future__ import annotations

import logging
import uuid
from datetime import datetime, timezone
from pathlib import Path
from typing import Any

from mlsgalerkin.io import CheckpointError, load_checkpoint, read_json_file, write_json
from mlsgalerkin.io.checkpoint import checkpoints_newest_first

__all__ = [
    "MANIFEST",
    "RESTART_MAY_CHANGE",
    "RestartMismatch",
    "RunDirectoryError",
    "claim_directory",
    "identity_differences",
    "newest_checkpoint_of_run",
    "read_manifest",
    "run_files",
]

logger = logging.getLogger(__name__)

MANIFEST = "run.json"
#: Parameters a restart may change: they decide what is written, not what is computed.
RESTART_MAY_CHANGE = frozenset({"t_end", "gif", "frame_every", "probe_every", "checkpoint_every"})
#: Files a run writes into its directory (besides the frame series and the checkpoints).
_RUN_FILES = (MANIFEST, "summary.json", "timeseries.csv", "animation.gif", "final.png", "snapshots.png")


class RunDirectoryError(ValueError):
    """The output directory holds another run (or is not usable)."""


class RestartMismatch(ValueError):
    """A restart would continue a different run; the message lists what differs."""


def run_files(out: Path) -> list[Path]:
    """The files of a run in ``out``: manifest, summary, time series, pictures, every ``.pvd``
    series with its ``.vtu`` frames, and the checkpoints."""
    found = [out / f for f in _RUN_FILES if (out / f).is_file()]
    for pvd in sorted(out.glob("*.pvd")):
        found.append(pvd)
        found += sorted(out.glob(f"{pvd.stem}_*.vtu"))
    ck = out / "checkpoints"
    if ck.is_dir():
        found += sorted(p for p in ck.iterdir() if p.suffix == ".npz")
    return found


def read_manifest(out: Path) -> dict[str, Any] | None:
    """The manifest of the run in ``out`` (``None`` if there is none)."""
    path = out / MANIFEST
    if not path.is_file():
        return None
    try:
        return read_json_file(path)
    except ValueError as exc:
        raise RunDirectoryError(f"{path} is damaged ({exc}); move the directory away or use overwrite") from exc


def claim_directory(out: Path, identity: dict[str, Any], overwrite: bool) -> dict[str, Any]:
    """Make ``out`` this run's directory: refuse if it holds a run (unless ``overwrite``, which
    deletes that run's files first), then write the manifest. Returns the identity with its new
    ``run_id``."""
    existing = run_files(out)
    if existing and not overwrite:
        old = read_manifest(out) or {}
        what = (f"a run of {(old.get('identity') or {}).get('scene', '?')!r} started {old.get('started', '?')}" if old
                else f"files of an earlier run ({', '.join(p.name for p in existing[:3])}"
                     + (", …)" if len(existing) > 3 else ")"))
        raise RunDirectoryError(
            f"{out} already holds {what}. Continue it with --restart (restart='latest'), write to "
            "another directory with --out, or replace it with --overwrite (overwrite=True)")
    for f in existing:
        f.unlink()
    if existing:
        logger.info("overwrite: removed %d files of the previous run in %s", len(existing), out)
    identity = dict(identity, run_id=uuid.uuid4().hex)
    write_json(out / MANIFEST, {"identity": identity,
                                "started": datetime.now(timezone.utc).isoformat(timespec="seconds")})
    return identity


def identity_differences(saved: dict[str, Any], current: dict[str, Any]) -> list[str]:
    """What differs between the identity in a checkpoint and the scene about to continue it
    (``RESTART_MAY_CHANGE`` parameters excepted)."""
    out = []
    for key in ("scene", "problem", "settings", "initial_state_sha256", "mlsgalerkin_version"):
        a, b = saved.get(key), current.get(key)
        if a == b:
            continue
        if key == "settings" and isinstance(a, dict) and isinstance(b, dict):
            out += [f"setting {k}: {a.get(k)!r} in the checkpoint, {b.get(k)!r} now"
                    for k in sorted(set(a) | set(b)) if a.get(k) != b.get(k)]
        elif key == "initial_state_sha256":
            out.append("the initial state (positions, velocities, densities, masses) differs: another geometry "
                       "or resolution")
        else:
            out.append(f"{key}: {a!r} in the checkpoint, {b!r} now")
    pa, pb = saved.get("parameters", {}) or {}, current.get("parameters", {}) or {}
    for k in sorted(set(pa) | set(pb)):
        if k not in RESTART_MAY_CHANGE and pa.get(k) != pb.get(k):
            out.append(f"parameter {k}: {pa.get(k)!r} in the checkpoint, {pb.get(k)!r} now")
    return out


def newest_checkpoint_of_run(out: Path, run_id: str | None) -> tuple[Path, dict, dict, list[str]]:
    """The newest checkpoint in ``out/checkpoints`` that loads and belongs to the run
    ``run_id`` (any run if ``None``): ``(path, arrays, meta, notes)``; ``notes`` say which
    newer files were skipped and why. Raises FileNotFoundError if there is none."""
    notes = []
    for path in checkpoints_newest_first(out / "checkpoints"):
        try:
            arrays, meta = load_checkpoint(path)
        except CheckpointError as exc:
            notes.append(f"skipped {path.name}: {exc}")
            continue
        found = (meta.get("identity") or {}).get("run_id")
        if run_id is not None and found != run_id:
            notes.append(f"skipped {path.name}: it belongs to another run ({found})")
            continue
        return path, arrays, meta, notes
    detail = ("; ".join(notes)) if notes else "there is none"
    raise FileNotFoundError(f"no valid checkpoint of this run in {out / 'checkpoints'} ({detail}); "
                            "the run cannot be continued, start it again")
