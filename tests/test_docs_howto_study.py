"""The how-to ``docs/howto/write_a_convergence_study.md`` stays true.

Its ```python blocks run in order, in one namespace named ``__main__`` (as the script a reader
would assemble from them, so the guarded ``main()`` runs: on a local Dask cluster), in an empty
temporary directory. A ```text block right after a python block is the output the page claims;
it must equal what the code printed. The files the page says it writes must exist.
"""

from __future__ import annotations

import csv
from pathlib import Path

from howto_pages import missing_links, run_python, steps

HOWTO = Path(__file__).resolve().parents[1] / "docs" / "howto" / "write_a_convergence_study.md"


def test_howto_runs_its_study_and_prints_what_the_page_says(tmp_path, monkeypatch):
    blocks = [(code, claimed, line) for kind, code, claimed, line in steps(HOWTO.read_text(encoding="utf-8"))
              if kind == "python"]
    assert len(blocks) >= 3 and sum(c is not None for _, c, _ in blocks) >= 2
    monkeypatch.chdir(tmp_path)
    namespace: dict = {"__name__": "__main__"}
    for code, claimed, line in blocks:
        printed = run_python(code, namespace, f"{HOWTO.name}:{line}")
        if claimed is not None:
            assert printed.splitlines() == claimed.rstrip("\n").splitlines(), f"block at line {line} printed:\n{printed}"
    with open(tmp_path / "mls_study.csv", newline="") as fh:
        rows = list(csv.DictReader(fh))
    assert list(rows[0]) == ["kernel", "spacing", "error_rms", "n_nodes", "wall_time_s", "worker"]
    assert len(rows) == 8 and all(float(r["wall_time_s"]) > 0 for r in rows)
    assert all(r["worker"].startswith("tcp://") for r in rows)  # measured on the local cluster
    assert (tmp_path / "work_precision.png").read_bytes()[:4] == b"\x89PNG"


def test_the_index_links_the_howto_and_its_links_resolve():
    docs = HOWTO.parents[1]
    assert "(howto/write_a_convergence_study.md)" in (docs / "index.md").read_text(encoding="utf-8")
    assert "](" in HOWTO.read_text(encoding="utf-8")
    assert not missing_links(HOWTO), f"the how-to links to missing {missing_links(HOWTO)}"
