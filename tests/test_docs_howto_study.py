"""The how-to ``docs/howto/write_a_convergence_study.md`` stays true.

Its ```python blocks run in order, in one namespace named ``__main__`` (as the script a reader
would assemble from them, so the guarded ``main()`` runs: on a local Dask cluster), in an empty
temporary directory. A ```text block right after a python block is the output the page claims;
it must equal what the code printed. The files the page says it writes must exist.
"""

from __future__ import annotations

import contextlib
import csv
import io
import re
from pathlib import Path

HOWTO = Path(__file__).resolve().parents[1] / "docs" / "howto" / "write_a_convergence_study.md"
FENCE = re.compile(r"^```(\w*)\n(.*?)^```[ \t]*$", flags=re.S | re.M)


def python_blocks(text: str) -> list[tuple[str, str | None, int]]:
    """``(code, claimed output or None, line number)`` of each python block, in order."""
    blocks = [(m.group(1), m.group(2), m.start(), m.end()) for m in FENCE.finditer(text)]
    out = []
    for k, (lang, code, start, end) in enumerate(blocks):
        if lang != "python":
            continue
        nxt = blocks[k + 1] if k + 1 < len(blocks) else None
        claimed = nxt[1] if nxt and nxt[0] == "text" and not text[end:nxt[2]].strip() else None
        out.append((code, claimed, text.count("\n", 0, start) + 1))
    return out


def test_howto_runs_its_study_and_prints_what_the_page_says(tmp_path, monkeypatch):
    blocks = python_blocks(HOWTO.read_text(encoding="utf-8"))
    assert len(blocks) >= 3 and sum(c is not None for _, c, _ in blocks) >= 2
    monkeypatch.chdir(tmp_path)
    namespace: dict = {"__name__": "__main__"}
    for code, claimed, line in blocks:
        buf = io.StringIO()
        with contextlib.redirect_stdout(buf):
            exec(compile(code, f"{HOWTO.name}:{line}", "exec", dont_inherit=True), namespace)
        if claimed is not None:
            assert buf.getvalue().splitlines() == claimed.rstrip("\n").splitlines(), (
                f"block at line {line} printed:\n{buf.getvalue()}")
    with open(tmp_path / "mls_study.csv", newline="") as fh:
        rows = list(csv.DictReader(fh))
    assert list(rows[0]) == ["kernel", "spacing", "error_rms", "n_nodes", "wall_time_s", "worker"]
    assert len(rows) == 8 and all(float(r["wall_time_s"]) > 0 for r in rows)
    assert all(r["worker"].startswith("tcp://") for r in rows)  # measured on the local cluster
    assert (tmp_path / "work_precision.png").read_bytes()[:4] == b"\x89PNG"


def test_the_index_links_the_howto_and_its_links_resolve():
    docs = HOWTO.parents[1]
    assert "(howto/write_a_convergence_study.md)" in (docs / "index.md").read_text(encoding="utf-8")
    links = re.findall(r"\]\(([^)#\s]+)(?:#[^)]*)?\)", HOWTO.read_text(encoding="utf-8"))
    relative = [ln for ln in links if "://" not in ln]
    assert relative
    for link in relative:
        assert (HOWTO.parent / link).resolve().exists(), f"the how-to links to missing {link}"
