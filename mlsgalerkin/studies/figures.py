"""The look of every study figure: an Agg pyplot, readable log axes, atomic PNG output.

Shared by the engine's work-precision plot and the shipped studies' report figures
(``verification/``), so that all of them read alike.
"""

from __future__ import annotations

import io
import logging
import math
from pathlib import Path
from typing import Any

from mlsgalerkin.io.files import atomic_write

__all__ = ["PLOT_FLOOR", "pyplot", "save_png", "tidy_log_axes"]

logger = logging.getLogger(__name__)

#: Errors are clipped to this before they are drawn on log axes (exact zeros would vanish).
PLOT_FLOOR = 1e-17


def pyplot() -> Any:
    """``matplotlib.pyplot`` on the non-interactive Agg backend (no display needed)."""
    import matplotlib

    matplotlib.use("Agg", force=True)
    import matplotlib.pyplot as plt

    return plt


def save_png(fig: Any, path: str | Path, *, dpi: int = 110, compact: bool = False) -> Path:
    """Write ``fig`` as a PNG at ``dpi`` atomically, close it, and return the path.

    ``compact`` quantises the image to a 128-colour palette (about 3x smaller; Pillow), which
    keeps committed figures small.
    """
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=dpi)
    data = buf.getvalue()
    if compact:
        try:
            from PIL import Image

            im = Image.open(io.BytesIO(data)).convert("RGB")
            im = im.quantize(colors=128, method=Image.Quantize.MEDIANCUT, dither=Image.Dither.NONE)
            out = io.BytesIO()
            im.save(out, format="PNG", optimize=True)
            data = out.getvalue()
        except Exception as exc:  # Pillow missing or too old: keep the plain PNG
            logger.info("PNG quantisation skipped: %s", exc)
    path = atomic_write(path, data)
    if getattr(fig.canvas, "manager", None) is not None:  # a pyplot figure: release it
        import matplotlib.pyplot as plt

        plt.close(fig)
    return path


def tidy_log_axes(ax: Any, which: str = "xy") -> None:
    """Readable labels on the log-scaled axes among ``which`` (``"x"``, ``"y"`` or ``"xy"``).

    Below 1.5 decades the ticks are 1-2-3-5 (1-2-5 when that gives more than six) times a power
    of ten, below 2.5 decades 1-3, labelled as plain numbers; wider ranges keep matplotlib's
    decade labels. Minor tick labels (which overlap on short ranges) are removed.
    """
    from matplotlib.ticker import FuncFormatter, NullFormatter

    for name in which:
        axis = ax.xaxis if name == "x" else ax.yaxis
        if (ax.get_xscale() if name == "x" else ax.get_yscale()) != "log":
            continue
        lo, hi = ax.get_xlim() if name == "x" else ax.get_ylim()
        if not (lo > 0 and hi > lo):
            continue
        decades = math.log10(hi / lo)
        axis.set_minor_formatter(NullFormatter())
        if decades >= 2.5:
            continue
        mantissas = (1, 2, 3, 5) if decades < 1.5 else (1, 3)
        ticks = [m * 10.0**e for e in range(math.floor(math.log10(lo)) - 1,
                                              math.ceil(math.log10(hi)) + 1) for m in mantissas]
        ticks = [t for t in ticks if lo <= t <= hi]
        if len(ticks) > 6:
            ticks = [t for t in ticks
                     if round(t / 10.0 ** math.floor(math.log10(t)), 6) in (1, 2, 5)]
        axis.set_ticks(ticks)
        axis.set_major_formatter(FuncFormatter(lambda v, _: f"{v:g}"))
        axis.set_minor_formatter(NullFormatter())
        if name == "x":
            ax.set_xlim(lo, hi)
        else:
            ax.set_ylim(lo, hi)
