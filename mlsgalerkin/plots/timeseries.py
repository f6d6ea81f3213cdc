r"""A figure of a run's time series (``timeseries.csv``): one panel per group of columns.

The columns are those the run wrote (SI units; see the how-to on scenes for their meaning).
In 2D every extensive quantity is per metre of depth (the out-of-plane direction). Panels,
each drawn only when its columns are present:

=========================  ====================================================  ===============
panel                      columns                                               unit (2D)
=========================  ====================================================  ===============
energy                     ``kinetic_energy``; changes since ``t = 0`` of        J/m
                           ``potential_energy`` and of probes named ``*energy``
mass                       relative change of ``total_mass``, ``(M − M0)/M0``    –
momentum                   ``momentum_x``, ``momentum_y`` (``momentum_z``)       kg·m/s per m
largest speed              ``max_speed``                                         m/s
density-ratio range        ``min_density_ratio``, ``max_density_ratio``          –
shape-function fallbacks   ``fallback_points`` (only when not all zero)          count
wall penetration           ``wall_penetrations``, ``max_wall_penetration_dx``    count, Δx
volume error               ``volume_error`` (geometric / Σ M/ρ − 1), in %        %
pair distances             ``min_pair_distance_dx``, ``min_wall_distance_dx``    Δx
clumped pairs              ``clumped_pairs`` (only when not all zero)            count
Mach number                ``mach`` (max |v|/c0)                                 –
time step                  ``dt``                                                s
each probe                 every other column (a problem's probes)               as recorded
=========================  ====================================================  ===============

A probe's unit is not recorded in the CSV file; pass ``units={"front_x": "m"}`` to label it.
The figure is drawn on an Agg canvas; :func:`render_timeseries` writes it as a PNG.

>>> import numpy as np
>>> cols = {"time": np.array([0.0, 0.1]), "dt": np.array([0.0, 0.1]), "max_speed": np.array([0.0, 1.0])}
>>> fig = timeseries_figure(cols)
>>> [ax.get_ylabel() for ax in fig.axes]
['speed (m/s)', 'dt (s)']
"""

from __future__ import annotations

import io
import logging
from collections.abc import Mapping
from pathlib import Path

import numpy as np

from mlsgalerkin.io.files import atomic_write

__all__ = ["render_timeseries", "timeseries_figure"]

logger = logging.getLogger(__name__)

_SKIP = {"time", "step"}
_CORE = {"kinetic_energy", "potential_energy", "total_mass", "momentum_x", "momentum_y", "momentum_z",
         "max_speed", "min_density_ratio", "max_density_ratio", "dt", "fallback_points",
         "wall_penetrations", "max_wall_penetration_dx", "geometric_volume", "volume_error",
         "min_pair_distance_dx", "clumped_pairs", "min_wall_distance_dx", "mach"}


def _per_depth(unit: str, dim: int) -> str:
    return f"{unit} per m" if dim == 2 else unit


def _panels(cols: Mapping[str, np.ndarray], dim: int, units: Mapping[str, str]) -> list[dict]:
    """``[{"title", "ylabel", "lines": [(label, values, style)], "ref": float|None}]``."""
    panels = []
    energy = []
    if "kinetic_energy" in cols:
        energy.append(("kinetic", cols["kinetic_energy"], "-"))
    for name in cols:
        if name == "kinetic_energy" or not name.endswith("energy"):
            continue
        v = np.asarray(cols[name], dtype=np.float64)
        if name in ("potential_energy", "total_energy"):
            energy.append((f"{name.replace('_', ' ').removesuffix(' energy')} − initial", v - v[0], "--"))
        else:
            energy.append((name.replace("_", " ").removesuffix(" energy"), v, ":"))
    if energy:
        unit = "J/m" if dim == 2 else "J"
        panels.append({"title": "energy", "ylabel": f"energy ({unit})", "lines": energy, "ref": 0.0})
    if "total_mass" in cols:
        m = np.asarray(cols["total_mass"], dtype=np.float64)
        rel = (m - m[0]) / m[0] if m[0] != 0 else m - m[0]
        panels.append({"title": "total mass", "ylabel": "(M − M0)/M0 (–)", "lines": [("mass change", rel, "-")],
                       "ref": 0.0})
    mom = [(f"momentum {c}", cols[f"momentum_{c}"], "-") for c in "xyz" if f"momentum_{c}" in cols]
    if mom:
        panels.append({"title": "momentum", "ylabel": f"momentum ({_per_depth('kg·m/s', dim)})",
                       "lines": mom, "ref": 0.0})
    if "max_speed" in cols:
        panels.append({"title": "largest speed", "ylabel": "speed (m/s)",
                       "lines": [("max |v|", cols["max_speed"], "-")], "ref": None})
    ratio = [(label, cols[k], "-") for k, label in (("max_density_ratio", "max ρ/ρ0"),
                                                    ("min_density_ratio", "min ρ/ρ0")) if k in cols]
    if ratio:
        panels.append({"title": "density-ratio range", "ylabel": "ρ/ρ0 (–)", "lines": ratio, "ref": 1.0})
    if "fallback_points" in cols and np.any(np.asarray(cols["fallback_points"]) != 0):
        panels.append({"title": "shape-function fallbacks", "ylabel": "points (count)",
                       "lines": [("fallback points", cols["fallback_points"], "-")], "ref": None})
    if "wall_penetrations" in cols:
        panels.append({"title": "fluid particles inside a wall", "ylabel": "particles (count)",
                       "lines": [("inside a wall", cols["wall_penetrations"], "-")], "ref": None})
    if "max_wall_penetration_dx" in cols:
        panels.append({"title": "deepest wall penetration", "ylabel": "depth (particle spacings)",
                       "lines": [("deepest", cols["max_wall_penetration_dx"], "-")], "ref": None})
    if "volume_error" in cols:
        panels.append({"title": "volume error", "ylabel": "V_geo / Σ M/ρ − 1 (%)",
                       "lines": [("volume error", 100.0 * np.asarray(cols["volume_error"], dtype=np.float64), "-")],
                       "ref": 0.0})
    pairs = [(label, np.where(np.isfinite(v := np.asarray(cols[k], dtype=np.float64)), v, np.nan), "-")
             for k, label in (("min_pair_distance_dx", "fluid–fluid"), ("min_wall_distance_dx", "fluid–wall"))
             if k in cols]
    if pairs:
        panels.append({"title": "smallest pair distance", "ylabel": "distance (particle spacings)",
                       "lines": pairs, "ref": 0.5})
    if "clumped_pairs" in cols and np.any(np.asarray(cols["clumped_pairs"]) != 0):
        panels.append({"title": "clumped pairs (closer than 0.5 spacings)", "ylabel": "pairs (count)",
                       "lines": [("clumped pairs", cols["clumped_pairs"], "-")], "ref": None})
    if "mach" in cols:
        panels.append({"title": "Mach number", "ylabel": "max |v| / c0 (–)",
                       "lines": [("Mach", cols["mach"], "-")], "ref": 0.1})
    if "dt" in cols:
        dt = np.asarray(cols["dt"], dtype=np.float64)
        panels.append({"title": "time step", "ylabel": "dt (s)",
                       "lines": [("dt", np.where(dt > 0, dt, np.nan), "-")], "ref": None})
    for name in cols:
        if name in _SKIP or name in _CORE or name.endswith("energy"):
            continue
        unit = units.get(name)
        label = f"{name} ({unit})" if unit else name
        panels.append({"title": f"probe {name}", "ylabel": label, "lines": [(name, cols[name], "-")], "ref": None})
    return panels


def timeseries_figure(columns: Mapping[str, np.ndarray], *, title: str = "", dim: int | None = None,
                      units: Mapping[str, str] | None = None):
    """A :class:`~matplotlib.figure.Figure` with one panel per column group (module docstring).

    Parameters
    ----------
    columns : mapping of str to ndarray (n_rows,)
        The time series, e.g. from :func:`~mlsgalerkin.io.timeseries.read_timeseries`; needs
        ``time`` (s) and at least one row.
    title : str
        Heading of the figure.
    dim : int, optional
        2 or 3; default 3 if there is a ``momentum_z`` column, else 2 (per-depth units).
    units : mapping of str to str, optional
        Units of probe columns, e.g. ``{"front_x": "m"}``.

    The panels' axes are ``fig.axes`` in the order of the module docstring's table; the
    bottom row is labelled ``time t (s)``.
    """
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    if "time" not in columns:
        raise ValueError(f"the time series has no 'time' column (columns: {', '.join(columns) or 'none'}); "
                         "it is not a time series written by a run")
    t = np.asarray(columns["time"], dtype=np.float64)
    if t.size == 0:
        raise ValueError("the time series has no rows yet; the run stopped before its first recorded step")
    dim = dim or (3 if "momentum_z" in columns else 2)
    panels = _panels(columns, dim, units or {})
    if not panels:
        raise ValueError(f"the time series has nothing to plot besides the time (columns: {', '.join(columns)})")
    ncols = 2 if len(panels) > 1 else 1
    nrows = -(-len(panels) // ncols)
    fig = Figure(figsize=(10.0 if ncols == 2 else 6.0, 0.6 + 2.3 * nrows), dpi=100, layout="constrained")
    FigureCanvasAgg(fig)
    axes = fig.subplots(nrows, ncols, squeeze=False, sharex=True)
    for k, (ax, panel) in enumerate(zip(axes.ravel(), panels)):
        for label, values, style in panel["lines"]:
            ax.plot(t, np.asarray(values, dtype=np.float64), style, label=label, linewidth=1.3)
        if panel["ref"] is not None:
            ax.axhline(panel["ref"], color="0.7", linewidth=0.8, zorder=0)
        ax.set_title(panel["title"], fontsize=10, loc="left")
        ax.set_ylabel(panel["ylabel"])
        ax.grid(True, linewidth=0.4, alpha=0.5)
        if len(panel["lines"]) > 1:
            ax.legend(fontsize=8, frameon=False)
    for ax in axes.ravel()[len(panels):]:
        ax.remove()
    for k, ax in enumerate(axes.ravel()[:len(panels)]):
        if k + ncols >= len(panels):  # nothing below it: label the time axis
            ax.set_xlabel("time t (s)")
            ax.xaxis.set_tick_params(labelbottom=True)
    if title:
        fig.suptitle(title)
    return fig


def render_timeseries(csv_path: str | Path, out_png: str | Path, *, title: str = "",
                      units: Mapping[str, str] | None = None) -> Path:
    """Plot the time series of ``csv_path`` (a run's ``timeseries.csv``) to ``out_png``
    (atomically); see :func:`timeseries_figure`."""
    from mlsgalerkin.io.timeseries import read_timeseries

    fig = timeseries_figure(read_timeseries(csv_path), title=title, units=units)
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=100)
    atomic_write(out_png, buf.getvalue())
    logger.debug("wrote %s", out_png)
    return Path(out_png)
