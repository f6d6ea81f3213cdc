"""Smoke runs of every problem (its SMOKE size) through run_problem and the command line."""

import json

import numpy as np
import pytest

from mlsgalerkin.cli import main
from mlsgalerkin.problems import PROBLEMS, get_problem, run_problem


@pytest.mark.parametrize("name", PROBLEMS)
def test_problem_smoke_run_writes_outputs(name, tmp_path):
    mod = get_problem(name)
    overrides = dict(mod.SMOKE)
    if "gif" in {f for f in mod.Parameters.__dataclass_fields__}:
        overrides["gif"] = False
    result, results = run_problem(name, overrides, out=tmp_path, progress=False)
    assert result.state.t == pytest.approx(overrides["t_end"])
    for f in ("timeseries.csv", "particles.pvd", "summary.json"):
        assert (tmp_path / f).is_file()
    summary = json.loads((tmp_path / "summary.json").read_text())
    assert summary["results"]["headline"] == results["headline"]
    assert summary["wall_time_s"] > 0 and summary["steps"] > 0
    ts = result.timeseries
    assert np.all(ts["total_mass"] == ts["total_mass"][0])  # mass exact
    assert all(np.all(np.isfinite(ts[c])) for c in ("kinetic_energy", "max_speed"))


def test_cli_run_sets_parameters_and_reports(tmp_path, capsys):
    out = tmp_path / "gc"
    code = main(["run", "gravity_current", "--set", "depth=0.03", "--set", "rho_heavy=1200", "--dx", "0.006",
                 "--t-end", "0.02", "--out", str(out), "--no-gif", "--no-progress"])
    assert code == 0
    text = capsys.readouterr().out
    assert "gravity_current" in text and "head speed" in text
    summary = json.loads((out / "summary.json").read_text())
    assert summary["parameters"]["depth"] == 0.03 and summary["parameters"]["rho_heavy"] == 1200.0
    # the reference follows the parameters: 0.4 sqrt(g D drho/rho0)
    assert summary["results"]["reference_head_speed_m_s"] == pytest.approx(0.4 * (9.81 * 0.03 * 0.2) ** 0.5)


def test_cli_run_rejects_unknown_parameter(tmp_path, capsys):
    code = main(["run", "dam_break", "--set", "colum_width=0.1", "--out", str(tmp_path), "--no-progress"])
    assert code == 2
    err = capsys.readouterr().err
    assert "colum_width" in err and "column_width" in err  # names the bad one and lists valid ones


def test_cli_restart_continues_latest_checkpoint(tmp_path, capsys):
    out = tmp_path / "hs"
    args = ["run", "hydrostatic", "--dx", "0.05", "--out", str(out), "--no-progress"]
    assert main(args + ["--t-end", "0.02"]) == 0
    assert main(args + ["--t-end", "0.04", "--restart"]) == 0
    summary = json.loads((out / "summary.json").read_text())
    assert summary["t_end_s"] == pytest.approx(0.04)
    assert summary["steps_this_run"] < summary["steps"]
