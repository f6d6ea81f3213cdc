"""The verification scripts' partial reruns: a case whose run directory is not at hand keeps its
row of the committed table, and the table says which rows were kept."""

from __future__ import annotations

import argparse
import csv
from pathlib import Path

from verification.fluid_core import kept_note, previous_rows, runner


def test_a_case_without_its_run_keeps_its_row_of_the_table(tmp_path: Path):
    (tmp_path / "clamped.csv").write_text("case,status,period_s,run_commit\ndx=2mm,completed,0.599377,162a1b3\n")
    previous = previous_rows(tmp_path, "clamped")
    one = runner(argparse.Namespace(reanalyse=True, rerun=None), previous)
    runs = tmp_path / "runs"
    runs.mkdir()
    kept = one("beam_clamped", "dx=2mm", {"dx": 0.002}, runs)
    assert kept["period_s"] == "0.599377" and kept["run_commit"] == "162a1b3" and kept["kept_from_table"]
    missing = one("beam_clamped", "dx=1mm", {"dx": 0.001}, runs)      # in no table and never run
    assert missing["status"] == "not run" and not missing.get("kept_from_table")
    assert "dx=2mm" in kept_note([kept, missing]) and "dx=1mm" not in kept_note([kept, missing])
    assert kept_note([missing]) == "" and previous_rows(tmp_path, "spring") == {}


def test_a_case_run_by_the_runner_records_the_commit_its_summary_names(tmp_path: Path):
    """The summary a run returns in memory has no provenance (it is added as ``summary.json`` is
    written), so the row's ``run_commit`` is read from the file: empty before, in every table run
    since partial reruns came."""
    import json

    one = runner(argparse.Namespace(reanalyse=False, rerun=None), {})
    row = one("hydrostatic", "tiny", {"dx": 0.1, "t_end": 0.002}, tmp_path)
    written = json.loads((Path(row["run_dir"]) / "summary.json").read_text())["provenance"].get("git_commit")
    assert row["status"] == "completed" and row["run_commit"] == written


def test_every_fluid_core_section_keeps_the_rows_whose_runs_are_not_at_hand(tmp_path: Path):
    """A partial ``--rerun`` (here ``--reanalyse`` with no run directory at all) writes each
    section's committed rows back, marked as kept, instead of rows reading "not run"."""
    from verification import fluid_core

    out, runs = tmp_path / "tables", tmp_path / "runs"
    out.mkdir()
    runs.mkdir()
    args = argparse.Namespace(reanalyse=True, rerun=None, quick=True, finest=80)
    for section in ("rest", "gravity_lid", "dam_break"):
        cases = {"rest": fluid_core.rest_cases, "gravity_lid": fluid_core.gravity_lid_cases}.get(section)
        labels = [label for label, _ in cases(True)] if cases else ["a/dx=10"]
        with (out / f"{section}.csv").open("w", newline="") as f:
            csv.writer(f).writerows([["case", "status", "steps", "run_commit"],
                                     *([label, "completed", 123, "abc1234"] for label in labels)])
        getattr(fluid_core, f"section_{section}")(args, out, runs)
        text = (out / f"{section}.md").read_text()
        assert "not run" not in text and "Kept from the previous table" in text, section
        assert all(label in text for label in labels) and "abc1234" in text, section
