"""Reading a how-to page the way a reader follows it (shared by the tests of the docs/howto pages).

A page is a sequence of fenced blocks. A ```python block is code to run; a ```text block right
after it is the output the page claims; a ```python file=NAME block is a file to save; the
``mlsgalerkin ...`` lines of a ```bash block are commands to run.
"""

from __future__ import annotations

import contextlib
import io
import re
from pathlib import Path

FENCE = re.compile(r"^```(\w*)([^\n]*)\n(.*?)^```[ \t]*$", flags=re.S | re.M)
LINK = re.compile(r"\]\(([^)#\s]+)(?:#[^)]*)?\)")


def fenced_blocks(text: str) -> list[tuple[str, str, str, int, int]]:
    """``(language, info, code, start, end)`` of every fenced block, in order (``info`` is what
    follows the language on the opening line, e.g. ``file=my_case.py``)."""
    return [(m.group(1), m.group(2).strip(), m.group(3), m.start(), m.end()) for m in FENCE.finditer(text)]


def steps(text: str) -> list[tuple[str, str, str | None, int]]:
    """``(kind, payload, claimed output, line)`` in page order: kind ``"python"`` (run it),
    ``"file"`` (payload ``"NAME\\ncode"``: save it) or ``"command"`` (an ``mlsgalerkin`` line)."""
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


def run_python(code: str, namespace: dict, where: str) -> str:
    """Run ``code`` in ``namespace`` as pasted (without the test file's ``__future__`` imports);
    returns what it printed."""
    buf = io.StringIO()
    with contextlib.redirect_stdout(buf):
        exec(compile(code, where, "exec", dont_inherit=True), namespace)
    return buf.getvalue()


def missing_links(page: Path) -> list[str]:
    """The relative links of ``page`` that point at no existing file."""
    links = [ln for ln in LINK.findall(page.read_text(encoding="utf-8")) if "://" not in ln]
    return [ln for ln in links if not (page.parent / ln).resolve().exists()]
