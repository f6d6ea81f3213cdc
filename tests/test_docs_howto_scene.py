"""The how-to ``docs/howto/write_a_scene_and_an_effect.md`` stays true.

Its ```python blocks are executed in order, in one namespace, in an empty temporary
directory (as a reader would paste them); where a block is followed directly by a ```text
block, that block is the output the page claims, and it must equal what the code printed.
The ``mlsgalerkin ...`` lines of its ```bash blocks are run through the CLI entry point and
must exit with status 0.

The examples are tiny (a few hundred particles), so they run on one numba thread: parallel
threads only add overhead at that size and slow down badly on a loaded machine.
"""

from __future__ import annotations

import contextlib
import io
import re
import shlex
from pathlib import Path

import pytest

HOWTO = Path(__file__).resolve().parents[1] / "docs" / "howto" / "write_a_scene_and_an_effect.md"
FENCE = re.compile(r"^```(\w*)\n(.*?)^```[ \t]*$", flags=re.S | re.M)


@pytest.fixture
def one_numba_thread():
    import numba

    before = numba.get_num_threads()
    numba.set_num_threads(1)
    try:
        yield
    finally:
        numba.set_num_threads(before)


def fenced_blocks(text: str) -> list[tuple[str, str, int, int]]:
    """``(language, code, start, end)`` of every fenced block, in order."""
    return [(m.group(1), m.group(2), m.start(), m.end()) for m in FENCE.finditer(text)]


def python_blocks_with_output(text: str) -> list[tuple[str, str | None, int]]:
    """``(code, claimed output or None, line number)`` of each python block."""
    blocks = fenced_blocks(text)
    out = []
    for k, (lang, code, start, end) in enumerate(blocks):
        if lang != "python":
            continue
        claimed = None
        if k + 1 < len(blocks):
            nlang, ncode, nstart, _ = blocks[k + 1]
            if nlang == "text" and text[end:nstart].strip() == "":
                claimed = ncode
        out.append((code, claimed, text.count("\n", 0, start) + 1))
    return out


def test_howto_python_blocks_run_and_print_what_the_page_says(tmp_path, monkeypatch, one_numba_thread):
    text = HOWTO.read_text(encoding="utf-8")
    blocks = python_blocks_with_output(text)
    assert len(blocks) >= 6, "the how-to lost its examples"
    assert sum(claimed is not None for _, claimed, _ in blocks) >= 5
    monkeypatch.chdir(tmp_path)
    namespace: dict = {"__name__": "__howto__"}
    for code, claimed, line in blocks:
        buf = io.StringIO()
        with contextlib.redirect_stdout(buf):
            # dont_inherit: run as pasted, without this file's ``from __future__ import annotations``
            exec(compile(code, f"{HOWTO.name}:{line}", "exec", dont_inherit=True), namespace)
        if claimed is not None:
            printed = buf.getvalue().rstrip("\n").splitlines()
            expected = claimed.rstrip("\n").splitlines()
            assert printed == expected, f"block at line {line} of {HOWTO.name} printed:\n{buf.getvalue()}"


def test_howto_cli_commands_run(tmp_path, monkeypatch, capsys, one_numba_thread):
    from mlsgalerkin.cli import main

    text = HOWTO.read_text(encoding="utf-8")
    commands = [line.strip() for lang, code, _, _ in fenced_blocks(text) if lang == "bash"
                for line in code.splitlines() if line.strip().startswith("mlsgalerkin ")]
    assert any(c.startswith("mlsgalerkin run ") for c in commands)
    monkeypatch.chdir(tmp_path)
    for command in commands:
        assert main(shlex.split(command)[1:]) == 0, command
        out = capsys.readouterr().out
        if command.startswith("mlsgalerkin run "):
            args = shlex.split(command)
            run_dir = Path(args[args.index("--out") + 1])
            for name in ("timeseries.csv", "particles.pvd", "summary.json"):
                assert (run_dir / name).is_file(), name
            assert f"output: {run_dir}/" in out
        if command == "mlsgalerkin problems":
            assert "hydrostatic" in out


def test_relative_links_of_the_fluid_pages_resolve():
    """The how-to, the theory page and the index link to each other, and every relative link
    of the two pages points at an existing file."""
    docs = HOWTO.parents[1]
    theory = docs / "theory" / "galerkin_fluid.md"
    index = (docs / "index.md").read_text(encoding="utf-8")
    assert "(theory/galerkin_fluid.md)" in index and "(howto/write_a_scene_and_an_effect.md)" in index
    for page in (HOWTO, theory):
        links = re.findall(r"\]\(([^)#\s]+)(?:#[^)]*)?\)", page.read_text(encoding="utf-8"))
        relative = [ln for ln in links if "://" not in ln]
        assert relative, page.name
        for link in relative:
            assert (page.parent / link).resolve().exists(), f"{page.name} links to missing {link}"
