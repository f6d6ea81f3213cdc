r"""Hydrostatic tank: water at rest in a walled box settles to ``p = ρ0 g (H − y)``.

The water starts at the hydrostatic Tait density; the discrete forces of the nodal-integrated
weak form are not exactly in balance at the free surface and the walls, so the water moves a
little and settles (kinetic energy decays under the artificial viscosity). Checked after
settling (the last quarter of the run): the RMS pressure error over the fluid against
``ρ0 g (H − y)`` in units of ``ρ0 g H`` (acceptance: below 2 %), the kinetic-energy decay,
and that no particle crossed a wall.

Settings: the one recommended set (``mlsgalerkin.fluid.RECOMMENDED``: α = 0.02, density
diffusion, shifting, the pressure's linear fit integrated exactly), tension released by
cavitation. Measured (``verification/results/fluid_validation/summary.md``, 2 s, 2026-12-02): the
RMS pressure error after settling is 0.16, 0.12 and 0.12 % of ``ρ0 g H`` at ``Δx`` = 0.04, 0.02
and 0.01 m (with the former α = 0.2 and a Shepard filter: 1.17, 0.40 and 0.20 %), the largest
speed 0.03, 0.02 and 0.02 % of ``sqrt(g H)`` (0.26, 0.19 and 0.13 % before the corner where the
free surface meets a wall was covered, ``docs/theory/stabilisation.md`` §7). With that start
transient gone the table's decay check (kinetic energy of the last quarter below the first's)
fails at the two coarser spacings: at 0.04 m the kinetic energy grows 3.5 times over the 2 s
(largest speed 0.34 → 0.65 mm/s, 0.02 → 0.04 % of ``sqrt(g H)``), at 0.02 m 1.2 times, at
0.01 m not at all. Water 0.3 m deep in a 1 m tank stays at rest for
10 s at two resolutions (``verification/quiet_state.py``; the tables in
``verification/results/quiet_state/``). Under a lid (``lid``) the tank lists
:class:`~mlsgalerkin.fluid.ClosedVolume`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from mlsgalerkin.analysis.measured import not_measured
from mlsgalerkin.fluid import (
    ClosedVolume,
    FluidBody,
    Phase,
    hydrostatic_density,
    wall_box,
    water,
)
from mlsgalerkin.fluid.presets import RECOMMENDED
from mlsgalerkin.problem import require, require_nonnegative, require_positive
from mlsgalerkin.scene import Output, Probe, Scene

__all__ = ["Parameters", "make_scene", "analyse", "check", "SMOKE"]

SMOKE = {"dx": 0.04, "t_end": 0.2}


@dataclass(frozen=True)
class Parameters:
    depth: float = 0.4          #: water depth H (m)
    width: float = 0.4          #: tank width (m)
    dx: float = 0.01            #: particle spacing (m)
    t_end: float = 2.0          #: end time (s)
    rho: float = 1000.0         #: water density (kg/m³)
    alpha: float = RECOMMENDED.alpha  #: Monaghan artificial viscosity α (–)
    c0_factor: float = 10.0     #: sound speed / sqrt(2 g H) (–)
    h_factor: float = 1.3       #: smoothing length / particle spacing, h/dx (–)
    g: float = 9.81             #: gravitational acceleration (m/s²)
    slip: str = "free_slip"     #: wall condition: free_slip, no_slip or fixed (choice)
    lid: bool = False           #: a rigid lid on the water instead of a free surface (bool)
    closed_volume: bool = True     #: with the lid: hold the closed tank's volume in the continuity equation (ClosedVolume) (bool)
    delta: float = RECOMMENDED.delta  #: density diffusion δ (δ-SPH); 0 drops it (–)
    shifting: str = RECOMMENDED.shifting  #: particle shifting: local (speed |v|), design (c0/10) or off (choice)
    density_filter: int = RECOMMENDED.density_filter  #: Shepard density filter every this many steps; 0 drops it (–)
    negative_pressure: str = "cavitate"  #: tension treatment: allow, clamp, cavitate or free_surface (choice)
    consistent_integration: bool = RECOMMENDED.consistent_integration  #: the constant-only consistent nodal integration (bool)
    linear_consistency: bool = RECOMMENDED.linear_consistency  #: the pressure's linear fit integrated exactly, with the free-surface term (bool)
    volume_consistency: float = RECOMMENDED.volume_consistency  #: the density relaxed towards the particles' packing at rate ε where the fluid has a free surface (0: off) (–)
    frame_every: float = 0.1    #: time between VTU frames (s)
    gif: bool = False           #: render animation.gif and final.png (bool)


def make_scene(p: Parameters = Parameters()) -> Scene:
    c0 = p.c0_factor * math.sqrt(2.0 * p.g * p.depth)
    water_body = FluidBody.block("water", (0.0, 0.0), (p.width, p.depth), p.dx, [Phase("water", p.rho)])
    y = water_body.positions[:, 1]
    water_body.density[:] = hydrostatic_density(np.full(water_body.n, p.rho), p.depth - y, p.g, c0)
    top = p.depth if p.lid else 1.5 * p.depth
    walls = wall_box((0.0, 0.0), (p.width, top), p.dx, layers=3, reference_density=p.rho, open_top=not p.lid)
    n = water_body.n
    scale = p.rho * p.g * p.depth

    def pressure_rms_error(state) -> float:
        s = state.fluid
        exact = p.rho * p.g * (p.depth - s.x[:n, 1])
        return float(np.sqrt(np.mean((s.p[:n] - exact) ** 2)) / scale)

    def max_speed_ratio(state) -> float:
        v = state.fluid.v[:n]
        return float(np.sqrt(np.einsum("id,id->i", v, v).max()) / math.sqrt(p.g * p.depth)) if n else 0.0

    def wall_crossings(state) -> float:
        x = state.fluid.x[:n]
        out = (x[:, 0] < 0) | (x[:, 0] > p.width) | (x[:, 1] < 0)
        return float(np.count_nonzero(out))

    return Scene(
        [water_body, walls],
        [water(c0, gravity=(0.0, -p.g), slip=p.slip, alpha=p.alpha, delta=p.delta, shifting=p.shifting,
               density_filter=p.density_filter, negative_pressure=p.negative_pressure,
               consistent_integration=p.consistent_integration, linear_consistency=p.linear_consistency,
                   volume_consistency=p.volume_consistency,
               spacing=p.dx, h_factor=p.h_factor,
               extra=[ClosedVolume()] if p.lid and p.closed_volume else [])],
        t_end=p.t_end, name="hydrostatic",
        output=Output(every=p.frame_every, probe_every=0.005, gif=p.gif, png=p.gif, color_by="pressure"),
        probes=[Probe("pressure_rms_error", pressure_rms_error), Probe("max_speed_ratio", max_speed_ratio),
                Probe("wall_crossings", wall_crossings)],
        parameters=dict(p.__dict__),
    )


#: Acoustic periods ``4 H/c0`` of the water column a run must last before it counts as settled.
SETTLE_PERIODS = 2


def settling_time(p: Parameters) -> float:
    """``SETTLE_PERIODS`` acoustic periods ``4 H/c0`` of the water column (s): the pressure waves
    of the start have run down and back this often before "after settling" means anything."""
    return SETTLE_PERIODS * 4.0 * p.depth / (p.c0_factor * math.sqrt(2.0 * p.g * p.depth))


def analyse(result, p: Parameters) -> dict:
    """Pressure error over the last quarter of the run and the kinetic energy early and late,
    measured once the run has lasted :func:`settling_time`."""
    ts = result.timeseries
    t = np.asarray(ts["time"])
    m_total = float(ts["total_mass"][0])
    ke_scale = m_total * p.g * p.depth
    out = {"kinetic_energy_scale_MgH_J": ke_scale, "max_wall_crossings": int(np.max(ts["wall_crossings"])),
           "pressure_rms_error_final": float(np.asarray(ts["pressure_rms_error"])[-1]),
           "pressure_rms_error_max": float(np.max(ts["pressure_rms_error"])),
           "max_speed_ratio": float(np.max(ts["max_speed_ratio"]))}
    if "volume_error" in ts:
        out["largest_volume_error"] = float(np.max(np.abs(ts["volume_error"])))
    settle = settling_time(p)
    if t[-1] + 1e-9 < settle:
        text = not_measured(out, ("pressure_rms_error_settled", "kinetic_energy_max_early_J", "kinetic_energy_max_late_J",
                                  "kinetic_energy_decays"),
                            f"the run ended at t = {t[-1]:.3g} s, before {SETTLE_PERIODS} acoustic periods of the "
                            "column (4 H/c0 each) had passed", run_to=settle)
        out["headline"] = f"pressure RMS error after settling {text}; {out['max_wall_crossings']} wall crossings"
        return out
    late = t >= 0.75 * t[-1]
    ke = np.asarray(ts["kinetic_energy"])
    err = np.asarray(ts["pressure_rms_error"])
    early = (t > 0) & (t <= 0.25 * t[-1])
    out.update({
        "pressure_rms_error_settled": float(err[late].mean()),
        "kinetic_energy_max_early_J": float(ke[early].max()),
        "kinetic_energy_max_late_J": float(ke[late].max()),
        "kinetic_energy_decays": bool(ke[late].max() < ke[early].max()),
    })
    out["headline"] = (f"pressure RMS error {100 * out['pressure_rms_error_settled']:.2f} % of rho g H after settling; "
                       f"largest speed {100 * out['max_speed_ratio']:.2f} % of sqrt(g H); "
                       f"KE late/early max {out['kinetic_energy_max_late_J'] / max(out['kinetic_energy_max_early_J'], 1e-300):.2g}; "
                       f"{out['max_wall_crossings']} wall crossings")
    return out


def check(p: Parameters) -> list[str]:
    """Problems with the parameters (see ``mlsgalerkin.problem``)."""
    out = require_positive(p, "depth", "width", "dx", "t_end", "rho", "c0_factor", "h_factor", "g", "frame_every")
    out += require_nonnegative(p, "alpha")
    if not out:
        out += require(min(p.depth, p.width) >= 4 * p.dx,
                       f"dx = {p.dx:g} m leaves fewer than 4 particles across the {min(p.depth, p.width):g} m tank; "
                       f"choose dx <= {min(p.depth, p.width) / 4:g} m")
    out += require(p.slip in ("free_slip", "no_slip", "fixed"), f"slip must be free_slip, no_slip or fixed, got {p.slip!r}")
    out += require(p.shifting in ("local", "design", "off"), f"shifting must be local, design or off, got {p.shifting!r}")
    out += require(p.negative_pressure in ("allow", "clamp", "cavitate", "free_surface"),
                   f"negative_pressure must be allow, clamp, cavitate or free_surface, got {p.negative_pressure!r}")
    out += require_nonnegative(p, "delta", "density_filter")
    return out
