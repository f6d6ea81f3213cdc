r"""The run loop: bodies advance, interactions exchange forces, monitors observe.

``Simulation(scene).run(out="DIR")`` validates the scene (every problem at once, before any
work), builds one solver per kind of body (:meth:`~mlsgalerkin.scene.Scene.solver_groups`), and
per step of size ``Δt = min(solver and interaction limits, t_end − t)``:

1. every solver's :meth:`~mlsgalerkin.dynamics.Solver.begin_step` (positions to ``t + Δt``;
   a structure may sub-cycle here);
2. every interaction's :meth:`~mlsgalerkin.dynamics.Interaction.exchange` (forces at
   ``t + Δt`` on both bodies);
3. every solver's :meth:`~mlsgalerkin.dynamics.Solver.end_step` (forces, final kick);
4. every interaction's :meth:`~mlsgalerkin.dynamics.Interaction.after_step` (forces a solver
   computed in its ``end_step``, for the other body's next step);
5. every monitor's :meth:`~mlsgalerkin.monitors.Monitor.handle` with the :class:`RunState`.

``summary.json`` is written at the end of **every** run that has an output directory —
completed, paused at ``max_steps``, stopped by the watchdog (with its diagnosis), interrupted,
or failed — with the status, the wall time, each solver's report and the problem's results.
The loop knows no physics: see ``docs/architecture.md``.
"""

from __future__ import annotations

import contextlib
import logging
import signal
import threading
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Callable

import numpy as np
from threadpoolctl import threadpool_limits

from mlsgalerkin.dynamics import Solver, SystemState
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
from mlsgalerkin.run_state import RunState
from mlsgalerkin.run_directory import (
    CLOCK_ARRAY,
    RestartMismatch,
    RunDirectoryError,
    RunDirectoryLock,
    check_checkpoint_clock,
    claim_directory,
    identity_differences,
    newest_checkpoint_of_run,
    read_manifest,
)
from mlsgalerkin.scene import Scene

__all__ = ["RestartMismatch", "RunInterrupted", "RunResult", "RunState", "Simulation", "SimulationDiverged"]

logger = logging.getLogger(__name__)

#: Layout of the checkpoint metadata written by :meth:`Simulation.snapshot`.
CHECKPOINT_LAYOUT = 2


class RunInterrupted(KeyboardInterrupt):
    """SIGINT, SIGTERM or SIGHUP stopped a run after a complete step; its files and a checkpoint are
    written (``checkpoint``), and ``restart="latest"`` continues it."""

    def __init__(self, signum: int, t: float, step: int) -> None:
        super().__init__(f"interrupted by {_signal_name(signum)} at t = {t:.6g} s (step {step})")
        self.signum, self.t, self.step = signum, t, step
        self.checkpoint: Path | None = None


def _signal_name(signum: int) -> str:
    try:
        return signal.Signals(signum).name
    except ValueError:
        return f"signal {signum}"


#: The signals that stop a run after the step in progress, with its files and a checkpoint written:
#: Ctrl-C, ``kill``, and the terminal (or SSH connection) closing under it.
STOP_SIGNALS = tuple(getattr(signal, name) for name in ("SIGINT", "SIGTERM", "SIGHUP") if hasattr(signal, name))


@contextlib.contextmanager
def _stop_on_signals():
    """While active (main thread only), :data:`STOP_SIGNALS` (SIGINT, SIGTERM, SIGHUP) append their
    number to the yielded list instead of interrupting; a second one of the same kind acts as usual.
    A signal the caller ignores (``nohup`` ignores SIGHUP) stays ignored."""
    stop: list[int] = []
    if threading.current_thread() is not threading.main_thread():
        yield stop
        return
    previous = {}

    def handler(signum, frame):
        stop.append(signum)
        signal.signal(signum, previous[signum])  # a second Ctrl-C stops at once

    for sig in STOP_SIGNALS:
        if signal.getsignal(sig) is signal.SIG_IGN and sig != signal.SIGINT:
            continue  # nohup: the caller wants the run to go on when the terminal closes
        previous[sig] = signal.getsignal(sig)
        signal.signal(sig, handler)
    try:
        yield stop
    finally:
        for sig, old in previous.items():
            signal.signal(sig, old)


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
        view = scene.view()
        for cls, bodies in scene.solver_groups().items():
            solver = cls(bodies, scene.scheme_for(cls), view)
            if not isinstance(solver.state, SystemState):
                raise TypeError(f"{cls.__name__}.state is a {type(solver.state).__name__}, which lacks what monitors "
                                "call (observables(), health(limits), frame()): see mlsgalerkin.dynamics.SystemState")
            self.solvers.append(solver)
            self._solver_of.update({b.name: solver for b in bodies})
        for i in scene.interactions:
            i.setup(view)
        self.state = RunState(t=0.0, step=0, dt=0.0, systems={s.key: s.state for s in self.solvers},
                              interactions=tuple(scene.interactions), _snapshot=self.snapshot)
        self.started = False
        self._code_commit: str | None = None
        self.identity = self._identity()
        self._monitors: list[Monitor] = []
        self._changes: list[dict] = []

    def _identity(self, origin: dict | None = None) -> dict[str, Any]:
        """What makes this run this run: scene, problem, parameters, physics settings, version,
        and a SHA-256 of the initial state (every solver's arrays before the first step)."""
        import hashlib

        import mlsgalerkin
        from mlsgalerkin.io import to_jsonable

        sc = self.scene
        digest = hashlib.sha256()
        for s in self.solvers:
            arrays, _ = s.checkpoint()
            for name in sorted(arrays):
                a = np.ascontiguousarray(arrays[name])
                digest.update(f"{s.key}/{name}/{a.dtype}/{a.shape}".encode())
                digest.update(a.tobytes())
        settings: dict[str, Any] = {"bodies": [f"{type(b).__name__}({b.name!r})" for b in sc.bodies]}
        for cls in sc.solver_groups():  # each solver's scheme (the fluid's: effects, approximation, ...)
            settings.update(sc.scheme_for(cls).identity())
        settings["interactions"] = [repr(i) for i in sc.interactions]
        return {"scene": sc.name, "problem": origin, "parameters": to_jsonable(sc.parameters),
                "settings": to_jsonable(settings), "initial_state_sha256": digest.hexdigest(),
                "mlsgalerkin_version": mlsgalerkin.__version__}

    def solver(self, key: str) -> Solver:
        """The solver whose state is ``state.systems[key]`` (``"fluid"``)."""
        for s in self.solvers:
            if s.key == key:
                return s
        raise KeyError(f"no solver {key!r}; the scene's solvers are {[s.key for s in self.solvers]}")

    # ------------------------------------------------------------------ stepping
    def start(self) -> None:
        """First force evaluation of every solver at the initial time, then every interaction's
        :meth:`~mlsgalerkin.dynamics.Interaction.after_step` (forces the solvers' first
        evaluation produced, for the other body's first step)."""
        self._note_code_commit()
        for s in self.solvers:
            s.start()
        for i in self.scene.interactions:
            i.after_step(self.state.t, self._solver_of[i.first], self._solver_of[i.second])
        self.started = True

    def time_step(self) -> float:
        """The largest step every solver and interaction allows (s)."""
        limits = [s.stable_time_step() for s in self.solvers]
        limits += [i.stable_time_step() for i in self.scene.interactions]
        return min(limits)

    def step(self, dt: float) -> None:
        """Advance every body by ``dt``: begin, exchange, end, after-step (no monitors). With an
        iterating interaction (:attr:`~mlsgalerkin.dynamics.Interaction.iterates`) the step is
        repeated from the same start, every solver restored, until each such interaction says
        it has converged (:meth:`~mlsgalerkin.dynamics.Interaction.end_iteration`)."""
        st = self.state
        t = st.t
        iterating = [i for i in self.scene.interactions if i.iterates]
        if not iterating:
            self._one_pass(t, dt)
        else:
            saved = [(s, s.checkpoint()) for s in self.solvers]
            others = [(i, i.state_dict()) for i in self.scene.interactions if not i.iterates]
            limit = max(i.max_iterations for i in iterating)
            for k in range(limit):
                if k:
                    for s, (arrays, meta) in saved:
                        s.restore(arrays, meta)
                    for i, d in others:
                        i.load_state_dict(d)
                for i in iterating:
                    i.begin_iteration(k, t, dt, self._solver_of[i.first], self._solver_of[i.second])
                self._one_pass(t, dt)
                done = [i.end_iteration(k, t + dt, self._solver_of[i.first], self._solver_of[i.second])
                        for i in iterating]
                if all(done):
                    break
        st.t = t + dt
        st.step += 1
        st.dt = dt

    def _one_pass(self, t: float, dt: float) -> None:
        for s in self.solvers:
            s.begin_step(t, dt)
        if self.scene.interactions:
            for s in self.solvers:
                s.clear_surface_forces()
            for i in self.scene.interactions:
                i.exchange(t + dt, self._solver_of[i.first], self._solver_of[i.second])
        for s in self.solvers:
            s.end_step(t, dt)
        for i in self.scene.interactions:
            i.after_step(t + dt, self._solver_of[i.first], self._solver_of[i.second])

    # ------------------------------------------------------------------ checkpoints
    def snapshot(self) -> tuple[dict[str, np.ndarray], dict[str, Any]]:
        """Arrays and metadata of every solver (keys ``<solver>__<array>``) plus the run's clock."""
        from mlsgalerkin.io import to_jsonable

        st = self.state
        arrays: dict[str, np.ndarray] = {}
        meta: dict[str, Any] = {"layout": CHECKPOINT_LAYOUT, "scene": self.scene.name, "t": st.t,
                                "step": st.step, "dt": st.dt, "parameters": to_jsonable(self.scene.parameters),
                                "identity": self.identity, "changes": self._changes, "solvers": {},
                                "monitors": {m.name: m.state_dict() for m in self._monitors},
                                "interactions": [to_jsonable(i.state_dict()) for i in self.scene.interactions]}
        for s in self.solvers:
            a, m = s.checkpoint()
            arrays.update({f"{s.key}__{k}": v for k, v in a.items()})
            meta["solvers"][s.key] = m
        arrays[CLOCK_ARRAY] = np.array([st.t, st.dt, st.step], dtype=np.float64)  # checked on restart
        return arrays, meta

    def restore(self, arrays: dict[str, np.ndarray], meta: dict[str, Any]) -> None:
        """Load a :meth:`snapshot` into this simulation (built from the same scene). A checkpoint
        whose metadata is incomplete raises :class:`~mlsgalerkin.io.CheckpointError`."""
        from mlsgalerkin.io import CheckpointError

        try:
            self._restore(arrays, meta)
        except (KeyError, TypeError, AttributeError, IndexError) as exc:
            raise CheckpointError(f"checkpoint metadata is damaged or incomplete ({type(exc).__name__}: {exc}); "
                                  "restart from an earlier checkpoint") from exc

    def _restore(self, arrays: dict[str, np.ndarray], meta: dict[str, Any]) -> None:
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
        for i, d in zip(self.scene.interactions, meta.get("interactions", [])):
            i.load_state_dict(d)  # in scene order (the scene is the one that wrote the checkpoint)
        st = self.state
        st.t, st.step, st.dt = float(meta["t"]), int(meta["step"]), float(meta["dt"])
        self._changes = list(meta.get("changes", []))
        self._note_code_commit()
        self.started = True

    def _note_code_commit(self) -> None:
        """The commit of the code that steps from here (``summary.json``'s ``git_commit``: a run
        reports the code it ran, not the code current when its summary is written)."""
        from mlsgalerkin.io import git_commit

        try:
            self._code_commit = git_commit()
        except Exception:  # best effort, as the rest of the provenance
            self._code_commit = None

    # ------------------------------------------------------------------ run
    def monitors(self, out: Path | None, progress: bool) -> list[Monitor]:
        """The standard monitors of the scene (watchdog, time series, frames, checkpoints,
        progress bar, pictures), then ``scene.monitors``."""
        sc = self.scene
        o = sc.output
        series = TimeSeries(sc.probes, every=o.probe_every)
        ms: list[Monitor] = [sc.watchdog, series]
        if out is not None:
            if o.vtu:
                ms.append(Frames(every=o.every, times=o.times))
            every = o.checkpoint_every if o.checkpoint_every is not None else sc.t_end / 10
            ms.append(Checkpoints(every=every, keep=o.keep_checkpoints, wall_every=o.checkpoint_wall_every,
                                  before_write=[series]))
        if progress:
            ms.append(ProgressBar())
        if out is not None and (o.gif or o.png):
            ms.append(Pictures(gif=o.gif, png=o.png, color_by=o.color_by))
        return ms + list(sc.monitors)

    def run(self, out: str | Path | None = None, *, progress: bool = True, restart: str | Path | None = None,
            max_steps: int | None = None, analyse: Callable[[RunResult], dict] | None = None,
            overwrite: bool = False, allow_changes: bool = False, origin: dict | None = None) -> RunResult:
        """Run to ``scene.t_end`` (or ``max_steps`` steps) and return a :class:`RunResult`.

        ``out``: run directory for ``run.json``, ``timeseries.csv``, the VTU/PVD series,
        checkpoints, ``summary.json`` and pictures (nothing is written without it; the time series
        is kept in memory either way). A directory that holds another run is refused unless
        ``overwrite`` (which deletes that run's files). ``restart``: ``"latest"`` continues from
        the newest valid checkpoint of the run in ``out``, or a checkpoint file; the scene must be
        the one that wrote it (:mod:`mlsgalerkin.run_directory`) unless ``allow_changes``, which
        records the changes in ``summary.json``. ``analyse(result) -> dict``: the problem's
        analysis, run before ``summary.json`` is written; its results go under ``"results"``.
        ``origin``: where the scene came from (problem name or file and its hash), part of the
        run's identity.

        SIGINT (Ctrl-C), SIGTERM and SIGHUP stop the run after the step in progress: the files and
        a checkpoint are written, and :class:`RunInterrupted` is raised; ``restart="latest"``
        continues to the same end state and time series as a run that never stopped. One process
        at a time writes ``out`` (:class:`~mlsgalerkin.run_directory.RunDirectoryLock`): a second
        is refused with :class:`~mlsgalerkin.run_directory.RunDirectoryError` naming the first's pid.

        BLAS libraries run on one thread for the whole run (restored afterwards): numba's threads
        own the cores, and OpenBLAS worker threads that busy-wait after a call on a large array
        would fight them (above about 10⁴ particles a 2-thread run was slower than a 1-thread one).
        """
        if restart is not None and overwrite:
            raise ValueError("restart and overwrite contradict each other: restart continues the run in the "
                             "directory, overwrite deletes it; give one (--restart or --overwrite)")
        lock = RunDirectoryLock(out) if out is not None else contextlib.nullcontext()
        if out is not None:
            if Path(out).exists() and not Path(out).is_dir():
                raise RunDirectoryError(f"the output directory {out} is a file; choose a directory (--out)")
            Path(out).mkdir(parents=True, exist_ok=True)
        with lock, threadpool_limits(limits=1, user_api="blas"):
            return self._run(out, progress=progress, restart=restart, max_steps=max_steps, analyse=analyse,
                             overwrite=overwrite, allow_changes=allow_changes, origin=origin)

    def _run(self, out: str | Path | None, *, progress: bool, restart: str | Path | None, max_steps: int | None,
             analyse: Callable[[RunResult], dict] | None, overwrite: bool, allow_changes: bool,
             origin: dict | None) -> RunResult:
        out = Path(out) if out is not None else None
        self.identity = self._identity(origin)
        monitors = self.monitors(out, progress)
        saved_monitors: dict = {}
        if restart is not None:
            saved_monitors = self._restart_from(restart, out, allow_changes)
        else:
            if out is not None:
                self.identity = claim_directory(out, self.identity, overwrite)
            if not self.started:
                self.start()
        sc, st = self.scene, self.state
        info = RunInfo(scene=sc.name, t_end=sc.t_end, dim=sc.dim, out=out, resumed=restart is not None,
                       parameters=dict(sc.parameters))
        series = next(m for m in monitors if isinstance(m, TimeSeries))
        self._monitors = monitors
        status, diagnosis, error = "running", None, None
        # the stop signals are caught before any monitor writes a file: one that arrives while the
        # monitors start stops the run after its first step, with its files and a checkpoint
        with _stop_on_signals() as stop:
            for m in monitors:
                m.start(st, info)
                if m.name in saved_monitors:
                    m.load_state_dict(saved_monitors[m.name])
            wall0 = time.perf_counter()
            steps0 = st.step
            try:
                while st.t < sc.t_end * (1 - 1e-12) and (max_steps is None or st.step - steps0 < max_steps):
                    dt = min(self.time_step(), sc.t_end - st.t)
                    self.step(dt)
                    for m in monitors:
                        m.handle(st, st.t)
                    if stop:
                        break
                if stop:
                    status = "interrupted"
                    signame = _signal_name(stop[0])
                    diagnosis = {"signal": signame}
                    error = RunInterrupted(stop[0], st.t, st.step)
                else:
                    status = "completed" if st.t >= sc.t_end * (1 - 1e-12) else "paused"
            except SimulationDiverged as err:
                status, diagnosis, error = "diverged", err.diagnosis, err
            except KeyboardInterrupt as err:  # outside the main thread: the state may be mid-step
                status, error = "aborted", err
            except Exception as err:
                status, diagnosis, error = "failed", {"error": f"{type(err).__name__}: {err}"}, err
        wall = time.perf_counter() - wall0
        for m in monitors:
            try:
                m.finish(st, status)
            except Exception as exc:  # a monitor must not hide the run's own outcome
                if error is None or isinstance(error, RunInterrupted):
                    status, diagnosis, error = "failed", {"error": f"{type(exc).__name__}: {exc}"}, exc
                else:
                    logger.warning("monitor %s failed while finishing (%s)", m.name, exc)
        self._monitors = []
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
            try:
                self._write_summary(out, summary)
            except OSError as exc:
                logger.error("could not write %s (%s)", out / "summary.json", exc)
                error = error or exc
        if isinstance(error, RunInterrupted):
            error.checkpoint = next((m.last for m in monitors if isinstance(m, Checkpoints)), None)
        if error is not None:
            raise error
        return result

    def _restart_from(self, restart: str | Path, out: Path | None, allow_changes: bool) -> dict:
        """Load the checkpoint to continue from; returns the monitors' saved states."""
        from mlsgalerkin.io import load_checkpoint

        if str(restart) == "latest":
            if out is None:
                raise ValueError("restart='latest' needs the run directory: pass out=")
            manifest = read_manifest(out)
            run_id = ((manifest or {}).get("identity") or {}).get("run_id")
            path, arrays, meta, notes = newest_checkpoint_of_run(out, run_id)
            for note in notes:
                logger.warning("restart: %s", note)
        else:
            path = Path(restart)
            arrays, meta = load_checkpoint(path)
            check_checkpoint_clock(path, arrays, meta, out / "timeseries.csv" if out is not None else None)
        saved = meta.get("identity") or {}
        differences = identity_differences(saved, self.identity)
        if float(meta.get("t", 0.0)) > self.scene.t_end * (1 + 1e-12):
            differences.append(f"the checkpoint is at t = {meta.get('t')} s, after t_end = {self.scene.t_end} s")
        if differences and not allow_changes:
            raise RestartMismatch(
                f"{path} was written by a different run, so continuing it would mix two runs:\n  - "
                + "\n  - ".join(differences)
                + "\nRestart with the parameters of that run (only t_end and output settings may change), start a "
                "new run in another directory, or pass --allow-changes (allow_changes=True) to continue with the "
                "changes recorded in summary.json")
        self.restore(arrays, meta)
        if saved.get("run_id"):
            self.identity["run_id"] = saved["run_id"]
        if differences:
            self._changes.append({"t": self.state.t, "step": self.state.step, "changes": differences})
            logger.warning("restart with changes at t = %.6g s: %s", self.state.t, "; ".join(differences))
        logger.info("restarted from %s at t = %.6g s (step %d)", path, self.state.t, self.state.step)
        return meta.get("monitors") or {}

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
        if self._changes:
            out["continued_with_changes"] = self._changes
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
            summary["provenance"] = provenance(f"run {self.scene.name}", extra={"git_commit": self._code_commit}
                                               if self._code_commit else None)
        except Exception:  # provenance is best effort (no git in an installed package)
            pass
        write_json(out / "summary.json", summary)
