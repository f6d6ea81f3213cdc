"""The Makefile's promises: ``make verify`` runs every validation (the structure validation too),
and ``make demo`` (any ``mlsgalerkin run``) says when the first step will compile numba kernels."""

from __future__ import annotations

import ast
import shlex
import shutil
import subprocess
from pathlib import Path

import pytest

import mlsgalerkin.cli as cli
from mlsgalerkin.cli import COMPILING_NOTE, main, numba_cache_is_cold

ROOT = Path(__file__).resolve().parents[1]


def _verify_commands() -> list[list[str]]:
    """The script commands of ``make verify`` (``make -n``: printed, not run)."""
    done = subprocess.run(["make", "-n", "-o", ".venv/.installed", "verify"], cwd=ROOT,
                          capture_output=True, text=True, timeout=60)
    assert done.returncode == 0, done.stderr
    return [shlex.split(line) for line in done.stdout.splitlines() if "verification/" in line]


def _options_of(script: Path) -> set[str]:
    """The option strings a verification script's argparse parser declares."""
    found = set()
    for node in ast.walk(ast.parse(script.read_text())):
        if isinstance(node, ast.Call) and getattr(node.func, "attr", None) == "add_argument":
            found |= {a.value for a in node.args if isinstance(a, ast.Constant) and str(a.value).startswith("--")}
    return found


@pytest.mark.skipif(shutil.which("make") is None, reason="needs make")
def test_make_verify_runs_every_validation_with_options_its_scripts_know():
    commands = _verify_commands()
    scripts = {Path(w).name: words for words in commands for w in words
               if w.startswith("verification/") and w.endswith(".py")}
    assert {"structure_validation.py", "fluid_validation.py", "fluid_core.py", "kernel_study.py",
            "galerkin_convergence.py"} <= set(scripts)
    for name, words in scripts.items():
        known = _options_of(ROOT / "verification" / name)
        used = {w for w in words if w.startswith("--")}
        assert used <= known, (name, used - known)
    structure = scripts["structure_validation.py"]
    assert structure[structure.index("--section") + 1] == "all"


def test_a_cold_numba_cache_is_recognised(tmp_path, monkeypatch):
    monkeypatch.setenv("NUMBA_CACHE_DIR", str(tmp_path))
    assert numba_cache_is_cold()
    index = tmp_path / "src" / "mlsgalerkin" / "fluid" / "kernels.step-10.py311.nbi"
    index.parent.mkdir(parents=True)
    index.write_bytes(b"")
    assert not numba_cache_is_cold()


@pytest.mark.parametrize("cold", [True, False])
def test_run_says_it_is_compiling_before_the_first_step_only_when_the_cache_is_cold(cold, tmp_path, monkeypatch,
                                                                                   capsys):
    monkeypatch.setattr(cli, "numba_cache_is_cold", lambda: cold)
    assert main(["run", "hydrostatic", "--dx", "0.05", "--t-end", "0.01", "--no-progress", "--no-gif",
                 "--out", str(tmp_path / "r")]) == 0
    lines = capsys.readouterr().out.splitlines()
    assert (COMPILING_NOTE in lines) is cold
    if cold:
        assert lines.index(COMPILING_NOTE) == 1  # after the description, before the run's report
    capsys.readouterr()
    assert main(["run", "hydrostatic", "--dx", "0.05", "--check"]) == 0
    assert COMPILING_NOTE not in capsys.readouterr().out  # --check compiles nothing
