"""Smoke runs of every shipped problem (its SMOKE size) through run_problem and the command line,
a user's own problem file, and ``python -m mlsgalerkin``."""

import json
import re
import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from mlsgalerkin.analysis.measured import unexplained_values
from mlsgalerkin.cli import main
from mlsgalerkin.problem import ProblemError, load_problem, parse_overrides, run_problem
from mlsgalerkin.problems import PROBLEMS


def test_every_shipped_module_is_listed():
    assert set(PROBLEMS) >= {"hydrostatic", "dam_break", "gravity_current", "drop_impact", "wave_maker"}


@pytest.mark.parametrize("name", PROBLEMS)
def test_problem_smoke_run_writes_outputs(name, tmp_path):
    mod = load_problem(name)
    overrides = dict(mod.SMOKE)
    if "gif" in {f for f in mod.Parameters.__dataclass_fields__}:
        overrides["gif"] = False
    result, results = run_problem(name, overrides, out=tmp_path, progress=False)
    assert result.state.t == pytest.approx(overrides["t_end"])
    for f in ("timeseries.csv", "particles.pvd", "summary.json"):
        assert (tmp_path / f).is_file()
    summary = json.loads((tmp_path / "summary.json").read_text())
    assert summary["status"] == "completed"
    assert summary["results"]["headline"] == results["headline"]
    assert summary["wall_time_s"] > 0 and summary["steps"] > 0
    ts = result.timeseries
    assert np.all(ts["total_mass"] == ts["total_mass"][0])  # mass exact
    assert all(np.all(np.isfinite(ts[c])) for c in ("kinetic_energy", "max_speed"))
    # honest results: a smoke run covers no event, so its headline says what was not measured and
    # why; it never shows NaN, infinity or "None", and every number is finite or None with a reason
    headline = results["headline"]
    assert not re.search(r"\b(nan|inf|infinity|none)\b", headline, flags=re.IGNORECASE), headline
    assert unexplained_values(results) == [], (name, unexplained_values(results))
    assert unexplained_values(summary["results"]) == []
    reasons = {k: v for k, v in results.items() if k.endswith("_not_measured")}
    assert all(isinstance(v, str) and len(v) > 20 for v in reasons.values()), reasons
    if "not measured" in headline:     # the headline's reason is one of the results' reasons
        assert any(v in headline for v in reasons.values()), (headline, reasons)


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


@pytest.mark.parametrize("value, expected", [("true", True), ("No", False), ("1", True), ("off", False)])
def test_boolean_parameters_are_read_strictly(value, expected):
    mod = load_problem("gravity_current")
    assert parse_overrides(mod.Parameters, {"lid": value}).lid is expected


@pytest.mark.parametrize("name, value", [("lid", "ture"), ("dx", "abc"), ("depth", "inf"), ("dx", "nan")])
def test_unreadable_parameter_values_are_refused(name, value):
    mod = load_problem("gravity_current")
    with pytest.raises(ProblemError, match=f"parameter {name}"):
        parse_overrides(mod.Parameters, {name: value})


def test_cli_restart_continues_latest_checkpoint(tmp_path, capsys):
    out = tmp_path / "hs"
    args = ["run", "hydrostatic", "--dx", "0.05", "--out", str(out), "--no-progress"]
    assert main(args + ["--t-end", "0.02"]) == 0
    assert main(args + ["--t-end", "0.04", "--restart"]) == 0
    summary = json.loads((out / "summary.json").read_text())
    assert summary["t_end_s"] == pytest.approx(0.04)
    assert summary["steps_this_run"] < summary["steps"]


# ------------------------------------------------------------------ a user's own problem file
def test_a_copied_shipped_problem_runs_as_a_file(tmp_path, capsys):
    """The starting point of a user's case: copy a shipped problem out of the package, edit it,
    run it by path. It needs only the public API."""
    src = Path(load_problem("hydrostatic").__file__)
    mine = tmp_path / "my_tank.py"
    shutil.copyfile(src, mine)
    mine.write_text(mine.read_text().replace('name="hydrostatic"', 'name="my_tank"'))
    out = tmp_path / "run"
    code = main(["run", str(mine), "--dx", "0.05", "--t-end", "0.05", "--out", str(out), "--no-progress"])
    assert code == 0, capsys.readouterr().err
    text = capsys.readouterr().out
    assert text.startswith("my_tank:") and "pressure RMS error" in text
    summary = json.loads((out / "summary.json").read_text())
    assert summary["scene"] == "my_tank" and summary["status"] == "completed"
    assert summary["parameters"]["dx"] == 0.05


def test_bad_problem_files_get_clear_errors(tmp_path, capsys):
    assert main(["run", str(tmp_path / "missing.py"), "--no-progress"]) == 2
    assert "does not exist" in capsys.readouterr().err
    broken = tmp_path / "broken.py"
    broken.write_text("import numpy as np\nx = 1 +\n")
    assert main(["run", str(broken), "--no-progress"]) == 2
    assert "could not import the problem file" in capsys.readouterr().err
    empty = tmp_path / "empty_case.py"
    empty.write_text('"""Not a problem."""\n')
    assert main(["run", str(empty), "--no-progress"]) == 2
    err = capsys.readouterr().err
    assert "Parameters" in err and "make_scene" in err
    assert main(["run", "no_such_problem", "--no-progress"]) == 2
    err = capsys.readouterr().err
    assert "unknown problem 'no_such_problem'" in err and "dam_break" in err


# ------------------------------------------------------------------ the entry points
def test_python_dash_m_and_version():
    import mlsgalerkin

    done = subprocess.run([sys.executable, "-m", "mlsgalerkin", "--version"], capture_output=True, text=True,
                          timeout=120)
    assert done.returncode == 0 and done.stdout.strip() == f"mlsgalerkin {mlsgalerkin.__version__}"
    done = subprocess.run([sys.executable, "-m", "mlsgalerkin", "problems"], capture_output=True, text=True,
                          timeout=120)
    assert done.returncode == 0 and "wave_maker" in done.stdout and "my_case.py" in done.stdout


def test_gravity_current_measures_both_fronts_over_the_heavy_heads_window():
    """The light front is fitted over the heavy head's window: a synthetic exchange whose light
    front runs at half the head's speed reads a ratio of 0.5 and the light Froude number half the
    head's; with no light-front column (a run from before it was probed) nothing is reported."""
    from types import SimpleNamespace

    from mlsgalerkin.problems import gravity_current as gc

    p = gc.Parameters(depth=0.12, rho_heavy=1100.0)
    length, _ = gc.tank(p)
    lock = 0.5 * length
    t = np.linspace(0.0, 1.5, 751)
    head = lock - 0.15 * t
    light = lock + 0.075 * t
    res = gc.analyse(SimpleNamespace(timeseries={"time": t, "head_x": head, "light_front_x": light}), p)
    assert res["head_speed_m_s"] == pytest.approx(0.15)
    assert res["light_front_speed_m_s"] == pytest.approx(0.075)
    assert res["front_speed_ratio"] == pytest.approx(0.5)
    assert res["light_froude_number"] == pytest.approx(0.5 * res["froude_number"])
    assert "light front" in res["headline"]
    old = gc.analyse(SimpleNamespace(timeseries={"time": t, "head_x": head}), p)
    assert "front_speed_ratio" not in old and old["head_speed_m_s"] == pytest.approx(0.15)


def test_stratified_rest_jitter_disorders_the_lattice_the_same_way_every_time():
    """``jitter`` moves each particle by at most ``jitter · dx`` per axis, keeps it inside the
    tank, gives it the density of its new height, and is seeded (bit-identical repeat runs);
    half a spacing or more is refused before any work."""
    from mlsgalerkin.problems import stratified_rest as sr

    p = sr.Parameters(jitter=0.25)
    a, b = sr.make_scene(p).bodies[0], sr.make_scene(p).bodies[0]
    lattice = sr.make_scene(sr.Parameters()).bodies[0]
    offset = a.positions - lattice.positions
    assert np.array_equal(a.positions, b.positions) and np.array_equal(a.density, b.density)
    assert np.abs(offset).max() <= 0.25 * p.dx + 1e-15 and np.abs(offset).max() > 0.2 * p.dx
    assert a.positions[:, 1].min() >= 0.3 * p.dx - 1e-15 and a.positions[:, 1].max() <= p.depth - 0.3 * p.dx + 1e-15
    lower = a.positions[:, 1] < lattice.positions[:, 1]            # moved down: under more fluid, denser
    same_phase = a.phase == lattice.phase
    assert same_phase.all() and (a.density[lower] > lattice.density[lower]).all()
    assert any("jitter" in msg for msg in sr.check(sr.Parameters(jitter=0.5)))


def test_gravity_current_spacing_follows_the_depth():
    """The default spacing is 20 rows per depth (3 mm at the default depth, exactly as the fixed
    default before it); a spacing given is kept; the scene has that many rows."""
    mod = load_problem("gravity_current")
    P = mod.Parameters
    assert mod.spacing(P()) == 0.003
    assert mod.spacing(P(depth=0.04)) == 0.002 and mod.spacing(P(depth=0.12)) == 0.006
    assert mod.spacing(P(depth=0.04, rows=40)) == 0.001
    assert mod.spacing(P(depth=0.04, dx=0.003)) == 0.003
    assert parse_overrides(P, {"depth": "0.04"}).dx == 0.0            # 0 stays the parameter; spacing() resolves it
    for depth in (0.04, 0.06, 0.09, 0.12):
        p = P(depth=depth)
        assert round(mod.tank(p)[1] / mod.spacing(p)) == 20
