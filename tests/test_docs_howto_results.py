"""The how-to ``docs/howto/read_results.md`` stays true.

Its ```python blocks run in order, in one namespace, in an empty temporary directory (as a
reader would paste them); a ```text block right after a python block is the output the page
claims, and it must equal what the code printed. The run it reads is tiny (178 particles for
0.05 s), so it runs on one numba thread.
"""

from __future__ import annotations

import json
from pathlib import Path

from howto_pages import missing_links, run_python, steps

HOWTO = Path(__file__).resolve().parents[1] / "docs" / "howto" / "read_results.md"


def test_howto_reads_a_run_as_written(tmp_path, monkeypatch, one_numba_thread):
    blocks = [(code, claimed, line) for kind, code, claimed, line in steps(HOWTO.read_text(encoding="utf-8"))
              if kind == "python"]
    assert len(blocks) >= 6 and sum(c is not None for _, c, _ in blocks) >= 6, "the how-to lost its examples"
    monkeypatch.chdir(tmp_path)
    namespace: dict = {"__name__": "__howto__"}
    for code, claimed, line in blocks:
        printed = run_python(code, namespace, f"{HOWTO.name}:{line}")
        if claimed is not None:
            assert printed.rstrip("\n").splitlines() == claimed.rstrip("\n").splitlines(), (
                f"block at line {line} of {HOWTO.name} printed:\n{printed}")
    assert (tmp_path / "pressure_error.png").read_bytes()[:4] == b"\x89PNG"


def test_the_tables_name_every_key_and_field_of_a_run(tmp_path, one_numba_thread):
    """The page's tables cover what a run writes: every top-level key of ``summary.json``,
    every field of a frame and every array of a checkpoint (the page's examples print them,
    this checks that the tables explain each)."""
    from mlsgalerkin.io import latest_checkpoint, load_checkpoint, read_pvd, read_vtu
    from mlsgalerkin.problem import run_problem

    text = HOWTO.read_text(encoding="utf-8")
    run_problem("hydrostatic", {"dx": 0.05, "t_end": 0.05}, out=tmp_path, progress=False)
    summary = json.loads((tmp_path / "summary.json").read_text())
    for key in summary:
        assert f"| `{key}`" in text or f", `{key}`" in text, f"summary key {key} is not explained"
    _, data = read_vtu(read_pvd(tmp_path / "particles.pvd")[-1][1])
    for field in data:
        assert f"`{field}`" in text.split("## 3.")[1].split("## 4.")[0], f"frame field {field} is not explained"
    arrays, _ = load_checkpoint(latest_checkpoint(tmp_path / "checkpoints"))
    for name in arrays:
        assert f"| `{name.split('__', 1)[1]}` |" in text, f"checkpoint array {name} is not explained"


def test_the_index_links_the_howto_and_its_links_resolve():
    docs = HOWTO.parents[1]
    assert "(howto/read_results.md)" in (docs / "index.md").read_text(encoding="utf-8")
    assert not missing_links(HOWTO), f"the how-to links to missing {missing_links(HOWTO)}"
