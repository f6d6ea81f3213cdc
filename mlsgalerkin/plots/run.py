r"""The pictures of a run directory, from its files alone: frames, animation, time-series plots.

:func:`render_run` reads what a run wrote — ``particles.pvd`` with its ``particles_*.vtu``
frames and ``timeseries.csv`` — and draws, into the run directory or another one:

==================  ===================================================================
file                content
==================  ===================================================================
``final.png``       the last frame (``png=True``)
``frames.png``      a panel of ``snapshots`` frames spread over the run (``snapshots > 0``)
``animation.gif``   every frame (``gif=True``)
``timeseries.png``  the time series, one panel per group of columns (``timeseries=True``)
==================  ===================================================================

It needs no ``summary.json``, so it works on a run that was interrupted or is still going
(the ``.pvd`` and the CSV file are rewritten atomically, so what is read is always whole).
The run's :class:`~mlsgalerkin.monitors.Pictures` monitor and ``mlsgalerkin render RUN_DIR``
both call it. :func:`inspect_run` checks a directory and the colour field before any drawing,
with a :class:`RenderError` saying what is missing and what to do.

Example (``results/dam_break`` from ``mlsgalerkin run dam_break``)::

    from mlsgalerkin.plots.run import render_run
    render_run("results/dam_break", color_by="speed", gif=False)
"""

from __future__ import annotations

import json
import logging
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from mlsgalerkin.plots.fields import resolve_field
from mlsgalerkin.plots.frames import Frame, figure_png, frame_figure, frame_view, with_structure, write_gif

__all__ = ["RenderError", "RunContents", "inspect_run", "read_frames", "render_frame", "render_run"]

logger = logging.getLogger(__name__)

FRAMES_FILE = "particles.pvd"
#: The frames of a run's structures, drawn with the particles when present.
STRUCTURE_FILE = "structure.pvd"
TIMESERIES_FILE = "timeseries.csv"


class RenderError(ValueError):
    """A run directory cannot be drawn as asked; the message says what is missing and what to do."""


@dataclass(frozen=True)
class RunContents:
    """What a run directory holds, for drawing.

    ``frames``: ``(time (s), path)`` of each VTU frame listed in ``particles.pvd`` whose file
    exists; ``timeseries``: the CSV file or ``None``; ``title``: the scene's name from
    ``summary.json`` (else the directory's name); ``status``: the run's status from
    ``summary.json``, ``None`` without one (a run that is still going or was killed).
    """

    directory: Path
    frames: tuple[tuple[float, Path], ...]
    timeseries: Path | None
    title: str
    status: str | None


def inspect_run(run_dir: str | Path, *, color_by: str | None = None, need_frames: bool = True,
                need_timeseries: bool = False) -> RunContents:
    """Check ``run_dir`` before drawing; returns its :class:`RunContents`.

    Raises :class:`RenderError` when the directory does not exist, when frames are
    needed and there are none, when the time series is needed and missing, or when
    ``color_by`` is not a field of the first frame (the message lists the available fields).
    """
    from mlsgalerkin.io.vtk import read_pvd, read_vtu

    d = Path(run_dir)
    if not d.exists():
        raise RenderError(f"run directory {d} does not exist; give the --out directory of a run "
                                "(default results/PROBLEM)")
    if not d.is_dir():
        raise RenderError(f"{d} is a file, not a run directory")
    title, status = d.resolve().name, None
    summary = d / "summary.json"
    if summary.is_file():
        try:
            s = json.loads(summary.read_text(encoding="utf-8"))
            title, status = str(s.get("scene") or title), s.get("status")
        except (OSError, ValueError) as exc:
            logger.warning("could not read %s (%s); drawing without it", summary, exc)
    frames: list[tuple[float, Path]] = []
    pvd = d / FRAMES_FILE
    if pvd.is_file():
        try:
            listed = read_pvd(pvd)
        except ValueError as exc:
            raise RenderError(f"{pvd} cannot be read ({exc})") from exc
        missing = [p.name for _, p in listed if not p.is_file()]
        if missing:
            logger.warning("%d frame file(s) listed in %s are missing (%s); drawing the others",
                           len(missing), pvd, ", ".join(missing[:3]))
        frames = [(t, p) for t, p in listed if p.is_file()]
    ts = d / TIMESERIES_FILE
    timeseries = ts if ts.is_file() else None
    if need_frames and not frames:
        vtus = sorted(d.glob("particles_*.vtu"))
        if vtus and not pvd.is_file():
            why = (f"it holds {len(vtus)} particles_*.vtu file(s) but no {FRAMES_FILE}, which lists their "
                   "times")
        elif pvd.is_file():
            why = f"{FRAMES_FILE} lists no frame files that exist"
        else:
            why = (f"it has no {FRAMES_FILE}: the run wrote no VTU frames (Output(vtu=False)) or stopped "
                   "before its first frame")
        hint = (f"; its time series can still be plotted (mlsgalerkin render {d} --no-gif --no-png)"
                if timeseries else "")
        raise RenderError(f"{d} has no frames to draw: {why}{hint}")
    if need_timeseries and timeseries is None:
        raise RenderError(f"{d} has no {TIMESERIES_FILE}; it is not a run directory or the run "
                                "stopped before its first step")
    if color_by is not None and frames:
        points, data = read_vtu(frames[0][1])
        try:
            resolve_field(data, color_by, _dim(points))
        except ValueError as exc:
            raise RenderError(f"cannot colour by {color_by!r}: {exc}") from None
    return RunContents(d, tuple(frames), timeseries, title, status)


def _dim(points: np.ndarray) -> int:
    return 3 if points.shape[1] == 3 and float(np.ptp(points[:, 2])) > 0.0 else 2


def read_frames(listed: Sequence[tuple[float, Path]]) -> list[Frame]:
    """``(time, points, point_data)`` of each ``(time, path)``; 2D series come back ``(n, 2)``.
    A run with structures (``structure.pvd`` beside the particle frames) gets the structure's
    nodes of the same time added to each frame (:func:`~mlsgalerkin.plots.frames.with_structure`)."""
    from mlsgalerkin.io.vtk import read_pvd, read_vtu

    structure: list[tuple[float, Path]] = []
    if listed:
        spvd = Path(listed[0][1]).parent / STRUCTURE_FILE
        if spvd.is_file():
            try:
                structure = [(t, p) for t, p in read_pvd(spvd) if p.is_file()]
            except ValueError as exc:
                logger.warning("could not read %s (%s); drawing the particles alone", spvd, exc)
    out = []
    for t, path in listed:
        points, data = read_vtu(path)
        frame = (float(t), points[:, :2] if _dim(points) == 2 else points, data)
        match = [p for ts, p in structure if abs(ts - t) <= 1e-9 * max(1.0, abs(t))]
        if match:
            spoints, _ = read_vtu(match[0])
            frame = with_structure(frame, spoints)
        out.append(frame)
    return out


def _spread(n_frames: int, k: int) -> list[int]:
    """``k`` frame indices spread evenly from the first to the last (no repeats)."""
    if k >= n_frames:
        return list(range(n_frames))
    return sorted({int(round(i)) for i in np.linspace(0, n_frames - 1, k)})


def render_frame(run_dir: str | Path, out_png: str | Path, *, color_by: str = "pressure",
                 time: float | None = None, title: str | None = None, width: float = 8.0,
                 dpi: float = 100.0, clim: tuple[float, float] | None = None) -> tuple[Path, float]:
    """One frame of a run as a PNG: the frame nearest ``time`` (s; default the last).

    Returns ``(path, the frame's time)``. The colour range is that frame's own (or ``clim``).
    """
    contents = inspect_run(run_dir, color_by=color_by)
    times = np.array([t for t, _ in contents.frames])
    k = len(times) - 1 if time is None else int(np.argmin(np.abs(times - float(time))))
    frames = read_frames([contents.frames[k]])
    view = frame_view(frames, color_by, title=contents.title if title is None else title, clim=clim)
    path = figure_png(frame_figure(view, frames, width=width, dpi=dpi), out_png, cmap=view.style.cmap)
    return path, float(times[k])


def render_run(
    run_dir: str | Path,
    *,
    color_by: str = "pressure",
    out: str | Path | None = None,
    gif: bool = True,
    png: bool = True,
    snapshots: int = 0,
    timeseries: bool = False,
    fps: float = 8.0,
    title: str | None = None,
) -> list[Path]:
    """Draw the pictures of the run in ``run_dir`` (module docstring); returns the files written.

    Parameters
    ----------
    run_dir : str or Path
        A run directory (``Simulation.run(out=...)``, ``mlsgalerkin run --out``).
    color_by : str
        The colour field (see :mod:`mlsgalerkin.plots.fields`), checked first.
    out : str or Path, optional
        Where to write (created if needed); default ``run_dir``.
    gif, png : bool
        ``animation.gif`` of all frames; ``final.png`` of the last.
    snapshots : int
        Frames in the panel ``frames.png`` (0: no panel).
    timeseries : bool
        ``timeseries.png`` from ``timeseries.csv``.
    fps : float
        Frames per second of the animation.
    title : str, optional
        Title of the frames; default the scene's name.

    All frames share one colour range (the fluid's 0.5th to 99.5th percentile over the frames)
    and one framed region.
    """
    from mlsgalerkin.plots.timeseries import render_timeseries

    need_frames = bool(gif or png or snapshots)
    if not (need_frames or timeseries):
        raise ValueError("nothing to draw: ask for the animation, the final picture, snapshots or the "
                         "time series")
    if isinstance(snapshots, bool) or not isinstance(snapshots, int) or snapshots < 0:
        raise ValueError(f"snapshots must be a whole number >= 0, got {snapshots!r}")
    contents = inspect_run(run_dir, color_by=color_by if need_frames else None, need_frames=need_frames,
                           need_timeseries=timeseries)
    dest = Path(out) if out is not None else contents.directory
    dest.mkdir(parents=True, exist_ok=True)
    name = contents.title if title is None else title
    written: list[Path] = []
    if need_frames:
        frames = read_frames(contents.frames)
        view = frame_view(frames, color_by, title=name)
        if png:
            written.append(figure_png(frame_figure(view, frames[-1:]), dest / "final.png", cmap=view.style.cmap))
        if snapshots:
            chosen = [frames[k] for k in _spread(len(frames), snapshots)]
            fig = frame_figure(view, chosen, suptitle=f"{name}: {view.style.axis_label}")
            written.append(figure_png(fig, dest / "frames.png", cmap=view.style.cmap))
        if gif:
            written.append(write_gif(view, frames, dest / "animation.gif", fps=fps))
    if timeseries:
        written.append(render_timeseries(contents.timeseries, dest / "timeseries.png",
                                         title=f"{name}: time series"))
    logger.info("drew %s", ", ".join(p.name for p in written))
    return written
