"""A restart continues the same run or nothing: identity checks, this run's newest valid
checkpoint, one run per directory."""

from __future__ import annotations

import json
import shutil

import numpy as np
import pytest

from mlsgalerkin.cli import main
from mlsgalerkin.io import CheckpointError, checkpoints_newest_first, load_checkpoint, save_checkpoint
from mlsgalerkin.problem import run_problem
from mlsgalerkin.run_directory import RestartMismatch, RunDirectoryError

BASE = ["run", "dam_break", "--dx", "0.0057", "--no-progress", "--no-gif", "--checkpoint-every", "0.005"]


@pytest.fixture
def paused(tmp_path, capsys):
    """A dam break run to 0.02 s with checkpoints every 0.005 s."""
    out = tmp_path / "run"
    assert main(BASE + ["--t-end", "0.02", "--out", str(out)]) == 0
    capsys.readouterr()
    return out


@pytest.mark.parametrize("change, named", [
    (["--set", "g=20"], "parameter g: 9.81 in the checkpoint, 20.0 now"),
    (["--set", "alpha=0.1"], "parameter alpha"),
    (["--set", "c0_factor=12"], "parameter c0_factor"),
    (["--set", "rho=1100"], "parameter rho"),
    (["--dx", "0.005"], "parameter dx"),
])
def test_restart_with_other_physics_is_refused_naming_the_difference(paused, capsys, change, named):
    assert main(BASE + ["--t-end", "0.04", "--out", str(paused), "--restart"] + change) == 2
    err = capsys.readouterr().err
    assert named in err and "--allow-changes" in err and "Traceback" not in err


def test_restart_may_extend_t_end_and_allowed_changes_are_recorded(paused, capsys):
    assert main(BASE + ["--t-end", "0.03", "--out", str(paused), "--restart"]) == 0
    summary = json.loads((paused / "summary.json").read_text())
    assert summary["t_end_s"] == pytest.approx(0.03) and "continued_with_changes" not in summary
    assert main(BASE + ["--t-end", "0.04", "--out", str(paused), "--restart", "--set", "alpha=0.08",
                        "--allow-changes"]) == 0
    summary = json.loads((paused / "summary.json").read_text())
    change = summary["continued_with_changes"][0]
    assert change["t"] == pytest.approx(0.03) and any("alpha" in c for c in change["changes"])
    assert summary["parameters"]["alpha"] == 0.08  # and the record says from when


def test_a_second_run_into_a_run_directory_is_refused_unless_overwrite(paused, capsys):
    assert main(BASE + ["--t-end", "0.01", "--out", str(paused)]) == 2
    err = capsys.readouterr().err
    assert "already holds a run of 'dam_break'" in err and "--overwrite" in err and "--restart" in err
    old_vtu = sorted(paused.glob("particles_*.vtu"))
    assert main(BASE + ["--t-end", "0.01", "--out", str(paused), "--overwrite"]) == 0
    summary = json.loads((paused / "summary.json").read_text())
    assert summary["t_end_s"] == pytest.approx(0.01) and summary["steps_this_run"] == summary["steps"]
    assert len(sorted(paused.glob("particles_*.vtu"))) < len(old_vtu)  # the old frames are gone


def test_restart_takes_this_runs_newest_valid_checkpoint(paused, tmp_path, capsys):
    newest, older = checkpoints_newest_first(paused / "checkpoints")[:2]
    start_step = load_checkpoint(older)[1]["step"]
    # a damaged newest file is skipped with a note
    newest.write_bytes(newest.read_bytes()[:500])
    # a checkpoint of another run (with a higher step) dropped into the folder is skipped
    other = tmp_path / "other"
    assert main(BASE + ["--t-end", "0.03", "--out", str(other)]) == 0
    foreign = checkpoints_newest_first(other / "checkpoints")[0]
    shutil.copyfile(foreign, paused / "checkpoints" / foreign.name)
    capsys.readouterr()
    result, _ = run_problem("dam_break", {"dx": 0.0057, "t_end": 0.025, "gif": False}, out=paused,
                            progress=False, restart="latest", output={"checkpoint_every": 0.005})
    assert result.summary["steps"] - result.summary["steps_this_run"] == start_step


def test_damaged_checkpoint_metadata_is_a_clear_error(paused, capsys):
    path = checkpoints_newest_first(paused / "checkpoints")[0]
    arrays, meta = load_checkpoint(path)
    del meta["solvers"]["fluid"]["counters"]
    save_checkpoint(path, arrays, meta)
    assert main(BASE + ["--t-end", "0.03", "--out", str(paused), "--restart"]) == 2
    err = capsys.readouterr().err
    assert "damaged or incomplete" in err and "Traceback" not in err


def test_identity_of_a_problem_file_includes_its_contents(tmp_path, capsys):
    from mlsgalerkin.problem import load_problem

    src = load_problem("hydrostatic").__file__
    mine = tmp_path / "tank.py"
    shutil.copyfile(src, mine)
    args = ["run", str(mine), "--dx", "0.05", "--no-progress", "--out", str(tmp_path / "r")]
    assert main(args + ["--t-end", "0.02"]) == 0
    changed = mine.read_text().replace("water(c0,", "water(1.1 * c0,")
    assert changed != mine.read_text()  # the edit must change the physics, or the test proves nothing
    mine.write_text(changed)
    assert main(args + ["--t-end", "0.04", "--restart"]) == 2
    err = capsys.readouterr().err
    assert "problem:" in err and "tank.py" in err


def test_python_api_refuses_like_the_cli(paused):
    with pytest.raises(RunDirectoryError):
        run_problem("dam_break", {"dx": 0.0057, "t_end": 0.01}, out=paused, progress=False)
    with pytest.raises(RestartMismatch, match="parameter g"):
        run_problem("dam_break", {"dx": 0.0057, "t_end": 0.03, "g": 9.7}, out=paused, progress=False, restart="latest")
    assert CheckpointError is not None and np is not None
