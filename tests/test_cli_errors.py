"""Every command-line path answers a mistake with one line on stderr and a nonzero exit code, never a
traceback; a closed output pipe (``mlsgalerkin problems | head``) ends quietly; a study keeps the
rows it measured when it cannot finish."""

from __future__ import annotations

import errno
import os
import shlex
import subprocess
import sys
from pathlib import Path

import pytest

from mlsgalerkin.cli import EXIT_BROKEN_PIPE, main


def _one_line_error(err: str) -> str:
    lines = [line for line in err.splitlines() if line.strip()]
    assert len(lines) == 1 and lines[0].startswith("error: ") and "Traceback" not in err, err
    return lines[0]


@pytest.fixture(scope="module")
def run_dir(tmp_path_factory):
    """A tiny finished run with frames and a time series."""
    out = tmp_path_factory.mktemp("run")
    assert main(["run", "hydrostatic", "--dx", "0.05", "--t-end", "0.02", "--frame-every", "0.01", "--no-gif",
                 "--no-progress", "--out", str(out), "--overwrite"]) == 0
    return out


def test_render_onto_an_existing_file_is_one_line(run_dir, tmp_path, capsys):
    blocker = tmp_path / "pictures"
    blocker.write_text("not a directory")
    capsys.readouterr()
    assert main(["render", str(run_dir), "--out", str(blocker), "--no-gif", "--snapshots", "0"]) == 4
    line = _one_line_error(capsys.readouterr().err)
    assert str(blocker) in line and "--out" in line


@pytest.mark.skipif(not hasattr(os, "geteuid") or os.geteuid() == 0, reason="root writes into read-only folders")
def test_render_into_a_read_only_folder_is_one_line(run_dir, tmp_path, capsys):
    locked = tmp_path / "locked"
    locked.mkdir(mode=0o500)
    capsys.readouterr()
    assert main(["render", str(run_dir), "--out", str(locked / "pics"), "--no-gif", "--snapshots", "0"]) == 4
    assert "Permission denied" in _one_line_error(capsys.readouterr().err)


@pytest.fixture
def read_only(tmp_path, monkeypatch):
    """A folder in which nothing can be created, also for root (who ignores the mode bits): making a
    directory in it fails as in a read-only folder."""
    locked = tmp_path / "locked"
    locked.mkdir()
    real_mkdir = Path.mkdir

    def mkdir(self, *args, **kwargs):
        if str(self).startswith(str(locked) + os.sep):
            raise PermissionError(errno.EACCES, "Permission denied", str(self))
        return real_mkdir(self, *args, **kwargs)

    monkeypatch.setattr(Path, "mkdir", mkdir)
    return locked


def test_render_and_study_into_a_read_only_place_are_one_line(run_dir, read_only, capsys):
    capsys.readouterr()
    assert main(["render", str(run_dir), "--out", str(read_only / "pics"), "--no-gif", "--snapshots", "0"]) == 4
    assert "Permission denied" in _one_line_error(capsys.readouterr().err)
    assert main(["study", "kernels", "--quick", "--scheduler", "serial", "--no-progress",
                 "--out", str(read_only / "study")]) == 4
    assert "Permission denied" in _one_line_error(capsys.readouterr().err)


@pytest.mark.parametrize("study", ["kernels", "galerkin"])
def test_study_onto_an_existing_file_is_one_line_before_any_work(study, tmp_path, capsys):
    blocker = tmp_path / "results"
    blocker.write_text("not a directory")
    assert main(["study", study, "--quick", "--scheduler", "serial", "--no-progress", "--out", str(blocker)]) == 4
    line = _one_line_error(capsys.readouterr().err)
    assert str(blocker) in line and "writable directory" in line


@pytest.mark.parametrize("address", ["garbage", "tcp://nohost", "local:host:1:2"])
def test_study_with_a_garbage_scheduler_is_one_line(address, tmp_path, capsys):
    assert main(["study", "kernels", "--quick", "--scheduler", address, "--no-progress",
                 "--out", str(tmp_path / "s")]) == 2
    assert "Dask scheduler address" in _one_line_error(capsys.readouterr().err)


def test_a_study_that_cannot_write_its_table_keeps_its_rows(tmp_path, monkeypatch, capsys):
    """A full disk when the table is written at the end: the rows measured are in the row log."""
    import mlsgalerkin.studies.kernels.study as kernel_study
    from mlsgalerkin.studies.engine import read_rows

    def full_disk(path, *args, **kwargs):
        raise OSError(errno.ENOSPC, "No space left on device", str(path))

    monkeypatch.setattr(kernel_study, "write_csv_rows", full_disk)
    out = tmp_path / "g"
    assert main(["study", "kernels", "--quick", "--scheduler", "serial", "--no-progress", "--out", str(out)]) == 4
    assert "No space left on device" in _one_line_error(capsys.readouterr().err)
    rows = read_rows(out / kernel_study.ROWS_LOG)
    assert len(rows) > 10 and all("error_abs" in r for r in rows)


def test_problems_into_a_closed_pipe_ends_quietly():
    """``mlsgalerkin problems | head -0``: the reader is gone before the first line."""
    read, write = os.pipe()
    os.close(read)
    try:
        done = subprocess.run([sys.executable, "-m", "mlsgalerkin", "problems"], stdout=write,
                              stderr=subprocess.PIPE, text=True, timeout=120)
    finally:
        os.close(write)
    assert done.returncode == EXIT_BROKEN_PIPE and done.stderr == "", done.stderr


def test_problems_into_head_ends_quietly():
    shell = f"{shlex.quote(sys.executable)} -m mlsgalerkin problems | head -n 2; exit ${{PIPESTATUS[0]}}"
    done = subprocess.run(["bash", "-c", shell], capture_output=True, text=True, timeout=120)
    assert len(done.stdout.splitlines()) == 2 and done.stderr == "", done.stderr
    assert done.returncode in (0, EXIT_BROKEN_PIPE)


def test_an_unexpected_error_is_one_line_and_verbose_shows_the_traceback(monkeypatch, capsys):
    import mlsgalerkin.kernels as kernels

    class Broken(dict):
        def values(self):
            raise RuntimeError("a bug\nwith a second line")

    monkeypatch.setattr(kernels, "KERNELS", Broken())
    assert main(["kernels"]) == 1
    line = _one_line_error(capsys.readouterr().err)
    assert "RuntimeError: a bug" in line and "-v" in line
    with pytest.raises(RuntimeError):
        main(["-v", "kernels"])


def test_run_into_a_file_is_one_line(tmp_path, capsys):
    blocker = Path(tmp_path / "out")
    blocker.write_text("")
    assert main(["run", "hydrostatic", "--dx", "0.05", "--t-end", "0.02", "--no-progress", "--out", str(blocker)]) == 2
    assert "is a file" in _one_line_error(capsys.readouterr().err)


def test_a_run_into_a_closed_pipe_ends_quietly(tmp_path):
    """A run's console output going nowhere is not a failed write of its files."""
    read, write = os.pipe()
    os.close(read)
    try:
        done = subprocess.run([sys.executable, "-m", "mlsgalerkin", "run", "hydrostatic", "--dx", "0.05", "--t-end",
                               "0.01", "--no-progress", "--no-gif", "--out", str(tmp_path / "r")], stdout=write,
                              stderr=subprocess.PIPE, text=True, timeout=300)
    finally:
        os.close(write)
    assert done.returncode == EXIT_BROKEN_PIPE and "Traceback" not in done.stderr, done.stderr
    assert "writing the run's files failed" not in done.stderr
