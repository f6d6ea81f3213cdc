r"""Piston wave maker: a wall oscillating with stroke ``S`` and period ``T`` makes waves in a long tank.

The left wall of a tank of still water of depth ``d`` is a piston, a
:class:`~mlsgalerkin.fluid.WallBody` moving with the prescribed motion
:class:`~mlsgalerkin.motion.Oscillation`: ``X(t) = r(t) (S/2) sin(ω t)``, switched on smoothly
over ``ramp_periods`` periods. Linear wave-maker theory (Dean & Dalrymple 1991, §6.2) gives the
height ``H`` of the progressive wave it makes,

.. math:: \frac{H}{S} = \frac{2(\cosh 2kd - 1)}{\sinh 2kd + 2kd},\qquad \omega^2 = g k \tanh kd,

plus evanescent modes that decay within a few depths of the paddle. The defaults (``d = 0.2`` m,
``T = 1`` s: ``kd = 1.04``, intermediate depth; ``S = 2`` cm: ``H/d ≈ 0.1``, ``H/L ≈ 0.016``)
keep the wave close to linear.

Monitored: ``eta`` (m), the free-surface elevation at ``probe_x``, from the fluid's volume in a
smoothed vertical column, ``η(x_p) = Σ_i V_i W(x_i − x_p) − d`` with ``V_i = M_i/ρ_i`` and a 1D
cubic-spline weight ``W`` of support ``±4 Δx`` (``∫W = 1``), and ``piston_x`` (m), the paddle
displacement. :func:`analyse` fits ``η(t) ≈ c + a cos ωt + b sin ωt`` over the window in which
the wave train at the probe is steady — after the ramp, the arrival of the front
(group velocity ``c_g``) and one more period, and before the wave reflected by the far wall
returns — and reports ``H = 2 sqrt(a² + b²)`` against the theory.

The tank is long instead of ending in a beach: ``tank_length`` (default 4 m) keeps the
reflection away from the probe until ``t ≈ (2 L − x_p)/c_g``. A shorter tank can end in a sponge
(``sponge_length`` > 0, off by default): a :class:`~mlsgalerkin.fluid.SpongeZone` over the tank's last
``sponge_length`` whose rate rises as ``ξ²`` to ``sponge_rate / T`` at the far wall; the fit window
then runs to ``t_end`` and ``analyse`` compares the height before and after the far wall's damped
reflection returns.

How much the tank's end reflects is measured in every run whose tank has room: three gauges
(``eta_gauge_1 … 3``, at Mansard & Funke's 1980 spacing, the last two depths before the sponge or
the far wall) split the first harmonic into incident and reflected waves
(:func:`~mlsgalerkin.analysis.waves.incident_reflected`), over two-period windows in which both
stand steady at the gauges: after the reflected wave has reached them at full height, before the
paddle sends it back (:func:`reflection_window`). ``reflection_coefficient`` is the median of
``|a_R|/|a_I|`` over the windows (``_min``, ``_max`` their spread); ``sponge_round_trip_attenuation``
``exp(−σ_max L_s / (3 c_g))`` is what the sponge's damping alone leaves of a wave that crosses it,
meets the wall and comes back (its floor), ``viscous_decay_round_trip`` what the artificial
viscosity takes from a round trip between the gauges and the far wall. Measured at 10 rows per
depth with the sponge 3 m from the paddle (``verification/results/wave_absorption/summary.md``,
2026-12-03; paddle started over one period): a bare wall 0.89 (0.81–0.98 over the windows; a perfect reflector would read 0.94 after the artificial viscosity); a one-wavelength sponge (1.2 m)
at ``sponge_rate`` 3 / 5 / 10 reflects 0.29 / 0.13 / 0.19 (floors 0.27 / 0.12 / 0.01: at 3 the
damping is too weak, at 10 the rise of ``σ_max = 10/s`` above ``ω = 6.3/s`` reflects a part of
the wave itself); 0.6 m at 10: 0.14; two wavelengths (2.4 m) at 5: **0.06**, and 0.05 at 20 rows. Without the recommended set's volume consistency (``--set volume_consistency=0``) these runs lose geometric volume against Σ M/ρ, 3–7 % by their end, a compaction the continuity equation cannot see; with it, the default, the 10-row run keeps 0.97 % over 14.2 s (5.0 % without; ``docs/theory/stabilisation.md`` §10). The default
``sponge_rate`` is 5; a sponge of two wavelengths is the recommendation. The start's long wave
(at ``sqrt(g d)``, many metres long) is not absorbed by a zone this short. The walls are free-slip; the
pressure of the piston's wall particles uses ``g − a_piston``. The gauge stands two depths from
the paddle, where the first evanescent mode has decayed to ``e^{-2π}`` and the wave has lost
little to the artificial viscosity, which acts as a kinematic viscosity ``ν ≈ α h c0 / 8``
(reported as ``numerical_viscosity_m2_s``; it damps the wave amplitude at the rate ``2νk²``,
Lamb 1932, so by about ``1 − exp(−2νk² x_p/c_g)`` between paddle and gauge:
``viscous_decay_to_gauge``; the wave Reynolds number ``ω/(νk²)`` is reported too).
Settings: the one recommended set (``mlsgalerkin.fluid.RECOMMENDED``: α = 0.02, density
diffusion, shifting, the pressure's linear fit integrated exactly, the volume consistency),
tension released by cavitation. Measured at the defaults
(``verification/results/fluid_validation/summary.md``, 2026-12-04, with the loose side and
droplets: 19.76 mm, −2.7 %, at 20 rows and 20.57 mm, +1.3 %, at 30; 2026-12-03, before
them): the wave height is 19.68 mm
against 20.30 mm, −3.1 %, at 20 rows per depth (``Δx = 0.01`` m) and 20.34 mm, +0.2 %, at 30
rows, both within 5 %, with a second harmonic of 10.6 and 9.8 % of the first (wave Reynolds
numbers 514 and 771) and the geometric volume within 0.35 and 0.40 %; without the volume
consistency (2026-12-02) −1.9 and −0.3 %, volume within 0.64 and 0.96 %. Before the linear consistency's
surface fix of 2026-12-02 they were −3.8 and +7.2 % (the 30 rows outside the 5 %); at 10 rows
−5.9 % (``verification/results/quiet_state/investigation.md`` §8, before the fix). The former set
(α = 0.1, a Shepard filter, no density diffusion or shifting, direct nodal integration; α = 0.02
without the linear consistency let a lattice mode grow) gives −4.3 % at 20 rows (Re 103; −2.5 %
at 30 rows, measured before).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from mlsgalerkin.analysis.measured import not_measured
from mlsgalerkin.analysis.waves import (
    complex_amplitude,
    gauge_positions,
    harmonic_fit,
    incident_reflected,
)
from mlsgalerkin.fluid import (
    SHIFTING_MODES,
    FluidBody,
    Phase,
    WallBody,
    hydrostatic_density,
    lattice,
    water,
)
from mlsgalerkin.fluid.eos import NEGATIVE_PRESSURE_MODES
from mlsgalerkin.fluid.presets import RECOMMENDED
from mlsgalerkin.fluid.sponge import SpongeZone
from mlsgalerkin.motion import Oscillation
from mlsgalerkin.problem import require, require_nonnegative, require_positive
from mlsgalerkin.scene import Output, Probe, Scene

__all__ = ["Parameters", "make_scene", "analyse", "check", "wave_number", "height_over_stroke", "SMOKE"]

SMOKE = {"dx": 0.02, "t_end": 0.3, "tank_length": 1.0}


@dataclass(frozen=True)
class Parameters:
    depth: float = 0.2              #: still-water depth d (m)
    period: float = 1.0             #: paddle period T (s)
    stroke: float = 0.02            #: paddle stroke S, peak to peak (m)
    probe_x: float = 0.4            #: position of the wave gauge from the paddle's mean position (m)
    tank_length: float = 4.0        #: distance from the paddle to the far wall (m)
    sponge_length: float = 0.0      #: a damping zone before the far wall, this long; 0: none, the wall reflects (m)
    sponge_rate: float = 5.0        #: the sponge's damping rate at the far wall times the period, sigma_max T (–)
    dx: float = 0.01                #: particle spacing (m)
    t_end: float = 7.0              #: end time (s)
    ramp_periods: float = 2.0       #: paddle periods over which the paddle is switched on (–)
    alpha: float = RECOMMENDED.alpha  #: Monaghan artificial viscosity α (–)
    delta: float = RECOMMENDED.delta  #: density diffusion δ (δ-SPH); 0 drops it (–)
    shifting: str = RECOMMENDED.shifting  #: particle shifting: local (speed |v|), design (c0/10) or off (choice)
    density_filter: int = RECOMMENDED.density_filter  #: Shepard density filter every this many steps; 0 drops it (–)
    negative_pressure: str = "cavitate"  #: tension treatment: allow, clamp, cavitate or free_surface (choice)
    linear_consistency: bool = RECOMMENDED.linear_consistency  #: the pressure's linear fit integrated exactly, with the free-surface term (bool)
    volume_consistency: float = RECOMMENDED.volume_consistency  #: the density relaxed towards the particles' packing at rate ε where the fluid has a free surface (0: off) (–)
    c0_factor: float = 10.0         #: sound speed / sqrt(g d) (–)
    h_factor: float = 1.3           #: smoothing length / particle spacing, h/dx (–)
    g: float = 9.81                 #: gravitational acceleration (m/s²)
    probe_every: float = 0.01       #: time between time-series rows (s)
    frame_every: float = 0.25       #: time between VTU frames (s)
    gif: bool = False               #: render animation.gif and final.png (bool)


def wave_number(period: float, depth: float, g: float = 9.81) -> float:
    """``k`` (1/m) of the linear dispersion relation ``ω² = g k tanh kd`` (Newton iteration)."""
    omega2 = (2.0 * math.pi / period) ** 2
    k = max(omega2 / g, math.sqrt(omega2 / (g * depth)))
    for _ in range(60):
        t = math.tanh(k * depth)
        f = g * k * t - omega2
        df = g * t + g * k * depth * (1.0 - t * t)
        step = f / df
        k -= step
        if abs(step) < 1e-15 * k:
            break
    return k


def height_over_stroke(kd: float) -> float:
    """Linear piston wave-maker theory ``H/S = 2(cosh 2kd − 1)/(sinh 2kd + 2kd)``."""
    return 2.0 * (math.cosh(2 * kd) - 1.0) / (math.sinh(2 * kd) + 2 * kd)


def group_velocity(period: float, depth: float, g: float = 9.81) -> float:
    """``c_g = ½ (ω/k) (1 + 2kd / sinh 2kd)`` (m/s)."""
    k = wave_number(period, depth, g)
    kd = k * depth
    return 0.5 * (2 * math.pi / period / k) * (1.0 + 2 * kd / math.sinh(2 * kd))


def _column_weights(x: np.ndarray, x_p: float, half_width: float) -> np.ndarray:
    """1D cubic-spline weights ``W(x − x_p)`` with support ``±half_width`` and ``∫ W dx = 1``."""
    h = 0.5 * half_width
    q = np.abs(x - x_p) / h
    w = np.where(q < 1, 1 - 1.5 * q**2 + 0.75 * q**3, np.where(q < 2, 0.25 * (2 - q) ** 3, 0.0))
    return w * (2.0 / (3.0 * h))


def make_scene(p: Parameters = Parameters()) -> Scene:
    """The wave tank for parameters ``p``."""
    dx, d = p.dx, p.depth
    c0 = p.c0_factor * math.sqrt(p.g * d)
    water_body = FluidBody.block("water", (0.0, 0.0), (p.tank_length, d), dx, [Phase("water", 1000.0)])
    water_body.density[:] = hydrostatic_density(np.full(water_body.n, 1000.0), d - water_body.positions[:, 1], p.g, c0)
    top = 1.6 * d
    layers = 3 * dx
    # fixed tank: a floor reaching under the paddle's whole travel, and the far wall
    x_left = -(0.5 * p.stroke + 2 * layers)
    floor = lattice((x_left, -layers), (p.tank_length + layers, 0.0), dx)
    far = lattice((p.tank_length, 0.0), (p.tank_length + layers, top), dx)
    tank_x = np.vstack([floor, far])
    closest = np.clip(tank_x, (x_left - 10 * dx, 0.0), (p.tank_length, top))
    normals = closest - tank_x
    normals /= np.linalg.norm(normals, axis=1, keepdims=True)
    tank = WallBody("tank", tank_x, dx, normals=normals)
    # the paddle: three layers of wall particles behind x = 0, moving as a piston
    paddle_x = lattice((-layers, 0.0), (0.0, top), dx)
    paddle = WallBody("paddle", paddle_x, dx, normals=np.tile([1.0, 0.0], (len(paddle_x), 1)),
                      motion=Oscillation(p.stroke, p.period, direction=(1.0, 0.0), ramp=p.ramp_periods * p.period))
    n = water_body.n
    half_width = 4.0 * dx

    def elevation_at(x_g: float):
        def eta(state) -> float:
            s = state.fluid
            w = _column_weights(s.x[:n, 0], x_g, half_width)
            return float(np.dot(w, s.M[:n] / s.rho[:n])) - d
        return eta

    def piston_x(state) -> float:
        return float(paddle.motion.displacement(state.t)[0])

    u_max = 0.5 * p.stroke * 2 * math.pi / p.period / math.tanh(wave_number(p.period, d, p.g) * d)
    scheme = water(c0, u_max=u_max, gravity=(0.0, -p.g), alpha=p.alpha, delta=p.delta, shifting=p.shifting,
                   density_filter=p.density_filter, negative_pressure=p.negative_pressure,
                   linear_consistency=p.linear_consistency,
                   volume_consistency=p.volume_consistency, spacing=p.dx, h_factor=p.h_factor,
                   extra=[sponge(p)] if p.sponge_length > 0 else [])
    return Scene(
        [water_body, tank, paddle], [scheme], t_end=p.t_end, name="wave_maker",
        output=Output(every=p.frame_every, probe_every=p.probe_every, gif=p.gif, png=p.gif, color_by="pressure"),
        probes=[Probe("eta", elevation_at(p.probe_x)), Probe("piston_x", piston_x)]
        + [Probe(f"eta_gauge_{j + 1}", elevation_at(x_g)) for j, x_g in enumerate(reflection_gauges(p))],
        parameters=dict(p.__dict__),
    )


def sponge(p: Parameters) -> SpongeZone:
    """The damping zone over the last ``sponge_length`` of the tank: the rate rises as ``ξ²`` from 0 at
    ``tank_length − sponge_length`` to ``sponge_rate / period`` (1/s) at the far wall."""
    return SpongeZone(p.tank_length - p.sponge_length, p.sponge_length, p.sponge_rate / p.period, name="sponge")


def reflection_gauges(p: Parameters) -> np.ndarray:
    """Three gauges (m from the paddle) for splitting the waves into incident and reflected ones
    (:func:`~mlsgalerkin.analysis.waves.incident_reflected`) at Mansard & Funke's spacing (a tenth and
    a quarter of the wavelength), the last two depths before the sponge (the far wall without one):
    as far from the paddle as they can stand, so that the reflected wave is measured before the
    paddle sends it back (:func:`reflection_window`). Shape ``(3,)``, or ``(0,)`` when they would
    stand within two depths of the probe (no ``eta_gauge_*`` columns then)."""
    wavelength = 2 * math.pi / wave_number(p.period, p.depth, p.g)
    x_end = p.tank_length - p.sponge_length - 2 * p.depth
    x = gauge_positions(x_end - wavelength / 8.0, wavelength)
    return x if x[0] - p.probe_x >= 2 * p.depth else np.zeros(0)


def reflection_window(p: Parameters) -> tuple[float, float]:
    """``(t_from, t_to)`` (s) in which both waves stand steady at the :func:`reflection_gauges`: from
    one period after the wave reflected at the far wall has reached the first gauge at full height
    (its front at the group velocity ``c_g``, the paddle's ramp behind it) to the arrival at the
    first gauge of the paddle's own reflection of it, or the end of the run:
    ``t_from = t_ramp + (2 L − x₁)/c_g + T``, ``t_to = min(t_end, (2 L + x₁)/c_g)``."""
    t_from, t_return, _ = _reflection_timing(p)
    return t_from, min(p.t_end, t_return)


def _reflection_timing(p: Parameters) -> tuple[float, float, np.ndarray]:
    """``(t_from, t_return, x)``: :func:`reflection_window`'s start, the paddle's reflection's
    arrival at the first gauge ``(2 L + x₁)/c_g`` (s, not clamped to ``t_end``) and the gauges
    ``x`` (m, :func:`reflection_gauges`)."""
    cg = group_velocity(p.period, p.depth, p.g)
    x = reflection_gauges(p)
    x_first = float(x[0]) if x.size else p.probe_x
    t_from = p.ramp_periods * p.period + (2 * p.tank_length - x_first) / cg + p.period
    return t_from, (2 * p.tank_length + x_first) / cg, x


def end_reflection(t: np.ndarray, gauges: list[np.ndarray], p: Parameters) -> dict:
    """The reflection coefficient of the tank's end (the far wall, or the sponge before it) at the
    paddle's frequency, from the three gauges over :func:`reflection_window`. The window is cut
    into windows of two periods, half a period apart; each is split into incident and reflected
    waves (:func:`~mlsgalerkin.analysis.waves.incident_reflected`). ``reflection_coefficient``
    ``|a_R|/|a_I|`` is their median, ``reflection_coefficient_min`` and ``_max`` their spread
    (the tank's long waves pass), the incident and reflected heights and the two-wave model's
    misfit their medians. Not measured when the window is shorter than two periods (the run ends
    too early, or the gauges stand too close to the paddle: the reflected wave comes back before
    the paddle's ramp is over) or the tank has no gauges."""
    t_from, t_return, x = _reflection_timing(p)
    t_to = min(p.t_end, t_return)
    out: dict = {"reflection_window_s": [t_from, t_to]}
    keys = ("reflection_coefficient", "reflection_coefficient_min", "reflection_coefficient_max",
            "incident_height_m", "reflected_height_m", "reflection_misfit")
    if not gauges:
        not_measured(out, keys, f"the {p.tank_length:g} m tank leaves no room for three gauges two depths from the "
                                f"probe and from the {'sponge' if p.sponge_length > 0 else 'far wall'}; lengthen the tank")
        return out
    starts = np.arange(t_from, min(t_to, float(t[-1])) - 2 * p.period + 1e-9, 0.5 * p.period)
    windows = [(t >= a) & (t < a + 2 * p.period) for a in starts]
    if not windows or min(np.count_nonzero(w) for w in windows) < 20:
        if t_return < t_from + 2 * p.period:
            not_measured(out, keys, f"the paddle reflects the reflected wave back to the gauges before two periods of "
                                    f"it were steady there (from {t_from:.2f} s): lengthen the tank between the "
                                    f"paddle and the sponge (the gauges stand two depths before it)")
        else:
            not_measured(out, keys, f"the run ended at t = {t[-1]:.3g} s, before two periods of the reflected wave at "
                                    f"the gauges (from {t_from:.2f} s)", run_to=t_from + 2 * p.period)
        return out
    omega, k = 2 * math.pi / p.period, wave_number(p.period, p.depth, p.g)
    splits = [incident_reflected(x, [complex_amplitude(t[w], g[w], omega) for g in gauges], k) for w in windows]
    kr = np.array([sp.reflection_coefficient for sp in splits])
    cg, nu = group_velocity(p.period, p.depth, p.g), numerical_viscosity(p)
    out.update({"reflection_coefficient": float(np.median(kr)), "reflection_coefficient_min": float(kr.min()),
                "reflection_coefficient_max": float(kr.max()), "reflection_windows": len(splits),
                "incident_height_m": float(np.median([2 * abs(sp.incident) for sp in splits])),
                "reflected_height_m": float(np.median([2 * abs(sp.reflected) for sp in splits])),
                "reflection_misfit": float(np.median([sp.relative_misfit for sp in splits])),
                # what a perfect reflector at the far wall would read: the viscous decay (Lamb 1932)
                # of the wave's round trip from the gauges' centre to the far wall and back
                "viscous_decay_round_trip": 1.0 - math.exp(-2.0 * nu * k * k * 2 * (p.tank_length - float(x.mean())) / cg),
                "reflection_gauges_m": x.tolist()})
    if p.sponge_length > 0:
        out["sponge_round_trip_attenuation"] = sponge_round_trip_attenuation(p)
    return out


def sponge_round_trip_attenuation(p: Parameters) -> float:
    r"""What is left of a wave after it has crossed the sponge, been reflected by the wall behind it
    and crossed back (–): in a zone of Rayleigh damping ``σ ≪ ω`` a progressive wave's energy decays
    at the rate ``σ`` (its kinetic energy is half of it), its amplitude over distance at
    ``σ / (2 c_g)``, so the round trip leaves
    :math:`\exp(-\int_0^{L_s} σ\,dx / c_g) = \exp(-σ_{max} L_s / (3 c_g))` for ``σ = σ_max ξ²``.
    The reflection coefficient cannot fall below it; the zone's own reflection, from the rise of
    ``σ``, adds to it as ``σ_max`` approaches ``ω``."""
    sigma_max = p.sponge_rate / p.period
    return math.exp(-sigma_max * p.sponge_length / (3.0 * group_velocity(p.period, p.depth, p.g)))


def numerical_viscosity(p: Parameters) -> float:
    """The kinematic viscosity the artificial viscosity acts as, ``ν ≈ α h c0 / 8`` (m²/s)."""
    return p.alpha * p.h_factor * p.dx * p.c0_factor * math.sqrt(p.g * p.depth) / 8.0


def measurement_window(p: Parameters) -> tuple[float, float]:
    """``(t_from, t_to)``: steady waves at the probe (s), before the far wall's reflection returns;
    with a sponge, to the end of the run (``analyse`` then reports the height before and after
    the sponge's residual reflection returns; the module docstring says how much it leaves)."""
    cg = group_velocity(p.period, p.depth, p.g)
    t_from = p.ramp_periods * p.period + p.probe_x / cg + p.period
    if p.sponge_length > 0:
        return t_from, p.t_end
    t_to = (2 * p.tank_length - p.probe_x) / cg - p.period
    return t_from, min(t_to, p.t_end)


def analyse(result, p: Parameters) -> dict:
    """Wave height at the probe (harmonic fit over the steady window) against linear theory."""
    ts = result.timeseries
    t, eta = np.asarray(ts["time"]), np.asarray(ts["eta"])
    k = wave_number(p.period, p.depth, p.g)
    kd = k * p.depth
    ratio_theory = height_over_stroke(kd)
    H_theory = ratio_theory * p.stroke
    t_from, t_to = measurement_window(p)
    out = {"kd": kd, "wavelength_m": 2 * math.pi / k, "group_velocity_m_s": group_velocity(p.period, p.depth, p.g),
           "H_over_S_theory": ratio_theory, "wave_height_theory_m": H_theory,
           "window_s": [t_from, t_to], "rows_per_depth": p.depth / p.dx}
    columns = [f"eta_gauge_{j + 1}" for j in range(reflection_gauges(p).size)]
    gauges = [np.asarray(ts[c]) for c in columns] if all(c in ts for c in columns) else []
    out.update(end_reflection(t, gauges, p))
    sel = (t >= t_from) & (t <= t_to)
    if t_to - t_from < 2 * p.period or np.count_nonzero(sel) < 20:
        cg = out["group_velocity_m_s"]
        reflection = (2 * p.tank_length - p.probe_x) / cg - p.period   # when the far wall's reflection returns
        if p.sponge_length == 0 and reflection - t_from < 2 * p.period:
            why, run_to = (f"no steady window: the far wall's reflection reaches the probe at {reflection:.2f} s, less "
                           f"than two periods after the waves settle there ({t_from:.2f} s); lengthen the tank "
                           f"(tank_length) or move the probe (probe_x)"), None
        else:
            why, run_to = (f"no steady window: the run ended at t = {t[-1]:.3g} s, before two periods of steady waves "
                           f"at the probe (from {t_from:.2f} s)"), t_from + 2 * p.period
        text = not_measured(out, ("wave_height_m", "H_over_S", "relative_error"), why, run_to=run_to)
        out["note"] = out["wave_height_m_not_measured"]
        out["headline"] = f"wave height {text}"
        return out
    omega = 2 * math.pi / p.period
    coef, resid = harmonic_fit(t[sel], eta[sel], omega)
    H = 2.0 * math.hypot(coef[1], coef[2])
    out.update({
        "wave_height_m": H, "H_over_S": H / p.stroke, "relative_error": (H - H_theory) / H_theory,
        "mean_level_m": float(coef[0]), "second_harmonic_over_first": math.hypot(coef[3], coef[4]) / (0.5 * H),
        "fit_rms_residual_m": float(np.sqrt(np.mean(resid**2))),
        "crest_to_trough_m": float(eta[sel].max() - eta[sel].min()),
    })
    if p.sponge_length > 0:
        # the far wall's reflection (what is left of it after the sponge) reaches the probe at
        # t_back; the height fitted after it against the height before it bounds the reflection
        t_back = (2 * p.tank_length - p.probe_x) / out["group_velocity_m_s"]
        before, after = sel & (t < t_back), sel & (t >= t_back + p.period)
        out["reflection_arrives_s"] = t_back
        if t_back - t_from >= 2 * p.period and t[after].size and t[after][-1] - t[after][0] >= 2 * p.period:
            h_before = 2.0 * math.hypot(*harmonic_fit(t[before], eta[before], omega)[0][1:3])
            h_after = 2.0 * math.hypot(*harmonic_fit(t[after], eta[after], omega)[0][1:3])
            out.update({"wave_height_before_reflection_m": h_before, "wave_height_after_reflection_m": h_after,
                        "height_change_after_reflection": h_after / h_before - 1.0})
    # the artificial viscosity acts as nu = alpha h c0 / 8; a progressive wave loses amplitude at the
    # rate 2 nu k^2 (Lamb 1932, §348), so between the paddle and the gauge it decays by about
    # 1 - exp(-2 nu k^2 x_p / c_g); the wave Reynolds number is omega / (nu k^2)
    nu = numerical_viscosity(p)
    out["numerical_viscosity_m2_s"] = nu
    out["wave_reynolds_number"] = omega / (nu * k * k)
    out["viscous_decay_to_gauge"] = 1.0 - math.exp(-2.0 * nu * k * k * p.probe_x / out["group_velocity_m_s"])
    out["headline"] = (f"wave height {1e3 * H:.2f} mm at x = {p.probe_x:g} m vs linear wave-maker theory "
                       f"{1e3 * H_theory:.2f} mm (H/S {H / p.stroke:.3f} vs {ratio_theory:.3f}, "
                       f"{100 * out['relative_error']:+.1f} %), kd = {kd:.2f}, {p.depth / p.dx:.0f} rows per depth")
    return out


def check(p: Parameters) -> list[str]:
    """Problems with the parameters (see ``mlsgalerkin.problem``)."""
    out = require_positive(p, "depth", "period", "tank_length", "dx", "t_end", "c0_factor", "h_factor", "g",
                           "probe_every", "frame_every")
    out += require_nonnegative(p, "stroke", "ramp_periods", "alpha", "delta", "density_filter", "sponge_length")
    out += require_positive(p, "sponge_rate")
    out += require(p.shifting in SHIFTING_MODES,
                   f"shifting = {p.shifting!r}: choose one of {', '.join(SHIFTING_MODES)}")
    out += require(p.negative_pressure in NEGATIVE_PRESSURE_MODES,
                   f"negative_pressure = {p.negative_pressure!r}: choose one of {', '.join(NEGATIVE_PRESSURE_MODES)}")
    if not out:
        out += require(p.stroke < p.depth, f"the stroke ({p.stroke:g} m) must be smaller than the depth ({p.depth:g} m)")
        out += require(0 < p.probe_x < p.tank_length,
                       f"probe_x = {p.probe_x:g} m must lie inside the tank (0, {p.tank_length:g}) m")
        out += require(p.depth >= 4 * p.dx, f"dx = {p.dx:g} m leaves fewer than 4 particle rows in the {p.depth:g} m "
                                            f"depth; choose dx <= {p.depth / 4:g} m")
        out += require(p.tank_length >= 2 * p.depth, f"the tank ({p.tank_length:g} m) must be at least two depths long")
        out += require(p.sponge_length == 0 or p.probe_x < p.tank_length - p.sponge_length,
                       f"the probe (x = {p.probe_x:g} m) stands inside the sponge, which starts at "
                       f"{p.tank_length - p.sponge_length:g} m: the flow there is damped, not physical; shorten "
                       f"sponge_length or move probe_x towards the paddle")
    return out
