r"""Monitors observe a run: time series, VTU frames, checkpoints, the watchdog, the progress bar,
pictures. Every side effect of a run is a monitor; the solvers know nothing of files.

A monitor follows py-pde's trackers: :meth:`Monitor.start` once (with the
:class:`~mlsgalerkin.simulation.RunState` and the :class:`RunInfo`), :meth:`Monitor.handle`
after every step, :meth:`Monitor.finish` once at the end of every run — completed, paused
(``max_steps``), stopped by the watchdog, interrupted — with the run's status. What a monitor
needs to continue after a restart exactly as it would have without it (the next sampling
time, the next frame) is its :meth:`Monitor.state_dict`, stored in every checkpoint. Monitors see
the state (positions, velocities, the observables of each system, ``state.snapshot()`` for a
checkpoint) and the run's metadata, never the solvers. Each decides itself when to act (every
step, every so many simulated seconds, at given times).

The :class:`~mlsgalerkin.simulation.Simulation` builds the standard ones from
``Scene.output``, ``Scene.probes`` and ``Scene.watchdog``; ``Scene.monitors`` adds more:

==================  ==============================================================================
monitor             writes
==================  ==============================================================================
:class:`Watchdog`   nothing while the state is sound; ``checkpoints/last_good.npz`` and a
                    :class:`SimulationDiverged` with the system's :class:`~mlsgalerkin.dynamics.Diagnosis`
                    (system, body, point, quantity, step) otherwise
:class:`TimeSeries` ``timeseries.csv``: ``time, dt, step``, each system's observables (and the
                    interactions', e.g. a contact's stored energy), the probes
:class:`Frames`     ``particles.pvd`` + ``particles_*.vtu`` (one series per system)
:class:`Checkpoints` ``checkpoints/checkpoint_<step>.npz`` every ``checkpoint_every`` simulated
                    seconds or ``checkpoint_wall_every`` seconds of wall clock, and at the end
:class:`ProgressBar` a tqdm bar of simulated time (steps/s, ``dt``)
:class:`Pictures`   ``animation.gif``, ``final.png`` from the frames
==================  ==============================================================================
"""

from __future__ import annotations

import logging
import math
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any, Callable, Sequence

import numpy as np

from mlsgalerkin.dynamics import Diagnosis

if TYPE_CHECKING:  # pragma: no cover
    from mlsgalerkin.run_state import RunState

__all__ = [
    "Checkpoints",
    "Frames",
    "Monitor",
    "Output",
    "Pictures",
    "Probe",
    "ProgressBar",
    "RunInfo",
    "SimulationDiverged",
    "TimeSeries",
    "Watchdog",
]

logger = logging.getLogger(__name__)

#: Times closer than this (s) count as equal when matching output schedules.
TIME_TOLERANCE = 1e-12


class SimulationDiverged(RuntimeError):
    """The watchdog stopped a run. ``record`` is the :class:`~mlsgalerkin.dynamics.Diagnosis`
    (which system, body, point, quantity, step); ``diagnosis`` its JSON form
    (:meth:`~mlsgalerkin.dynamics.Diagnosis.as_dict`, ``summary.json``'s ``"diagnosis"``);
    ``checkpoint`` the last good state written, if any."""

    def __init__(self, message: str, diagnosis: Diagnosis | dict, checkpoint: Path | None = None) -> None:
        super().__init__(message)
        self.record = diagnosis if isinstance(diagnosis, Diagnosis) else Diagnosis.from_mapping(diagnosis)
        self.diagnosis = diagnosis.as_dict() if isinstance(diagnosis, Diagnosis) else dict(diagnosis)
        self.checkpoint = checkpoint


@dataclass(frozen=True)
class RunInfo:
    """What a run is, for the monitors: scene name and parameters, end time, dimension, output
    directory (``None``: write nothing), whether it continues from a checkpoint."""

    scene: str
    t_end: float
    dim: int
    out: Path | None
    resumed: bool = False
    parameters: dict = field(default_factory=dict)


@dataclass(frozen=True)
class Output:
    """What a run writes (into the run directory given to ``Simulation.run(out=...)``).

    ``every``: simulated seconds between VTU frames; ``times``: explicit frame times instead;
    ``probe_every``: seconds between time-series rows (default every step); ``checkpoint_every``:
    simulated seconds between checkpoints (default ``t_end/10``); ``checkpoint_wall_every``:
    wall-clock seconds between checkpoints (default 120; ``None``: none by wall clock) — a
    checkpoint is written when either is due, so a killed run loses at most that much work;
    ``vtu``: write frames; ``gif``/``png``: render the animation / a final snapshot coloured by
    ``color_by``; ``keep_checkpoints``: how many periodic checkpoints to keep.
    """

    every: float | None = None
    times: tuple[float, ...] = ()
    probe_every: float | None = None
    checkpoint_every: float | None = None
    checkpoint_wall_every: float | None = 120.0
    vtu: bool = True
    gif: bool = False
    png: bool = False
    color_by: str = "pressure"
    keep_checkpoints: int = 2

    def problems(self) -> list[str]:
        out = []
        for name in ("every", "probe_every", "checkpoint_every", "checkpoint_wall_every"):
            v = getattr(self, name)
            if v is not None and not (isinstance(v, (int, float)) and math.isfinite(v) and v > 0):
                out.append(f"output.{name} must be a positive number of seconds, got {v!r}")
        if any(not (isinstance(t, (int, float)) and math.isfinite(t) and t >= 0) for t in self.times):
            out.append(f"output.times must be non-negative times (s), got {self.times!r}")
        if not (isinstance(self.keep_checkpoints, int) and self.keep_checkpoints >= 1):
            out.append(f"output.keep_checkpoints must be an integer >= 1, got {self.keep_checkpoints!r}")
        from mlsgalerkin.plots.fields import field_name_problem

        color_problem = field_name_problem(self.color_by)
        if color_problem:
            out.append(f"output.color_by: {color_problem}")
        return out


@dataclass(frozen=True)
class Probe:
    """A monitored scalar: ``func(state) -> float`` recorded as a column of ``timeseries.csv``.

    ``state`` is the :class:`~mlsgalerkin.simulation.RunState` (``state.fluid`` the
    :class:`~mlsgalerkin.fluid.state.FluidState`); ``reads`` names the quantities it needs
    beyond the solver's, so validation can check that a listed effect provides them.
    """

    name: str
    func: Callable[[Any], float]
    reads: tuple[str, ...] = ()


class Monitor:
    """Base class of a monitor (module docstring). Override what you need."""

    name: str = "monitor"

    def problems(self) -> list[str]:
        """Problems with this monitor's settings (checked with the scene, before any work)."""
        return []

    def start(self, state: "RunState", info: RunInfo) -> None:
        """Called once before the first step (or after a restart's restore)."""

    def handle(self, state: "RunState", t: float) -> None:
        """Called after every step; ``t`` is ``state.t``."""

    def finish(self, state: "RunState", status: str) -> None:
        """Called once at the end of every run. ``status``: ``"completed"``, ``"paused"``
        (stopped at ``max_steps``), ``"diverged"``, ``"interrupted"`` or ``"failed"``."""

    def summary(self) -> dict[str, Any]:
        """Report for ``summary.json`` (JSON-serialisable; empty: nothing to report)."""
        return {}

    def state_dict(self) -> dict[str, Any]:
        """What this monitor needs to continue identically after a restart (JSON-serialisable)."""
        return {}

    def load_state_dict(self, d: dict[str, Any]) -> None:
        """Restore :meth:`state_dict` (called after :meth:`start` when a run is restarted)."""


# --------------------------------------------------------------------------------------
# the watchdog
# --------------------------------------------------------------------------------------


@dataclass
class Watchdog(Monitor):
    """Stops a diverging run when a system's :meth:`~mlsgalerkin.dynamics.SystemState.health`
    returns a :class:`~mlsgalerkin.dynamics.Diagnosis`: for the fluid, non-finite values,
    ``ρ/ρ0`` outside ``density_ratio``, or a speed above ``max_speed`` (m/s; default ``2 c0``);
    for a structure, a non-finite state or a node displaced more than ``max_displacement`` (m;
    default: no limit). Keeps the state of every ``keep_every``-th step and writes the last good
    one to ``checkpoints/last_good.npz`` when it stops the run."""

    density_ratio: tuple[float, float] = (0.5, 2.0)
    max_speed: float | None = None
    keep_every: int = 50
    max_displacement: float | None = None
    name = "watchdog"

    def problems(self) -> list[str]:
        out = []
        lo, hi = self.density_ratio
        if not (0 < lo < 1 < hi):
            out.append(f"watchdog.density_ratio must bracket 1, (lo, hi) with 0 < lo < 1 < hi, got {self.density_ratio!r}")
        for name in ("max_speed", "max_displacement"):
            v = getattr(self, name)
            if v is not None and not (isinstance(v, (int, float)) and v > 0):
                unit = "m/s" if name == "max_speed" else "m"
                out.append(f"watchdog.{name} must be positive ({unit}) or None, got {v!r}")
        if not (isinstance(self.keep_every, int) and self.keep_every >= 1):
            out.append(f"watchdog.keep_every must be an integer >= 1, got {self.keep_every!r}")
        return out

    def start(self, state: "RunState", info: RunInfo) -> None:
        self._out = info.out
        self._last_good = state.snapshot()
        self.record: Diagnosis | None = None
        self.diagnosis: dict | None = None

    def handle(self, state: "RunState", t: float) -> None:
        diag = state.health(self)
        if diag is not None:
            self.record, self.diagnosis = diag, diag.as_dict()
            arrays, meta = self._last_good
            path = None
            if self._out is not None:
                from mlsgalerkin.io import save_checkpoint

                (self._out / "checkpoints").mkdir(parents=True, exist_ok=True)
                path = save_checkpoint(self._out / "checkpoints" / "last_good.npz", arrays, meta)
            raise SimulationDiverged(self.message(diag, meta["step"], path), diag, path)
        if state.step % self.keep_every == 0:
            self._last_good = state.snapshot()

    @staticmethod
    def message(diag: Diagnosis, last_good_step: int, path: Path | None) -> str:
        """What the watchdog says when it stops a run: the diagnosis's one line, where the last
        good state is, and the system's hint."""
        kept = f"saved to {path}" if path else "kept in memory (no output directory)"
        hint = f" {diag.hint}" if diag.hint else ""
        return f"run diverged {diag.message}. Last good state (step {last_good_step}) {kept}.{hint}"

    def summary(self) -> dict[str, Any]:
        return {"diagnosis": self.diagnosis} if getattr(self, "diagnosis", None) else {}


# --------------------------------------------------------------------------------------
# files
# --------------------------------------------------------------------------------------


class TimeSeries(Monitor):
    """``timeseries.csv``: ``time, dt, step``, each system's and interaction's observables, then one column per
    probe, every ``every`` simulated seconds (every step if ``None``) and at the end.

    The rows are kept in memory (:meth:`columns`) and the file, when there is an output
    directory, is rewritten atomically every ``flush_every`` wall-clock seconds and at the end.
    """

    name = "timeseries"

    def __init__(self, probes: Sequence[Probe] = (), every: float | None = None, flush_every: float = 10.0) -> None:
        self.probes = list(probes)
        self.every = every
        self.flush_every = flush_every

    def start(self, state: "RunState", info: RunInfo) -> None:
        from mlsgalerkin.io import TimeSeriesWriter

        self._t_end = info.t_end
        path = (info.out / "timeseries.csv") if info.out is not None else None
        cols = ["time", "dt", "step"]
        for obs in state.observables().values():
            cols += [c for c in obs if c not in cols]
        cols += [p.name for p in self.probes]
        self.column_names = cols
        if info.resumed and path is not None:
            self._writer = TimeSeriesWriter.resume(path, after_time=state.t)
            self._next = state.t + (self.every or 0.0)
        else:
            self._writer = TimeSeriesWriter(path if path is not None else Path("timeseries.csv"), cols)
            self.record(state)
            self._next = 0.0
        self._path = path
        self._flushed = time.perf_counter()
        self.flush()

    def record(self, state: "RunState") -> None:
        """Append the row of the current state."""
        row: dict[str, Any] = {"time": state.t, "dt": state.dt, "step": state.step}
        for obs in state.observables().values():
            row.update(obs)
        for p in self.probes:
            row[p.name] = float(p.func(state))
        self._writer.append(row)

    def handle(self, state: "RunState", t: float) -> None:
        if self.every is None or t >= self._next - TIME_TOLERANCE or t >= self._t_end * (1 - 1e-12):
            self.record(state)
            self._next = t + (self.every or 0.0)
        if self._path is not None and time.perf_counter() - self._flushed > self.flush_every:
            self.flush()

    def flush(self) -> None:
        """Rewrite ``timeseries.csv`` with every row so far (no-op without an output directory)."""
        if self._path is not None:
            self._writer.flush()
        self._flushed = time.perf_counter()

    def finish(self, state: "RunState", status: str) -> None:
        # the last step of a completed run is always recorded by handle(); a paused or
        # interrupted run gets no extra row, so that a restart continues the same rows
        self.flush()

    def state_dict(self) -> dict[str, Any]:
        return {"next": getattr(self, "_next", 0.0)}

    def load_state_dict(self, d: dict[str, Any]) -> None:
        if "next" in d:
            self._next = float(d["next"])

    def columns(self) -> dict[str, np.ndarray]:
        """One array per column (``int64`` for integer columns, else ``float64``)."""
        from mlsgalerkin.io.timeseries import columns_of

        return columns_of(self._writer.columns, [[r[c] for c in self._writer.columns] for r in self._writer.rows])


class Frames(Monitor):
    """VTU frames of every system (``particles.pvd`` for the fluid, ``structure.pvd`` for the
    structures, with their meshes as cells) at ``times`` or every ``every`` simulated seconds
    (default: the start and the end), and at the end of the run; with several systems also
    ``frames.pvd``, one multiblock (``frames_*.vtm``) per frame time with a block per system."""

    name = "frames"

    def __init__(self, every: float | None = None, times: Sequence[float] = ()) -> None:
        self.every = every
        self.times = tuple(times)

    def start(self, state: "RunState", info: RunInfo) -> None:
        from mlsgalerkin.io import PVDSeries

        if self.times:
            self.frame_times = sorted(float(t) for t in self.times)
        elif self.every:
            n = int(math.floor(info.t_end / self.every + 1e-9))
            self.frame_times = [k * self.every for k in range(n + 1)]
        else:
            self.frame_times = [0.0, info.t_end]
        self._series = {}
        self._out = info.out
        if info.out is None:
            return
        for key, system in state.systems.items():
            name = getattr(system, "frame_name", key)
            self._series[key] = (PVDSeries.resume(info.out, name, after_time=state.t) if info.resumed
                                 else PVDSeries(info.out, name))
        if info.resumed:
            self._next = sum(1 for t in self.frame_times if t <= state.t + TIME_TOLERANCE)
        else:
            self._next = 0
            self.handle(state, state.t)

    def write(self, state: "RunState") -> None:
        for key, series in self._series.items():
            system = state.systems[key]
            points, data = system.frame()
            cells = system.frame_cells() if hasattr(system, "frame_cells") else None
            series.add(state.t, points, data, cells)
        self._combine()

    def _combine(self) -> None:
        """With several systems (fluid and structures): ``frames.pvd`` over ``frames_*.vtm``, one
        multiblock per frame time with a block per system, for ParaView to show them together."""
        if len(self._series) > 1 and self._out is not None:
            from mlsgalerkin.io import write_multiblock_series

            write_multiblock_series(self._out, {getattr(s, "name", k): s for k, s in self._series.items()})

    def handle(self, state: "RunState", t: float) -> None:
        if not self._series:
            return
        ft = self.frame_times
        while self._next < len(ft) and t >= ft[self._next] - TIME_TOLERANCE:
            self.write(state)
            # several frame times inside one step: write the frame once
            while self._next < len(ft) and ft[self._next] <= t + TIME_TOLERANCE:
                self._next += 1

    def finish(self, state: "RunState", status: str) -> None:
        # only a completed run gets a final frame: a paused or interrupted run continues later
        # and must then write the same frames as one that never stopped
        if status != "completed":
            return
        for key, series in self._series.items():
            if not series.frames or series.frames[-1][0] < state.t - TIME_TOLERANCE:
                system = state.systems[key]
                points, data = system.frame()
                series.add(state.t, points, data, system.frame_cells() if hasattr(system, "frame_cells") else None)
        self._combine()

    def summary(self) -> dict[str, Any]:
        return {"frames": {k: len(s.frames) for k, s in self._series.items()}} if self._series else {}

    def state_dict(self) -> dict[str, Any]:
        return {"next": getattr(self, "_next", 0)}

    def load_state_dict(self, d: dict[str, Any]) -> None:
        if "next" in d:
            self._next = int(d["next"])


class Checkpoints(Monitor):
    """Restart files ``checkpoints/checkpoint_<step>.npz`` every ``every`` simulated seconds or
    every ``wall_every`` seconds of wall clock (whichever is due first; ``None`` disables
    either), keeping the newest ``keep``; and the final state of a completed, paused or
    interrupted run.

    ``before_write``: monitors flushed before each checkpoint (the time series), so that the
    files on disk always hold everything up to the newest checkpoint.
    """

    name = "checkpoints"

    def __init__(self, every: float | None = None, keep: int = 2, wall_every: float | None = None,
                 before_write: Sequence[Any] = ()) -> None:
        self.every = every
        self.keep = keep
        self.wall_every = wall_every
        self.before_write = list(before_write)

    def start(self, state: "RunState", info: RunInfo) -> None:
        self._dir = info.out / "checkpoints" if info.out is not None else None
        if self._dir is not None:
            self._dir.mkdir(parents=True, exist_ok=True)
        ce = self.every
        if ce and info.resumed:
            self._next = (math.floor(state.t / ce + 1e-9) + 1) * ce
        else:
            self._next = ce if ce else math.inf
        self._wall = time.perf_counter()
        self.written = 0
        self.last: Path | None = None

    def write(self, state: "RunState") -> Path | None:
        """Write the current state's checkpoint and prune old ones; returns its path."""
        if self._dir is None:
            return None
        from mlsgalerkin.io import checkpoint_path, prune_checkpoints, save_checkpoint

        for m in self.before_write:
            m.flush()
        arrays, meta = state.snapshot()
        path = save_checkpoint(checkpoint_path(self._dir, int(state.step)), arrays, meta)
        prune_checkpoints(self._dir, keep=self.keep)
        self.written += 1
        self.last = path
        self._wall = time.perf_counter()
        return path

    def handle(self, state: "RunState", t: float) -> None:
        due = t >= self._next - TIME_TOLERANCE
        if due or (self.wall_every is not None and time.perf_counter() - self._wall >= self.wall_every):
            self.write(state)
        if due:
            self._next = (math.floor(t / self.every + 1e-9) + 1) * self.every

    def finish(self, state: "RunState", status: str) -> None:
        if status in ("completed", "paused", "interrupted"):
            self.write(state)

    def state_dict(self) -> dict[str, Any]:
        nxt = getattr(self, "_next", math.inf)
        return {"next": nxt if math.isfinite(nxt) else None}

    def load_state_dict(self, d: dict[str, Any]) -> None:
        if d.get("next") is not None:
            self._next = float(d["next"])

    def summary(self) -> dict[str, Any]:
        return {"written": self.written, "last": self.last.name if self.last else None} if self._dir else {}


# --------------------------------------------------------------------------------------
# console and pictures
# --------------------------------------------------------------------------------------


class ProgressBar(Monitor):
    """A tqdm bar of simulated time with the time step and steps per second."""

    name = "progress"

    def start(self, state: "RunState", info: RunInfo) -> None:
        from tqdm.auto import tqdm

        self._bar = tqdm(total=info.t_end, initial=state.t, unit="s", unit_scale=False, desc="simulated time",
                         mininterval=1.0,
                         bar_format="{l_bar}{bar}| {n:.4f}/{total:.4f} s [{elapsed}<{remaining}{postfix}]")
        self._t = state.t
        self._step0 = state.step
        self._wall0 = time.perf_counter()

    def handle(self, state: "RunState", t: float) -> None:
        self._bar.update(t - self._t)
        self._t = t
        if state.step % 20 == 0:
            el = time.perf_counter() - self._wall0
            self._bar.set_postfix_str(f"dt={state.dt:.2e} s, {(state.step - self._step0) / max(el, 1e-9):.0f} steps/s")

    def finish(self, state: "RunState", status: str) -> None:
        self._bar.close()


class Pictures(Monitor):
    """``animation.gif`` and/or ``final.png`` of the fluid frames coloured by ``color_by``
    (rendered at the end of a completed or paused run by
    :func:`~mlsgalerkin.plots.run.render_run`: axes in metres, the field's unit, the time,
    walls in grey; a rendering failure is logged, never fatal: the frames and tables are
    written). ``color_by`` is checked against the field table with the scene (``Output.problems``)
    and against the fluid's frame before the first step: a field the scene does not write
    (``free_surface`` without ``FreeSurfaceDetection``) is reported in a warning and the run goes
    on without pictures."""

    name = "pictures"

    def __init__(self, gif: bool = True, png: bool = True, color_by: str = "pressure") -> None:
        self.gif, self.png, self.color_by = gif, png, color_by

    def problems(self) -> list[str]:
        from mlsgalerkin.plots.fields import field_name_problem

        msg = field_name_problem(self.color_by)
        return [f"Pictures(color_by={self.color_by!r}): {msg}"] if msg else []

    def start(self, state: "RunState", info: RunInfo) -> None:
        self._info = info
        if info.out is None or not (self.gif or self.png):
            return
        from mlsgalerkin.plots.fields import resolve_field

        self._skip = None
        for key, system in state.systems.items():
            if getattr(system, "frame_name", key) == "particles" and hasattr(system, "frame"):
                _, data = system.frame()
                try:
                    resolve_field(data, self.color_by, info.dim)
                except ValueError as err:
                    # a field of the table that this scene does not write (free_surface without
                    # FreeSurfaceDetection): the run goes on, without pictures
                    self._skip = (f"the pictures cannot be coloured by {self.color_by!r} ({err}); the run "
                                  f"writes none (after it: mlsgalerkin render {info.out} --color-by FIELD)")
                    logger.warning("%s", self._skip)

    def finish(self, state: "RunState", status: str) -> None:
        info = self._info
        if info.out is None or status not in ("completed", "paused") or not (self.gif or self.png) or \
                getattr(self, "_skip", None):
            return
        try:
            self.render(info.out, info.scene, info.dim)
        except Exception as exc:  # pictures must not lose a finished run
            logger.warning("rendering failed (%s); the VTU series and tables are written", exc)

    def render(self, directory: Path, title: str, dim: int) -> None:
        """Draw ``animation.gif``/``final.png`` of ``directory/particles.pvd`` (if it exists)."""
        from mlsgalerkin.plots.run import render_run

        if not (directory / "particles.pvd").is_file():
            return
        render_run(directory, color_by=self.color_by, gif=self.gif, png=self.png, title=title)
