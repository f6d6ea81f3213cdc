r"""Plane Poiseuille flow: a body force drives fluid between two no-slip walls, periodic along the channel.

The channel is ``H`` high (walls at ``y = 0`` and ``y = H``, three layers of wall particles
each) and ``length`` long, periodic in x. A body force ``g`` along x (listed as ``Gravity((g, 0))``)
starts the fluid from rest; the start-up flow is the series

.. math::

    u(y, t) = \frac{g}{2\nu} y (H - y) - \sum_{n\ \mathrm{odd}} \frac{4 g H^2}{\nu \pi^3 n^3}
              \sin\frac{n\pi y}{H} \exp\left(-\frac{n^2 \pi^2 \nu t}{H^2}\right),

which tends to the parabola ``u = g/(2ν) y (H − y)`` with centre speed ``u_max = g H²/(8ν)``. The
body force is set from the centre speed and the Reynolds number ``Re = u_max H/ν``.

Measured (``analyse``): at the end, the fluid particles' x velocity averaged over each lattice row
(``Δx`` thick) against the series at the row's mean height; the largest deviation and the RMS
deviation over the rows in units of ``u_max`` (acceptance: largest below 1 %), and the centre-row
speed against the series. The deviation is split into its smooth part (both profiles filtered
over three rows with weights ¼, ½, ¼, which removes a row-to-row alternation) and the amplitude
of the alternation itself (``mlsgalerkin.analysis.channel``). Measured with the defaults (linear MLS basis, ``h = 1.3 Δx``,
``α = 0``, ``δ = 0.1``, local shifting, ``c0 = 10 u_max``, no-slip wall particles continuing the
fluid velocity per particle, the stabilised Newtonian viscosity), to ``t = 5 s``: largest
deviation 0.04 % and 0.02 % of ``u_max`` at ``H/Δx = 20`` and 40 (row alternation 0.01 %). Before
the per-particle wall continuation and the viscous stabilisation it was 20.7 % and 11 %, nearly
all an alternation of the rows forced by the wall velocities and left undamped by the nodal
viscous term (``docs/theory/galerkin_fluid.md`` §13 has the ablation). ``verification/fluid_periodic.py`` runs two resolutions.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from mlsgalerkin.analysis.channel import channel_profile_errors, row_means
from mlsgalerkin.approximation.settings import Approximation
from mlsgalerkin.deprecation import moved_names
from mlsgalerkin.fluid import FluidBody, Periodic, Phase, WallBody, water
from mlsgalerkin.fluid.presets import RECOMMENDED
from mlsgalerkin.problem import require, require_nonnegative, require_positive
from mlsgalerkin.scene import Output, Probe, Scene

__all__ = ["Parameters", "make_scene", "analyse", "check", "SMOKE", "series_velocity", "row_profile"]

SMOKE = {"dx": 0.125, "t_end": 0.05}

#: the profile filter moved to the analysis package with the rest of the profile analysis
__getattr__ = moved_names(__name__, {"three_row_filter": "mlsgalerkin.analysis.channel"})

#: Largest deviation of the row-averaged profile from the series solution, in units of ``u_max``.
PROFILE_TOLERANCE = 0.01


@dataclass(frozen=True)
class Parameters:
    height: float = 1.0              #: channel height H between the walls (m)
    length: float = 1.0              #: periodic length of the channel (m)
    u_max: float = 1.0               #: centre speed of the steady parabola (m/s)
    reynolds: float = 10.0           #: Reynolds number u_max H / ν (–)
    rho: float = 1000.0              #: density (kg/m³)
    dx: float = 0.05                 #: particle spacing (m)
    t_end: float = 5.0               #: end time (s)
    c0_factor: float = 10.0          #: sound speed / u_max (–)
    alpha: float = 0.0               #: Monaghan artificial viscosity α (0: none; its ν_art ≈ α h c0/8) (–)
    delta: float = 0.1               #: δ-SPH density diffusion coefficient (0: none) (–)
    shifting: str = "local"          #: particle shifting: local, design or off (choice)
    consistent_integration: bool = False  #: consistent nodal integration (bool)
    linear_consistency: bool = RECOMMENDED.linear_consistency  #: the pressure's linear fit integrated exactly, with the free-surface term (bool)
    volume_consistency: float = RECOMMENDED.volume_consistency  #: the density relaxed towards the particles' packing at rate ε where the fluid has a free surface (0: off) (–)
    h_factor: float = 1.3            #: smoothing length / particle spacing, h/dx (–)
    basis: str = "linear"            #: MLS basis: linear or quadratic (choice)
    frame_every: float = 1.0         #: time between VTU frames (s)
    gif: bool = False                #: render animation.gif and final.png (bool)


def viscosity(p: Parameters) -> float:
    """The kinematic viscosity ``ν = u_max H / Re`` (m²/s)."""
    return p.u_max * p.height / p.reynolds


def body_force(p: Parameters) -> float:
    """The driving acceleration ``g = 8 ν u_max / H²`` (m/s²)."""
    return 8.0 * viscosity(p) * p.u_max / p.height**2


def series_velocity(y: np.ndarray, t: float, p: Parameters, terms: int = 200) -> np.ndarray:
    """The start-up velocity ``u(y, t)`` (m/s) at heights ``y`` (m) (module docstring; ``terms`` odd terms)."""
    y = np.asarray(y, dtype=float)
    nu, g, H = viscosity(p), body_force(p), p.height
    u = g / (2.0 * nu) * y * (H - y)
    for n in range(1, 2 * terms, 2):
        u -= 4.0 * g * H * H / (nu * math.pi**3 * n**3) * np.sin(n * math.pi * y / H) * math.exp(
            -(n * math.pi) ** 2 * nu * t / H**2)
    return u


def row_profile(x: np.ndarray, v: np.ndarray, p: Parameters) -> tuple[np.ndarray, np.ndarray]:
    """Mean height (m) and mean x velocity (m/s) of the fluid particles in each row ``Δx`` thick."""
    return row_means(x[:, 1], v[:, 0], p.height, p.dx)


def make_scene(p: Parameters = Parameters()) -> Scene:
    c0 = p.c0_factor * p.u_max
    nu = viscosity(p)
    body = FluidBody.block("fluid", (0.0, 0.0), (p.length, p.height), p.dx, [Phase("fluid", p.rho, viscosity=p.rho * nu)])
    n = body.n
    columns = (np.arange(int(round(p.length / p.dx))) + 0.5) * p.dx
    depth = (np.arange(3) + 0.5) * p.dx
    below = np.column_stack([np.tile(columns, 3), np.repeat(-depth, columns.size)])
    above = np.column_stack([np.tile(columns, 3), np.repeat(p.height + depth, columns.size)])
    walls = WallBody("walls", np.vstack([below, above]), p.dx,
                     normals=np.vstack([np.tile([0.0, 1.0], (below.shape[0], 1)), np.tile([0.0, -1.0], (above.shape[0], 1))]),
                     reference_density=p.rho)

    def profile_error(state) -> float:
        s = state.fluid
        y, u = row_profile(s.x[:n], s.v[:n], p)
        return float(np.max(np.abs(u - series_velocity(y, s.t, p))) / p.u_max)

    scheme = water(c0, u_max=p.u_max, gravity=(body_force(p), 0.0), slip="no_slip", alpha=p.alpha,
                   flow=(p.u_max, p.height), newtonian=True, delta=p.delta, shifting=p.shifting,
                   negative_pressure="allow", consistent_integration=p.consistent_integration,
                   linear_consistency=p.linear_consistency,
                   volume_consistency=p.volume_consistency, spacing=p.dx,
                   approximation=Approximation(h_factor=p.h_factor, basis=p.basis),
                   periodic=Periodic(x=(0.0, p.length)))
    return Scene(
        [body, walls], [scheme], t_end=p.t_end, name="poiseuille",
        output=Output(every=p.frame_every, probe_every=p.t_end / 100.0, gif=p.gif, png=p.gif, color_by="speed"),
        probes=[Probe("profile_error", profile_error)],
        parameters=dict(p.__dict__),
    )


def analyse(result, p: Parameters) -> dict:
    """The row-averaged velocity profile at the end against the start-up series."""
    s = result.state.fluid
    n = s.n_fluid
    y, u = row_profile(s.x[:n], s.v[:n], p)
    errors = channel_profile_errors(y, u, series_velocity(y, s.t, p), p.u_max, p.height)
    ts = result.timeseries
    out = {
        "reynolds_number": p.reynolds,
        "viscosity_m2_s": viscosity(p),
        "body_force_m_s2": body_force(p),
        "time_s": float(s.t),
        "steady_fraction": float(series_velocity(np.array([0.5 * p.height]), s.t, p)[0] / p.u_max),
        **errors.results(),
        "profile_error_max_over_run": float(np.max(np.asarray(ts["profile_error"], dtype=float))),
        "profile_within_tolerance": errors.max <= PROFILE_TOLERANCE,
        "rows": errors.rows,
    }
    out["headline"] = errors.headline("u_max", s.t, out["steady_fraction"], p.reynolds)
    return out


def check(p: Parameters) -> list[str]:
    """Problems with the parameters (see ``mlsgalerkin.problem``)."""
    out = require_positive(p, "height", "length", "u_max", "reynolds", "rho", "dx", "t_end", "c0_factor", "h_factor",
                           "frame_every")
    out += require_nonnegative(p, "alpha", "delta")
    out += require(p.basis in ("linear", "quadratic"), f"basis must be linear or quadratic, got {p.basis!r}")
    out += require(p.shifting in ("local", "design", "off"), f"shifting must be local, design or off, got {p.shifting!r}")
    if not out:
        for name in ("height", "length"):
            cells = getattr(p, name) / p.dx
            out += require(abs(cells - round(cells)) < 1e-6 * cells,
                           f"the channel {name} {getattr(p, name):g} m is not a whole number of spacings dx = {p.dx:g} m; "
                           f"choose dx = {name} / N")
        out += require(p.height >= 4 * p.dx, f"dx = {p.dx:g} m leaves fewer than 4 particles across the channel; "
                       f"choose dx <= {p.height / 4:g}")
    return out
