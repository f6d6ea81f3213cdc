"""Writing files so that nothing a user computed is ever half-written: atomic writes, JSON, CSV.

Every file of the package goes through :func:`atomic_output` (for third-party writers such as
``numpy.savez`` or meshio) or :func:`atomic_write` (bytes or text): the data go to a temporary
file in the target directory, which is then moved into place with ``os.replace``, so a reader
(or a crash) sees the previous file or the complete new one, never a partial one.

>>> print(csv_text(["a", "b"], [["1", "0.5"], ["2", ""]]), end="")
a,b
1,0.5
2,
>>> to_jsonable({"x": (1, float("nan")), "y": np.float32(0.5)})
{'x': [1, None], 'y': 0.5}
"""

from __future__ import annotations

import csv
import io
import json
import math
import os
import tempfile
from contextlib import contextmanager
from pathlib import Path
from typing import Any, Iterable, Iterator, Sequence

import numpy as np

__all__ = [
    "atomic_output",
    "atomic_write",
    "csv_text",
    "format_cell",
    "read_json_file",
    "to_jsonable",
    "write_csv_rows",
    "write_json",
]


@contextmanager
def atomic_output(path: str | Path) -> Iterator[Path]:
    """Context manager giving a temporary path next to ``path`` for a third-party writer.

    Write the complete file to the yielded temporary path (same directory, so the final
    ``os.replace`` is atomic); on a normal exit it gets mode ``0o644`` and replaces ``path``.
    If the body raises, the temporary file is removed and ``path`` is left untouched.

    Parameters
    ----------
    path : str or Path
        The final file. Its directory must exist.

    Yields
    ------
    Path
        The temporary file to write (it exists, empty, when the body starts).
    """
    path = Path(path)
    if not path.parent.is_dir():
        raise FileNotFoundError(
            f"cannot write {path}: directory {path.parent} does not exist; create it first"
        )
    fd, tmp_name = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp", dir=path.parent)
    os.close(fd)
    tmp = Path(tmp_name)
    try:
        yield tmp
        os.chmod(tmp, 0o644)
        os.replace(tmp, path)
    except BaseException:
        try:
            tmp.unlink()
        except OSError:
            pass
        raise


def atomic_write(path: str | Path, data: bytes | str) -> Path:
    """Write ``data`` (bytes, or ``str`` encoded as UTF-8) to ``path`` atomically; returns the path.

    Uses :func:`atomic_output`: on any error ``path`` is untouched and no temporary file is left.
    """
    path = Path(path)
    if isinstance(data, str):
        data = data.encode("utf-8")
    with atomic_output(path) as tmp:
        tmp.write_bytes(data)
    return path


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


#: What :func:`json_scalar` returns for a value that is not a JSON scalar.
NOT_SCALAR = object()


def json_scalar(v: Any) -> Any:
    """``v`` as a plain JSON scalar (``None``, ``str``, ``bool``, ``int``, ``float``; numpy scalars
    converted, non-finite floats kept), or :data:`NOT_SCALAR` (containers, arrays, objects)."""
    if v is None or isinstance(v, str):
        return v
    if isinstance(v, (bool, np.bool_)):
        return bool(v)
    if isinstance(v, (int, np.integer)):
        return int(v)
    if isinstance(v, (float, np.floating)):
        return float(v)
    return NOT_SCALAR


def to_jsonable(v):
    """``v`` with numpy scalars/arrays and tuples converted for JSON; non-finite floats become
    ``None`` (JSON has no NaN) and unknown objects their ``repr``."""
    if isinstance(v, dict):
        return {str(k): to_jsonable(x) for k, x in v.items()}
    if isinstance(v, (list, tuple)):
        return [to_jsonable(x) for x in v]
    if isinstance(v, np.ndarray):
        return to_jsonable(v.tolist())
    s = json_scalar(v)
    if s is NOT_SCALAR:
        return repr(v)
    return None if isinstance(s, float) and not math.isfinite(s) else s


def write_json(path: str | Path, data: dict) -> Path:
    """Atomic, indented JSON of :func:`to_jsonable` ``(data)``."""
    return atomic_write(path, json.dumps(to_jsonable(data), indent=2, ensure_ascii=False) + "\n")


def read_json_file(path: str | Path) -> dict:
    """The JSON object in ``path``; ValueError (naming the file) if it is not one."""
    path = Path(path)
    try:
        data = json.loads(path.read_text(encoding="utf-8"))
    except (UnicodeDecodeError, json.JSONDecodeError) as exc:
        raise ValueError(f"{path} is not valid JSON ({exc})") from exc
    if not isinstance(data, dict):
        raise ValueError(f"{path} does not hold a JSON object")
    return data
