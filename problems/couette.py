r"""Plane Couette flow: the top wall slides at speed ``U`` over fluid between two walls, periodic along the channel.

The channel is ``H`` high (no-slip wall particles at ``y = 0`` and ``y = H``, three layers each)
and ``length`` long, periodic in x. The bottom wall is at rest; the top wall stays in place with
the surface velocity ``U`` along x (``WallBody(velocity=(U, 0))``, a belt). Starting from rest,
the flow is the series

.. math::

    u(y, t) = U \frac{y}{H} + \sum_{n \ge 1} \frac{2U (-1)^n}{n\pi} \sin\frac{n\pi y}{H}
              \exp\left(-\frac{n^2 \pi^2 \nu t}{H^2}\right),

which tends to the linear profile ``u = U y/H``; ``Re = U H/ν``.

Measured (``analyse``): at the end, the fluid particles' x velocity averaged over each lattice row
(``Δx`` thick) against the series at the row's mean height; the largest deviation and the RMS
deviation over the rows in units of ``U`` (acceptance: largest below 1 %); and, as for the
Poiseuille flow, the deviation's smooth part (three-row filter ¼, ½, ¼) and the amplitude of the
row-to-row alternation (``mlsgalerkin.analysis.channel``). Measured with the defaults (as for the Poiseuille flow: linear MLS
basis, ``h = 1.3 Δx``, ``α = 0``, ``δ = 0.1``, local shifting, ``c0 = 10 U``), to ``t = 5 s``:
largest deviation 0.01 % of ``U`` at ``H/Δx = 20`` and 40 (5.9 % and 2.8 % before the per-particle
no-slip wall velocity and the stabilised viscous term; ``docs/theory/galerkin_fluid.md`` §13).
``verification/fluid_periodic.py`` runs two resolutions.
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

#: Largest deviation of the row-averaged profile from the series solution, in units of ``U``.
PROFILE_TOLERANCE = 0.01


@dataclass(frozen=True)
class Parameters:
    height: float = 1.0              #: channel height H between the walls (m)
    length: float = 1.0              #: periodic length of the channel (m)
    wall_speed: float = 1.0          #: speed U of the top wall (m/s)
    reynolds: float = 10.0           #: Reynolds number U H / ν (–)
    rho: float = 1000.0              #: density (kg/m³)
    dx: float = 0.05                 #: particle spacing (m)
    t_end: float = 5.0               #: end time (s)
    c0_factor: float = 10.0          #: sound speed / U (–)
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
    """The kinematic viscosity ``ν = U H / Re`` (m²/s)."""
    return p.wall_speed * p.height / p.reynolds


def series_velocity(y: np.ndarray, t: float, p: Parameters, terms: int = 400) -> np.ndarray:
    """The start-up velocity ``u(y, t)`` (m/s) at heights ``y`` (m) (module docstring; ``terms`` terms)."""
    y = np.asarray(y, dtype=float)
    nu, U, H = viscosity(p), p.wall_speed, p.height
    u = U * y / H
    for n in range(1, terms + 1):
        u += 2.0 * U * (-1) ** n / (n * math.pi) * np.sin(n * math.pi * y / H) * math.exp(
            -(n * math.pi) ** 2 * nu * t / H**2)
    return u


def row_profile(x: np.ndarray, v: np.ndarray, p: Parameters) -> tuple[np.ndarray, np.ndarray]:
    """Mean height (m) and mean x velocity (m/s) of the fluid particles in each row ``Δx`` thick."""
    return row_means(x[:, 1], v[:, 0], p.height, p.dx)


def make_scene(p: Parameters = Parameters()) -> Scene:
    c0 = p.c0_factor * p.wall_speed
    nu = viscosity(p)
    body = FluidBody.block("fluid", (0.0, 0.0), (p.length, p.height), p.dx, [Phase("fluid", p.rho, viscosity=p.rho * nu)])
    n = body.n
    columns = (np.arange(int(round(p.length / p.dx))) + 0.5) * p.dx
    depth = (np.arange(3) + 0.5) * p.dx
    below = np.column_stack([np.tile(columns, 3), np.repeat(-depth, columns.size)])
    above = np.column_stack([np.tile(columns, 3), np.repeat(p.height + depth, columns.size)])
    floor = WallBody("floor", below, p.dx, normals=np.tile([0.0, 1.0], (below.shape[0], 1)), reference_density=p.rho)
    lid = WallBody("lid", above, p.dx, normals=np.tile([0.0, -1.0], (above.shape[0], 1)),
                   velocity=(p.wall_speed, 0.0), reference_density=p.rho)

    def profile_error(state) -> float:
        s = state.fluid
        y, u = row_profile(s.x[:n], s.v[:n], p)
        return float(np.max(np.abs(u - series_velocity(y, s.t, p))) / p.wall_speed)

    scheme = water(c0, u_max=p.wall_speed, gravity=None, slip="no_slip", alpha=p.alpha,
                   flow=(p.wall_speed, p.height), newtonian=True, delta=p.delta, shifting=p.shifting,
                   negative_pressure="allow", consistent_integration=p.consistent_integration,
                   linear_consistency=p.linear_consistency,
                   volume_consistency=p.volume_consistency, spacing=p.dx,
                   approximation=Approximation(h_factor=p.h_factor, basis=p.basis),
                   periodic=Periodic(x=(0.0, p.length)))
    return Scene(
        [body, floor, lid], [scheme], t_end=p.t_end, name="couette",
        output=Output(every=p.frame_every, probe_every=p.t_end / 100.0, gif=p.gif, png=p.gif, color_by="speed"),
        probes=[Probe("profile_error", profile_error)],
        parameters=dict(p.__dict__),
    )


def analyse(result, p: Parameters) -> dict:
    """The row-averaged velocity profile at the end against the start-up series."""
    s = result.state.fluid
    n = s.n_fluid
    y, u = row_profile(s.x[:n], s.v[:n], p)
    errors = channel_profile_errors(y, u, series_velocity(y, s.t, p), p.wall_speed, p.height)
    ts = result.timeseries
    out = {
        "reynolds_number": p.reynolds,
        "viscosity_m2_s": viscosity(p),
        "time_s": float(s.t),
        "steady_fraction": float(series_velocity(np.array([0.5 * p.height]), s.t, p)[0] / (0.5 * p.wall_speed)),
        **errors.results(),
        "profile_error_max_over_run": float(np.max(np.asarray(ts["profile_error"], dtype=float))),
        "profile_within_tolerance": errors.max <= PROFILE_TOLERANCE,
        "rows": errors.rows,
    }
    out["headline"] = errors.headline("U", s.t, out["steady_fraction"], p.reynolds)
    return out


def check(p: Parameters) -> list[str]:
    """Problems with the parameters (see ``mlsgalerkin.problem``)."""
    out = require_positive(p, "height", "length", "wall_speed", "reynolds", "rho", "dx", "t_end", "c0_factor", "h_factor",
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
