"""One writer per run directory, SIGHUP like SIGTERM, contradictory flags refused before any work,
and a checkpoint whose clock was edited refused instead of continued from the wrong time."""

from __future__ import annotations

import json
import os
import shutil
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

from mlsgalerkin.cli import main
from mlsgalerkin.io import CheckpointError, checkpoints_newest_first, load_checkpoint, save_checkpoint
from mlsgalerkin.problem import prepare_problem
from mlsgalerkin.run_directory import LOCK_FILE, RunDirectoryError, RunDirectoryLock
from mlsgalerkin.simulation import Simulation

TINY = ["run", "hydrostatic", "--dx", "0.05", "--t-end", "0.02", "--no-progress", "--no-gif"]


def _default_hangup() -> None:
    # a run started under nohup (SIGHUP ignored) rightly goes on when the terminal closes; these
    # runs stand for one started from a terminal, whatever the test runner was started under
    signal.signal(signal.SIGHUP, signal.SIG_DFL)


def _cli(args: list[str]) -> subprocess.Popen:
    env = dict(os.environ, NUMBA_NUM_THREADS="1", PYTHONUNBUFFERED="1")
    return subprocess.Popen([sys.executable, "-m", "mlsgalerkin", *args], env=env, stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True, start_new_session=True,
                            preexec_fn=_default_hangup)


def _one_line_error(err: str) -> str:
    lines = [line for line in err.splitlines() if line.strip()]
    assert len(lines) == 1 and lines[0].startswith("error: ") and "Traceback" not in err, err
    return lines[0]


# ------------------------------------------------------------------ the lock
def test_a_second_writer_is_refused_naming_the_holders_pid(tmp_path, capsys):
    out = tmp_path / "run"
    out.mkdir()
    with RunDirectoryLock(out):
        for extra in ([], ["--overwrite"], ["--restart"]):
            assert main(TINY + ["--out", str(out), *extra]) == 2
            line = _one_line_error(capsys.readouterr().err)
            assert f"pid {os.getpid()}" in line and "being written by another process" in line
        with pytest.raises(RunDirectoryError, match=f"pid {os.getpid()}"):
            Simulation(prepare_problem("hydrostatic", {"dx": 0.05, "t_end": 0.02}).scene).run(out=out, progress=False)
        assert not (out / "run.json").exists()  # refused before anything was written
    assert not (out / LOCK_FILE).exists()  # released and removed
    assert main(TINY + ["--out", str(out)]) == 0  # free again
    assert not (out / LOCK_FILE).exists()


def test_a_lock_left_by_a_killed_process_is_taken_over(tmp_path, capsys):
    """A process killed with SIGKILL while holding the lock leaves run.lock behind; the next run
    takes it over without anyone removing it."""
    out = tmp_path / "run"
    out.mkdir()
    code = ("import os, signal, sys; from mlsgalerkin.run_directory import RunDirectoryLock; "
            "RunDirectoryLock(sys.argv[1]).acquire(); os.kill(os.getpid(), signal.SIGKILL)")
    done = subprocess.run([sys.executable, "-c", code, str(out)], capture_output=True, text=True, timeout=60)
    assert done.returncode == -signal.SIGKILL, done.stderr
    stale = json.loads((out / LOCK_FILE).read_text())
    assert stale["pid"] != os.getpid()  # the dead process's lock file is still there
    assert main(TINY + ["--out", str(out)]) == 0, capsys.readouterr().err
    assert json.loads((out / "summary.json").read_text())["status"] == "completed"


def test_restart_into_a_running_run_is_refused_and_sighup_stops_it_cleanly(tmp_path, capsys):
    """A run in another process holds its directory: ``--restart`` into it is refused naming that
    process. SIGHUP (the terminal closing) then stops it like SIGTERM: exit 129, files and a
    checkpoint written, and ``--restart`` continues it."""
    out = tmp_path / "run"
    args = ["run", "hydrostatic", "--dx", "0.04", "--t-end", "5", "--no-progress", "--no-gif", "--out", str(out)]
    proc = _cli(args)
    t0 = time.monotonic()
    while not (out / "timeseries.csv").exists():  # written after the first step's monitors start
        assert proc.poll() is None, proc.communicate()
        assert time.monotonic() - t0 < 120
        time.sleep(0.05)
    assert main(args + ["--restart"]) == 2
    assert f"pid {proc.pid}" in _one_line_error(capsys.readouterr().err)
    proc.send_signal(signal.SIGHUP)
    _, err = proc.communicate(timeout=120)
    assert proc.returncode == 128 + signal.SIGHUP, err
    assert "SIGHUP" in err and "--restart" in err and "Traceback" not in err
    summary = json.loads((out / "summary.json").read_text())
    assert summary["status"] == "interrupted" and summary["diagnosis"]["signal"] == "SIGHUP"
    assert not (out / LOCK_FILE).exists()
    assert main(args[:4] + ["--t-end", str(summary["t_end_s"] + 0.01), *args[6:], "--restart"]) == 0, \
        capsys.readouterr().err


# ------------------------------------------------------------------ contradictory flags
@pytest.mark.parametrize("flags, named", [
    (["--restart", "--overwrite"], "--restart continues the run in --out and --overwrite deletes it"),
    (["--allow-changes"], "--allow-changes applies to --restart only"),
    (["--set", "dx=0.06", "--dx", "0.05"], "dx is given twice, by --dx and by --set dx=0.06"),
    (["--set", "t-end=0.1", "--t-end", "0.02"], "t_end is given twice, by --t-end"),
    (["--set", "frame_every=0.01", "--frame-every", "0.02"], "frame_every is given twice"),
    (["--set", "gif=true", "--no-gif"], "gif is given twice, by --no-gif"),
])
def test_contradictory_flags_are_refused_before_any_work(flags, named, tmp_path, capsys):
    out = tmp_path / "run"
    assert main(["run", "hydrostatic", "--no-progress", "--out", str(out), *flags]) == 2
    assert named in _one_line_error(capsys.readouterr().err)
    assert not out.exists()


def test_restart_with_overwrite_is_refused_by_the_python_api(tmp_path):
    scene = prepare_problem("hydrostatic", {"dx": 0.05, "t_end": 0.02}).scene
    with pytest.raises(ValueError, match="restart and overwrite contradict each other"):
        Simulation(scene).run(out=tmp_path, restart="latest", overwrite=True, progress=False)


# ------------------------------------------------------------------ a checkpoint's clock
@pytest.fixture(scope="module")
def finished_once(tmp_path_factory):
    """A hydrostatic run to 0.04 s (49 steps) with checkpoints every 0.004 s."""
    out = tmp_path_factory.mktemp("clocked") / "run"
    assert main(CLOCKED + ["--t-end", "0.04", "--out", str(out)]) == 0
    return out


@pytest.fixture
def finished(finished_once, tmp_path, capsys):
    """A copy of that run for one test to edit."""
    capsys.readouterr()
    return Path(shutil.copytree(finished_once, tmp_path / "run"))


def _edit_newest(out: Path, edit) -> Path:
    path = checkpoints_newest_first(out / "checkpoints")[0]
    arrays, meta = load_checkpoint(path)
    edit(arrays, meta)
    save_checkpoint(path, arrays, meta)
    return path


CLOCKED = ["run", "hydrostatic", "--dx", "0.05", "--no-progress", "--no-gif", "--checkpoint-every", "0.004"]


def _shift(d: dict, key: str, by):
    d[key] = d[key] + by


@pytest.mark.parametrize("edit, named", [
    (lambda a, m: _shift(m, "t", 0.01), "stored clock says"),
    (lambda a, m: (_shift(m, "t", 0.01), a.pop("run__clock")), "the run is at t = "),
    (lambda a, m: (_shift(m, "t", -0.003), a.pop("run__clock"), _shift(m["solvers"]["fluid"], "t", -0.003)),
     "timeseries.csv"),
    (lambda a, m: (_shift(m, "step", 5), a.pop("run__clock")), "its file name says step"),
    (lambda a, m: m.update(t=float("nan")), "is not a finite number >= 0"),
    (lambda a, m: m.update(step=-3), "is not a whole number >= 0"),
    (lambda a, m: m["solvers"]["fluid"].update(n=m["solvers"]["fluid"]["n"] + 1), "particles but its positions hold"),
    (lambda a, m: a.update(fluid__v=a["fluid__v"][:-1]), "but its velocities"),
], ids=["t", "t-no-clock", "t-everywhere", "step", "nan-t", "negative-step", "size", "shapes"])
def test_a_checkpoint_whose_clock_was_edited_is_refused(finished, edit, named, capsys):
    paused = finished
    path = _edit_newest(paused, edit)
    args = CLOCKED + ["--t-end", "0.05", "--out", str(paused), "--restart"]
    before = (paused / "timeseries.csv").read_text()
    assert main(args) == 2
    line = _one_line_error(capsys.readouterr().err)
    assert path.name in line and named in line and "move it out of the checkpoints folder" in line
    assert (paused / "timeseries.csv").read_text() == before  # nothing continued
    scene = prepare_problem("hydrostatic", {"dx": 0.05, "t_end": 0.05}).scene
    with pytest.raises(CheckpointError, match="contradicts itself"):
        Simulation(scene).run(out=paused, progress=False, restart=path)


def test_an_unedited_checkpoint_continues(finished, capsys):
    assert main(CLOCKED + ["--t-end", "0.05", "--out", str(finished), "--restart"]) == 0, capsys.readouterr().err
    assert np.isclose(json.loads((finished / "summary.json").read_text())["t_end_s"], 0.05)


def test_under_nohup_sighup_stays_ignored(tmp_path):
    """``nohup mlsgalerkin run ...`` ignores SIGHUP: the run goes on when the terminal closes."""
    from mlsgalerkin.monitors import Monitor

    class HangUpAt(Monitor):
        name = "hang_up_at"

        def handle(self, state, t):
            if state.step == 5:
                os.kill(os.getpid(), signal.SIGHUP)

    scene = prepare_problem("hydrostatic", {"dx": 0.05, "t_end": 0.02}).scene
    scene.monitors = [HangUpAt()]
    before = signal.signal(signal.SIGHUP, signal.SIG_IGN)
    try:
        result = Simulation(scene).run(out=tmp_path, progress=False)
        assert signal.getsignal(signal.SIGHUP) is signal.SIG_IGN
    finally:
        signal.signal(signal.SIGHUP, before)
    assert result.summary["status"] == "completed" and result.state.step > 5


def test_a_checkpoint_before_the_first_step_continues(tmp_path):
    """A run paused before its first step (``max_steps=0``) has the clock ``t = 0, dt = 0``: valid."""
    scene = prepare_problem("hydrostatic", {"dx": 0.05, "t_end": 0.01}).scene
    Simulation(scene).run(out=tmp_path, progress=False, max_steps=0)
    assert load_checkpoint(checkpoints_newest_first(tmp_path / "checkpoints")[0])[1]["step"] == 0
    scene = prepare_problem("hydrostatic", {"dx": 0.05, "t_end": 0.01}).scene
    result = Simulation(scene).run(out=tmp_path, progress=False, restart="latest")
    assert result.summary["status"] == "completed"
