"""The how-to ``docs/howto/write_a_scene_and_an_effect.md`` stays true.

Its ```python blocks are executed in order, in one namespace, in an empty temporary
directory (as a reader would paste them); where a block is followed directly by a ```text
block, that block is the output the page claims, and it must equal what the code printed.
A ```python file=NAME block is saved as NAME instead (a problem file), and the
``mlsgalerkin ...`` lines of its ```bash blocks are run through the CLI entry point, in the
page's order, and must exit with status 0.

The examples are tiny (a few hundred particles), so they run on one numba thread: parallel
threads only add overhead at that size and slow down badly on a loaded machine.
"""

from __future__ import annotations

import shlex
from pathlib import Path

from howto_pages import missing_links, run_python, steps

HOWTO = Path(__file__).resolve().parents[1] / "docs" / "howto" / "write_a_scene_and_an_effect.md"


def test_howto_runs_as_written(tmp_path, monkeypatch, capsys, one_numba_thread):
    """Every python block runs and prints what the page says, the file blocks are saved, and the
    ``mlsgalerkin`` commands exit with 0 and write their run directory — in the page's order."""
    from mlsgalerkin.cli import main

    text = HOWTO.read_text(encoding="utf-8")
    todo = steps(text)
    assert sum(kind == "python" for kind, *_ in todo) >= 8, "the how-to lost its examples"
    assert sum(claimed is not None for *_, claimed, _ in todo) >= 7
    assert any(kind == "file" for kind, *_ in todo)
    assert any(kind == "command" and p.startswith("mlsgalerkin run my_case.py") for kind, p, *_ in todo)
    monkeypatch.chdir(tmp_path)
    namespace: dict = {"__name__": "__howto__"}
    for kind, payload, claimed, line in todo:
        if kind == "file":
            name, code = payload.split("\n", 1)
            (tmp_path / name).write_text(code)
            continue
        if kind == "command":
            capsys.readouterr()
            assert main(shlex.split(payload)[1:]) == 0, f"{payload} (line {line})"
            out = capsys.readouterr().out
            if payload.startswith("mlsgalerkin run "):
                args = shlex.split(payload)
                run_dir = Path(args[args.index("--out") + 1])
                for name in ("timeseries.csv", "particles.pvd", "summary.json"):
                    assert (run_dir / name).is_file(), name
                assert f"output: {run_dir}/" in out
            if payload == "mlsgalerkin problems":
                assert "hydrostatic" in out and "wave_maker" in out
            continue
        printed = run_python(payload, namespace, f"{HOWTO.name}:{line}")
        if claimed is not None:
            assert printed.rstrip("\n").splitlines() == claimed.rstrip("\n").splitlines(), (
                f"block at line {line} of {HOWTO.name} printed:\n{printed}")


def test_relative_links_of_the_fluid_pages_resolve():
    """The how-to, the theory page and the index link to each other, and every relative link
    of the two pages points at an existing file."""
    docs = HOWTO.parents[1]
    theory = docs / "theory" / "galerkin_fluid.md"
    index = (docs / "index.md").read_text(encoding="utf-8")
    assert "(theory/galerkin_fluid.md)" in index and "(howto/write_a_scene_and_an_effect.md)" in index
    for page in (HOWTO, theory):
        assert "](" in page.read_text(encoding="utf-8"), page.name
        assert not missing_links(page), f"{page.name} links to missing {missing_links(page)}"
