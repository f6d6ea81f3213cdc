"""Runs that survive interruption: SIGINT, SIGTERM, SIGKILL and a full disk each leave a run that
``--restart`` continues to the same final state and the same time series as a run that never
stopped."""

from __future__ import annotations

import errno
import os
import random
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

from mlsgalerkin.cli import main
from mlsgalerkin.io import latest_checkpoint, load_checkpoint
from mlsgalerkin.monitors import Monitor, Output
from mlsgalerkin.problem import prepare_problem
from mlsgalerkin.simulation import RunInterrupted, Simulation

HYDRO = {"dx": 0.04, "t_end": 0.3}


def _scene(**output):
    scene = prepare_problem("hydrostatic", HYDRO).scene
    scene.output = Output(**{"every": 0.05, "probe_every": 0.005, **output})
    return scene


def _final(run_dir: Path) -> dict[str, np.ndarray]:
    arrays, meta = load_checkpoint(latest_checkpoint(run_dir / "checkpoints"))
    assert meta["t"] == pytest.approx(HYDRO["t_end"]) or meta["t"] > 0
    return arrays


def _same_run(a: Path, b: Path) -> None:
    """Same final state bit for bit, same time series and frame list."""
    fa, fb = _final(a), _final(b)
    for k in ("fluid__x", "fluid__v", "fluid__rho", "fluid__p"):
        assert np.array_equal(fa[k], fb[k]), k
    assert (a / "timeseries.csv").read_text() == (b / "timeseries.csv").read_text()
    assert (a / "particles.pvd").read_text() == (b / "particles.pvd").read_text()


@pytest.fixture(scope="module")
def straight(tmp_path_factory):
    out = tmp_path_factory.mktemp("straight")
    Simulation(_scene()).run(out=out, progress=False)
    return out


class SendSignal(Monitor):
    """Sends ``signum`` to this process after step ``step``."""

    name = "send_signal"

    def __init__(self, signum: int, step: int) -> None:
        self.signum, self.step = signum, step

    def handle(self, state, t) -> None:
        if state.step == self.step:
            os.kill(os.getpid(), self.signum)


@pytest.mark.parametrize("signum", [signal.SIGINT, signal.SIGTERM, signal.SIGHUP], ids=["SIGINT", "SIGTERM", "SIGHUP"])
def test_a_signal_stops_after_the_step_and_restart_continues_identically(signum, straight, tmp_path, request):
    if signum == signal.SIGHUP and signal.getsignal(signal.SIGHUP) is signal.SIG_IGN:
        # the tests run under nohup, where a run rightly goes on when the terminal closes; this
        # one stands for a run started from a terminal
        signal.signal(signal.SIGHUP, signal.SIG_DFL)
        request.addfinalizer(lambda: signal.signal(signal.SIGHUP, signal.SIG_IGN))
    scene = _scene()
    scene.monitors = [SendSignal(signum, 97)]
    before = signal.getsignal(signal.SIGINT)  # default_int_handler, or SIG_IGN in a background job
    with pytest.raises(RunInterrupted) as info:
        Simulation(scene).run(out=tmp_path, progress=False)
    err = info.value
    assert err.signum == signum and err.step == 97 and err.checkpoint is not None
    assert load_checkpoint(err.checkpoint)[1]["step"] == 97
    summary = (tmp_path / "summary.json").read_text()
    assert '"status": "interrupted"' in summary and signal.Signals(signum).name in summary
    assert signal.getsignal(signal.SIGINT) is before  # handlers restored
    Simulation(_scene()).run(out=tmp_path, progress=False, restart="latest")
    _same_run(straight, tmp_path)


def test_a_full_disk_fails_cleanly_and_restart_continues_identically(straight, tmp_path, monkeypatch):
    """A write that fails with ENOSPC stops the run with an OSError; the files written before
    are intact (atomic writes), and a restart from the last checkpoint ends like a run that
    never stopped."""
    import mlsgalerkin.io.files as files

    real_replace = os.replace
    calls = {"n": 0}

    def replace(src, dst):
        calls["n"] += 1
        if calls["n"] > 12:
            raise OSError(errno.ENOSPC, "No space left on device", str(dst))
        return real_replace(src, dst)

    monkeypatch.setattr(files.os, "replace", replace)
    with pytest.raises(OSError, match="No space left"):
        Simulation(_scene(checkpoint_every=0.03)).run(out=tmp_path, progress=False)
    monkeypatch.setattr(files.os, "replace", real_replace)
    assert not list(tmp_path.rglob("*.tmp"))  # no half-written file left behind
    step = load_checkpoint(latest_checkpoint(tmp_path / "checkpoints"))[1]["step"]
    assert 0 < step < 400
    Simulation(_scene(checkpoint_every=0.03)).run(out=tmp_path, progress=False, restart="latest")
    _same_run(straight, tmp_path)


def _cli(args: list[str], **kw) -> subprocess.Popen:
    env = dict(os.environ, NUMBA_NUM_THREADS="1", PYTHONUNBUFFERED="1")
    return subprocess.Popen([sys.executable, "-m", "mlsgalerkin", *args], env=env, stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True, **kw)


RUN = ["run", "hydrostatic", "--dx", "0.04", "--t-end", "1.2", "--no-progress", "--no-gif",
       "--checkpoint-wall", "0.2", "--checkpoint-every", "10"]


def _wait_for_checkpoint(out: Path, proc: subprocess.Popen, timeout: float = 60.0) -> None:
    t0 = time.monotonic()
    while latest_checkpoint(out / "checkpoints") is None:
        assert proc.poll() is None, proc.communicate()
        assert time.monotonic() - t0 < timeout
        time.sleep(0.05)


def test_cli_runs_killed_or_interrupted_restart_to_the_same_end(tmp_path):
    """Through the command line, in subprocesses: an uninterrupted run; a run killed with SIGKILL
    at a random moment after its first wall-clock checkpoint; a run stopped with Ctrl-C (SIGINT).
    Both continue with --restart to the uninterrupted run's final state and time series."""
    straight = tmp_path / "straight"
    done = _cli(RUN + ["--out", str(straight)])
    out, err = done.communicate(timeout=300)
    assert done.returncode == 0, err

    killed = tmp_path / "killed"
    proc = _cli(RUN + ["--out", str(killed)])
    _wait_for_checkpoint(killed, proc)
    time.sleep(random.Random(7).uniform(0.05, 0.4))
    proc.send_signal(signal.SIGKILL)
    proc.communicate(timeout=60)
    assert proc.returncode == -signal.SIGKILL
    assert not (killed / "summary.json").exists()  # it really died mid-run
    resumed = _cli(RUN + ["--out", str(killed), "--restart"])
    out, err = resumed.communicate(timeout=300)
    assert resumed.returncode == 0, err

    stopped = tmp_path / "stopped"
    proc = _cli(RUN + ["--out", str(stopped)])
    _wait_for_checkpoint(stopped, proc)
    proc.send_signal(signal.SIGINT)
    out, err = proc.communicate(timeout=120)
    assert proc.returncode == 130 and "--restart" in err and "Traceback" not in err
    resumed = _cli(RUN + ["--out", str(stopped), "--restart"])
    out, err = resumed.communicate(timeout=300)
    assert resumed.returncode == 0, err

    for other in (killed, stopped):
        a, b = load_checkpoint(latest_checkpoint(straight / "checkpoints"))[0], \
            load_checkpoint(latest_checkpoint(other / "checkpoints"))[0]
        for k in ("fluid__x", "fluid__v", "fluid__rho"):
            assert np.array_equal(a[k], b[k]), (other.name, k)
        assert (straight / "timeseries.csv").read_text() == (other / "timeseries.csv").read_text(), other.name


def test_restart_without_a_checkpoint_is_a_clear_error(tmp_path, capsys):
    assert main(["run", "hydrostatic", "--dx", "0.05", "--t-end", "0.02", "--out", str(tmp_path), "--restart",
                 "--no-progress"]) == 2
    assert "no valid checkpoint" in capsys.readouterr().err
