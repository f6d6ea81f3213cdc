"""Markdown helpers of ``summary.md``: numbers, percentages and pipe tables."""

from __future__ import annotations

import numpy as np

__all__ = ["fmt_num", "fmt_pct", "md_table"]


def fmt_num(v: float | None, fmt: str = ".2f") -> str:
    """``v`` formatted with ``fmt``; an em dash for ``None`` and non-finite values."""
    return "—" if v is None or not np.isfinite(v) else format(v, fmt)


def fmt_pct(v: float | None) -> str:
    """``v`` as a percentage with two decimals; an em dash for ``None`` and non-finite values."""
    return "—" if v is None or not np.isfinite(v) else f"{100 * v:.2f} %"


def md_table(header: list[str], body: list[list[str]]) -> str:
    """A Markdown pipe table."""
    out = ["| " + " | ".join(header) + " |", "|" + "|".join("---" for _ in header) + "|"]
    out += ["| " + " | ".join(r) + " |" for r in body]
    return "\n".join(out)
