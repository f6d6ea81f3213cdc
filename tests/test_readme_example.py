"""The README's library example runs and prints what the README says it prints."""

from __future__ import annotations

import contextlib
import io
import re
from pathlib import Path

README = Path(__file__).resolve().parents[1] / "README.md"


def test_readme_example_runs_and_matches_its_printed_output():
    text = README.read_text(encoding="utf-8")
    blocks = re.findall(r"```python\n(.*?)```", text, flags=re.S)
    assert blocks, "README has no python example"
    code = blocks[0]
    claimed = [line.split("#", 1)[1].strip() for line in code.splitlines() if line.strip().startswith("#")
               and ("error" in line or "neighbours" in line)]
    out = io.StringIO()
    with contextlib.redirect_stdout(out):
        exec(compile(code, "README.md", "exec"), {"__name__": "__readme__"})
    printed = [line.strip() for line in out.getvalue().splitlines() if line.strip()]
    assert printed, "the example printed nothing"
    for line in claimed:
        assert line in printed, f"README claims {line!r}, the example printed {printed}"


def test_readme_fluid_example_runs(tmp_path, monkeypatch):
    """The README's second example (a short dam break through run_problem) runs as written."""
    text = README.read_text(encoding="utf-8")
    blocks = re.findall(r"```python\n(.*?)```", text, flags=re.S)
    code = next(b for b in blocks if "run_problem" in b)
    monkeypatch.chdir(tmp_path)
    out = io.StringIO()
    with contextlib.redirect_stdout(out):
        exec(compile(code, "README.md", "exec"), {"__name__": "__readme__"})
    assert "surge front" in out.getvalue()
    assert (tmp_path / "results" / "db" / "summary.json").is_file()
    claimed = [line.lstrip("# ").rstrip() for line in code.splitlines() if line.startswith("# ")]
    assert claimed, "the README shows no printed output for the run_problem example"
    printed = [line.strip() for line in out.getvalue().splitlines() if line.strip()]
    assert claimed == printed[-len(claimed):], f"README claims {claimed}, the example printed {printed}"
    assert not any(word in printed[-1].lower().split() for word in ("nan", "inf", "none"))
