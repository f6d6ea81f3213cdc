"""The how-to ``docs/howto/write_a_weak_form.md`` stays true.

Its ```python block runs as a reader would paste it (imports from the package's public modules,
a 21 x 21 SCNI reaction-diffusion solve with Nitsche conditions), and it prints exactly the line
the page quotes after "It prints".
"""

from __future__ import annotations

import re
from pathlib import Path

from howto_pages import fenced_blocks, run_python

HOWTO = Path(__file__).resolve().parents[1] / "docs" / "howto" / "write_a_weak_form.md"


def test_weak_form_howto_runs_and_prints_what_the_page_says(one_numba_thread):
    text = HOWTO.read_text(encoding="utf-8")
    blocks = [code for lang, _, code, _, _ in fenced_blocks(text) if lang == "python"]
    claims = re.findall(r"It prints `([^`]+)`", text)
    assert len(blocks) == 1 and len(claims) == 1, "the how-to's example or its quoted output moved"
    assert run_python(blocks[0], {"__name__": "__howto__"}, HOWTO.name).splitlines() == claims
