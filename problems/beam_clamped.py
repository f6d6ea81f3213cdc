r"""Dam break on a clamped elastic beam (Sun 2016): the wall the water hits bends and swings.

A water column ``0.1 m`` wide and ``0.2 m`` high stands against the left wall of a tank and
collapses at ``t = 0``; ``0.352 m`` from the left wall stands a steel-like beam clamped at its
base, ``0.304 m`` tall and ``6 mm`` thick (``E = 0.2`` GPa, ``47.16 kg/m``: ``ρ = 7860`` kg/m³;
Poisson's ratio, not given, 0.3). The surge hits the beam, runs up it and falls back; the tank
continues behind the beam so that water thrown over it lands on a floor. The beam is a
scikit-fem body (9-node Q2, plane stress so that the 2D body bends as the beam of Euler–Bernoulli
theory; one element through the thickness), loaded through the wall particles riding on it and
node-to-surface penalty contact (:class:`~mlsgalerkin.interactions.StructureCoupling`). By default
the coupling is explicit and the wall pressure does not see the beam's acceleration: with it
the explicit coupling diverged at 1.8 s (dx 4 mm); ``iterations=20`` with
``wall_acceleration=1`` runs the source's partitioned iteration instead (both are in
``verification/results/structure/``).

Reference: Sun (2016) reports the tip deflection oscillating with a period of about 0.6 s, close
to the beam's first dry period 0.5971 s (Euler–Bernoulli, clamped–free: ``T = 2π L²/(1.8751²
sqrt(EI/m))``), with small deflections that barely change the flow. Checked: the period of the
tip's horizontal displacement ``tip_x`` (m) after the first impact, against 0.5971 s and the 2D
beam's own dry period, and its largest deflection. The period is the peak of the tip signal's
spectrum from half a period after the first impact to the end (4 s by default, six periods).

Measured at the defaults (2026-12-04, with the volume consistency's loose side, its local part
and droplets; one thread, 403 s beside another run, 57 158 steps, commit 18d70bb;
``verification/results/structure/clamped.md``): tip period 0.5938 s (−0.6 % on the source; five
upward crossings of the mean), largest tip deflection 15.4 mm. The water settles as one body: at
4 s no particle stands above 0.07 m. Seven splash particles (0.56 % of the water) fly over the
tank's walls at 0.35–0.82 s and are taken out of the run (``summary.json`` →
``fluid.domain_exit``; two before the local part). **The geometric volume reads up to +1.33 %,
outside the 1 % goal** (at 1.02 s; above 1 % in 5 % of the samples from 0.8 to 1.5 s, 0.2 % from
1.5 to 2.5 s, none after; its largest 50 ms mean 0.88 %; 0.36 % on average after 1.5 s, −0.16 %
at 4 s). Before the local part it read +2.27 % (60 % of the samples from 0.8 to 1.5 s above 1 %),
without the loose side +6.52 % (``docs/theory/stabilisation.md`` §10). What is left is water at the
cavitation floor (``p = 0``, density ``ρ0``): the jet that climbs the beam at the first load and
stretches along itself, which no density relaxation can give volume; it carries +1.6 to +2.1 % at
the first load at 4 and 2 mm alike. ``--set loose_local=0`` leaves the local part out,
``--set loose_band=0`` the loose side, ``--set droplet_rate=0`` the droplets. How much of the
error the measure's threshold carries: the same frames on 32 pixels per spacing with a sharp
half-spacing threshold read 0.3–1.7 % less (:mod:`mlsgalerkin.fluid.distribution`).

**Where the volume error sat before the local part, at three spacings**
(``verification/volume_attribution.py``: each particle's share of the geometric volume against
its ``M/ρ``, frames every 0.05 s after the first load; the runs of commit 6eca64d):

At 4, 2.5 and 2 mm: largest volume error (time series) +2.27, +1.46 and +1.43 %; mean over the
frames +0.73, +0.72 and +0.70 %; over the last second (settled) +0.55, +0.54 and +0.52 %. The
particles with 1–4 neighbours within 1.5 spacings are 17.3, 11.6 and 10.1 % of the water, each
8.1, 8.6 and 9.6 % looser than its ``M/ρ``, and contribute +1.39, +1.00 and +0.98 %; the rest
contribute −0.74, −0.34 and −0.33 %.

The excess sits in the ragged free surface, in the linings of the voids (the model has no air) the breaking
run-up traps against the left wall (they form and close within a few frames), and in the
collapsing run-up against the beam (at 4 mm, 1.2–1.4 s: about 170 particles 1.06 spacings from
their nearest neighbour, against 0.92 in the rest, at 100–170 Pa); the rest of the water is
slightly tighter. The settled water sat at the loose side's band (0.5 %): the loose side relaxed
the error to it and no further. The excursions above 1 % during the splash (at 2 mm: 47 % of the
samples from 0.8 to 1.5 s, 9 % from 1.5 to 2.5 s, none after) fell from 4 to 2.5 mm and hardly
from 2.5 to 2 mm, so a finer spacing alone did not bring this flow within 1 %. The local part
reaches that water (the collapsing run-up carries pressure, so its density can fall); what is left
is at the cavitation floor.
At ``--dx 0.0025`` (one thread, 1 516 s beside another run, 92 135 steps, 2026-12-04, with the
local part) the tip period reads 0.5928 s (−0.7 %), largest tip deflection 16.9 mm, the volume up
to +1.23 % (at 0.43 s, the jet at the first load; above 1 % in 73 samples from 0.25 to 0.5 s and one after; +0.43 % over
the last second; +1.46 % and 0.5942 s before the local part); at ``--dx 0.002`` (1 830 s on two
threads, 114 783 steps, with the local part) 0.5936 s (−0.6 %), 16.2 mm, the volume up to +1.30 %
(at 0.41 s, the jet again; +1.43 % and 0.5949 s before the local part); no particle
behind a wall. ``--set void_memory=0.2`` (the floor remembers part of the expansion) gave 3.0 %
before the volume consistency joined the set (period 0.5858 s, −1.9 %); it raises the pressure
noise of the dam break with impact.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from skfem import MeshQuad

from mlsgalerkin.analysis.measured import not_measured
from mlsgalerkin.analysis.signals import crossing_period, spectral_period
from mlsgalerkin.fluid import (
    SHIFTING_MODES,
    FluidBody,
    Phase,
    WallBody,
    hydrostatic_density,
    wall_box,
    water,
)
from mlsgalerkin.fluid.eos import NEGATIVE_PRESSURE_MODES
from mlsgalerkin.fluid.presets import RECOMMENDED
from mlsgalerkin.interactions import StructureCoupling
from mlsgalerkin.problem import (
    numerical_dissipation,
    require,
    require_nonnegative,
    require_positive,
)
from mlsgalerkin.scene import Output, Probe, Scene
from mlsgalerkin.structure import ElasticBody, ElasticMaterial
from mlsgalerkin.structure.checks import (
    explicit_substep_problems,
    mesh_size_problems,
    poisson_problems,
)

__all__ = ["Parameters", "make_scene", "analyse", "check", "SMOKE", "euler_bernoulli_period"]

SMOKE = {"dx": 0.02, "t_end": 0.01, "elements": 8}
#: The source's first dry period of the beam (s).
SOURCE_PERIOD = 0.5971


@dataclass(frozen=True)
class Parameters:
    column_width: float = 0.1     #: water column width (m)
    column_height: float = 0.2    #: water column height H (m)
    beam_x: float = 0.352         #: distance from the left wall to the beam's wet face (m)
    beam_height: float = 0.304    #: beam length above its clamped base (m)
    thickness: float = 0.006      #: beam thickness (m)
    young: float = 0.2e9          #: beam Young's modulus (Pa)
    poisson: float = 0.3          #: beam Poisson's ratio, not given by the source (–)
    rho_beam: float = 47.16 / 0.006  #: beam density, 47.16 kg/m over 6 mm (kg/m³)
    elements: int = 38            #: Q2 elements along the beam (one through its thickness) (–)
    integrator: str = "explicit"  #: beam time integrator: explicit or newmark (choice)
    wall_acceleration: float = 0.0  #: share of the beam's acceleration the wall pressure sees, 0 to 1 (–)
    iterations: int = 1           #: passes of the partitioned iteration per step; 1 is the explicit coupling (–)
    tank_length: float = 0.6      #: tank length; the floor continues behind the beam (m)
    dx: float = 0.004             #: particle spacing (m)
    t_end: float = 4.0            #: end time (s)
    rho: float = 1000.0           #: water density (kg/m³)
    alpha: float = RECOMMENDED.alpha  #: Monaghan artificial viscosity α (–)
    delta: float = RECOMMENDED.delta  #: density diffusion δ (δ-SPH) (–)
    shifting: str = RECOMMENDED.shifting  #: particle shifting: local, design or off (choice)
    negative_pressure: str = "cavitate"  #: tension treatment: allow, clamp, cavitate or free_surface (choice)
    void_memory: float = 0.0      #: void strain a cavitated particle remembers, 0 for none (cavitate only) (–)
    linear_consistency: bool = RECOMMENDED.linear_consistency  #: the pressure's linear fit integrated exactly, with the free-surface term (bool)
    volume_consistency: float = RECOMMENDED.volume_consistency  #: the density relaxed towards the particles' packing at rate ε where the fluid has a free surface (0: off) (–)
    loose_band: float = RECOMMENDED.loose_band  #: the volume consistency's loose side: past this volume error the density outside the deep bulk relaxes (0: off; off with the volume consistency) (–)
    loose_local: float = RECOMMENDED.loose_local  #: the loose side's local part: weight of each loose particle's neighbourhood excess, away from the walls (0: off) (–)
    droplet_rate: float = RECOMMENDED.droplet_rate  #: droplets (fewer neighbours than a line) relax to the rest density at this rate, in c0/h (0: off; off with the volume consistency) (–)
    c0_factor: float = 10.0       #: sound speed / 2 sqrt(gH) (–)
    g: float = 9.81               #: gravitational acceleration (m/s²)
    probe_every: float = 1.0e-3   #: time between time-series rows (s)
    frame_every: float = 0.05     #: time between VTU frames (s)
    gif: bool = False             #: render animation.gif and final.png (bool)


def euler_bernoulli_period(p: Parameters) -> float:
    """First period ``2π L²/(1.8751² sqrt(EI/m))`` (s) of the clamped–free beam, per unit width."""
    EI = p.young * p.thickness**3 / 12.0
    m = p.rho_beam * p.thickness
    return 2.0 * math.pi * p.beam_height**2 / (1.875104**2 * math.sqrt(EI / m))


def _beam(p: Parameters) -> ElasticBody:
    x0, x1 = p.beam_x, p.beam_x + p.thickness
    mesh = MeshQuad.init_tensor(np.array([x0, x1]), np.linspace(0.0, p.beam_height, p.elements + 1))
    return ElasticBody("beam", mesh, ElasticMaterial(p.young, p.poisson, p.rho_beam, plane="stress"), "Q2",
                       clamped=lambda x: np.isclose(x[1], 0.0), wet=lambda x: ~np.isclose(x[1], 0.0),
                       integrator=p.integrator, gravity=(0.0, -p.g),
                       points={"tip": (x0 + 0.5 * p.thickness, p.beam_height)})


def make_scene(p: Parameters = Parameters()) -> Scene:
    H = p.column_height
    u_max = 2.0 * math.sqrt(p.g * H)
    c0 = p.c0_factor * u_max
    water_body = FluidBody.block("water", (0.0, 0.0), (p.column_width, H), p.dx, [Phase("water", p.rho)])
    water_body.density[:] = hydrostatic_density(np.full(water_body.n, p.rho), H - water_body.positions[:, 1], p.g, c0)
    wall_top = math.ceil(1.5 * p.beam_height / p.dx) * p.dx
    tank = wall_box((0.0, 0.0), (p.tank_length, wall_top), p.dx, layers=3, reference_density=p.rho, surface=True)
    beam = _beam(p)
    # as many layers as fit inside the beam (a particle deeper than the beam would stand in the
    # water on its other side)
    layers = max(1, min(3, int(p.thickness / p.dx)))
    riding = WallBody.on_surface("beam_walls", beam.wet.contact_surface(), p.dx, follows="beam", layers=layers,
                                 reference_density=p.rho)
    coupling = StructureCoupling("water", "beam", walls="beam_walls", thickness=0.25 * p.dx,
                                 wall_acceleration=p.wall_acceleration, iterations=p.iterations, tolerance=1e-7)
    scheme = water(c0, u_max=u_max, gravity=(0.0, -p.g), alpha=p.alpha, delta=p.delta, shifting=p.shifting,
                   negative_pressure=p.negative_pressure, void_memory=p.void_memory, penalty_thickness=0.25 * p.dx,
                   linear_consistency=p.linear_consistency,
                   volume_consistency=p.volume_consistency,
                   loose_band=p.loose_band if p.volume_consistency else 0.0, droplet_rate=p.droplet_rate,
                   loose_local=p.loose_local, spacing=p.dx)

    def tip_x(state) -> float:
        m = state.body("beam")
        return float(beam.point_displacements(m.u)["tip"][0])

    return Scene(
        [water_body, tank, riding, beam], [scheme], t_end=p.t_end, name="beam_clamped", interactions=[coupling],
        output=Output(every=p.frame_every, probe_every=p.probe_every, gif=p.gif, png=p.gif, color_by="pressure"),
        probes=[Probe("tip_x", tip_x)], parameters=dict(p.__dict__),
    )


def oscillation_period(t: np.ndarray, y: np.ndarray, start: float) -> tuple[float, int]:
    """Mean period (s) of ``y`` after ``start`` from its upward crossings of its own mean, and the
    number of periods it is measured over (:func:`~mlsgalerkin.analysis.signals.crossing_period`)."""
    sel = t >= start
    return crossing_period(t[sel], y[sel])


def dominant_period(t: np.ndarray, y: np.ndarray, start: float, band: tuple[float, float] = (0.3, 1.5)) -> float:
    """The period (s) of the strongest oscillation of ``y`` after ``start`` within ``band``: the peak
    of the amplitude spectrum (Hann window, linear trend removed, zero-padded eightfold, the peak
    refined by a parabola through its three bins; :func:`~mlsgalerkin.analysis.signals.spectral_period`);
    NaN with fewer than 16 samples."""
    sel = t >= start
    if sel.sum() < 16:
        return float("nan")
    return spectral_period(t[sel], y[sel], detrend=1, hann=True, pad=8, band=band, refine=True)


#: Whole periods of the source the tip must swing through after the first impact (from half a
#: period after it) before its period is measured.
PERIODS_NEEDED = 2


def analyse(result, p: Parameters) -> dict:
    """The tip's period after the first impact (spectral peak and upward crossings) against the
    source and the 2D beam's dry period, measured only when the run covered ``PERIODS_NEEDED``
    periods after the first impact."""
    ts = result.timeseries
    t = np.asarray(ts["time"])
    tip = np.asarray(ts["tip_x"])
    beam = _beam(p)
    dry = 2.0 * math.pi / beam.lowest_frequency()
    out = {
        "tip_x_max_m": float(tip.max()), "tip_x_min_m": float(tip.min()),
        "source_period_s": SOURCE_PERIOD, "euler_bernoulli_period_s": euler_bernoulli_period(p),
        "dry_period_2d_model_s": dry,
    }
    out.update(numerical_dissipation(result, 2.0 * math.sqrt(p.g * p.column_height), p.column_height))
    largest = 1e3 * max(abs(out["tip_x_max_m"]), abs(out["tip_x_min_m"]))
    keys = ("first_load_s", "crossing_period_s", "period_s", "period_error_vs_source", "period_error_vs_dry_model")
    # the surge front runs at about 2 sqrt(g H) (Ritter): the earliest the water can reach the beam
    earliest = (p.beam_x - p.column_width) / (2.0 * math.sqrt(p.g * p.column_height))
    moved = np.abs(tip).max() > 0 and t[-1] >= earliest
    hit = float(t[np.argmax(np.abs(tip) > 0.05 * np.abs(tip).max())]) if moved else math.nan
    start = (hit if moved else earliest) + 0.5 * SOURCE_PERIOD
    needed = start + PERIODS_NEEDED * SOURCE_PERIOD
    if t[-1] < needed:
        why = (f"the run ended at t = {t[-1]:.3g} s, before {PERIODS_NEEDED} periods of the tip after the first "
               + (f"load at {hit:.3f} s" if moved else f"load (the surge reaches the beam at about {earliest:.2f} s)"))
        text = not_measured(out, keys, why, run_to=needed)
        out["periods_measured"] = 0
        out["headline"] = f"tip period {text}; largest tip deflection up to t = {t[-1]:.3g} s: {largest:.2f} mm"
        return out
    period, cycles = oscillation_period(t, tip, start)
    spectral = dominant_period(t, tip, start)
    out.update({"first_load_s": hit, "crossing_period_s": period, "periods_measured": cycles, "period_s": spectral})
    if not math.isfinite(period):
        not_measured(out, "crossing_period_s", "fewer than two upward crossings of the mean after the first load")
    if not math.isfinite(spectral):
        text = not_measured(out, ("period_s", "period_error_vs_source", "period_error_vs_dry_model"),
                            "no spectral peak within 0.3-1.5 s after the first load")
        out["headline"] = f"tip period {text}; largest tip deflection {largest:.2f} mm"
        return out
    out["period_error_vs_source"] = spectral / SOURCE_PERIOD - 1.0
    out["period_error_vs_dry_model"] = spectral / dry - 1.0
    out["headline"] = (f"tip period {spectral:.4f} s (spectral peak; {cycles} upward crossings) vs 0.5971 s dry (source; the 2D beam's own "
                       f"{dry:.4f} s), largest tip deflection {largest:.2f} mm")
    return out


def check(p: Parameters) -> list[str]:
    """Problems with the parameters (see ``mlsgalerkin.problem``)."""
    out = require_positive(p, "column_width", "column_height", "beam_x", "beam_height", "thickness", "young",
                           "rho_beam", "elements", "tank_length", "dx", "t_end", "rho", "c0_factor", "g",
                           "probe_every", "frame_every")
    out += require_nonnegative(p, "alpha", "delta", "wall_acceleration", "void_memory", "loose_band", "loose_local", "droplet_rate")
    out += require(p.void_memory == 0 or p.negative_pressure == "cavitate",
                   f"void_memory acts with negative_pressure=cavitate only, got {p.negative_pressure!r}")
    out += require(p.wall_acceleration <= 1.0, f"wall_acceleration is a share in [0, 1], got {p.wall_acceleration!r}")
    out += require(isinstance(p.iterations, int) and p.iterations >= 1, f"iterations must be >= 1, got {p.iterations!r}")
    out += poisson_problems(p.poisson, "the beam's material")
    out += mesh_size_problems(p.elements, "the beam's mesh")
    out += require(p.integrator in ("explicit", "newmark"), f"integrator must be explicit or newmark, got {p.integrator!r}")
    out += require(p.shifting in SHIFTING_MODES, f"shifting must be one of {SHIFTING_MODES}, got {p.shifting!r}")
    out += require(p.negative_pressure in NEGATIVE_PRESSURE_MODES,
                   f"negative_pressure must be one of {NEGATIVE_PRESSURE_MODES}, got {p.negative_pressure!r}")
    if not out:
        out += require(p.beam_x >= p.column_width + p.dx,
                       f"the beam at x = {p.beam_x:g} m stands in the water column ({p.column_width:g} m wide); move it "
                       "further from the left wall")
        out += require(p.tank_length >= p.beam_x + p.thickness + 2 * p.dx,
                       f"tank_length = {p.tank_length:g} m ends inside or just behind the beam; make it at least "
                       f"{p.beam_x + p.thickness + 2 * p.dx:g} m")
        out += require(min(p.column_width, p.column_height) >= 4 * p.dx,
                       f"dx = {p.dx:g} m leaves fewer than 4 particles across the column; choose dx <= "
                       f"{min(p.column_width, p.column_height) / 4:g} m")
        if p.integrator == "explicit":   # Q2 elements, one through the thickness
            out += explicit_substep_problems("the beam", p.young, p.poisson, p.rho_beam,
                                             0.5 * min(p.thickness, p.beam_height / p.elements), p.t_end,
                                             plane="stress")
    return out
