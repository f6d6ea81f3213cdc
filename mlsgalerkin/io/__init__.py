"""Files: atomic writes, provenance, VTU/PVD frames, checkpoints, CSV time series, pictures.

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
:mod:`mlsgalerkin.io.render`               :func:`render_snapshot`, :func:`render_animation`,
                                           :func:`render_vtu_series` (PNG / GIF, off screen)
:mod:`mlsgalerkin.io.render_fields`        :class:`FieldStyle`, :func:`register_field`: each
                                           field's label, unit and colour map
:mod:`mlsgalerkin.io.render_frames`        labelled pictures of particle frames (matplotlib)
:mod:`mlsgalerkin.io.render_timeseries`    :func:`render_timeseries`: the time series' panels
:mod:`mlsgalerkin.io.render_run`           :func:`render_run`, :func:`render_frame`: a run
                                           directory's pictures; :class:`RenderError`
=========================================  ==================================================

Every file is written atomically (temporary file in the same directory, then
``os.replace``) and nothing is ever pickled. This package imports nothing from the solvers or
the studies. meshio, pyvista and matplotlib are imported only
when a function needs them.
"""

from __future__ import annotations

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
from mlsgalerkin.io.render import (
    offscreen_backend,
    render_animation,
    render_snapshot,
    render_vtu_series,
)
from mlsgalerkin.io.render_fields import FieldStyle, register_field
from mlsgalerkin.io.render_run import RenderError, render_frame, render_run
from mlsgalerkin.io.render_timeseries import render_timeseries
from mlsgalerkin.io.timeseries import TimeSeriesWriter, read_timeseries
from mlsgalerkin.io.vtk import PVDSeries, read_pvd, read_vtu, write_multiblock_series, write_vtu

__all__ = [
    "CHECKPOINT_FORMAT",
    "CHECKPOINT_VERSION",
    "CheckpointError",
    "FieldStyle",
    "PVDSeries",
    "RenderError",
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
    "offscreen_backend",
    "provenance",
    "prune_checkpoints",
    "read_json_file",
    "read_pvd",
    "read_timeseries",
    "read_vtu",
    "register_field",
    "render_animation",
    "render_frame",
    "render_run",
    "render_snapshot",
    "render_timeseries",
    "render_vtu_series",
    "save_checkpoint",
    "to_jsonable",
    "write_csv_rows",
    "write_json",
    "write_multiblock_series",
    "write_vtu",
]
