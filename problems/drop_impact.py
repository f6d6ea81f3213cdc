r"""Drop impact of Cueto-Felgueroso et al. (2005): a circular drop at 2 m/s onto still liquid.

Their parameters: ``ρ = 1000 kg/m³``, ``μ = 0.5 Pa s`` (500 times water: a very viscous
liquid), impact speed 2 m/s, 5539 particles, output at their times up to 0.1557 s.
The paper gives no sizes; this reproduction chooses a drop of diameter 20 mm over a pool
120 mm wide and 43 mm deep with ``Δx = 1`` mm (5474 fluid particles, close to their 5539),
gravity acting, free-slip walls and ``c0 = 10 · 2 m/s``. The drop starts 1.5 Δx above the
surface. Settings: the one recommended set (``mlsgalerkin.fluid.RECOMMENDED``: α = 0.02,
δ-SPH density diffusion, shifting, the pressure's linear fit integrated exactly); tension is
allowed inside the liquid, and the density of the particles flagged as free surface is floored
at ``ρ0`` (``negative_pressure="free_surface"``: a surface against air carries no tension).
Measured at the defaults (``verification/results/fluid_validation/summary.md``): at ``Δx`` = 2
and 1 mm the drop reaches 0.16 s, the mass is exact, the energy never grows, and the largest
geometric-volume error is 0.68 and 0.39 % (0.77 and 0.31 % before 2026-12-02). Measured at
Δx = 1 mm with the set (``verification/results/fluid_core/drop.md``, regenerated 2026-12-02):

- with this floor, 2, 5 and 10 m/s all reach their end (0.16, 0.064, 0.032 s), the energy never
  growing;
- the floor on every particle (``"cavitate"``) also reaches the end at all three speeds, but
  at 2 m/s one splash particle crossed the side wall's particle layer at 0.135 s (2.8 Δx behind
  its surface at y = 0.095 m; 0.69 Δx into the layer, none through it, before the linear
  consistency's surface fix of 2026-12-02): the walls leak for that setting, not for the default;
- with tension allowed everywhere, 2 m/s reaches its end, but 5 and 10 m/s diverge at 6.0 and
  13.8 ms (at 42 and 7 ms with the former α = 0.05 and direct nodal integration): a particle of
  the thinning crown sheet falls below ``ρ/ρ0 = 0.5``. A surface against air needs the floor;
- without density diffusion and shifting, with tension allowed, the crown sheet lost density
  until the watchdog stopped the run at 5–10 ms.

Checked: no instability up to ``t_end`` (the watchdog stays silent), the mass is exact, and
the total energy ``E = KE + PE + E_int`` (``E_int = Σ M B/ρ0 [(r^{γ−1} − 1)/(γ−1) + 1/r − 1]``,
``r = ρ/ρ0``, the Tait fluid's stored energy) does not grow: the viscous and artificial
dissipation only remove energy. A panel of snapshots at the paper's output times is written
to ``snapshots.png``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from mlsgalerkin.fluid import (
    SHIFTING_MODES,
    FluidBody,
    Phase,
    hydrostatic_density,
    lattice,
    tait_stored_energy,
    wall_box,
    water,
)
from mlsgalerkin.fluid.eos import NEGATIVE_PRESSURE_MODES
from mlsgalerkin.fluid.presets import RECOMMENDED
from mlsgalerkin.problem import require, require_nonnegative, require_positive
from mlsgalerkin.scene import Output, Probe, Scene

__all__ = ["Parameters", "make_scene", "analyse", "check", "PAPER_OUTPUT_TIMES", "SMOKE"]

PAPER_OUTPUT_TIMES = (0.0018, 0.0099, 0.0297, 0.0477, 0.0657, 0.0837, 0.1017, 0.1197, 0.1377, 0.1557)
SMOKE = {"dx": 0.004, "t_end": 0.01}


@dataclass(frozen=True)
class Parameters:
    drop_diameter: float = 0.02    #: drop diameter (m)
    pool_width: float = 0.12       #: pool width, wall to wall (m)
    pool_depth: float = 0.043      #: still-liquid depth of the pool (m)
    speed: float = 2.0             #: impact speed of the drop, downwards (m/s)
    rho: float = 1000.0            #: liquid density (kg/m³)
    viscosity: float = 0.5         #: dynamic viscosity of the liquid (Pa s)
    dx: float = 0.001              #: particle spacing (m)
    t_end: float = 0.16            #: end time (s)
    c0_factor: float = 10.0        #: sound speed / impact speed (–)
    alpha: float = RECOMMENDED.alpha  #: Monaghan artificial viscosity α (–)
    delta: float = RECOMMENDED.delta  #: density diffusion δ (δ-SPH); 0 drops it (–)
    shifting: str = RECOMMENDED.shifting  #: particle shifting: local (speed |v|), design (c0/10) or off (choice)
    consistent_integration: bool = RECOMMENDED.consistent_integration  #: nodal integration that meets the integration constraint (VCI) (bool)
    linear_consistency: bool = RECOMMENDED.linear_consistency  #: the pressure's linear fit integrated exactly, with the free-surface term (bool)
    volume_consistency: float = RECOMMENDED.volume_consistency  #: the density relaxed towards the particles' packing at rate ε where the fluid has a free surface (0: off) (–)
    density_filter: int = RECOMMENDED.density_filter  #: Shepard density filter every this many steps; 0 drops it (–)
    negative_pressure: str = "free_surface"  #: tension treatment: allow, clamp, cavitate or free_surface (choice)
    h_factor: float = 1.3          #: smoothing length / particle spacing, h/dx (–)
    g: float = 9.81                #: gravitational acceleration (m/s²)
    gif: bool = True               #: render animation.gif and final.png (bool)


def internal_energy(s, n: int, c0: float, gamma: float = 7.0) -> float:
    """Stored energy of the Tait fluid of the first ``n`` particles of the fluid state ``s``,
    ``Σ M B/ρ0 [(r^{γ−1} − 1)/(γ−1) + 1/r − 1]`` (J/m)."""
    return float(np.sum(tait_stored_energy(s.M[:n], s.rho[:n] / s.rho0[:n], c0, gamma)))


def make_scene(p: Parameters = Parameters()) -> Scene:
    c0 = p.c0_factor * p.speed
    liquid = Phase("liquid", p.rho, p.viscosity)
    pool = lattice((0.0, 0.0), (p.pool_width, p.pool_depth), p.dx)
    R = 0.5 * p.drop_diameter
    centre = np.array([0.5 * p.pool_width, p.pool_depth + R + 1.5 * p.dx])
    box = lattice(centre - R - p.dx, centre + R + p.dx, p.dx)
    box = box - box.mean(axis=0) + centre  # centre the lattice on the drop
    drop = box[np.linalg.norm(box - centre, axis=1) < R]
    pos = np.vstack([pool, drop])
    vel = np.zeros_like(pos)
    vel[pool.shape[0]:, 1] = -p.speed
    depth = np.where(np.arange(len(pos)) < pool.shape[0], p.pool_depth - pos[:, 1], 0.0)
    rho = hydrostatic_density(np.full(len(pos), p.rho), depth, p.g, c0)
    body = FluidBody("liquid", pos, p.dx, [liquid], velocity=vel, density=rho)
    walls = wall_box((0.0, 0.0), (p.pool_width, 2.2 * p.pool_depth), p.dx, layers=3, reference_density=p.rho)
    n = body.n
    scheme = water(c0, u_max=p.speed, gravity=(0.0, -p.g), newtonian=True, alpha=p.alpha, delta=p.delta,
                   shifting=p.shifting, density_filter=p.density_filter, negative_pressure=p.negative_pressure,
                   consistent_integration=p.consistent_integration, linear_consistency=p.linear_consistency,
                   volume_consistency=p.volume_consistency,
                   spacing=p.dx, h_factor=p.h_factor)

    def total_energy(state) -> float:
        s = state.fluid
        ke = 0.5 * float(np.sum(s.M[:n] * np.einsum("ij,ij->i", s.v[:n], s.v[:n])))
        pe = float(np.sum(s.M[:n] * p.g * s.x[:n, 1]))
        return ke + pe + internal_energy(s, n, c0)

    return Scene(
        [body, walls],
        [scheme],
        t_end=p.t_end, name="drop_impact",
        output=Output(times=(0.0,) + tuple(t for t in PAPER_OUTPUT_TIMES if t <= p.t_end) + (p.t_end,),
                      probe_every=0.0005, gif=p.gif, png=p.gif, color_by="speed"),
        probes=[Probe("total_energy", total_energy),
                Probe("internal_energy", lambda state: internal_energy(state.fluid, n, c0))],
        parameters=dict(p.__dict__),
    )


def snapshot_figure(run_dir, out_png, color_by: str = "speed") -> None:
    """A grid of the frames of ``run_dir/particles.pvd`` (matplotlib), written atomically."""
    import io

    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from mlsgalerkin.io import atomic_write, read_pvd, read_vtu

    frames = read_pvd(run_dir / "particles.pvd")
    k = len(frames)
    cols = min(4, k)
    rows = (k + cols - 1) // cols
    fig, axes = plt.subplots(rows, cols, figsize=(3.2 * cols, 1.9 * rows), squeeze=False)
    vmax = None
    for ax, (t, path) in zip(axes.ravel(), frames):
        pts, data = read_vtu(path)
        val = np.asarray(data[color_by])
        wall = np.asarray(data["is_wall"]).astype(bool)
        vmax = vmax or float(np.percentile(val[~wall], 99.5)) or 1.0
        ax.scatter(pts[wall, 0], pts[wall, 1], s=0.3, c="0.6")
        ax.scatter(pts[~wall, 0], pts[~wall, 1], s=0.3, c=val[~wall], cmap="viridis", vmin=0, vmax=vmax)
        ax.set_title(f"t = {t:.4f} s", fontsize=8)
        ax.set_aspect("equal")
        ax.axis("off")
    for ax in axes.ravel()[k:]:
        ax.axis("off")
    fig.suptitle(f"drop impact, colour = {color_by} (0 to {vmax:.2g} m/s)", fontsize=9)
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=130, bbox_inches="tight")
    plt.close(fig)
    atomic_write(out_png, buf.getvalue())


def analyse(result, p: Parameters) -> dict:
    ts = result.timeseries
    E = np.asarray(ts["total_energy"])
    mass = np.asarray(ts["total_mass"])
    growth = float(np.max(E - E[0]))
    out = {
        "t_reached_s": float(ts["time"][-1]),
        "mass_change_kg": float(mass.max() - mass.min()),
        "energy_initial_J": float(E[0]), "energy_final_J": float(E[-1]),
        "energy_max_growth_J": growth,
        "energy_max_growth_relative_to_initial_kinetic": growth / float(ts["kinetic_energy"][0]),
        "energy_grows": bool(growth > 1e-3 * float(ts["kinetic_energy"][0])),
    }
    if result.out is not None:
        snapshot_figure(result.out, result.out / "snapshots.png")
        out["snapshots"] = "snapshots.png"
    out["headline"] = (f"reached t = {out['t_reached_s']:.4f} s; mass change {out['mass_change_kg']:.1e} kg; "
                       f"energy {out['energy_initial_J']:.4g} -> {out['energy_final_J']:.4g} J "
                       f"(max growth {out['energy_max_growth_relative_to_initial_kinetic']:+.2e} of the initial KE)")
    return out


def check(p: Parameters) -> list[str]:
    """Problems with the parameters (see ``mlsgalerkin.problem``)."""
    out = require_positive(p, "drop_diameter", "pool_width", "pool_depth", "speed", "rho", "dx", "t_end",
                           "c0_factor", "h_factor", "g")
    out += require_nonnegative(p, "viscosity", "alpha", "delta", "density_filter")
    out += require(p.shifting in SHIFTING_MODES,
                   f"shifting = {p.shifting!r}: choose one of {', '.join(SHIFTING_MODES)}")
    out += require(p.negative_pressure in NEGATIVE_PRESSURE_MODES,
                   f"negative_pressure = {p.negative_pressure!r}: choose one of {', '.join(NEGATIVE_PRESSURE_MODES)}")
    if not out:
        out += require(p.drop_diameter < p.pool_width,
                       f"the drop ({p.drop_diameter:g} m) must be narrower than the pool ({p.pool_width:g} m)")
        out += require(p.drop_diameter >= 4 * p.dx, f"dx = {p.dx:g} m leaves fewer than 4 particles across the drop; "
                                                    f"choose dx <= {p.drop_diameter / 4:g} m")
        out += require(p.pool_depth >= 3 * p.dx, f"dx = {p.dx:g} m leaves fewer than 3 particle rows in the pool; "
                                                 f"choose dx <= {p.pool_depth / 3:g} m")
    return out
