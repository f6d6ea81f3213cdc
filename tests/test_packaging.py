"""Packaging: the explicit package list of pyproject.toml names every package on disk, and a
built wheel (what `pip install .` installs) holds the shipped problems and the reference data."""

from __future__ import annotations

import shutil
import subprocess
import sys
import tomllib
import zipfile
from pathlib import Path

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


def test_wheel_holds_problems_and_reference_data(tmp_path):
    """`pip install .` installs from this wheel: the problems under mlsgalerkin/problems and the
    CSV files under mlsgalerkin/data. Built from a copy of the source tree (setuptools writes a
    build/ folder next to the sources)."""
    src = tmp_path / "src"
    shutil.copytree(ROOT, src, ignore=shutil.ignore_patterns(".venv", ".git", "results", "build", "*.egg-info",
                                                              "__pycache__", ".pytest_cache", ".hypothesis"))
    done = subprocess.run([sys.executable, "-m", "pip", "wheel", "--no-deps", "-w",
                           str(tmp_path), str(src)], capture_output=True, text=True, timeout=600)
    assert done.returncode == 0, done.stderr[-2000:]
    wheel = next(tmp_path.glob("mlsgalerkin-*.whl"))
    names = set(zipfile.ZipFile(wheel).namelist())
    for problem in ("hydrostatic", "dam_break", "gravity_current", "drop_impact", "wave_maker"):
        assert f"mlsgalerkin/problems/{problem}.py" in names
    assert "mlsgalerkin/data/martin_moyce_1952.csv" in names and "mlsgalerkin/data/README.md" in names
    assert not any(n.startswith("problems/") for n in names)
