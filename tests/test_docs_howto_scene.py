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

import contextlib
import io
import re
import shlex
from pathlib import Path

import pytest

HOWTO = Path(__file__).resolve().parents[1] / "docs" / "howto" / "write_a_scene_and_an_effect.md"
FENCE = re.compile(r"^```(\w*)([^\n]*)\n(.*?)^```[ \t]*$", flags=re.S | re.M)


@pytest.fixture
def one_numba_thread():
    import numba

    before = numba.get_num_threads()
    numba.set_num_threads(1)
    try:
        yield
    finally:
        numba.set_num_threads(before)


def fenced_blocks(text: str) -> list[tuple[str, str, str, int, int]]:
    """``(language, info, code, start, end)`` of every fenced block, in order (``info`` is what
    follows the language on the opening line, e.g. ``file=my_case.py``)."""
    return [(m.group(1), m.group(2).strip(), m.group(3), m.start(), m.end()) for m in FENCE.finditer(text)]


def steps(text: str) -> list[tuple[str, str, str | None, int]]:
    """The page as a reader follows it: ``(kind, payload, claimed output, line)`` with kind
    ``"python"`` (run it), ``"file"`` (payload ``name\ncode``: save it) or ``"command"`` (an
    ``mlsgalerkin ...`` line of a bash block)."""
    blocks = fenced_blocks(text)
    out = []
    for k, (lang, info, code, start, end) in enumerate(blocks):
        line = text.count("\n", 0, start) + 1
        if lang == "python" and info.startswith("file="):
            out.append(("file", info[len("file="):] + "\n" + code, None, line))
        elif lang == "python":
            claimed = None
            if k + 1 < len(blocks):
                nlang, _, ncode, nstart, _ = blocks[k + 1]
                if nlang == "text" and text[end:nstart].strip() == "":
                    claimed = ncode
            out.append(("python", code, claimed, line))
        elif lang == "bash":
            out += [("command", c.strip(), None, line) for c in code.splitlines() if c.strip().startswith("mlsgalerkin ")]
    return out


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
        buf = io.StringIO()
        with contextlib.redirect_stdout(buf):
            # dont_inherit: run as pasted, without this file's ``from __future__ import annotations``
            exec(compile(payload, f"{HOWTO.name}:{line}", "exec", dont_inherit=True), namespace)
        if claimed is not None:
            printed = buf.getvalue().rstrip("\n").splitlines()
            expected = claimed.rstrip("\n").splitlines()
            assert printed == expected, f"block at line {line} of {HOWTO.name} printed:\n{buf.getvalue()}"


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
