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
  pictures) may change; a longer ``t_end`` continues the run;
* **one process at a time** writes the directory: :class:`RunDirectoryLock` holds an exclusive
  ``flock`` on ``run.lock`` while a run writes, so a second writer (a ``--restart`` into a running
  run, a second ``--overwrite``) is refused naming the holder's pid. The operating system releases
  the lock when its process dies, so a run killed with SIGKILL leaves no lock that needs removing;
* a checkpoint is continued only if its **clock agrees with itself**
  (:func:`check_checkpoint_clock`): the time and step in its metadata, its file name, its solvers'
  own clocks, its binary copy of the clock and its arrays' sizes, and the run's time series.
"""

from __future__ import annotations

import json
import logging
import math
import os
import re
import uuid
from datetime import datetime, timezone
from pathlib import Path
from typing import Any

import numpy as np

from mlsgalerkin.io import CheckpointError, load_checkpoint, read_json_file, write_json
from mlsgalerkin.io.checkpoint import checkpoints_newest_first

__all__ = [
    "CLOCK_ARRAY",
    "LOCK_FILE",
    "MANIFEST",
    "RESTART_MAY_CHANGE",
    "RestartMismatch",
    "RunDirectoryError",
    "RunDirectoryLock",
    "check_checkpoint_clock",
    "claim_directory",
    "identity_differences",
    "newest_checkpoint_of_run",
    "read_manifest",
    "run_files",
]

logger = logging.getLogger(__name__)

MANIFEST = "run.json"
#: The lock file a writing run holds (``flock``); its text names the holder.
LOCK_FILE = "run.lock"
#: A checkpoint's binary copy of the run's clock, ``[t, dt, step]`` (float64).
CLOCK_ARRAY = "run__clock"
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
    newer files were skipped and why. Raises FileNotFoundError if there is none, and
    :class:`~mlsgalerkin.io.CheckpointError` if that checkpoint's clock contradicts itself
    (:func:`check_checkpoint_clock`)."""
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
        check_checkpoint_clock(path, arrays, meta, out / "timeseries.csv")
        return path, arrays, meta, notes
    detail = ("; ".join(notes)) if notes else "there is none"
    raise FileNotFoundError(f"no valid checkpoint of this run in {out / 'checkpoints'} ({detail}); "
                            "the run cannot be continued, start it again")


# ------------------------------------------------------------------ one writer at a time
class RunDirectoryLock:
    """An exclusive lock on a run directory, held by the one process that writes it.

    ``with RunDirectoryLock(out): ...`` takes a non-blocking ``fcntl.flock`` on ``out/run.lock``
    and writes the holder's pid, host and start time into it; a second process trying the same is
    refused at once with a :class:`RunDirectoryError` naming that pid. The lock belongs to the open
    file, so the operating system releases it when the holder exits in any way (SIGKILL
    included): a stale ``run.lock`` is simply taken over. On release the file is removed. On a
    file system without ``flock`` (or without :mod:`fcntl`) the run goes ahead unlocked, with a
    warning.
    """

    def __init__(self, out: str | Path) -> None:
        self.out = Path(out)
        self.path = self.out / LOCK_FILE
        self._fd: int | None = None

    def acquire(self) -> None:
        try:
            import fcntl
        except ImportError:  # not a POSIX system
            logger.warning("no file locking on this system: nothing stops a second process writing %s", self.out)
            return
        while True:
            fd = os.open(self.path, os.O_RDWR | os.O_CREAT, 0o644)
            try:
                fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
            except BlockingIOError:
                holder = _lock_holder(fd)
                os.close(fd)
                raise RunDirectoryError(
                    f"{self.out} is being written by another process ({holder}); wait for it to end, stop it "
                    "(it continues with --restart), or write to another directory with --out") from None
            except OSError as exc:  # e.g. a network file system without flock
                os.close(fd)
                logger.warning("could not lock %s (%s): nothing stops a second process writing it", self.path, exc)
                return
            try:  # the holder before us may have removed the file it locked: lock the file now there
                same = os.stat(self.path).st_ino == os.fstat(fd).st_ino
            except FileNotFoundError:
                same = False
            if same:
                break
            os.close(fd)
        self._fd = fd
        text = json.dumps({"pid": os.getpid(), "host": os.uname().nodename if hasattr(os, "uname") else None,
                           "started": datetime.now(timezone.utc).isoformat(timespec="seconds")})
        os.ftruncate(fd, 0)
        os.pwrite(fd, (text + "\n").encode(), 0)

    def release(self) -> None:
        if self._fd is None:
            return
        try:
            os.unlink(self.path)  # while still holding the lock (see acquire)
        except OSError:
            pass
        os.close(self._fd)  # releases the flock
        self._fd = None

    def __enter__(self) -> RunDirectoryLock:
        self.acquire()
        return self

    def __exit__(self, *exc: object) -> None:
        self.release()


def _lock_holder(fd: int) -> str:
    """``pid N on HOST since T`` from a lock file's text (best effort: it may be mid-write)."""
    try:
        info = json.loads(os.pread(fd, 4096, 0).decode() or "{}")
    except (OSError, ValueError):
        info = {}
    if not isinstance(info, dict) or "pid" not in info:
        return "pid unknown"
    host = f" on {info['host']}" if info.get("host") else ""
    since = f" since {info['started']}" if info.get("started") else ""
    return f"pid {info['pid']}{host}{since}"


# ------------------------------------------------------------------ a checkpoint's clock
_CHECKPOINT_NAME = re.compile(r"^checkpoint_(\d{8,})\.npz$")


def check_checkpoint_clock(path: Path, arrays: dict[str, np.ndarray], meta: dict[str, Any],
                           timeseries: Path | None = None) -> None:
    """Refuse a checkpoint whose clock disagrees with itself, before anything is restored.

    Checked: ``t`` finite and ``>= 0``, ``step`` a whole number ``>= 0``, ``dt`` finite and
    ``> 0`` (``0`` before the first step); the step in the file name ``checkpoint_{step:08d}.npz``; the binary copy
    :data:`CLOCK_ARRAY` ``[t, dt, step]`` (bit for bit; checkpoints written before it existed have
    none); every solver's own ``t`` and ``step``; a solver's particle count ``n`` against the
    length of its position array ``<solver>__x``, and the positions' shape against the velocities'
    ``<solver>__v``; and, given the run's ``timeseries.csv``, a row
    recorded at the checkpoint's step has its time, rows before it earlier times and rows after
    it later ones. Raises :class:`~mlsgalerkin.io.CheckpointError` naming what disagrees.
    """
    problems = _clock_problems(path, arrays, meta)
    if not problems and timeseries is not None and timeseries.is_file():
        problems = _timeseries_problems(meta, timeseries)
    if problems:
        raise CheckpointError(
            f"checkpoint {path} contradicts itself, so it cannot say where the run stands: " + "; ".join(problems)
            + ". It was edited or damaged: move it out of the checkpoints folder to continue from the one before, "
            "or start the run again")


def _clock_problems(path: Path, arrays: dict[str, np.ndarray], meta: dict[str, Any]) -> list[str]:
    t, step, dt = meta.get("t"), meta.get("step"), meta.get("dt")
    problems = []
    if not (isinstance(t, (int, float)) and not isinstance(t, bool) and math.isfinite(t) and t >= 0):
        problems.append(f"its time t = {t!r} is not a finite number >= 0")
    if not (isinstance(step, int) and not isinstance(step, bool) and step >= 0):
        problems.append(f"its step {step!r} is not a whole number >= 0")
    if not (isinstance(dt, (int, float)) and not isinstance(dt, bool) and math.isfinite(dt)
            and (dt > 0 or (dt == 0 and step == 0))):
        problems.append(f"its step size dt = {dt!r} is not a finite number > 0")
    if problems:
        return problems
    named = _CHECKPOINT_NAME.match(Path(path).name)
    if named and int(named.group(1)) != step:
        problems.append(f"its file name says step {int(named.group(1))}, its metadata step {step}")
    clock = arrays.get(CLOCK_ARRAY)
    if clock is not None:
        clock = np.asarray(clock, dtype=np.float64).ravel()
        if clock.shape != (3,) or clock[0] != t or clock[1] != dt or clock[2] != step:
            problems.append(f"its metadata says t = {t!r}, dt = {dt!r}, step {step} but its stored clock says "
                            f"{clock.tolist()}")
    for key, solver in sorted((meta.get("solvers") or {}).items()):
        if not isinstance(solver, dict):
            continue
        if "t" in solver and not (isinstance(solver["t"], (int, float))
                                  and math.isclose(solver["t"], t, rel_tol=1e-12, abs_tol=1e-300)):
            problems.append(f"the run is at t = {t!r} but its {key} solver at t = {solver['t']!r}")
        if "step" in solver and solver["step"] != step:
            problems.append(f"the run is at step {step} but its {key} solver at step {solver['step']}")
        x, v = arrays.get(f"{key}__x"), arrays.get(f"{key}__v")
        if "n" in solver and x is not None and np.ndim(x) >= 1 and np.shape(x)[0] != solver["n"]:
            problems.append(f"its {key} metadata counts {solver['n']} particles but its positions hold "
                            f"{np.shape(x)[0]}")
        if x is not None and v is not None and np.shape(x) != np.shape(v):
            problems.append(f"its {key} positions have the shape {np.shape(x)} but its velocities {np.shape(v)}")
    return problems


def _timeseries_problems(meta: dict[str, Any], timeseries: Path) -> list[str]:
    from mlsgalerkin.io import read_timeseries

    try:
        ts = read_timeseries(timeseries)
    except (OSError, ValueError):
        return []  # a damaged time series is the time series monitor's business
    if "time" not in ts or "step" not in ts:
        return []
    t, step = float(meta["t"]), int(meta["step"])
    times, steps = np.asarray(ts["time"], dtype=float), np.asarray(ts["step"])
    at = times[steps == step]
    if at.size and not np.all(at == t):
        return [f"{timeseries.name} recorded step {step} at t = {at[0]!r}, the checkpoint says t = {t!r}"]
    if np.any(times[steps < step] > t):
        return [f"{timeseries.name} has times later than the checkpoint's t = {t!r} at earlier steps than {step}"]
    if np.any(times[steps > step] <= t):
        return [f"{timeseries.name} has times up to the checkpoint's t = {t!r} at later steps than {step}"]
    return []
