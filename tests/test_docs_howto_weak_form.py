"""The how-to ``docs/howto/write_a_weak_form.md`` stays true.

Its ```python block runs as a reader would paste it (imports from the package's public modules,
a 21 x 21 SCNI reaction-diffusion solve with Nitsche conditions), and it prints exactly the line
the page quotes after "It prints".
"""

from __future__ import annotations

import contextlib
import io
import re
from pathlib import Path

import numba
import pytest

HOWTO = Path(__file__).resolve().parents[1] / "docs" / "howto" / "write_a_weak_form.md"
FENCE = re.compile(r"^```python\n(.*?)^```[ \t]*$", flags=re.S | re.M)


@pytest.fixture
def one_numba_thread():
    before = numba.get_num_threads()
    numba.set_num_threads(1)
    try:
        yield
    finally:
        numba.set_num_threads(before)


def test_weak_form_howto_runs_and_prints_what_the_page_says(one_numba_thread):
    text = HOWTO.read_text(encoding="utf-8")
    blocks = FENCE.findall(text)
    claims = re.findall(r"It prints `([^`]+)`", text)
    assert len(blocks) == 1 and len(claims) == 1, "the how-to's example or its quoted output moved"
    buf = io.StringIO()
    with contextlib.redirect_stdout(buf):
        # dont_inherit: run as pasted, without this file's ``from __future__ import annotations``
        exec(compile(blocks[0], HOWTO.name, "exec", dont_inherit=True), {"__name__": "__howto__"})
    assert buf.getvalue().splitlines() == claims
