r"""What a run writes into its directory, written atomically as it goes:

================================  =========================================================
file                              content
================================  =========================================================
``timeseries.csv``                ``time, dt, step`` + built-in monitors + the scene's probes
``particles.pvd`` + ``*.vtu``     particle frames (open the .pvd in ParaView)
``checkpoints/checkpoint_*.npz``  restart files (npz + JSON metadata; never pickle)
``summary.json``                  parameters, sizes, wall time, time per stage and effect,
                                  diagnostics, effect reports, the problem's results
``animation.gif``, ``final.png``  pictures (``Output(gif=True, png=True)``)
================================  =========================================================

Built-in monitors: kinetic energy, potential energy (if gravity is listed), total mass,
momentum, the largest speed, the density-ratio range and the number of shape-function
fallbacks in the last step.
"""

from __future__ import annotations

import logging
import math
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

if TYPE_CHECKING:  # pragma: no cover
    from mlsgalerkin.simulation import Simulation

__all__ = ["RunOutput", "frame_fields"]

logger = logging.getLogger(__name__)


def frame_fields(sim: "Simulation") -> dict[str, np.ndarray]:
    """Point data of a VTU frame: velocity, pressure, density, phase, body, flags."""
    s = sim.state
    data = {
        "velocity": s.v, "pressure": s.p, "density": s.rho, "density_ratio": s.rho / s.rho0,
        "phase": s.phase.astype(np.int32), "is_wall": (np.arange(s.n) >= s.n_fluid).astype(np.int32),
        "speed": np.sqrt(np.einsum("ij,ij->i", s.v, s.v)),
    }
    if sim._table is not None:
        data["mls_order"] = sim._table.order.astype(np.int32)
    for k, v in s.extra.items():
        data[k] = np.asarray(v).astype(np.int32) if np.asarray(v).dtype == bool else v
    return data


class RunOutput:
    """Writes the run directory of a :class:`~mlsgalerkin.simulation.Simulation`."""

    def __init__(self, sim: "Simulation", directory: str | Path) -> None:
        self.sim = sim
        self.dir = Path(directory)
        self.dir.mkdir(parents=True, exist_ok=True)
        (self.dir / "checkpoints").mkdir(exist_ok=True)
        sc = sim.scene
        o = sc.output
        if o.times:
            self.frame_times = sorted(float(t) for t in o.times)
        elif o.every:
            n = int(math.floor(sc.t_end / o.every + 1e-9))
            self.frame_times = [k * o.every for k in range(n + 1)]
        else:
            self.frame_times = [0.0, sc.t_end]
        self.next_frame = 0
        self.next_probe = 0.0
        self.next_checkpoint = o.checkpoint_every if o.checkpoint_every else math.inf
        grav = [e for e in sc.effects if type(e).__name__ == "Gravity"]
        self._g = grav[0].g if grav else None
        self.columns = ["time", "dt", "step", "kinetic_energy", "total_mass"]
        if self._g is not None:
            self.columns.append("potential_energy")
        d = sc.dim
        self.columns += [f"momentum_{'xyz'[a]}" for a in range(d)]
        self.columns += ["max_speed", "min_density_ratio", "max_density_ratio", "fallback_points"]
        self.columns += [p.name for p in sc.probes]
        self._last_dt = 0.0
        self._last_fallback = 0

    # ------------------------------------------------------------------ lifecycle
    def start(self, resumed: bool) -> None:
        from mlsgalerkin.io import PVDSeries, TimeSeriesWriter

        s = self.sim.state
        if resumed:
            self.series = PVDSeries.resume(self.dir, "particles", after_time=s.t)
            self.ts = TimeSeriesWriter.resume(self.dir / "timeseries.csv", after_time=s.t)
            self.next_frame = sum(1 for t in self.frame_times if t <= s.t + 1e-12)
            self.next_probe = s.t + (self.sim.scene.output.probe_every or 0.0)
            ce = self.sim.scene.output.checkpoint_every
            self.next_checkpoint = (math.floor(s.t / ce + 1e-9) + 1) * ce if ce else math.inf
        else:
            self.series = PVDSeries(self.dir, "particles")
            self.ts = TimeSeriesWriter(self.dir / "timeseries.csv", self.columns)
            self.record()
            self.maybe_frame()
        self.ts.flush()

    def after_step(self) -> None:
        s = self.sim.state
        pe = self.sim.scene.output.probe_every
        if pe is None or s.t >= self.next_probe - 1e-12 or s.t >= self.sim.scene.t_end * (1 - 1e-12):
            self.record()
            self.next_probe = s.t + (pe or 0.0)
        self.maybe_frame()
        if s.t >= self.next_checkpoint - 1e-12:
            self.write_checkpoint(*self.sim.checkpoint_data())
            self.ts.flush()
            ce = self.sim.scene.output.checkpoint_every
            self.next_checkpoint = (math.floor(s.t / ce + 1e-9) + 1) * ce

    def finish(self, summary: dict) -> None:
        s = self.sim.state
        if not self.ts.rows or self.ts.rows[-1]["time"] < s.t:
            self.record()
        self.ts.flush()
        if not self.series.frames or self.series.frames[-1][0] < s.t - 1e-12:
            self.write_frame()
        self.write_checkpoint(*self.sim.checkpoint_data())
        self.write_summary(summary)
        o = self.sim.scene.output
        if o.gif or o.png:
            try:
                self.render(gif=o.gif, png=o.png)
            except Exception as exc:  # pictures must not lose a finished run
                logger.warning("rendering failed (%s); the VTU series and tables are written", exc)

    # ------------------------------------------------------------------ pieces
    def record(self) -> None:
        sim, s = self.sim, self.sim.state
        f = s.fluid
        speed2 = np.einsum("ij,ij->i", s.v[f], s.v[f])
        ratio = s.rho[f] / s.rho0[f]
        row = {
            "time": s.t, "dt": self.sim.last_dt, "step": s.step,
            "kinetic_energy": s.kinetic_energy(), "total_mass": s.total_mass(),
        }
        if self._g is not None:
            row["potential_energy"] = -float(np.einsum("i,ij,j->", s.M[f], s.x[f], self._g))  # no BLAS
        mom = s.momentum()
        for a in range(s.dim):
            row[f"momentum_{'xyz'[a]}"] = float(mom[a])
        row["max_speed"] = float(np.sqrt(speed2.max())) if speed2.size else 0.0
        row["min_density_ratio"] = float(ratio.min()) if ratio.size else 1.0
        row["max_density_ratio"] = float(ratio.max()) if ratio.size else 1.0
        row["fallback_points"] = int(np.count_nonzero(sim._table.order[: s.n_fluid] < sim._order)) if sim._table is not None else 0
        for p in sim.scene.probes:
            row[p.name] = float(p.func(s))
        self.ts.append(row)

    def maybe_frame(self) -> None:
        s = self.sim.state
        while self.next_frame < len(self.frame_times) and s.t >= self.frame_times[self.next_frame] - 1e-12:
            self.write_frame()
            # several frame times inside one step: write the frame once
            while self.next_frame < len(self.frame_times) and self.frame_times[self.next_frame] <= s.t + 1e-12:
                self.next_frame += 1

    def write_frame(self) -> None:
        if not self.sim.scene.output.vtu:
            return
        s = self.sim.state
        self.series.add(s.t, s.x, frame_fields(self.sim))

    def write_checkpoint(self, arrays: dict, meta: dict, name: str | None = None) -> Path:
        from mlsgalerkin.io import checkpoint_path, prune_checkpoints, save_checkpoint

        folder = self.dir / "checkpoints"
        path = folder / f"{name}.npz" if name else checkpoint_path(folder, int(meta["step"]))
        save_checkpoint(path, arrays, meta)
        if name is None:
            prune_checkpoints(folder, keep=self.sim.scene.output.keep_checkpoints)
        return path

    def write_summary(self, summary: dict) -> None:
        from mlsgalerkin.io.files import write_json
        from mlsgalerkin.io.provenance import provenance

        summary = dict(summary)
        try:
            summary["provenance"] = provenance(f"run {self.sim.scene.name}")
        except Exception:  # provenance is best effort (no git in an installed package)
            pass
        write_json(self.dir / "summary.json", summary)

    def timeseries_dict(self) -> dict[str, np.ndarray]:
        from mlsgalerkin.io import read_timeseries

        return read_timeseries(self.dir / "timeseries.csv")

    def render(self, gif: bool = True, png: bool = True) -> None:
        from mlsgalerkin.io import read_vtu, render_snapshot, render_animation

        color = self.sim.scene.output.color_by
        frames = []
        for t, path in self.series.frames:
            pts, data = read_vtu(path)
            frames.append((t, pts[:, : self.sim.scene.dim], np.asarray(data[color])))
        if not frames:
            return
        allv = np.concatenate([fr[2] for fr in frames])
        clim = (float(np.percentile(allv, 1)), float(np.percentile(allv, 99)))
        if clim[0] == clim[1]:
            clim = (clim[0] - 1.0, clim[1] + 1.0)
        lo = np.min([fr[1].min(axis=0) for fr in frames], axis=0)
        hi = np.max([fr[1].max(axis=0) for fr in frames], axis=0)
        bounds = (float(lo[0]), float(hi[0]), float(lo[1]), float(hi[1]))
        if gif:
            render_animation(self.dir / "animation.gif", frames, clim=clim, title=self.sim.scene.name,
                             scalar_name=color, bounds=bounds)
        if png:
            t, pts, val = frames[-1]
            render_snapshot(self.dir / "final.png", pts, val, title=f"{self.sim.scene.name}  t = {t:.3f} s",
                            clim=clim, scalar_name=color, bounds=bounds)
