"""Restart checkpoints: one ``.npz`` file of named arrays plus JSON metadata.

A checkpoint is a single NumPy ``.npz`` archive (written with :func:`numpy.savez`,
uncompressed, ``allow_pickle=False``). Next to the caller's arrays it holds one reserved
member, ``"__meta__"``: a ``uint8`` array of the UTF-8 bytes of a JSON header ::

    {"format": "mlsgalerkin-checkpoint", "version": 1,
     "arrays": [<names of the stored arrays>], "meta": <the caller's meta dict>}

The archive is written to a temporary file in the target directory and moved into place with
``os.replace`` (:func:`atomic_output`), so a reader sees either the previous checkpoint or the
complete new one, never a half-written or mismatched one. Arrays are stored in binary, so they
round-trip bit for bit; floats in ``meta`` are written by :mod:`json` with ``repr``, which is
exact for IEEE doubles (``0.1 + 0.2`` comes back as ``0.30000000000000004``). The zip members
carry CRC-32 checksums, which :func:`load_checkpoint` verifies, so a truncated or corrupted
file is reported as a :class:`CheckpointError` instead of being loaded.

Files in a run directory are named ``checkpoint_{step:08d}.npz`` (:func:`checkpoint_path`);
:func:`latest_checkpoint` and :func:`prune_checkpoints` rely on that naming.

>>> checkpoint_path("run", 42).as_posix()
'run/checkpoint_00000042.npz'
"""

from __future__ import annotations

import json
import logging
import os
import re
import zipfile
from pathlib import Path
from typing import Any, Mapping

import numpy as np

from mlsgalerkin.io.files import NOT_SCALAR, atomic_output, json_scalar

__all__ = [
    "CHECKPOINT_FORMAT",
    "CHECKPOINT_VERSION",
    "CheckpointError",
    "checkpoint_path",
    "checkpoints_newest_first",
    "latest_checkpoint",
    "load_checkpoint",
    "prune_checkpoints",
    "save_checkpoint",
]

logger = logging.getLogger(__name__)

CHECKPOINT_FORMAT = "mlsgalerkin-checkpoint"
"""Value of the header's ``"format"`` field."""

CHECKPOINT_VERSION = 1
"""Version of the checkpoint layout written by :func:`save_checkpoint`."""

_META_KEY = "__meta__"
_NAME_RE = re.compile(r"^checkpoint_(\d{8,})\.npz$")


class CheckpointError(ValueError):
    """A checkpoint file exists but cannot be used (corrupt, truncated, foreign or too new)."""


# ------------------------------------------------------------------------------------------
# metadata
# ------------------------------------------------------------------------------------------


def _jsonable(value: Any, where: str) -> Any:
    """``value`` as plain JSON types (numpy scalars converted); ValueError naming ``where``."""
    scalar = json_scalar(value)
    if scalar is not NOT_SCALAR:
        return scalar
    if isinstance(value, Mapping):
        out = {}
        for k, v in value.items():
            if not isinstance(k, str):
                raise ValueError(
                    f"checkpoint meta{where}: key {k!r} is a {type(k).__name__}; JSON object "
                    "keys must be str, convert the key with str()"
                )
            out[k] = _jsonable(v, f"{where}[{k!r}]")
        return out
    if isinstance(value, (list, tuple)):
        return [_jsonable(v, f"{where}[{i}]") for i, v in enumerate(value)]
    if isinstance(value, np.ndarray):
        raise ValueError(
            f"checkpoint meta{where} is a numpy array of shape {value.shape}; store arrays in "
            "the `arrays` argument (bit-exact binary), or pass value.tolist() for a short list"
        )
    raise ValueError(
        f"checkpoint meta{where} has type {type(value).__name__}, which is not JSON-serialisable;"
        " use str, int, float, bool, None, list or dict (numpy scalars are converted)"
    )


def _check_arrays(arrays: Mapping[str, Any]) -> dict[str, np.ndarray]:
    if not isinstance(arrays, Mapping):
        raise ValueError(f"checkpoint arrays must be a dict of name -> array, got "
                         f"{type(arrays).__name__}")
    out: dict[str, np.ndarray] = {}
    for name, value in arrays.items():
        if not isinstance(name, str) or not name:
            raise ValueError(f"checkpoint array name {name!r} must be a non-empty str")
        if name.startswith("__") or "/" in name:
            raise ValueError(
                f"checkpoint array name {name!r} is not allowed: names starting with '__' are "
                "reserved and '/' would create a sub-folder in the archive; rename the array"
            )
        arr = np.asarray(value)
        if arr.dtype.hasobject:
            raise ValueError(
                f"checkpoint array {name!r} has dtype {arr.dtype} (Python objects), which could "
                "only be stored with pickle; checkpoints never pickle, so convert it to a "
                "numeric/bool/fixed-width-string array or put the values in `meta`"
            )
        out[name] = arr
    return out


# ------------------------------------------------------------------------------------------
# file names
# ------------------------------------------------------------------------------------------


def checkpoint_path(directory: str | Path, step: int) -> Path:
    """Path of the checkpoint of time step ``step``: ``directory/checkpoint_{step:08d}.npz``.

    Parameters
    ----------
    directory : str or Path
        Run directory.
    step : int
        Time-step index, ``>= 0``.
    """
    if isinstance(step, (bool, np.bool_)) or not isinstance(step, (int, np.integer)) or step < 0:
        raise ValueError(f"checkpoint step must be a non-negative int, got {step!r}")
    return Path(directory) / f"checkpoint_{int(step):08d}.npz"


def _checkpoints(directory: Path) -> list[tuple[int, Path]]:
    if not directory.is_dir():
        return []
    found = []
    for p in directory.iterdir():
        m = _NAME_RE.match(p.name)
        if m and p.is_file():
            found.append((int(m.group(1)), p))
    return sorted(found)


def checkpoints_newest_first(directory: str | Path) -> list[Path]:
    """The files ``checkpoint_{step:08d}.npz`` in ``directory``, highest step first (none if the
    directory does not exist); the files are not opened."""
    return [p for _, p in reversed(_checkpoints(Path(directory)))]


def latest_checkpoint(directory: str | Path) -> Path | None:
    """The checkpoint ``checkpoint_{step:08d}.npz`` in ``directory`` with the highest step.

    Returns ``None`` when the directory does not exist or holds no such file. Temporary files
    of an interrupted write (hidden ``.checkpoint_*.tmp``) are never returned. The file is not
    opened; :func:`load_checkpoint` reports a damaged one.
    """
    found = _checkpoints(Path(directory))
    return found[-1][1] if found else None


def prune_checkpoints(directory: str | Path, keep: int) -> list[Path]:
    """Delete all but the ``keep`` newest (highest step) checkpoints in ``directory``.

    Parameters
    ----------
    directory : str or Path
        Run directory; only files named ``checkpoint_{step:08d}.npz`` are considered.
    keep : int
        How many to keep, ``>= 1``.

    Returns
    -------
    list of Path
        The deleted files, oldest first.
    """
    if isinstance(keep, bool) or not isinstance(keep, (int, np.integer)) or keep < 1:
        raise ValueError(f"prune_checkpoints: keep must be an int >= 1, got {keep!r}")
    found = _checkpoints(Path(directory))
    doomed = [p for _, p in found[: max(len(found) - int(keep), 0)]]
    for p in doomed:
        p.unlink()
        logger.debug("removed old checkpoint %s", p)
    return doomed


# ------------------------------------------------------------------------------------------
# save / load
# ------------------------------------------------------------------------------------------


def save_checkpoint(
    path: str | Path, arrays: Mapping[str, np.ndarray], meta: Mapping[str, Any]
) -> Path:
    """Write a checkpoint atomically and return its path.

    Parameters
    ----------
    path : str or Path
        Target file; must end in ``.npz`` (see :func:`checkpoint_path`). Its directory must
        exist. An existing file is replaced atomically.
    arrays : dict of str to ndarray
        Named arrays of any shape and of a numeric, bool or fixed-width string dtype; stored
        bit for bit. Names must not start with ``"__"`` or contain ``"/"``.
    meta : dict
        JSON-serialisable metadata (str keys; values str, int, float, bool, None, list, dict;
        numpy scalars are converted to Python numbers, tuples become lists). Floats
        round-trip exactly, including ``nan`` and ``inf``.

    Returns
    -------
    Path
        ``path``.

    Raises
    ------
    ValueError
        On a bad path suffix, array name, object array or non-serialisable meta.
    """
    path = Path(path)
    if path.suffix != ".npz":
        raise ValueError(f"checkpoint path {path} must end in '.npz' (see checkpoint_path())")
    data = _check_arrays(arrays)
    if not isinstance(meta, Mapping):
        raise ValueError(f"checkpoint meta must be a dict, got {type(meta).__name__}")
    header = {
        "format": CHECKPOINT_FORMAT,
        "version": CHECKPOINT_VERSION,
        "arrays": sorted(data),
        "meta": _jsonable(meta, ""),
    }
    text = json.dumps(header, allow_nan=True, sort_keys=True)
    data[_META_KEY] = np.frombuffer(text.encode("utf-8"), dtype=np.uint8)
    with atomic_output(path) as tmp:
        with open(tmp, "wb") as fh:
            np.savez(fh, allow_pickle=False, **data)
            fh.flush()
            os.fsync(fh.fileno())
    logger.debug("wrote checkpoint %s (%d arrays)", path, len(data) - 1)
    return path


def load_checkpoint(path: str | Path) -> tuple[dict[str, np.ndarray], dict[str, Any]]:
    """Read a checkpoint written by :func:`save_checkpoint`.

    Parameters
    ----------
    path : str or Path
        The ``.npz`` file.

    Returns
    -------
    arrays : dict of str to ndarray
        The stored arrays, bit for bit, in memory (the file is closed).
    meta : dict
        The stored metadata (tuples come back as lists, numpy scalars as Python numbers).

    Raises
    ------
    FileNotFoundError
        If ``path`` does not exist.
    CheckpointError
        (a ValueError) If the file is truncated, corrupt, not a checkpoint, or of another
        format version.
    """
    path = Path(path)
    if not path.is_file():
        raise FileNotFoundError(
            f"checkpoint {path} does not exist; latest_checkpoint(directory) finds the newest"
        )
    try:
        with np.load(path, allow_pickle=False) as npz:
            arrays = {name: npz[name] for name in npz.files}
    except (zipfile.BadZipFile, OSError, ValueError, EOFError, KeyError) as exc:
        raise CheckpointError(
            f"checkpoint {path} is truncated or corrupt ({type(exc).__name__}: {exc}); "
            "restart from an earlier checkpoint"
        ) from exc
    raw = arrays.pop(_META_KEY, None)
    if raw is None:
        raise CheckpointError(
            f"{path} is an .npz file but not an mlsgalerkin checkpoint (no '{_META_KEY}' entry)"
        )
    try:
        header = json.loads(np.asarray(raw, dtype=np.uint8).tobytes().decode("utf-8"))
    except (UnicodeDecodeError, ValueError) as exc:
        raise CheckpointError(f"checkpoint {path}: metadata is corrupt ({exc})") from exc
    if not isinstance(header, dict) or header.get("format") != CHECKPOINT_FORMAT:
        raise CheckpointError(f"{path} is not an mlsgalerkin checkpoint (format "
                              f"{header.get('format') if isinstance(header, dict) else None!r})")
    version = header.get("version")
    if version != CHECKPOINT_VERSION:
        raise CheckpointError(
            f"checkpoint {path} has format version {version!r}; this mlsgalerkin reads version "
            f"{CHECKPOINT_VERSION} only: use the mlsgalerkin release that wrote it"
        )
    names = header.get("arrays")
    if names is None or sorted(names) != sorted(arrays):
        raise CheckpointError(
            f"checkpoint {path}: stored arrays {sorted(arrays)} do not match the header's list "
            f"{names}; the file is damaged, restart from an earlier checkpoint"
        )
    meta = header.get("meta")
    if not isinstance(meta, dict):
        raise CheckpointError(f"checkpoint {path}: metadata is not a JSON object")
    return arrays, meta

