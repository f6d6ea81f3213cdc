"""Number and table formatting of the studies' ``summary.md``: numbers, percentages, pipe tables.

>>> fmt_num(0.123456), fmt_num(None), fmt_num(float("nan")), fmt_num("n/a"), fmt_pct(0.0123)
('0.12', '—', '—', 'n/a', '1.23 %')
>>> print(md_table(["a", "b"], [["1", "2"]]))
| a | b |
|---|---|
| 1 | 2 |
"""

from __future__ import annotations

import math
from typing import Any

__all__ = ["fmt_num", "fmt_pct", "md_table"]


def fmt_num(v: Any, fmt: str = ".2f") -> str:
    """``v`` formatted with ``fmt``; an em dash for ``None`` and non-finite numbers, ``str(v)``
    for values that are not numbers."""
    if v is None:
        return "—"
    try:
        x = float(v)
    except (TypeError, ValueError):
        return str(v)
    return format(x, fmt) if math.isfinite(x) else "—"


def fmt_pct(v: float | None) -> str:
    """``v`` as a percentage with two decimals; an em dash for ``None`` and non-finite values."""
    return "—" if v is None or not math.isfinite(v) else f"{100 * v:.2f} %"


def md_table(header: list[str], body: list[list[str]]) -> str:
    """A Markdown pipe table."""
    out = ["| " + " | ".join(header) + " |", "|" + "|".join("---" for _ in header) + "|"]
    out += ["| " + " | ".join(r) + " |" for r in body]
    return "\n".join(out)
