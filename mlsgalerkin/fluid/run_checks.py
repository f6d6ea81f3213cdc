r"""Checks of a fluid run while it runs: volume, particle distribution, Mach number, fallbacks.

:class:`FluidRunChecks` keeps, for the fluid solver, what a run's time series and ``summary.json``
report beyond the state itself, and warns once when a documented limit is passed:

=======================  ==================================================  =============================
check                    measured                                            warned (once)
=======================  ==================================================  =============================
volume                   ``geometric_volume`` (:mod:`~mlsgalerkin.fluid.      ``|volume_error|`` >
                         distribution`), ``volume_error`` =                  :data:`VOLUME_ERROR_LIMIT`
                         :math:`V_\text{geo}/\sum_f M_f/\rho_f - 1`,         (:class:`VolumeErrorWarning`)
                         at a time-series row (*)
particle distribution    ``min_pair_distance_dx``, ``clumped_pairs``          ``clumped_pairs`` >
                         (closer than 0.5 Δx), ``min_wall_distance_dx``,     :data:`CLUMPED_PAIRS_LIMIT`
                         at a time-series row (*)                            (:class:`ParticleClumpingWarning`)
Mach number              ``mach`` :math:`= \max_f |\mathbf v_f| / c_0`,       ``mach`` > :data:`MACH_LIMIT`
                         every step (the column: at the row)                 (:class:`~mlsgalerkin.fluid.eos.
                                                                             MachNumberWarning`)
shape-function fallback  share of the force evaluations with a fallback,     point share >
                         share of the fluid point evaluations that fell      :data:`FALLBACK_POINT_SHARE_LIMIT`
                         back, every evaluation                              after :data:`FALLBACK_MIN_EVALUATIONS`
                                                                             (:class:`ShapeFunctionFallbackWarning`)
=======================  ==================================================  =============================

(*) at the start and at every :data:`DISTRIBUTION_EVERY_STEPS`-th step, whatever the rows; the
rows in between repeat the last evaluation, so a run restarted from a checkpoint evaluates at
the same steps as one that never stopped (the Martin & Moyce dam break at a/Δx = 20 writes a
row every step; evaluated every 10 steps, the checks took 3.3 % of its run, nearly all of it the
geometric volume of a fluid spread over a bounding box 20 times its area).

The weakly compressible model holds the density within about :math:`\mathrm{Ma}^2` of
:math:`\rho_0` (:math:`\Delta\rho/\rho_0 \approx \mathrm{Ma}^2/2` at a stagnation point), so
``c0`` is chosen as ten times the largest speed (:math:`\mathrm{Ma} \le 0.1`, density error
≤ 1 %); past :data:`MACH_LIMIT` = 0.15 (error ≈ 2.3 %) the warning names the ``c0`` that brings
the run back to Ma = 0.1. The geometric volume is the fluid's own measure of space
(:mod:`mlsgalerkin.fluid.distribution`): a fluid whose particles pack tighter than their
volumes ``M/ρ`` say loses volume that the density does not show. The summary keeps the largest
``|volume_error|`` and when, the largest ``|mean|`` of the errors over :data:`VOLUME_MEAN_WINDOW`
(50 ms; ``max_abs_mean_error``) and when, where the largest reading sits (``where_at_max``, below),
the smallest pair distance and when, the most clumped pairs and when, the largest Mach number and
when, and the fallback shares.

**Where a volume error sits.** From :data:`VOLUME_ATTRIBUTION_FROM` (0.5 %) on, a new largest
reading at least :data:`VOLUME_ATTRIBUTION_STEP` past the last one split, and the reading that is
warned about, are split by :func:`~mlsgalerkin.fluid.distribution.volume_error_by_class`: each
particle's share of the geometric volume against its ``M/ρ``, summed over the drops (no other
particle within 1.5 spacings), the sheets and ragged surface (1–4) and the surface rows and bulk (5
or more), and across them over the particles at ``p ≤ 0`` (the cavitation floor, where no density
relaxation can give a particle volume). A lost volume in the bulk is a packing (pairing, a
collapse); a gain in the sheets and at the floor is a jet or a sheet stretched at ``ρ0``
(``docs/theory/stabilisation.md`` §10). The warning names the split, and ``where_at_max`` keeps
the last one (``time_s``, ``volume_error``, per class its share of the particles and its
``contribution``; the contributions of the three neighbour classes add up to the error): at the
run's largest reading to within :data:`VOLUME_ATTRIBUTION_STEP`. Each split costs one
:func:`~mlsgalerkin.fluid.distribution.cell_volumes` (14 ms at 1 250 particles in 2D); a run with a
largest error of 2 % pays at most 31.

All of it is part of a checkpoint (:meth:`FluidRunChecks.state_dict`): a restarted run reports
the same extremes as an uninterrupted one.
"""

from __future__ import annotations

import math
import time
import warnings
from collections.abc import Callable
from typing import Any

import numpy as np

from mlsgalerkin.fluid.distribution import (
    AT_FLOOR,
    CLUMP_DISTANCE,
    NEIGHBOUR_CLASSES,
    pair_statistics,
    volume_error,
    volume_error_by_class,
)
from mlsgalerkin.fluid.domain_exit import still_in_run
from mlsgalerkin.fluid.eos import MachNumberWarning
from mlsgalerkin.fluid.state import FluidState

__all__ = [
    "CLUMPED_PAIRS_LIMIT",
    "DISTRIBUTION_EVERY_STEPS",
    "FALLBACK_MIN_EVALUATIONS",
    "FALLBACK_POINT_SHARE_LIMIT",
    "MACH_LIMIT",
    "MACH_TARGET",
    "VOLUME_ATTRIBUTION_FROM",
    "VOLUME_ATTRIBUTION_STEP",
    "VOLUME_ERROR_LIMIT",
    "VOLUME_MEAN_WINDOW",
    "FluidRunChecks",
    "ParticleClumpingWarning",
    "ShapeFunctionFallbackWarning",
    "VolumeErrorWarning",
]

#: ``|V_geo / Σ M/ρ − 1|`` beyond which the volume is warned about.
VOLUME_ERROR_LIMIT = 0.01
#: The window (s) of the volume error's running mean in the summary: the measure's pixel-wide
#: closing threshold scatters single readings by about 0.15–0.2 % in a splashing flow, at a
#: correlation time of about a millisecond (``docs/theory/stabilisation.md`` §10), so the
#: largest single reading of a long run sits that scatter's two or three standard deviations
#: above what the water does; the mean over 50 ms does not.
VOLUME_MEAN_WINDOW = 0.05
#: From this ``|volume_error|`` on, a new largest reading is split by where it sits
#: (:func:`~mlsgalerkin.fluid.distribution.volume_error_by_class`; ``where_at_max`` in the summary) ...
VOLUME_ATTRIBUTION_FROM = 0.005
#: ... when it is at least this much past the reading split last (so a run splits at most
#: ``(largest − FROM)/STEP + 1`` readings, each one :func:`~mlsgalerkin.fluid.distribution.cell_volumes`),
#: and always at the reading that is warned about.
VOLUME_ATTRIBUTION_STEP = 0.0005
#: More clumped pairs (closer than ``CLUMP_DISTANCE`` spacings) than this are warned about.
CLUMPED_PAIRS_LIMIT = 0
#: The Mach number ``max|v|/c0`` the sound speed is chosen for (``c0 = 10 u_max``).
MACH_TARGET = 0.1
#: The Mach number beyond which the run warns (density error ≈ Ma² ≈ 2.3 %).
MACH_LIMIT = 0.15
#: Share of the fluid point evaluations whose shape functions fell back, beyond which it warns:
#: three times the largest share of the healthy splashing runs measured (the dam break with impact
#: at H/Δx = 20 through T = 7: 0.67 %; the Martin & Moyce dam break at a/Δx = 20: 0.20 %).
FALLBACK_POINT_SHARE_LIMIT = 0.02
#: Force evaluations before the fallback share is judged (the first steps of a run are few).
FALLBACK_MIN_EVALUATIONS = 100
#: The volume and pair statistics are evaluated at the start and at every this-many-th step,
#: whatever the time-series rows (a problem that records a row every step or two would pay them
#: at every step); the rows in between repeat the last evaluation.
DISTRIBUTION_EVERY_STEPS = 20


class VolumeErrorWarning(UserWarning):
    """The fluid's geometric volume departs from ``Σ M/ρ`` by more than the limit."""


class ParticleClumpingWarning(UserWarning):
    """Fluid particle pairs closer than the clump distance (pairing or collapse)."""


class ShapeFunctionFallbackWarning(UserWarning):
    """Many fluid particles' shape functions fell back to a lower order."""


def _where(s: FluidState, k: int) -> str:
    body = next((name for name, sl in s.bodies.items() if sl.start <= k < sl.stop), "?")
    return f"particle {k} of body {body!r} at {np.round(s.x[k], 6).tolist()}"


class FluidRunChecks:
    """The run's volume, distribution, Mach-number and fallback records (module docstring)."""

    def __init__(self) -> None:
        self.volume = {"max_abs_error": 0.0, "time_of_max_s": None, "error_at_start": None, "error_last": None,
                       "time_of_last_s": None, "warned": False, "max_abs_mean_error": None,
                       "time_of_max_mean_s": None, "mean_window_s": VOLUME_MEAN_WINDOW,
                       "time_first_s": None, "where_at_max": None}
        self.recent_volume: list[tuple[float, float]] = []   # (t, error) of the last VOLUME_MEAN_WINDOW
        self.pairs = {"min_pair_distance_dx": math.inf, "time_of_min_s": None, "max_clumped_pairs": 0,
                      "time_of_max_clumped_s": None, "min_wall_distance_dx": math.inf, "warned": False}
        self.mach = {"max": 0.0, "time_of_max_s": None, "warned": False}
        self.fallback = {"evaluations": 0, "warned": False}
        self.last = {"step": None, "columns": {}}   # the last evaluation of the distribution columns
        self.seconds = 0.0   # wall time spent in the checks (not part of a checkpoint)

    # ------------------------------------------------------------------ every row
    def row(self, s: FluidState) -> dict[str, float]:
        """The time-series columns of the current state (geometric volume, volume error, pair
        statistics: those of the last evaluation — at the start, then every
        :data:`DISTRIBUTION_EVERY_STEPS`-th step, :meth:`after_step` —; the Mach number now)."""
        t0 = time.perf_counter()
        last = self.last
        if last["step"] is None:
            last["step"], last["columns"] = s.step, self._distribution(s)
        out = dict(last["columns"])
        if math.isfinite(s.c0):
            out["mach"] = self.mach_now(s)
        self.seconds += time.perf_counter() - t0
        return out

    def _distribution(self, s: FluidState) -> dict[str, float]:
        f = s.fluid
        out: dict[str, float] = {}
        inside = still_in_run(s)
        if inside.any():    # the particles taken out of the run (domain_exit) are left out
            vgeo, err = volume_error(s.x[f], s.M[f], s.rho[f], s.spacing, inside)
            out["geometric_volume"] = vgeo
            out["volume_error"] = err
            self._record_volume(s, err, lambda: self.volume_split(s, inside))
        if s.neighbors is not None and s.n_fluid:
            nb = s.neighbors
            ps = pair_statistics(nb.indptr, nb.indices, s.x, s.n_fluid, s.spacing, period=s.period)
            out["min_pair_distance_dx"] = ps.min_pair_distance_dx
            out["clumped_pairs"] = ps.clumped_pairs
            out["min_wall_distance_dx"] = ps.min_wall_distance_dx
            self._record_pairs(s, ps)
        return out

    def _record_volume(self, s: FluidState, err: float, split_now: Callable[[], dict[str, Any]] | None = None) -> None:
        """Records a reading ``err`` at ``s.t``; ``split_now()`` gives where it sits (:meth:`volume_split`),
        called when the reading is to be split (module docstring; never without it)."""
        rec = self.volume
        if rec["error_at_start"] is None:
            rec["error_at_start"] = err
        rec["error_last"], rec["time_of_last_s"] = err, s.t
        largest = abs(err) > rec["max_abs_error"]
        if largest:
            rec["max_abs_error"], rec["time_of_max_s"] = abs(err), s.t
        self._record_mean(s.t, err)
        warn = abs(err) > VOLUME_ERROR_LIMIT and not rec["warned"]
        split = rec["where_at_max"]
        if split_now is not None and (warn or (
                largest and abs(err) >= VOLUME_ATTRIBUTION_FROM
                and (split is None or abs(err) >= abs(split["volume_error"]) + VOLUME_ATTRIBUTION_STEP))):
            rec["where_at_max"] = split = split_now()
        if warn:
            rec["warned"] = True
            if err < 0:
                what = ("lost", "tighter", "pairing, clumping or a collapsing column",
                        "more particle shifting or density diffusion, or a finer resolution")
            else:
                what = ("gained", "looser", "voids, a spray of isolated particles or a fluid under tension",
                        "cavitation (TaitPressure(negative_pressure='cavitate')) or particle shifting")
            where, advice = "not split", f"Try {what[3]}"
            if split is not None:
                where = ", ".join(f"{name} {split[name]['contribution']:+.2%}" for name, _, _ in NEIGHBOUR_CLASSES
                                  if name in split)
                if AT_FLOOR in split:
                    where += f"; {AT_FLOOR} (p ≤ 0) {split[AT_FLOOR]['contribution']:+.2%}"
                    if err > 0 and split[AT_FLOOR]["contribution"] >= 0.5 * err:
                        advice = ("Most of it sits at the cavitation floor, where the density cannot fall: a jet or a "
                                  "sheet stretching at ρ0, which neither more cavitation nor a finer resolution "
                                  "removes (docs/theory/stabilisation.md §10)")
            warnings.warn(
                f"at t = {s.t:.6g} s the fluid has {what[0]} {abs(err):.2%} of its volume: its geometric volume (the "
                f"closed union of the particles' cells) is {err:+.2%} off the volume Σ M/ρ its masses and densities "
                f"say (limit {VOLUME_ERROR_LIMIT:.0%}). The particles fill space {what[1]} than their density says "
                f"({what[2]}). Where it sits (each class's part of the error, the classes by the other particles "
                f"within 1.5 spacings): {where}. {advice}; the columns geometric_volume "
                "and volume_error of timeseries.csv follow it, and summary.json's run_checks.volume.where_at_max "
                "splits its largest reading", VolumeErrorWarning, stacklevel=3)

    @staticmethod
    def volume_split(s: FluidState, inside: np.ndarray) -> dict[str, Any]:
        """The current volume error split by where it sits
        (:func:`~mlsgalerkin.fluid.distribution.volume_error_by_class` over the fluid particles
        still in the run, ``inside``, with those at ``p ≤ 0`` as the floor's class): ``time_s``,
        ``volume_error`` and, per class, its share of the particles and its contribution (they add
        up to the error)."""
        f = s.fluid
        x, volume = s.x[f][inside], (s.M[f] / s.rho[f])[inside]
        split = volume_error_by_class(x, volume, s.spacing, at_floor=(s.p[f] <= 0.0)[inside])
        out: dict[str, Any] = {"time_s": s.t, "volume_error": split.pop("volume_error")}
        for name, entry in split.items():
            out[name] = {"particles": entry["particles"], "contribution": entry["contribution"]}
        return out

    def _record_mean(self, t: float, err: float) -> None:
        """The largest ``|mean|`` of the errors evaluated in a window of :data:`VOLUME_MEAN_WINDOW`
        ending at an evaluation, once the run has evaluated over a whole window (the time of the
        window's end is kept)."""
        recent = self.recent_volume
        recent.append((t, err))
        first = self.volume["time_first_s"]
        if first is None:
            self.volume["time_first_s"] = first = t
        while recent and recent[0][0] <= t - VOLUME_MEAN_WINDOW:
            recent.pop(0)
        if t - first < VOLUME_MEAN_WINDOW:
            return
        mean = abs(sum(e for _, e in recent) / len(recent))
        best = self.volume["max_abs_mean_error"]
        if best is None or mean > best:
            self.volume["max_abs_mean_error"], self.volume["time_of_max_mean_s"] = mean, t

    def _record_pairs(self, s: FluidState, ps: Any) -> None:
        rec = self.pairs
        if ps.min_pair_distance_dx < rec["min_pair_distance_dx"]:
            rec["min_pair_distance_dx"], rec["time_of_min_s"] = ps.min_pair_distance_dx, s.t
        if ps.clumped_pairs > rec["max_clumped_pairs"]:
            rec["max_clumped_pairs"], rec["time_of_max_clumped_s"] = ps.clumped_pairs, s.t
        rec["min_wall_distance_dx"] = min(rec["min_wall_distance_dx"], ps.min_wall_distance_dx)
        if ps.clumped_pairs > CLUMPED_PAIRS_LIMIT and not rec["warned"]:
            rec["warned"] = True
            warnings.warn(
                f"at t = {s.t:.6g} s, {ps.clumped_pairs} pairs of fluid particles are closer than "
                f"{CLUMP_DISTANCE} spacings (the closest {ps.min_pair_distance_dx:.3f} spacings apart): the particles "
                "clump (the pairing or tensile instability), and the fluid packs tighter than its density says. "
                "Use particle shifting, a kernel that resists pairing (Wendland) or more dissipation; the columns "
                "min_pair_distance_dx and clumped_pairs of timeseries.csv follow it", ParticleClumpingWarning,
                stacklevel=3)

    # ------------------------------------------------------------------ every step
    @staticmethod
    def mach_now(s: FluidState) -> float:
        """``max_f |v_f| / c0`` over the fluid particles now (0 without fluid)."""
        f = s.fluid
        if not s.n_fluid:
            return 0.0
        speed2 = np.einsum("ij,ij->i", s.v[f], s.v[f])   # no BLAS (see FluidState.kinetic_energy)
        return math.sqrt(float(speed2.max())) / s.c0

    def after_step(self, s: FluidState, fallback_steps: int, fallback_points: int) -> None:
        """The Mach number of the step and the fallback shares so far (``fallback_steps``
        evaluations with a fallback and ``fallback_points`` fallen-back points, the solver's
        counters); the distribution columns at every :data:`DISTRIBUTION_EVERY_STEPS`-th step;
        warns once past :data:`MACH_LIMIT` or :data:`FALLBACK_POINT_SHARE_LIMIT` (and the
        distribution's limits)."""
        t0 = time.perf_counter()
        if s.step % DISTRIBUTION_EVERY_STEPS == 0:
            self.last["step"], self.last["columns"] = s.step, self._distribution(s)
        if math.isfinite(s.c0) and s.c0 > 0:
            ma = self.mach_now(s)
            rec = self.mach
            if ma > rec["max"]:
                rec["max"], rec["time_of_max_s"] = ma, s.t
            if ma > MACH_LIMIT and not rec["warned"]:
                rec["warned"] = True
                u = ma * s.c0
                k = int(np.argmax(np.einsum("ij,ij->i", s.v[s.fluid], s.v[s.fluid])))
                warnings.warn(
                    f"at t = {s.t:.6g} s the fluid moves at Mach {ma:.3g} ({_where(s, k)} at {u:.4g} m/s against "
                    f"c0 = {s.c0:.4g} m/s; limit {MACH_LIMIT}): the weakly compressible model's density errors grow "
                    f"like Ma² (≈ {ma * ma:.1%} here). Raise c0 to at least {u / MACH_TARGET:.4g} m/s (Mach "
                    f"{MACH_TARGET}); the column mach of timeseries.csv follows it", MachNumberWarning, stacklevel=3)
        ev = self.fallback["evaluations"]
        if (fallback_points and not self.fallback["warned"] and ev >= FALLBACK_MIN_EVALUATIONS
                and fallback_points > FALLBACK_POINT_SHARE_LIMIT * ev * s.n_fluid):
            shares = self.fallback_shares(fallback_steps, fallback_points, s.n_fluid)
            self.fallback["warned"] = True
            warnings.warn(
                f"at t = {s.t:.6g} s the shape functions of {shares['point_share']:.2%} of the fluid point evaluations "
                f"fell back to a lower order (on {shares['evaluation_share']:.0%} of the force evaluations; limit "
                f"{FALLBACK_POINT_SHARE_LIMIT:.0%} of the points): the particles there have too few or badly placed "
                "neighbours (a splash, a thin jet, clumping). Raise h_factor or refine; the column fallback_points of "
                "timeseries.csv and the mls_order frame field show where", ShapeFunctionFallbackWarning,
                stacklevel=3)
        self.seconds += time.perf_counter() - t0

    def count_evaluation(self) -> None:
        """One more force evaluation (the denominator of the fallback shares)."""
        self.fallback["evaluations"] += 1

    def fallback_shares(self, fallback_steps: int, fallback_points: int, n_fluid: int) -> dict[str, float]:
        """``evaluation_share``: evaluations with a fallback over all evaluations (one per step
        with ``kdk``); ``point_share``: fallen-back fluid points over ``evaluations × n_fluid``."""
        ev = self.fallback["evaluations"]
        return {"evaluation_share": fallback_steps / ev if ev else 0.0,
                "point_share": fallback_points / (ev * n_fluid) if ev and n_fluid else 0.0}

    # ------------------------------------------------------------------ report and checkpoint
    def summary(self, s: FluidState, fallback_steps: int, fallback_points: int) -> dict[str, Any]:
        """The ``summary.json`` entries (under the fluid's ``run_checks``)."""
        fin = lambda v: v if v is None or math.isfinite(v) else None  # noqa: E731  (JSON has no inf)
        return {
            "volume": dict(self.volume, limit=VOLUME_ERROR_LIMIT),
            "particle_distribution": dict(self.pairs, min_pair_distance_dx=fin(self.pairs["min_pair_distance_dx"]),
                                          min_wall_distance_dx=fin(self.pairs["min_wall_distance_dx"]),
                                          clump_distance_dx=CLUMP_DISTANCE, clumped_pairs_limit=CLUMPED_PAIRS_LIMIT),
            "mach": dict(self.mach, c0=fin(s.c0), limit=MACH_LIMIT, target=MACH_TARGET),
            "evaluated_every_steps": DISTRIBUTION_EVERY_STEPS,
            "time_s": round(self.seconds, 6),
            "shape_function_fallback": dict(self.fallback_shares(fallback_steps, fallback_points, s.n_fluid),
                                            evaluations=self.fallback["evaluations"], warned=self.fallback["warned"],
                                            point_share_limit=FALLBACK_POINT_SHARE_LIMIT),
        }

    def state_dict(self) -> dict[str, Any]:
        return {"volume": dict(self.volume), "pairs": dict(self.pairs), "mach": dict(self.mach),
                "fallback": dict(self.fallback), "last": {"step": self.last["step"],
                                                          "columns": dict(self.last["columns"])},
                "recent_volume": [list(r) for r in self.recent_volume]}

    def load_state_dict(self, d: dict[str, Any]) -> None:
        for key in ("volume", "pairs", "mach", "fallback", "last"):
            if key in d:
                getattr(self, key).update(d[key])
        self.recent_volume = [(float(t), float(e)) for t, e in d.get("recent_volume", [])]
