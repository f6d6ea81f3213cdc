r"""Gravity current (lock exchange) of Cueto-Felgueroso et al. (2005).

A 2D tank of depth ``D`` holds light fluid (``rho_light``) left of a lock at mid-length and
heavy fluid (``rho_heavy``) right of it; the lock is removed at ``t = 0`` and the heavy fluid
runs under the light one towards the left wall. Reference head speed (Rottman & Simpson 1983,
as quoted by Cueto-Felgueroso et al. 2005):

.. math:: v_h \approx 0.4 \sqrt{g D \,\Delta\rho/\rho_0},\qquad \rho_0 = \rho_{light},

0.217 m/s for ``D = 0.06`` m and ``Δρ/ρ0 = 0.5`` (their simulation gave about 0.2 m/s).
The tank length (0.34 m at their 5100 particles with ``Δx = 2`` mm, 30 × 170), the rigid
lid on top, no-slip walls and ``c0 = 10 max(2.5 v_h, sqrt(g D))`` (7.7 m/s: ten times the
long-wave speed ``sqrt(g D) = 0.77`` m/s) are this reproduction's choices. No-slip walls are
a laboratory tank's, with the water viscosity 1e-3 Pa s: measured at ``D = 0.04`` m and 20
rows, free-slip walls let the head run 13–15 % fast (Froude number 0.45–0.46, near
Benjamin's energy-conserving 0.5), no-slip walls 3–7 % slow (measured at commit d983bcb; the
3 × 3 matrix of ``verification/results/fluid_core/gravity.md``). The no-slip wall particles
continue the fluid's tangential velocity to their own depth, with the normal component
mirrored, and the Newtonian viscosity is stabilised (``docs/theory/galerkin_fluid.md`` §6, §13):
with direct nodal integration the default case (``D = 0.06`` m, ``Δρ/ρ0 = 0.5``, ``Δx = 3`` mm)
ran +6.0 %, at ``Δx = 6`` mm −8.9 %; with the normal component continued too −0.1 % and −14.4 %, with the top row's
pressure spread (median) 4113 and 2907 Pa instead of 532 and 364 Pa
(``verification/results/quiet_state/lid_clumping.md``). The particles start at the compressible
hydrostatic densities (``hydrostatic_density(..., compressible=True)``). The simulated tank is
``length`` and ``depth`` rounded to whole spacings (:func:`tank`), so the fluid fills it.

Stabilisation: the recommended set (``mlsgalerkin.fluid.RECOMMENDED``: δ-SPH density diffusion
within each phase, local shifting, the pressure's linear fit integrated exactly, with a fixed
hydrostatic reference under the lid where the fit falls back) except a lower
Monaghan ``α = 0.01``, plus the tank's penalty surface. The head is slow: its numerical Reynolds
number ``v_h D/ν`` with ``ν = α h c0/8`` is about 170 at the recommended ``α = 0.02`` at 20 rows
(reported in ``summary.json``), and there the head runs 8–10 % slow where ``α = 0.01`` gives
−5 to +4 % (``D = 0.04`` and 0.06 m, ``Δρ/ρ0 = 0.5``): of the nine cases at 20 rows in the scaled
tank all 9 are within 10 % at ``α = 0.01``, 8 at ``α = 0.02`` (−10.04 % at ``D = 0.04`` m,
``Δρ/ρ0 = 1``). Under the lid the pressure level is free (the fluid is closed in):
the tank starts at ``lid_pressure_factor · ρ_heavy g D`` under the lid (default 1), and
:class:`~mlsgalerkin.fluid.ClosedVolume` holds the closed tank's volume (``closed_volume``).
Without it the collocated continuity equation lost about 1 % of the volume per second under the
lid, the lid's pressure level ran out in about 0.8 s, and the top row went into tension and
clumped (``lid_clumping.md``; ``docs/theory/stabilisation.md`` §9).

Measured (``verification/results/fluid_core/gravity.md``, rerun 2026-12-05 with the hydrostatic
reference at one numba thread a run; the 3 × 3 matrix of ``D`` = 0.04, 0.06, 0.12 m and ``Δρ/ρ0`` =
0.1, 0.5, 1): every run completes; within 10 % of the formula are **9 of 9 in this 0.34 m tank at
the default spacing, 20 rows per depth** (−9.9 to +1.0 %), 8 of 9 in the tank scaled with the depth
at 20 rows (−10.6 to +1.0 %; −10.6 % at ``D = 0.04`` m, ``Δρ/ρ0 = 0.1``) and 6 of 9 at a fixed ``Δx
= 3`` mm (the default before 2026-12-04), which is 13 rows at ``D = 0.04`` m (−15.3, −10.6 and
−12.3 %; the heads converge from below) and 40 at 0.12 m (−0.5, +9.5 and +9.3 %). Both fronts
(``analyse`` reports ``light_froude_number`` and ``front_speed_ratio``, the light front's speed
over the heavy head's): the Boussinesq exchanges (``Δρ/ρ0 = 0.1``) run alike, the light front at
0.93–0.98 of the head; the strong stratifications are not Boussinesq, and their light front runs at
0.69–0.87 of the head. The Boussinesq heads converge from below: the deep exchange ``D = 0.12`` m,
``Δρ/ρ0 = 0.1`` runs −6.9, −0.5 and +2.8 % at 20, 40 and 60 rows with the fronts at 0.98, 0.95 and
0.98 (``verification/results/fluid_core/gravity_lid.md``, ``python verification/fluid_core.py
--section gravity_lid``): at the default 20 rows the symmetric exchange runs at Froude number
0.36–0.37 in the weak stratifications, 7–11 % under the formula. The issue's deep weakly stratified
case (``D = 0.09`` m, ``Δρ/ρ0 = 0.05``) runs −8.9 % at the default spacing (20 rows) and −2.4 % at
3 mm (30 rows), the light front at 0.97 and 0.94 of the head's speed. Pairs: at most 7 clumped
pairs in the 0.34 m tank at the default spacing but at ``D = 0.04`` m, ``Δρ/ρ0 = 1`` (26, late, on
the no-slip floor where light particles are left under the heavy current); at ``Δρ/ρ0 = 1`` the
scaled tank and 3 mm rows pair more too (12–23; before 4–9). The weakest stratification,
``Δρ/ρ0 = 0.03`` at ``D = 0.12`` m and 40 rows, runs −3.5 % with the fronts alike (1.03; before
+51.2 %, 0.32); with a free surface, which the reference does not reach, +47.0 % and 0.51.

Before 2026-12-05 (``--set hydrostatic_reference=false`` runs it): the head met the formula in both
tanks (9 of 9, −9.6 to +9.2 %) while the exchange was lopsided, the light front at 0.37–0.83 of the
head, and weakly stratified exchanges ran faster with resolution (``D = 0.12`` m, ``Δρ/ρ0 = 0.1``:
−8.4, +20.5 and +31.6 % at 20, 40 and 60 rows, the light front at 0.83, 0.68 and 0.61 of the head;
``D = 0.09`` m, ``Δρ/ρ0 = 0.05``: +7.0 and +49.3 % at 20 and 30 rows). The mechanism
(``docs/theory/stabilisation.md`` §7): the fronts' pressure leaves the linear consistency's
linearity limit first, those nodes fall back to direct nodal integration, whose error on the
disordered lattice of the mixing zone scales with the pressure itself (so with ``g``, not ``g′``),
and its noise trips their neighbours until no node is corrected. The fixed hydrostatic reference
integrates the hydrostatic part exactly at those nodes, so what falls back scales with ``g′``. The
rows of ``gravity_lid.md`` that change one setting at a time at 40 rows were measured before it
(their ``run_commit`` says so): free-slip walls, no shifting or a free surface moved the light
front towards the head; the penalty surface, direct nodal integration, the lid's pressure level,
``α = 0.02`` and ``δ = 0.05`` did not.

With a free surface at ``Δρ/ρ0 = 0.1`` the two fronts run alike (1.06 and 1.00 at 40 and 60 rows)
and approach the energy-conserving 0.5 (Froude numbers 0.41 and 0.48: +2.9 and +19.6 % against the
formula's 0.4): Shin, Dalziel & Linden (2004) measure lock-exchange currents a few per cent under
0.5 at high Reynolds numbers (here ``v_h D/ν ≈ 2·10⁴``), so as the numerical viscosity falls the
head leaves the 10 % band around Rottman & Simpson's 0.4 from above, in either configuration. The
default case runs −1.7 % (``D = 0.06`` m, ``Δρ/ρ0 = 0.5`` at 3 mm = 20 rows; +3.6 % before the
hydrostatic reference). The largest geometric-volume error is 0.1–1.2 % under the lid. With a free
surface the deep case keeps its volume through the recommended set's volume consistency: 0.71 and
0.68 % at 40 and 60 rows, 0.77 % at ``Δρ/ρ0 = 0.03`` (3.3, 4.8 and 6.9 % with ``--set
volume_consistency=0``; ``gravity_lid.md``, ``docs/theory/stabilisation.md`` §10); the run warns
past 1 %. Pressure noise under the lid: the probes ``top_pressure_spread`` (max − min of the top
row's pressure) and ``top_pressure_mean``, reported by ``analyse`` after 0.2 s.

Why a lid: the formula comes from laboratory currents with ``Δρ/ρ0`` of a few per cent, whose
free surface barely moves. At ``Δρ/ρ0 = 0.5`` an open surface does move: measured with
``lid=False``, it rose by about 20 % of ``D`` over the light fluid and drove an extra
barotropic flow, and the head ran at Froude number 0.45–0.51 (+12 to +28 % against the
formula, growing with resolution) instead of 0.39–0.42 with the lid.

Monitored: ``head_x`` — the third-smallest ``x`` of the heavy particles in the lower half of
the tank (robust to two stray particles). The head speed is the slope of a straight-line fit
of ``head_x(t)`` while the head has travelled between 20 % and 80 % of the lock-to-wall
distance (the constant-speed phase).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from mlsgalerkin.analysis.measured import not_measured
from mlsgalerkin.fluid import (
    SHIFTING_MODES,
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

__all__ = ["Parameters", "make_scene", "analyse", "check", "reference_head_speed", "SMOKE"]

SMOKE = {"dx": 0.006, "t_end": 0.05}


@dataclass(frozen=True)
class Parameters:
    depth: float = 0.06            #: tank depth D (m)
    length: float = 0.34           #: tank length; the lock is at mid-length (m)
    rho_light: float = 1000.0      #: density of the light fluid, left of the lock (kg/m³)
    rho_heavy: float = 1500.0      #: density of the heavy fluid, right of the lock (kg/m³)
    viscosity: float = 1.0e-3      #: dynamic viscosity of both fluids; 0 drops the effect (Pa s)
    dx: float = 0.0                #: particle spacing; 0 picks depth / rows, 3 mm at the default depth (m)
    rows: int = 20                 #: particle rows across the depth when dx is 0 (–)
    t_end: float = 0.8             #: end time (s)
    c0: float = 0.0                #: sound speed; 0 picks 10 max(2.5 v_h, sqrt(g D)) (m/s)
    alpha: float = 0.01            #: Monaghan artificial viscosity α; the recommended 0.02 runs the head 10–15 % slow at the coarser spacings (module docstring) (–)
    delta: float = RECOMMENDED.delta  #: density diffusion δ (δ-SPH, same-phase pairs); 0 drops it (–)
    shifting: str = RECOMMENDED.shifting  #: particle shifting: local (speed |v|), design (c0/10) or off (choice)
    density_filter: int = RECOMMENDED.density_filter  #: Shepard density filter every this many steps; 0 drops it (–)
    consistent_integration: bool = RECOMMENDED.consistent_integration  #: nodal integration that meets the integration constraint (VCI) (bool)
    linear_consistency: bool = RECOMMENDED.linear_consistency  #: the pressure's linear fit integrated exactly, with the free-surface term (bool)
    hydrostatic_reference: bool = RECOMMENDED.hydrostatic_reference  #: with the linear consistency, under a lid: a fixed hydrostatic field integrated exactly where the fit falls back (bool)
    volume_consistency: float = RECOMMENDED.volume_consistency  #: the density relaxed towards the particles' packing at rate ε where the fluid has a free surface (0: off) (–)
    penalty_walls: bool = True     #: the tank's inner surface as a penalty-contact backstop (bool)
    negative_pressure: str = "allow"  #: tension treatment: allow, clamp or cavitate (choice)
    lid_pressure_factor: float = 1.0  #: pressure under the lid at the start / (rho_heavy g D), a closed tank's free level (–)
    h_factor: float = 1.3          #: smoothing length / particle spacing, h/dx (–)
    g: float = 9.81                #: gravitational acceleration (m/s²)
    slip: str = "no_slip"          #: wall condition: free_slip, no_slip or fixed (choice)
    lid: bool = True               #: rigid lid at the initial surface; false: free surface (bool)
    closed_volume: bool = True     #: with the lid: hold the closed tank's volume in the continuity equation (ClosedVolume) (bool)
    frame_every: float = 0.02      #: time between VTU frames (s)
    gif: bool = True               #: render animation.gif and final.png (bool)


def reference_head_speed(p: Parameters) -> float:
    """``0.4 sqrt(g D Δρ/ρ0)`` in m/s."""
    return 0.4 * math.sqrt(p.g * tank(p)[1] * (p.rho_heavy - p.rho_light) / p.rho_light)


def spacing(p: Parameters) -> float:
    """The particle spacing ``Δx`` (m): the parameter ``dx``, or for ``dx = 0`` the spacing of
    ``rows`` rows across the depth, ``D / rows`` rounded to 10⁻¹² m (so that 0.06 m / 20 is
    3 mm to the bit): 20 rows, where the 3 × 3 matrix is validated, at every depth."""
    if p.dx != 0:
        return p.dx
    return round(p.depth / p.rows, 12)


def sound_speed(p: Parameters) -> float:
    """``c0`` (m/s): the parameter, or for ``c0 = 0`` ten times the larger of the expected
    largest speed ``2.5 v_h`` and the long-wave speed ``sqrt(g D)`` (density variations of
    about 1 % from both the flow and the hydrostatic pressure)."""
    if p.c0 > 0:
        return p.c0
    return 10.0 * max(2.5 * reference_head_speed(p), math.sqrt(p.g * tank(p)[1]))


def tank(p: Parameters) -> tuple[float, float]:
    """The tank's length and depth (m) as simulated: ``length`` and ``depth`` rounded to whole
    particle spacings, so the fluid lattice fills the tank and every wall stands ``Δx/2`` from
    the outer particle row (with ``depth = 0.04`` m and ``Δx = 3`` mm the 13 rows would otherwise
    leave a gap of 0.83 Δx under the lid, which the compressed fluid expands into). The
    reference head speed is the formula's at the simulated depth."""
    dx = spacing(p)
    return max(round(p.length / dx), 1) * dx, max(round(p.depth / dx), 1) * dx


def make_scene(p: Parameters = Parameters()) -> Scene:
    """The lock-exchange scene for parameters ``p``."""
    light = Phase("light", p.rho_light, p.viscosity)
    heavy = Phase("heavy", p.rho_heavy, p.viscosity)
    length, depth = tank(p)
    dx = spacing(p)
    body = FluidBody.block("fluid", (0.0, 0.0), (length, depth), dx, [light, heavy])
    x, y = body.positions[:, 0], body.positions[:, 1]
    body.phase[:] = (x > 0.5 * length).astype(np.int64)
    rho0 = body.reference_density
    top_pressure = p.lid_pressure_factor * p.rho_heavy * p.g * depth if p.lid else 0.0
    body.density[:] = hydrostatic_density(rho0, depth - y, p.g, sound_speed(p), top_pressure, compressible=True)
    top = depth if p.lid else 1.5 * depth
    walls = wall_box((0.0, 0.0), (length, top), dx, layers=3, open_top=not p.lid,
                     reference_density=p.rho_light, surface=p.penalty_walls)
    c0 = sound_speed(p)
    u_max = reference_head_speed(p) * 2.5
    scheme = water(c0, u_max=u_max, gravity=(0.0, -p.g), slip=p.slip, alpha=p.alpha,
                   flow=(reference_head_speed(p), depth), newtonian=p.viscosity > 0, delta=p.delta,
                   shifting=p.shifting, density_filter=p.density_filter, negative_pressure=p.negative_pressure,
                   penalty_thickness=0.25 * dx if p.penalty_walls else None,
                   consistent_integration=p.consistent_integration, linear_consistency=p.linear_consistency,
                   hydrostatic_reference=p.hydrostatic_reference,
                   volume_consistency=p.volume_consistency,
                   spacing=dx, h_factor=p.h_factor,
                   extra=[ClosedVolume()] if p.lid and p.closed_volume else [])
    n_fluid = body.n
    half = 0.5 * depth

    def head_x(state) -> float:
        s = state.fluid
        f = slice(0, n_fluid)
        sel = (s.phase[f] == 1) & (s.x[f, 1] < half)
        return kth_smallest(s.x[f][sel, 0], 2) - 0.5 * dx

    def light_front_x(state) -> float:
        s = state.fluid
        f = slice(0, n_fluid)
        sel = (s.phase[f] == 0) & (s.x[f, 1] > half)
        return -kth_smallest(-s.x[f][sel, 0], 2) + 0.5 * dx

    def top_row_pressure(state) -> np.ndarray:
        s = state.fluid
        y = s.x[:n_fluid, 1]
        return s.p[:n_fluid][y > depth - dx]

    def top_pressure_spread(state) -> float:
        top = top_row_pressure(state)
        return float(top.max() - top.min()) if top.size else float("nan")

    def top_pressure_mean(state) -> float:
        top = top_row_pressure(state)
        return float(top.mean()) if top.size else float("nan")

    probes = [Probe("head_x", head_x), Probe("light_front_x", light_front_x)]
    if p.lid:
        probes += [Probe("top_pressure_spread", top_pressure_spread), Probe("top_pressure_mean", top_pressure_mean)]
    return Scene(
        [body, walls], [scheme], t_end=p.t_end, name="gravity_current",
        output=Output(every=p.frame_every, probe_every=0.002, gif=p.gif, png=p.gif, color_by="density"),
        probes=probes,
        parameters=dict(p.__dict__),
    )


def kth_smallest(a: np.ndarray, k: int) -> float:
    """The ``k``-th smallest value (0-based): a front position robust to ``k`` stray particles."""
    if a.size == 0:
        return float("nan")
    k = min(k, a.size - 1)
    return float(np.partition(a, k)[k])


def head_speed(t: np.ndarray, head_x: np.ndarray, lock_x: float, window: tuple[float, float] = (0.2, 0.8)) -> dict:
    """Straight-line fit of the head position over the constant-speed phase.

    The window is where the head has travelled between ``window[0]`` and ``window[1]`` of the
    lock-to-wall distance ``lock_x``. Returns speed (m/s, positive towards the left wall), the
    window times and the fit's r²; the speed is ``None`` (with a ``"note"``) when the head has not
    travelled through the whole window.
    """
    travelled = (lock_x - head_x) / lock_x
    sel = (travelled >= window[0]) & (travelled <= window[1]) & np.isfinite(head_x)
    finite = travelled[np.isfinite(travelled)]
    if np.count_nonzero(sel) < 5 or finite.size == 0 or finite.max() < window[1]:
        far = float(finite.max()) if finite.size else 0.0
        return {"speed": None, "t_from": None, "t_to": None, "r2": None, "points": int(np.count_nonzero(sel)),
                "note": f"the head travelled {100 * max(far, 0.0):.0f} % of the lock-to-wall distance, not through the "
                        f"whole fit window ({100 * window[0]:.0f}-{100 * window[1]:.0f} %)"}
    tt, xx = t[sel], head_x[sel]
    slope, icpt = np.polyfit(tt, xx, 1)
    resid = xx - (slope * tt + icpt)
    r2 = 1.0 - resid.var() / xx.var() if xx.var() > 0 else 1.0
    return {"speed": float(-slope), "t_from": float(tt[0]), "t_to": float(tt[-1]), "r2": float(r2),
            "points": int(sel.sum())}


def light_front(t: np.ndarray, light_x: np.ndarray, fit: dict, reference: float) -> dict:
    """The light current's front along the top, fitted over the heavy head's fit window
    ``fit["t_from"] … fit["t_to"]`` (a straight line): its speed (m/s, towards the right wall), its
    Froude number ``0.4 v/reference`` and its speed over the heavy head's. A Boussinesq exchange
    under a lid runs both fronts alike (ratio 1); a ratio well below 1 is a lopsided exchange."""
    sel = (t >= fit["t_from"]) & (t <= fit["t_to"]) & np.isfinite(light_x)
    if np.count_nonzero(sel) < 5:
        return {}
    speed = float(np.polyfit(t[sel], light_x[sel], 1)[0])
    return {"light_front_speed_m_s": speed, "light_froude_number": 0.4 * speed / reference,
            "front_speed_ratio": speed / fit["speed"]}


#: The head's fit window, as shares of the lock-to-wall distance travelled.
FIT_WINDOW = (0.2, 0.8)


def analyse(result, p: Parameters) -> dict:
    """Head speed against ``0.4 sqrt(g D Δρ/ρ0)``, measured once the head has travelled through
    the whole fit window ``FIT_WINDOW``."""
    ts = result.timeseries
    length, depth = tank(p)
    lock_x = 0.5 * length
    fit = head_speed(np.asarray(ts["time"]), np.asarray(ts["head_x"]), lock_x, FIT_WINDOW)
    ref = reference_head_speed(p)
    noise = {}
    if "top_pressure_spread" in ts:
        t = np.asarray(ts["time"])
        late = t >= min(0.2, 0.5 * t[-1])
        spread = np.asarray(ts["top_pressure_spread"])[late]
        mean = np.asarray(ts["top_pressure_mean"])[late]
        scale = (p.rho_heavy - p.rho_light) * p.g * depth
        noise = {"top_pressure_spread_median_pa": float(np.median(spread)), "top_pressure_spread_max_pa": float(spread.max()),
                 "top_pressure_spread_median_over_drho_g_d": float(np.median(spread) / scale),
                 "top_pressure_mean_start_pa": float(mean[0]), "top_pressure_mean_end_pa": float(mean[-1])}
    out = {**noise, "reference_head_speed_m_s": ref, "energy_conserving_froude_number": 0.5,
           "rows_per_depth": depth / spacing(p), "depth_simulated_m": depth, "length_simulated_m": length, "fit": fit}
    if fit["speed"] is None:
        # at about the reference speed the head crosses the window's end at 0.8 lock_x / U (+10 %: it starts at rest)
        text = not_measured(out, ("head_speed_m_s", "relative_error", "froude_number"), fit["note"],
                            run_to=1.1 * FIT_WINDOW[1] * lock_x / ref)
        out["headline"] = f"head speed {text}"
        return out
    rel = (fit["speed"] - ref) / ref
    froude = 0.4 * fit["speed"] / ref
    out.update({"head_speed_m_s": fit["speed"], "relative_error": rel, "froude_number": froude})
    if "light_front_x" in ts:
        out.update(light_front(np.asarray(ts["time"]), np.asarray(ts["light_front_x"]), fit, ref))
    out["headline"] = (f"head speed {fit['speed']:.4f} m/s vs 0.4 sqrt(g D dρ/ρ0) = {ref:.4f} m/s "
                       f"({100 * rel:+.1f} %); Froude number {froude:.3f}")
    if "light_froude_number" in out:
        out["headline"] += (f"; the light front's {out['light_froude_number']:.3f} "
                            f"({out['front_speed_ratio']:.2f} of the heavy head's speed)")
    return out


def check(p: Parameters) -> list[str]:
    """Problems with the parameters (see ``mlsgalerkin.problem``)."""
    out = require_positive(p, "depth", "length", "rho_light", "rho_heavy", "t_end", "h_factor", "g",
                           "frame_every")
    out += require_nonnegative(p, "viscosity", "alpha", "delta", "c0", "density_filter", "dx")
    out += require(p.shifting in SHIFTING_MODES,
                   f"shifting = {p.shifting!r}: choose one of {', '.join(SHIFTING_MODES)}")
    out += require(p.negative_pressure in ("allow", "clamp", "cavitate"),
                   f"negative_pressure = {p.negative_pressure!r}: choose one of allow, clamp, cavitate")
    out += require_nonnegative(p, "lid_pressure_factor")
    if p.dx == 0:
        out += require(isinstance(p.rows, int) and p.rows >= 4,
                       f"rows = {p.rows!r}: give a whole number of particle rows across the depth, at least 4 "
                       "(20 is the validated default), or a spacing dx")
    if not out:
        out += require(p.rho_heavy > p.rho_light,
                       f"rho_heavy = {p.rho_heavy:g} must exceed rho_light = {p.rho_light:g}: the heavy fluid runs "
                       "under the light one")
        dx = spacing(p)
        out += require(p.depth >= 4 * dx, f"dx = {dx:g} m leaves fewer than 4 particle rows in the {p.depth:g} m "
                                          f"depth; choose dx <= {p.depth / 4:g} m")
        out += require(p.length >= 8 * dx, f"the tank ({p.length:g} m) must be at least 8 particles long")
    out += require(p.slip in ("free_slip", "no_slip", "fixed"), f"slip must be free_slip, no_slip or fixed, got {p.slip!r}")
    return out
