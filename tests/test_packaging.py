"""Packaging: the explicit package list of pyproject.toml names every package on disk, and a
built wheel (what `pip install .` installs) holds the shipped problems and the reference data."""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
import tomllib
import zipfile
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]


def _config() -> dict:
    return tomllib.loads((ROOT / "pyproject.toml").read_text())["tool"]["setuptools"]


def test_the_package_list_names_every_package_on_disk():
    cfg = _config()
    listed = set(cfg["packages"])
    mapped = cfg.get("package-dir", {})
    on_disk = {".".join(p.parent.relative_to(ROOT).parts) for p in (ROOT / "mlsgalerkin").rglob("__init__.py")}
    on_disk |= {name for name, folder in mapped.items() if (ROOT / folder / "__init__.py").is_file()}
    assert on_disk == listed, f"add to / remove from [tool.setuptools] packages: {sorted(on_disk ^ listed)}"
    assert mapped == {"mlsgalerkin.problems": "problems"}


def test_the_installed_problems_package_is_the_top_level_folder():
    import mlsgalerkin.problems

    assert Path(mlsgalerkin.problems.__file__).resolve().parent == ROOT / "problems"


@pytest.fixture(scope="module")
def wheel(tmp_path_factory) -> Path:
    """The wheel `pip install .` installs, built from a copy of the source tree (setuptools
    writes a build/ folder next to the sources)."""
    tmp = tmp_path_factory.mktemp("wheel")
    src = tmp / "src"
    shutil.copytree(ROOT, src, ignore=shutil.ignore_patterns(".venv", ".git", "results", "build", "*.egg-info",
                                                              "__pycache__", ".pytest_cache", ".hypothesis"))
    done = subprocess.run([sys.executable, "-m", "pip", "wheel", "--no-deps", "-w",
                           str(tmp), str(src)], capture_output=True, text=True, timeout=600)
    assert done.returncode == 0, done.stderr[-2000:]
    return next(tmp.glob("mlsgalerkin-*.whl"))


def test_wheel_holds_problems_and_reference_data(wheel):
    """The problems under mlsgalerkin/problems and the CSV files under mlsgalerkin/data."""
    names = set(zipfile.ZipFile(wheel).namelist())
    for problem in ("hydrostatic", "dam_break", "gravity_current", "drop_impact", "wave_maker"):
        assert f"mlsgalerkin/problems/{problem}.py" in names
    assert "mlsgalerkin/data/martin_moyce_1952.csv" in names and "mlsgalerkin/data/README.md" in names
    assert not any(n.startswith("problems/") for n in names)


@pytest.fixture(scope="module")
def installed(wheel, tmp_path_factory) -> tuple[Path, dict]:
    """The wheel installed (not editable) into a folder far from the repository, and the
    environment that imports the package from there."""
    target = tmp_path_factory.mktemp("site")
    done = subprocess.run([sys.executable, "-m", "pip", "install", "--no-deps", "--quiet", "--target",
                           str(target), str(wheel)], capture_output=True, text=True, timeout=600)
    assert done.returncode == 0, done.stderr[-2000:]
    return target, dict(os.environ, PYTHONPATH=str(target), NUMBA_NUM_THREADS="1")


def test_a_non_editable_install_finds_its_problems_and_data(installed, tmp_path):
    """Run from a directory far from the repository, the installed package (not this checkout)
    lists and describes the shipped problems, and the dam break's analysis reads the shipped
    Martin & Moyce data. The whole run from the wheel is the slow test below (the installed copy
    compiles every numba kernel afresh: about two minutes)."""
    target, env = installed
    where = subprocess.run([sys.executable, "-c", "import mlsgalerkin, mlsgalerkin.problems as p; "
                            "print(mlsgalerkin.__file__); print(p.__file__)"], capture_output=True, text=True,
                           cwd=tmp_path, env=env, timeout=120)
    assert where.returncode == 0 and all(line.startswith(str(target)) for line in where.stdout.split()), where.stdout
    described = subprocess.run([sys.executable, "-m", "mlsgalerkin", "problems", "dam_break"], capture_output=True,
                               text=True, cwd=tmp_path, env=env, timeout=120)
    assert described.returncode == 0, described.stderr[-3000:]
    assert "Martin" in described.stdout
    data = subprocess.run([sys.executable, "-c", "from mlsgalerkin.problems.dam_break import load_martin_moyce; "
                           "d = load_martin_moyce(); print(len(d), sum(len(v) for v in d.values()))"],
                          capture_output=True, text=True, cwd=tmp_path, env=env, timeout=120)
    assert data.returncode == 0, data.stderr[-3000:]
    series, points = map(int, data.stdout.split())
    assert series >= 1 and points > 10


@pytest.mark.slow
def test_a_problem_runs_end_to_end_from_a_non_editable_install(installed, tmp_path):
    """Installed from the wheel (not editable), run from a directory far from the repository:
    the dam break runs and its analysis reads the shipped Martin & Moyce data."""
    _, env = installed
    run = subprocess.run([sys.executable, "-m", "mlsgalerkin", "run", "dam_break", "--dx", "0.0095", "--t-end", "0.08",
                          "--out", "db", "--no-progress", "--no-gif"], capture_output=True, text=True, cwd=tmp_path,
                         env=env, timeout=900)
    assert run.returncode == 0, run.stderr[-3000:]
    summary = json.loads((tmp_path / "db" / "summary.json").read_text())
    assert summary["status"] == "completed"
    # 0.08 s ends before the experiment's last point (T = 2.95): the analysis says so, with no number
    assert summary["results"]["rms_deviation_Z"] is None
    assert "run to t ≥" in summary["results"]["rms_deviation_Z_not_measured"]
    assert "surge front" in run.stdout
