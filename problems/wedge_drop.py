r"""Free drop of a rigid 30° wedge into calm water (Zhao, Faltinsen & Aarsnes 1996).

A symmetric wedge of dead-rise angle 30°, 0.5 m wide (keel-to-knuckle height 0.144 m, vertical
sides above the knuckles), of mass 241 kg per metre of length, touches the calm surface of a tank
2 m wide and 1 m deep with its keel at ``t = 0``, falling at 6.15 m/s. It moves vertically only
(a :class:`~mlsgalerkin.structure.RigidBody` with the ``"vertical"`` constraint, with its
weight). The water slows it; the vertical force rises to a peak at about 15 ms as the wetted
width grows, then falls once the flow separates at the knuckles. The water loads the wedge
through the wall particles riding on it and node-to-surface penalty contact
(:class:`~mlsgalerkin.interactions.StructureCoupling`); the wall pressure sees the wedge's
acceleration (the wedge is 40 times heavier than the water layer its wall particles stand for).

Reference: the drop test of Zhao et al. (1996) (shipped as
``mlsgalerkin/data/zhao_1996_wedge_drop.csv``): the wedge's velocity ``velocity`` (m/s, downward
positive) and the vertical force ``force`` (N) on the 0.2 m long measuring section (the 2D
force per metre times 0.2 m), every 2.5 ms to 25 ms. Checked: the velocity within 3 % at every
reference time, the peak force within 15 % and its time within 3 ms. The two measured curves do
not agree with each other in 2D: a wedge of 241 kg/m slowed by the measured sectional force
(``v0 + g t − ∫F dt/(0.2 m · 241 kg/m)``) is 3.6 % slower at 25 ms than the measured velocity
(the ends of the 1 m model carry less force than its middle section), so the velocity is also
compared with that force-consistent velocity (``velocity_max_error_vs_measured_force``).

Physics listed: Tait pressure with ``c0 = c0_factor · V0``, gravity, free-slip wall particles,
Monaghan viscosity, δ-SPH density diffusion, particle shifting and the tension treatment, as in
``dam_break_impact``, except that tension is released at free-surface particles
(``negative_pressure="free_surface"``, as in ``drop_impact``): where the flow leaves the knuckles
the cavitation floor held the water to the wedge, and the velocity at 25 ms was 5–7 % low at
every resolution (measured at 20 and 10 mm; 2.9 % at 5 mm with the release).

Measured at the one recommended set (``verification/results/structure/wedge.md``, every row
rerun at the current set: 10 and 5 mm on 2026-12-04 at commit f9f85f6, 2.5 mm on 2026-12-04 at
commit 6eca64d, one thread a run, 2 882 s for the 2.5 mm run): at 10, 5 and 2.5 mm the velocity
is within 4.86, 3.21 and 3.31 % (1.72, 1.02 and 0.55 % of the force-consistent velocity), the
peak force **+21.6, +11.4 and +3.7 %** at −0.7, +1.0 and +0.6 ms, the force's RMS error 410, 574
and 334 N: the force converges on the measurement. (The 2.5 mm row of 2026-12-03, at commit
a2a2d2d, read +56.5 %: two time-series samples, 6035 and 8061 N, taken as a particle left the
spray root at 57 m/s, with the rest of its record at +3.1 %. The run at the current set has no
such spike.) (The previous table, before the linear
consistency's surface fix: +21.6, +14.1 and +5.8 %, velocity 4.40, 3.99 and 3.20 %.) Direct
nodal integration read 5.06, 2.94 and 3.26 %; +18.2, +9.4 and +5.8 %. The velocity misses the
3 % against the measured curve at every resolution, inside the 3.6 % by which the two measured
curves disagree.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from mlsgalerkin.analysis.measured import not_measured
from mlsgalerkin.contact import ContactSurface
from mlsgalerkin.data import reference_columns
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
from mlsgalerkin.structure import RigidBody

__all__ = ["Parameters", "make_scene", "analyse", "check", "load_reference", "wedge_surface", "SMOKE"]

SMOKE = {"dx": 0.05, "t_end": 0.002, "tank_width": 1.0, "depth": 0.5}
#: Length of the measuring section the reference force acts on (m).
SECTION = 0.2


@dataclass(frozen=True)
class Parameters:
    deadrise_deg: float = 30.0    #: dead-rise angle, from the horizontal at the keel (deg)
    breadth: float = 0.5          #: wedge breadth between the knuckles (m)
    side_height: float = 0.2      #: height of the vertical sides above the knuckles (m)
    mass: float = 241.0           #: wedge mass per metre of length (kg/m)
    velocity: float = 6.15        #: downward speed at the keel's first touch (m/s)
    tank_width: float = 2.0       #: tank width (m)
    depth: float = 1.0            #: water depth (m)
    dx: float = 0.01              #: particle spacing (m)
    t_end: float = 0.025          #: end time (s)
    wall_acceleration: float = 1.0  #: share of the wedge's acceleration the wall pressure sees, 0 to 1 (–)
    rho: float = 1000.0           #: water density (kg/m³)
    alpha: float = RECOMMENDED.alpha  #: Monaghan artificial viscosity α (–)
    delta: float = RECOMMENDED.delta  #: density diffusion δ (δ-SPH) (–)
    shifting: str = RECOMMENDED.shifting  #: particle shifting: local, design or off (choice)
    negative_pressure: str = "free_surface"  #: tension treatment: allow, clamp, cavitate or free_surface (choice)
    linear_consistency: bool = RECOMMENDED.linear_consistency  #: the pressure's linear fit integrated exactly, with the free-surface term (bool)
    volume_consistency: float = RECOMMENDED.volume_consistency  #: the density relaxed towards the particles' packing at rate ε where the fluid has a free surface (0: off) (–)
    c0_factor: float = 10.0       #: sound speed / entry speed (–)
    g: float = 9.81               #: gravitational acceleration (m/s²)
    probe_every: float = 2.5e-4   #: time between time-series rows (s)
    frame_every: float = 0.005    #: time between VTU frames (s)
    gif: bool = False             #: render animation.gif and final.png (bool)


def wedge_surface(p: Parameters, keel: tuple[float, float]) -> ContactSurface:
    """The wedge's outline, counter-clockwise (normals out of the wedge): keel, right knuckle,
    right top, left top, left knuckle."""
    x, y = keel
    b = 0.5 * p.breadth
    k = b * math.tan(math.radians(p.deadrise_deg))
    top = k + p.side_height
    pts = [(x, y), (x + b, y + k), (x + b, y + top), (x - b, y + top), (x - b, y + k)]
    return ContactSurface.polyline(pts, closed=True)


def load_reference() -> dict[str, np.ndarray]:
    """Zhao et al. (1996): ``t`` (s), ``force`` (N on the 0.2 m section), ``velocity`` (m/s)."""
    cols = reference_columns("zhao_1996_wedge_drop.csv")
    return {"t": cols["t_ms"] * 1e-3, "force": cols["force_measured_N"], "velocity": cols["velocity_measured_m_s"]}


def make_scene(p: Parameters = Parameters()) -> Scene:
    c0 = p.c0_factor * p.velocity
    half = 0.5 * p.tank_width
    water_body = FluidBody.block("water", (-half, 0.0), (half, p.depth), p.dx, [Phase("water", p.rho)])
    water_body.density[:] = hydrostatic_density(np.full(water_body.n, p.rho), p.depth - water_body.positions[:, 1], p.g, c0)
    top = math.ceil(1.6 * p.depth / p.dx) * p.dx
    tank = wall_box((-half, 0.0), (half, top), p.dx, layers=3, reference_density=p.rho, surface=True)
    surface = wedge_surface(p, (0.0, p.depth))
    nodes = surface.nodes
    centre = nodes.mean(axis=0)   # the mass centre's height does not enter a vertical-only motion
    wedge = RigidBody("wedge", surface, p.mass, p.mass * p.breadth**2 / 12.0, centre, constraint="vertical",
                      velocity=np.array([0.0, -p.velocity]), gravity=np.array([0.0, -p.g]))
    riding = WallBody.on_surface("wedge_walls", surface, p.dx, follows="wedge", reference_density=p.rho)
    coupling = StructureCoupling("water", "wedge", walls="wedge_walls", thickness=0.25 * p.dx,
                                 wall_acceleration=p.wall_acceleration)
    scheme = water(c0, u_max=p.velocity, gravity=(0.0, -p.g), alpha=p.alpha, delta=p.delta, shifting=p.shifting,
                   negative_pressure=p.negative_pressure, penalty_thickness=0.25 * p.dx,
                   linear_consistency=p.linear_consistency,
                   volume_consistency=p.volume_consistency, spacing=p.dx)

    def velocity(state) -> float:
        return -float(state.body("wedge").V[1])

    def force(state) -> float:
        return SECTION * float(state.body("wedge").F[1])

    return Scene(
        [water_body, tank, riding, wedge], [scheme], t_end=p.t_end, name="wedge_drop", interactions=[coupling],
        output=Output(every=p.frame_every, probe_every=p.probe_every, gif=p.gif, png=p.gif, color_by="pressure"),
        probes=[Probe("velocity", velocity), Probe("force", force)], parameters=dict(p.__dict__),
    )


#: The run must reach this multiple of the reference force peak's time before a peak is measured.
PEAK_MARGIN = 1.25


def analyse(result, p: Parameters) -> dict:
    """Velocity and force against Zhao et al. (errors over every reference point, once the run
    covered them all) and the force peak (once the run is past ``PEAK_MARGIN`` times the reference
    peak's time and the force has fallen from its largest value)."""
    ts = result.timeseries
    t = np.asarray(ts["time"])
    v, f = np.asarray(ts["velocity"]), np.asarray(ts["force"])
    ref = load_reference()
    kr = int(np.argmax(ref["force"]))
    out = {"reference_force_peak_N": float(ref["force"][kr]), "reference_force_peak_time_s": float(ref["t"][kr])}
    # the velocity a 2D wedge of this mass would have under the measured sectional force:
    # v_F = v0 + g t − ∫ F dt / (m · SECTION); the measured velocity and force disagree with it
    v_force = p.velocity + p.g * ref["t"] - np.concatenate(
        [[0.0], np.cumsum(0.5 * (ref["force"][1:] + ref["force"][:-1]) * np.diff(ref["t"]))]) / (p.mass * SECTION)
    out["velocity_from_measured_force_error"] = float(np.max(np.abs(v_force / ref["velocity"] - 1.0)))
    if ref["t"][-1] <= t[-1] + 1e-6:    # the run covered the reference (to a microsecond of round-off)
        inside = ref["t"] <= t[-1] + 1e-12
        v_err = np.interp(ref["t"][inside], t, v) / ref["velocity"][inside] - 1.0
        out["velocity_max_error"] = float(np.max(np.abs(v_err)))
        out["velocity_errors"] = v_err.tolist()
        out["force_rms_error_N"] = float(np.sqrt(np.mean((np.interp(ref["t"][inside], t, f) - ref["force"][inside]) ** 2)))
        out["velocity_max_error_vs_measured_force"] = float(
            np.max(np.abs(np.interp(ref["t"][inside], t, v) / v_force[inside] - 1.0)))
        velocity_text = f"velocity within {100 * out['velocity_max_error']:.2f} %"
    else:
        velocity_text = "velocity " + not_measured(
            out, ("velocity_max_error", "velocity_errors", "force_rms_error_N", "velocity_max_error_vs_measured_force"),
            f"the run ended at t = {1e3 * t[-1]:.3g} ms, before the reference's last point at "
            f"{1e3 * ref['t'][-1]:.3g} ms", run_to=float(ref["t"][-1]))
    k = int(np.argmax(f))
    peak_after = PEAK_MARGIN * out["reference_force_peak_time_s"]
    peak_keys = ("force_peak_N", "force_peak_time_s", "force_peak_error", "force_peak_time_error_s")
    if t[-1] < peak_after:
        force_text = not_measured(out, peak_keys, f"the run ended at t = {1e3 * t[-1]:.3g} ms, before the reference "
                                                  f"peak at {1e3 * out['reference_force_peak_time_s']:.3g} ms had passed",
                                  run_to=peak_after)
    elif k == t.size - 1:
        force_text = not_measured(out, peak_keys, "the force was still rising at the end of the run",
                                  run_to=t[-1] + 0.25 * out["reference_force_peak_time_s"])
    else:
        out["force_peak_N"], out["force_peak_time_s"] = float(f[k]), float(t[k])
        out["force_peak_error"] = out["force_peak_N"] / out["reference_force_peak_N"] - 1.0
        out["force_peak_time_error_s"] = out["force_peak_time_s"] - out["reference_force_peak_time_s"]
        force_text = ""
    out.update(numerical_dissipation(result, p.velocity, 0.5 * p.breadth))
    measured = f"{out['force_peak_N']:.0f} N at {1e3 * out['force_peak_time_s']:.1f} ms" if not force_text else force_text
    versus = (f" ({100 * out['force_peak_error']:+.1f} %, {1e3 * out['force_peak_time_error_s']:+.1f} ms)"
              if not force_text else "")
    reference = f"{out['reference_force_peak_N']:.0f} N at {1e3 * out['reference_force_peak_time_s']:.1f} ms"
    out["headline"] = (f"{velocity_text}; peak force {measured} vs {reference}{versus}" if not force_text
                       else f"{velocity_text}; peak force {measured} (reference {reference})")
    return out


def check(p: Parameters) -> list[str]:
    """Problems with the parameters (see ``mlsgalerkin.problem``)."""
    out = require_positive(p, "deadrise_deg", "breadth", "side_height", "mass", "velocity", "tank_width", "depth",
                           "dx", "t_end", "rho", "c0_factor", "g", "probe_every", "frame_every")
    out += require_nonnegative(p, "alpha", "delta", "wall_acceleration")
    out += require(p.deadrise_deg < 80.0, f"deadrise_deg must be below 80°, got {p.deadrise_deg!r}")
    out += require(p.wall_acceleration <= 1.0, f"wall_acceleration is a share in [0, 1], got {p.wall_acceleration!r}")
    out += require(p.shifting in SHIFTING_MODES, f"shifting must be one of {SHIFTING_MODES}, got {p.shifting!r}")
    out += require(p.negative_pressure in NEGATIVE_PRESSURE_MODES,
                   f"negative_pressure must be one of {NEGATIVE_PRESSURE_MODES}, got {p.negative_pressure!r}")
    if not out:
        out += require(p.tank_width >= 2.0 * p.breadth, "the tank must be at least twice as wide as the wedge")
        out += require(min(p.breadth, p.depth) >= 8 * p.dx,
                       f"dx = {p.dx:g} m leaves fewer than 8 particles across the wedge or the depth")
    return out
