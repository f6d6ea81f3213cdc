"""Every shipped problem, at its ``SMOKE`` size, is reproducible: two runs in two processes give the
same ``timeseries.csv`` and final state bit for bit, and so do a run stopped by SIGINT and a run
killed by SIGKILL once each is continued with ``restart="latest"``.

Kept short: every run takes ``STEPS`` steps (``max_steps``; a problem whose smoke run is shorter
completes earlier, the same for every run). The second process (the repeat run, then the run it
kills) is started for all problems at once at the beginning, two at a time, while this process
makes the straight run, the SIGINT run and both continuations. Every run uses one numba thread
(a parallel sum's round-off depends on how the work is split between threads). SIGKILL strikes after the time
series has recorded a step but before that step's checkpoint is written (a checkpoint follows
every step), so the continuation starts one step back and must overwrite what the killed run
wrote after its last checkpoint.
"""

from __future__ import annotations

import dataclasses
import os
import signal
import subprocess
import sys
import time
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import numpy as np
import pytest

from mlsgalerkin.io import latest_checkpoint, load_checkpoint
from mlsgalerkin.monitors import Checkpoints, Monitor
from mlsgalerkin.problem import load_problem, prepare_problem
from mlsgalerkin.problems import PROBLEMS
from mlsgalerkin.simulation import RunInterrupted, Simulation

STEPS = 12          #: steps of every run
SIGINT_AT = 3       #: the SIGINT run stops after this step (its checkpoint is of this step)
SIGKILL_AT = 5      #: the killed run dies in this step, after the time series and before the checkpoint

#: Output for these runs: no pictures, a checkpoint after every step (wall clock every 1 ns).
OUTPUT = {"gif": False, "png": False, "checkpoint_wall_every": 1e-9}


def smoke_overrides(name: str) -> dict:
    mod = load_problem(name)
    overrides = dict(mod.SMOKE)
    if "gif" in {f.name for f in dataclasses.fields(mod.Parameters)}:
        overrides["gif"] = False
    return overrides


class SignalAt(Monitor):
    """Sends ``signum`` to this process when the run reaches step ``step``."""

    name = "signal_at"

    def __init__(self, signum: int, step: int) -> None:
        self.signum, self.step = signum, step

    def handle(self, state, t) -> None:
        if state.step == self.step:
            os.kill(os.getpid(), self.signum)


class KilledBeforeCheckpoint(Simulation):
    """A simulation whose process is killed (SIGKILL) at step ``step``, after the time series and
    frames have seen that step and before its checkpoint is written."""

    def __init__(self, scene, step: int) -> None:
        super().__init__(scene)
        self._kill_step = step

    def monitors(self, out, progress):
        ms = super().monitors(out, progress)
        k = next(i for i, m in enumerate(ms) if isinstance(m, Checkpoints))
        return ms[:k] + [SignalAt(signal.SIGKILL, self._kill_step)] + ms[k:]


def _simulation(name: str, cls=Simulation, **kw) -> Simulation:
    return cls(prepare_problem(name, smoke_overrides(name), output=OUTPUT).scene, **kw)


#: The second process: the repeat run into argv[2], then the run killed at SIGKILL_AT into argv[3].
SECOND_PROCESS = f"""
import sys
sys.path.insert(0, {str(Path(__file__).parent)!r})
from test_repeat_and_restart_every_problem import KilledBeforeCheckpoint, STEPS, SIGKILL_AT, _simulation
name, repeat, killed = sys.argv[1:4]
_simulation(name).run(out=repeat, progress=False, max_steps=STEPS)
_simulation(name, KilledBeforeCheckpoint, step=SIGKILL_AT).run(out=killed, progress=False, max_steps=STEPS)
raise SystemExit("the run was not killed")
"""


def _second_process(name: str, root: Path) -> tuple[int, str]:
    env = dict(os.environ, NUMBA_NUM_THREADS="1")
    done = subprocess.run([sys.executable, "-c", SECOND_PROCESS, name, str(root / "repeat"), str(root / "killed")],
                          env=env, capture_output=True, text=True, timeout=600)
    return done.returncode, done.stderr


@pytest.fixture(scope="module")
def second_processes(tmp_path_factory):
    """The second process of every problem, started at once, two at a time."""
    roots = {name: tmp_path_factory.mktemp(name) for name in PROBLEMS}
    pool = ThreadPoolExecutor(max_workers=2)
    futures = {name: pool.submit(_second_process, name, root) for name, root in roots.items()}
    yield roots, futures
    pool.shutdown(wait=True)


def _final_arrays(run_dir: Path) -> dict[str, np.ndarray]:
    return load_checkpoint(latest_checkpoint(run_dir / "checkpoints"))[0]


def _assert_same_run(expected: Path, got: Path, what: str) -> None:
    assert (got / "timeseries.csv").read_text() == (expected / "timeseries.csv").read_text(), \
        f"{what}: timeseries.csv differs"
    a, b = _final_arrays(expected), _final_arrays(got)
    assert sorted(a) == sorted(b), what
    moved = [k for k in sorted(a) if not np.array_equal(a[k], b[k], equal_nan=True)]
    assert not moved, f"{what}: final arrays differ: {moved}"
    for pvd in sorted(expected.glob("*.pvd")):
        assert (got / pvd.name).read_text() == pvd.read_text(), f"{what}: {pvd.name} differs"


@pytest.mark.parametrize("name", PROBLEMS)
def test_repeat_and_restarts_end_bit_for_bit(name, second_processes, tmp_path, one_numba_thread):
    roots, futures = second_processes
    straight = tmp_path / "straight"
    _simulation(name).run(out=straight, progress=False, max_steps=STEPS)

    stopped = tmp_path / "stopped"
    sim = _simulation(name)
    sim.scene.monitors = [*sim.scene.monitors, SignalAt(signal.SIGINT, SIGINT_AT)]
    with pytest.raises(RunInterrupted) as info:
        sim.run(out=stopped, progress=False, max_steps=STEPS)
    assert info.value.step == SIGINT_AT
    _simulation(name).run(out=stopped, progress=False, restart="latest", max_steps=STEPS - SIGINT_AT)
    _assert_same_run(straight, stopped, f"{name}: SIGINT at step {SIGINT_AT}, then restart")

    code, err = futures[name].result(timeout=600)
    assert code == -signal.SIGKILL, err[-3000:]
    repeat, killed = roots[name] / "repeat", roots[name] / "killed"
    _assert_same_run(straight, repeat, f"{name}: a second run in another process")
    assert not (killed / "summary.json").exists()  # it really died mid-run
    assert load_checkpoint(latest_checkpoint(killed / "checkpoints"))[1]["step"] == SIGKILL_AT - 1
    t0 = time.perf_counter()
    _simulation(name).run(out=killed, progress=False, restart="latest", max_steps=STEPS - SIGKILL_AT + 1)
    assert time.perf_counter() - t0 < 120
    _assert_same_run(straight, killed, f"{name}: SIGKILL in step {SIGKILL_AT}, then restart")
