"""Output of particle simulations: VTU/PVD frames, checkpoints, CSV time series, pictures.

=====================================  ==================================================
:mod:`mlsgalerkin.io.vtk`              :func:`write_vtu`, :func:`read_vtu`,
                                       :class:`PVDSeries` (ParaView ``.pvd`` series)
:mod:`mlsgalerkin.io.checkpoint`       :func:`save_checkpoint`, :func:`load_checkpoint`,
                                       :func:`latest_checkpoint`, :func:`prune_checkpoints`
:mod:`mlsgalerkin.io.timeseries`       :class:`TimeSeriesWriter`, :func:`read_timeseries`
:mod:`mlsgalerkin.io.render`           :func:`render_snapshot`, :func:`render_animation`,
                                       :func:`render_vtu_series` (PNG / GIF, off screen)
=====================================  ==================================================

Every file is written atomically (temporary file in the same directory, then
``os.replace``) and nothing is ever pickled. meshio, pyvista and matplotlib are imported only
when a function needs them.
"""

from __future__ import annotations

from mlsgalerkin.io.checkpoint import (
    CHECKPOINT_FORMAT,
    CHECKPOINT_VERSION,
    CheckpointError,
    atomic_output,
    checkpoint_path,
    latest_checkpoint,
    load_checkpoint,
    prune_checkpoints,
    save_checkpoint,
)
from mlsgalerkin.io.render import (
    offscreen_backend,
    render_animation,
    render_snapshot,
    render_vtu_series,
)
from mlsgalerkin.io.timeseries import TimeSeriesWriter, read_timeseries
from mlsgalerkin.io.vtk import PVDSeries, read_pvd, read_vtu, write_vtu

__all__ = [
    "CHECKPOINT_FORMAT",
    "CHECKPOINT_VERSION",
    "CheckpointError",
    "PVDSeries",
    "TimeSeriesWriter",
    "atomic_output",
    "checkpoint_path",
    "latest_checkpoint",
    "load_checkpoint",
    "offscreen_backend",
    "prune_checkpoints",
    "read_pvd",
    "read_timeseries",
    "read_vtu",
    "render_animation",
    "render_snapshot",
    "render_vtu_series",
    "save_checkpoint",
    "write_vtu",
]
