"""The how-to ``docs/howto/put_a_structure_in_your_scene.md`` stays true.

Its ```python blocks run in order, in one namespace, in an empty temporary directory (as a
reader would paste them); a ```text block right after a python block is the output the page
claims, and it must equal what the code printed. The runs are tiny (a few hundred particles,
0.02 s), so they run on one numba thread.
"""

from __future__ import annotations

from pathlib import Path

from howto_pages import missing_links, run_python, steps

HOWTO = Path(__file__).resolve().parents[1] / "docs" / "howto" / "put_a_structure_in_your_scene.md"


def test_howto_builds_and_runs_a_structure_as_written(tmp_path, monkeypatch, one_numba_thread):
    blocks = [(code, claimed, line) for kind, code, claimed, line in steps(HOWTO.read_text(encoding="utf-8"))
              if kind == "python"]
    assert len(blocks) >= 4 and all(c is not None for _, c, _ in blocks), "the how-to lost its examples"
    monkeypatch.chdir(tmp_path)
    namespace: dict = {"__name__": "__howto__"}
    for code, claimed, line in blocks:
        printed = run_python(code, namespace, f"{HOWTO.name}:{line}")
        assert printed.rstrip("\n").splitlines() == claimed.rstrip("\n").splitlines(), (
            f"block at line {line} of {HOWTO.name} printed:\n{printed}")
    assert (tmp_path / "run_plate" / "structure.pvd").is_file()


def test_howto_links_resolve():
    assert not missing_links(HOWTO)
