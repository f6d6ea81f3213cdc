"""Pictures of a run, drawn from its files: frames, animations, time-series panels.

=========================================  ==================================================
:mod:`mlsgalerkin.plots.fields`            :class:`FieldStyle`, :func:`register_field`: each
                                           field's label, unit and colour map
:mod:`mlsgalerkin.plots.frames`            labelled pictures of particle frames (matplotlib)
:mod:`mlsgalerkin.plots.timeseries`        :func:`render_timeseries`: the time series' panels
:mod:`mlsgalerkin.plots.run`               :func:`render_run`, :func:`render_frame`: a run
                                           directory's pictures; :class:`RenderError`
=========================================  ==================================================

This package reads files through :mod:`mlsgalerkin.io` and imports nothing from the solvers,
the run loop or the studies; matplotlib is imported only when a picture is drawn.
"""

from __future__ import annotations

from mlsgalerkin.plots.fields import FieldStyle, register_field
from mlsgalerkin.plots.run import RenderError, inspect_run, render_frame, render_run
from mlsgalerkin.plots.timeseries import render_timeseries

__all__ = ["FieldStyle", "RenderError", "inspect_run", "register_field", "render_frame", "render_run",
           "render_timeseries"]
