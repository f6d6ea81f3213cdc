"""Files: atomic writes, provenance, VTU/PVD frames, checkpoints, CSV time series.

=========================================  ==================================================
:mod:`mlsgalerkin.io.files`                :func:`atomic_output`, :func:`atomic_write`,
                                           :func:`write_json`, :func:`to_jsonable`,
                                           :func:`csv_text`, :func:`write_csv_rows`
:mod:`mlsgalerkin.io.provenance`           :func:`provenance`, :func:`git_commit`,
                                           :func:`command_line`
:mod:`mlsgalerkin.io.vtk`                  :func:`write_vtu`, :func:`read_vtu`,
                                           :class:`PVDSeries` (ParaView ``.pvd`` series)
:mod:`mlsgalerkin.io.checkpoint`           :func:`save_checkpoint`, :func:`load_checkpoint`,
                                           :func:`latest_checkpoint`, :func:`prune_checkpoints`
:mod:`mlsgalerkin.io.timeseries`           :class:`TimeSeriesWriter`, :func:`read_timeseries`
=========================================  ==================================================

Every file is written atomically (temporary file in the same directory, then
``os.replace``) and nothing is ever pickled. This package imports nothing from the solvers or
the studies. meshio is imported only when a function needs it. The pictures of a run are in
:mod:`mlsgalerkin.plots`.
"""

from __future__ import annotations

from mlsgalerkin.deprecation import moved_names
from mlsgalerkin.io.checkpoint import (
    CHECKPOINT_FORMAT,
    CHECKPOINT_VERSION,
    CheckpointError,
    checkpoint_path,
    checkpoints_newest_first,
    latest_checkpoint,
    load_checkpoint,
    prune_checkpoints,
    save_checkpoint,
)
from mlsgalerkin.io.files import (
    atomic_output,
    atomic_write,
    csv_text,
    format_cell,
    read_json_file,
    to_jsonable,
    write_csv_rows,
    write_json,
)
from mlsgalerkin.io.provenance import command_line, git_commit, provenance
from mlsgalerkin.io.timeseries import TimeSeriesWriter, read_timeseries
from mlsgalerkin.io.vtk import PVDSeries, read_pvd, read_vtu, write_multiblock_series, write_vtu

__all__ = [
    "CHECKPOINT_FORMAT",
    "CHECKPOINT_VERSION",
    "CheckpointError",
    "PVDSeries",
    "TimeSeriesWriter",
    "atomic_output",
    "atomic_write",
    "checkpoint_path",
    "checkpoints_newest_first",
    "command_line",
    "csv_text",
    "format_cell",
    "git_commit",
    "latest_checkpoint",
    "load_checkpoint",
    "provenance",
    "prune_checkpoints",
    "read_json_file",
    "read_pvd",
    "read_timeseries",
    "read_vtu",
    "save_checkpoint",
    "to_jsonable",
    "write_csv_rows",
    "write_json",
    "write_multiblock_series",
    "write_vtu",
]

#: Names that moved to :mod:`mlsgalerkin.plots` (still reachable here for one release, with a
#: DeprecationWarning) and names that were removed with the unused off-screen renderer.
_forward = moved_names(__name__, {name: "mlsgalerkin.plots" for name in (
    "FieldStyle", "register_field", "RenderError", "render_frame", "render_run", "render_timeseries")})
_REMOVED = ("render_snapshot", "render_animation", "render_vtu_series", "offscreen_backend")


def __getattr__(name: str):
    if name in _REMOVED:
        raise AttributeError(f"mlsgalerkin.io.{name} was removed (an off-screen renderer nothing used); draw a run's "
                             "frames with mlsgalerkin.plots.render_run or render_frame")
    return _forward(name)
