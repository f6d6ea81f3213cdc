r"""The run loop: bodies advance, interactions exchange forces, monitors observe.

``Simulation(scene).run(out="DIR")`` validates the scene (every problem at once, before any
work), builds one solver per kind of body (:meth:`~mlsgalerkin.scene.Scene.solver_groups`), and
per step of size ``Δt = min(solver and interaction limits, t_end − t)``:

1. every solver's :meth:`~mlsgalerkin.dynamics.Solver.begin_step` (positions to ``t + Δt``;
   a structure may sub-cycle here);
2. every interaction's :meth:`~mlsgalerkin.dynamics.Interaction.exchange` (forces at
   ``t + Δt`` on both bodies);
3. every solver's :meth:`~mlsgalerkin.dynamics.Solver.end_step` (forces, final kick);
4. every monitor's :meth:`~mlsgalerkin.monitors.Monitor.handle` with the :class:`RunState`.

``summary.json`` is written at the end of **every** run that has an output directory —
completed, paused at ``max_steps``, stopped by the watchdog (with its diagnosis), interrupted,
or failed — with the status, the wall time, each solver's report and the problem's results.
The loop knows no physics: see ``docs/architecture.md``.
"""

from __future__ import annotations

import logging
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Callable

import numpy as np

from mlsgalerkin.dynamics import Solver
from mlsgalerkin.monitors import (
    Checkpoints,
    Frames,
    Monitor,
    Pictures,
    ProgressBar,
    RunInfo,
    SimulationDiverged,
    TimeSeries,
)
from mlsgalerkin.scene import Scene

__all__ = ["RunResult", "RunState", "Simulation", "SimulationDiverged"]

logger = logging.getLogger(__name__)

#: Layout of the checkpoint metadata written by :meth:`Simulation.snapshot`.
CHECKPOINT_LAYOUT = 2


@dataclass
class RunState:
    """What monitors and probes see: the time, the step, the last step size and the state of
    every system (``systems["fluid"]`` is the :class:`~mlsgalerkin.fluid.state.FluidState`)."""

    t: float
    step: int
    dt: float
    systems: dict[str, Any]
    _snapshot: Callable[[], tuple[dict, dict]] = field(repr=False, default=None)  # type: ignore[assignment]

    @property
    def fluid(self) -> Any:
        """The fluid state (``None`` without fluid bodies)."""
        return self.systems.get("fluid")

    def observables(self) -> dict[str, dict[str, float]]:
        """Each system's built-in time-series quantities, by system."""
        return {k: s.observables() for k, s in self.systems.items() if hasattr(s, "observables")}

    def health(self, limits: Any) -> dict | None:
        """The first system's diagnosis of an unsound state (``None`` if all are sound)."""
        for s in self.systems.values():
            diag = s.health(limits) if hasattr(s, "health") else None
            if diag is not None:
                return diag
        return None

    def snapshot(self) -> tuple[dict[str, np.ndarray], dict[str, Any]]:
        """Arrays and metadata of a checkpoint from which the run continues bit for bit."""
        return self._snapshot()


@dataclass
class RunResult:
    """What :meth:`Simulation.run` returns: final state, time series, summary, output folder,
    and the problem's results (from ``analyse``)."""

    state: RunState
    timeseries: dict[str, np.ndarray]
    summary: dict[str, Any]
    out: Path | None = None
    results: dict[str, Any] | None = None


class Simulation:
    """Runs a validated :class:`~mlsgalerkin.scene.Scene`: ``Simulation(scene).run(out="DIR")``."""

    def __init__(self, scene: Scene) -> None:
        scene.validate()
        self.scene = scene
        self.solvers: list[Solver] = []
        self._solver_of: dict[str, Solver] = {}  # body name -> the solver that advances it
        for cls, bodies in scene.solver_groups().items():
            solver = cls(bodies, scene)
            self.solvers.append(solver)
            self._solver_of.update({b.name: solver for b in bodies})
        self.state = RunState(t=0.0, step=0, dt=0.0, systems={s.key: s.state for s in self.solvers},
                              _snapshot=self.snapshot)
        self.started = False

    def solver(self, key: str) -> Solver:
        """The solver whose state is ``state.systems[key]`` (``"fluid"``)."""
        for s in self.solvers:
            if s.key == key:
                return s
        raise KeyError(f"no solver {key!r}; the scene's solvers are {[s.key for s in self.solvers]}")

    # ------------------------------------------------------------------ stepping
    def start(self) -> None:
        """First force evaluation of every solver at the initial time."""
        for s in self.solvers:
            s.start()
        self.started = True

    def time_step(self) -> float:
        """The largest step every solver and interaction allows (s)."""
        limits = [s.stable_time_step() for s in self.solvers]
        limits += [i.stable_time_step() for i in self.scene.interactions]
        return min(limits)

    def step(self, dt: float) -> None:
        """Advance every body by ``dt``: begin, exchange, end (no monitors)."""
        st = self.state
        t = st.t
        for s in self.solvers:
            s.begin_step(t, dt)
        if self.scene.interactions:
            for s in self.solvers:
                s.clear_surface_forces()
            for i in self.scene.interactions:
                i.exchange(t + dt, self._solver_of[i.first], self._solver_of[i.second])
        for s in self.solvers:
            s.end_step(t, dt)
        st.t = t + dt
        st.step += 1
        st.dt = dt

    # ------------------------------------------------------------------ checkpoints
    def snapshot(self) -> tuple[dict[str, np.ndarray], dict[str, Any]]:
        """Arrays and metadata of every solver (keys ``<solver>__<array>``) plus the run's clock."""
        from mlsgalerkin.io import to_jsonable

        st = self.state
        arrays: dict[str, np.ndarray] = {}
        meta: dict[str, Any] = {"layout": CHECKPOINT_LAYOUT, "scene": self.scene.name, "t": st.t,
                                "step": st.step, "dt": st.dt, "parameters": to_jsonable(self.scene.parameters),
                                "solvers": {}}
        for s in self.solvers:
            a, m = s.checkpoint()
            arrays.update({f"{s.key}__{k}": v for k, v in a.items()})
            meta["solvers"][s.key] = m
        return arrays, meta

    def restore(self, arrays: dict[str, np.ndarray], meta: dict[str, Any]) -> None:
        """Load a :meth:`snapshot` into this simulation (built from the same scene)."""
        if meta.get("layout") != CHECKPOINT_LAYOUT:
            raise ValueError(
                f"checkpoint metadata layout {meta.get('layout')!r} is not {CHECKPOINT_LAYOUT}: it was written by "
                "another version of mlsgalerkin; rerun from the start")
        keys = sorted(meta.get("solvers", {}))
        if keys != sorted(s.key for s in self.solvers):
            raise ValueError(f"checkpoint holds the solvers {keys} but the scene has "
                             f"{sorted(s.key for s in self.solvers)}; restart with the scene that wrote it")
        for s in self.solvers:
            prefix = f"{s.key}__"
            s.restore({k[len(prefix):]: v for k, v in arrays.items() if k.startswith(prefix)}, meta["solvers"][s.key])
        st = self.state
        st.t, st.step, st.dt = float(meta["t"]), int(meta["step"]), float(meta["dt"])
        self.started = True

    # ------------------------------------------------------------------ run
    def monitors(self, out: Path | None, progress: bool) -> list[Monitor]:
        """The standard monitors of the scene (watchdog, time series, frames, checkpoints,
        progress bar, pictures), then ``scene.monitors``."""
        sc = self.scene
        o = sc.output
        ms: list[Monitor] = [sc.watchdog, TimeSeries(sc.probes, every=o.probe_every)]
        if out is not None:
            if o.vtu:
                ms.append(Frames(every=o.every, times=o.times))
            ms.append(Checkpoints(every=o.checkpoint_every, keep=o.keep_checkpoints))
        if progress:
            ms.append(ProgressBar())
        if out is not None and (o.gif or o.png):
            ms.append(Pictures(gif=o.gif, png=o.png, color_by=o.color_by))
        return ms + list(sc.monitors)

    def run(self, out: str | Path | None = None, *, progress: bool = True, restart: str | Path | None = None,
            max_steps: int | None = None, analyse: Callable[[RunResult], dict] | None = None) -> RunResult:
        """Run to ``scene.t_end`` (or ``max_steps`` steps) and return a :class:`RunResult`.

        ``out``: run directory for ``timeseries.csv``, the VTU/PVD series, checkpoints,
        ``summary.json`` and pictures (nothing is written without it; the time series is kept
        in memory either way). ``restart``: a checkpoint file, or ``"latest"`` for the newest in
        ``out/checkpoints``. ``analyse(result) -> dict``: the problem's analysis, run before
        ``summary.json`` is written; its results go under ``"results"``.
        """
        from mlsgalerkin.io import latest_checkpoint, load_checkpoint

        out = Path(out) if out is not None else None
        if out is not None:
            out.mkdir(parents=True, exist_ok=True)
        if restart is not None:
            if str(restart) == "latest":
                if out is None:
                    raise ValueError("restart='latest' needs the run directory: pass out=")
                path = latest_checkpoint(out / "checkpoints")
                if path is None:
                    raise FileNotFoundError(f"no checkpoint found in {out / 'checkpoints'}")
            else:
                path = Path(restart)
            arrays, meta = load_checkpoint(path)
            self.restore(arrays, meta)
            logger.info("restarted from %s at t = %.6g s (step %d)", path, self.state.t, self.state.step)
        elif not self.started:
            self.start()
        sc, st = self.scene, self.state
        info = RunInfo(scene=sc.name, t_end=sc.t_end, dim=sc.dim, out=out, resumed=restart is not None,
                       parameters=dict(sc.parameters))
        monitors = self.monitors(out, progress)
        series = next(m for m in monitors if isinstance(m, TimeSeries))
        for m in monitors:
            m.start(st, info)
        wall0 = time.perf_counter()
        steps0 = st.step
        status, diagnosis, error = "running", None, None
        try:
            while st.t < sc.t_end * (1 - 1e-12) and (max_steps is None or st.step - steps0 < max_steps):
                dt = min(self.time_step(), sc.t_end - st.t)
                self.step(dt)
                for m in monitors:
                    m.handle(st, st.t)
            status = "completed" if st.t >= sc.t_end * (1 - 1e-12) else "paused"
        except SimulationDiverged as err:
            status, diagnosis, error = "diverged", err.diagnosis, err
        except KeyboardInterrupt as err:
            status, error = "interrupted", err
        except Exception as err:
            status, diagnosis, error = "failed", {"error": f"{type(err).__name__}: {err}"}, err
        wall = time.perf_counter() - wall0
        for m in monitors:
            try:
                m.finish(st, status)
            except Exception as exc:  # a monitor must not hide the run's own outcome
                if error is None:
                    status, diagnosis, error = "failed", {"error": f"{type(exc).__name__}: {exc}"}, exc
                else:
                    logger.warning("monitor %s failed while finishing (%s)", m.name, exc)
        summary = self.summary(wall, st.step - steps0, status, diagnosis, monitors)
        result = RunResult(state=st, timeseries=series.columns(), summary=summary, out=out)
        if analyse is not None and status in ("completed", "paused"):
            try:
                result.results = analyse(result)
                summary["results"] = result.results
            except Exception as exc:
                summary["analysis_error"] = f"{type(exc).__name__}: {exc}"
                error = error or exc
        if out is not None:
            self._write_summary(out, summary)
        if error is not None:
            raise error
        return result

    def summary(self, wall: float, steps: int, status: str = "completed", diagnosis: dict | None = None,
                monitors: list[Monitor] = ()) -> dict[str, Any]:
        """The run's report: status, clock, wall time, throughput, each solver's and monitor's part."""
        from mlsgalerkin.io import to_jsonable

        st = self.state
        nodes = sum(int(getattr(s, "n", 0)) for s in st.systems.values())
        out: dict[str, Any] = {
            "scene": self.scene.name, "status": status, "diagnosis": diagnosis,
            "parameters": to_jsonable(self.scene.parameters),
            "t_end_s": st.t, "steps": st.step, "steps_this_run": steps, "wall_time_s": wall,
            "particle_steps_per_s": nodes * steps / wall if wall > 0 else None,
        }
        for s in self.solvers:
            out[s.key] = s.summary()
        if self.scene.interactions:
            out["interactions"] = {i.name: to_jsonable(i.summary()) for i in self.scene.interactions}
        reports = {m.name: to_jsonable(m.summary()) for m in monitors if m.summary()}
        if reports:
            out["monitors"] = reports
        return out

    def _write_summary(self, out: Path, summary: dict[str, Any]) -> None:
        from mlsgalerkin.io import provenance, write_json

        summary = dict(summary)
        try:
            summary["provenance"] = provenance(f"run {self.scene.name}")
        except Exception:  # provenance is best effort (no git in an installed package)
            pass
        write_json(out / "summary.json", summary)
