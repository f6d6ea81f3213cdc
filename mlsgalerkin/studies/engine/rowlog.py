"""The rows of a study on disk as they are measured, so a crash or a full disk keeps them.

:func:`~mlsgalerkin.studies.engine.runner.run_study` with ``rows_log=PATH`` appends every
point's records to ``PATH`` the moment the point is measured, one JSON object per line
(`JSON Lines <https://jsonlines.org>`_), flushed to the operating system after each point::

    {"index": 3, "record": {"kernel": "wendland_c2", "spacing": 0.0625, "error_l2": 1.2e-05,
                            "wall_time_s": 0.0041, "worker": "tcp://127.0.0.1:40117"}}

``index`` is the point's place in the grid (points arrive in completion order). Floats are
written with ``repr`` (exact; NaN and infinities as ``NaN``/``Infinity``); values JSON cannot
hold (arrays, objects) are left out, as in the study's CSV. The study's own tables are written
atomically at its end; a study that stops before (a crash, an exception, a full disk) leaves
this file with every row measured so far, and :func:`read_rows` reads it back.
"""

from __future__ import annotations

import json
import os
from collections.abc import Iterable, Mapping
from pathlib import Path
from typing import Any

from mlsgalerkin.io.files import NOT_SCALAR, json_scalar

__all__ = ["RowLog", "read_rows"]




class RowLog:
    """Appends records to a JSON Lines file, flushed after every point.

    Opening creates the parent directory and the file (so an unwritable place is reported before
    any measurement); an existing file is replaced: it belongs to an earlier study.
    """

    def __init__(self, path: str | Path) -> None:
        self.path = Path(path)
        self.path.parent.mkdir(parents=True, exist_ok=True)
        self._file = open(self.path, "w", encoding="utf-8")  # noqa: SIM115 (closed in close())
        self.rows = 0

    def append(self, index: int, records: Iterable[Mapping[str, Any]]) -> None:
        """Write the records of grid point ``index`` and flush them to the operating system."""
        lines = []
        for record in records:
            plain = {k: v for k, v in ((k, json_scalar(v)) for k, v in record.items()) if v is not NOT_SCALAR}
            lines.append(json.dumps({"index": int(index), "record": plain}, allow_nan=True) + "\n")
        self._file.write("".join(lines))
        self._file.flush()
        self.rows += len(lines)

    def close(self, remove: bool = False) -> None:
        """Close the file (after an fsync); ``remove``: delete it (the study's tables hold its rows)."""
        if self._file.closed:
            return
        try:
            self._file.flush()
            os.fsync(self._file.fileno())
        finally:
            self._file.close()
        if remove:
            self.path.unlink(missing_ok=True)

    def __enter__(self) -> RowLog:
        return self

    def __exit__(self, *exc: object) -> None:
        try:
            self.close()
        except OSError:
            pass  # the study's own error is the one to report


def read_rows(path: str | Path) -> list[dict[str, Any]]:
    """The records of a row log, in grid order (a last line cut short by a crash is skipped)."""
    rows = []
    for line in Path(path).read_text(encoding="utf-8").splitlines():
        try:
            item = json.loads(line)
        except ValueError:
            continue
        rows.append((item["index"], len(rows), item["record"]))
    rows.sort(key=lambda r: (r[0], r[1]))
    return [r for _, _, r in rows]

