r"""A :class:`Scene` lists bodies, effects, end time, outputs and probes; it is validated as a
whole before step 1, and every problem is reported at once in one :class:`SceneError`.

>>> from mlsgalerkin.fluid import FluidBody, Phase, TaitPressure, Gravity, Walls, wall_box
>>> water = FluidBody.block("water", (0, 0), (0.1, 0.05), 0.01, [Phase("water", 1000.0)])
>>> scene = Scene([water], [Gravity()], t_end=0.1)
>>> try:
...     scene.validate()
... except SceneError as err:
...     print(err)
scene 'scene' has 1 problem:
  - no pressure model: list exactly one of TaitPressure (...)
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Callable, Sequence

import numpy as np

from mlsgalerkin.fluid.bodies import FluidBody, WallBody
from mlsgalerkin.fluid.effects import SOLVER_QUANTITIES, STAGES, Effect

__all__ = ["Approximation", "Output", "Probe", "Scene", "SceneError", "Watchdog"]


class SceneError(ValueError):
    """A scene cannot run; the message lists every problem found."""


@dataclass(frozen=True)
class Approximation:
    """How the fields are approximated: kernel, ``h = h_factor · Δx``, basis, method, skin.

    ``skin`` (in units of ``Δx``) pads the neighbour search radius so the list is rebuilt only
    when some particle has moved more than ``skin/2``.

    ``condition_limit``: a particle whose scaled moment matrix has a 1-norm condition number
    above this uses a lower order (down to Shepard). The fluid default 100 is far stricter
    than the library's 1e8: interior particles sit at 3–10 and splashing ones reach 250, and
    such a particle's large linear-MLS gradients made a stiff mode that the ``h/c`` time step
    does not resolve (a 5 m/s drop impact diverged at 16 ms with 1e8 and runs with 100).
    """

    kernel: str = "cubic_spline"
    h_factor: float = 1.3
    basis: str = "linear"
    method: str = "mls"
    skin: float = 0.15
    condition_limit: float = 100.0


@dataclass(frozen=True)
class Output:
    """What a run writes (into the run directory given to ``Simulation.run(out=...)``).

    ``every``: simulated seconds between VTU frames; ``times``: explicit frame times instead;
    ``probe_every``: seconds between time-series rows (default every step); ``checkpoint_every``:
    seconds between checkpoints (``None``: only at the end); ``gif``/``png``: render the
    animation / a final snapshot of ``color_by``.
    """

    every: float | None = None
    times: tuple[float, ...] = ()
    probe_every: float | None = None
    checkpoint_every: float | None = None
    vtu: bool = True
    gif: bool = False
    png: bool = False
    color_by: str = "pressure"
    keep_checkpoints: int = 2


@dataclass(frozen=True)
class Probe:
    """A monitored scalar: ``func(state) -> float`` recorded in ``timeseries.csv``."""

    name: str
    func: Callable
    reads: tuple[str, ...] = ()


@dataclass(frozen=True)
class Watchdog:
    """Stop a diverging run: non-finite values, ``ρ/ρ0`` outside ``density_ratio``, or a speed
    above ``max_speed`` (m/s; default ``2 c0``)."""

    density_ratio: tuple[float, float] = (0.5, 2.0)
    max_speed: float | None = None
    keep_every: int = 50


@dataclass
class Scene:
    """Bodies, effects, end time, outputs and probes of a simulation."""

    bodies: list
    effects: list
    t_end: float
    name: str = "scene"
    approximation: Approximation = field(default_factory=Approximation)
    integrator: str = "kdk"
    mass: str = "lumped"
    dt_max: float | None = None
    safety: float = 1.0
    output: Output = field(default_factory=Output)
    probes: Sequence[Probe] = ()
    watchdog: Watchdog = field(default_factory=Watchdog)
    parameters: dict = field(default_factory=dict)

    @property
    def fluid_bodies(self) -> list[FluidBody]:
        return [b for b in self.bodies if isinstance(b, FluidBody)]

    @property
    def wall_bodies(self) -> list[WallBody]:
        return [b for b in self.bodies if isinstance(b, WallBody)]

    @property
    def dim(self) -> int:
        dims = {b.dim for b in self.bodies if hasattr(b, "dim")}
        return dims.pop() if len(dims) == 1 else 0

    @property
    def spacing(self) -> float:
        return self.fluid_bodies[0].spacing

    def effect(self, kind: type) -> Effect | None:
        """The listed effect of class ``kind`` (or ``None``)."""
        found = [e for e in self.effects if isinstance(e, kind)]
        return found[0] if found else None

    # ------------------------------------------------------------------ validation
    def problems(self) -> list[str]:
        """Every problem with this scene (empty list if it can run)."""
        from mlsgalerkin.kernels import KERNELS

        out: list[str] = []
        names = [getattr(b, "name", repr(b)) for b in self.bodies]
        for b in self.bodies:
            if not isinstance(b, (FluidBody, WallBody)):
                out.append(f"unknown body {b!r}: bodies must be FluidBody or WallBody")
        dup = sorted({n for n in names if names.count(n) > 1})
        if dup:
            out.append(f"body names must be unique, repeated: {dup}")
        if not self.fluid_bodies:
            out.append("no FluidBody: a scene needs at least one fluid body")
        dims = {b.dim for b in self.bodies if isinstance(b, (FluidBody, WallBody))}
        if len(dims) > 1:
            out.append(f"bodies mix dimensions {sorted(dims)}")
        spacings = {b.spacing for b in self.fluid_bodies}
        if len(spacings) > 1:
            out.append(f"fluid bodies must share one particle spacing, got {sorted(spacings)}")
        if not (np.isfinite(self.t_end) and self.t_end > 0):
            out.append(f"t_end must be positive, got {self.t_end!r}")
        if self.dt_max is not None and not self.dt_max > 0:
            out.append(f"dt_max must be positive, got {self.dt_max!r}")
        if not (0 < self.safety <= 1.5):
            out.append(f"safety factor must be in (0, 1.5], got {self.safety!r}")
        if self.integrator not in ("kdk", "predictor_corrector"):
            out.append(f"integrator must be 'kdk' or 'predictor_corrector', got {self.integrator!r}")
        if self.mass not in ("lumped", "particle", "consistent"):
            out.append(f"mass must be 'lumped', 'particle' or 'consistent', got {self.mass!r}")
        ap = self.approximation
        if ap.kernel not in KERNELS:
            out.append(f"unknown kernel {ap.kernel!r}; choose from {sorted(KERNELS)}")
        elif not KERNELS[ap.kernel].nonnegative:
            out.append(f"kernel {ap.kernel!r} changes sign and cannot be an MLS weight")
        if ap.method not in ("mls", "rkpm", "shepard", "orthogonal"):
            out.append(f"approximation method must be mls, rkpm, shepard or orthogonal, got {ap.method!r}")
        if not (0.5 <= ap.h_factor <= 4):
            out.append(f"h_factor = h/Δx must be in [0.5, 4], got {ap.h_factor!r}")
        if not (0 <= ap.skin <= 1):
            out.append(f"skin must be in [0, 1] (units of Δx), got {ap.skin!r}")

        # effects: types, the pressure model, and who provides what each reads
        effects = [e for e in self.effects]
        for e in effects:
            if not isinstance(e, Effect):
                out.append(f"unknown effect {e!r}: effects must be Effect instances")
        effects = [e for e in effects if isinstance(e, Effect)]
        pressure = [e for e in effects if e.role == "pressure"]
        if not pressure:
            out.append("no pressure model: list exactly one of TaitPressure (or another effect with role 'pressure')")
        elif len(pressure) > 1:
            out.append(f"two pressure models listed: {pressure}; keep exactly one")
        kinds = [type(e) for e in effects]
        dup_e = sorted({k.__name__ for k in kinds if kinds.count(k) > 1})
        if dup_e:
            out.append(f"effects listed twice: {dup_e}")
        enames = [e.name for e in effects]
        dup_n = sorted({n for n in enames if enames.count(n) > 1})
        if dup_n:
            out.append(f"effect names must be unique (timings, reports and checkpoints are keyed by "
                       f"name), repeated: {dup_n}; set a distinct `name` on each custom effect")
        provided = set(SOLVER_QUANTITIES)
        for e in effects:
            provided |= set(e.provides)
        for e in effects:
            bad = [s for s in e.stages if s not in STAGES]
            if bad:
                out.append(f"{e!r}: unknown stage(s) {bad}; stages are {STAGES}")
            missing = sorted(set(e.reads) - provided)
            if missing:
                out.append(f"{e!r} reads {missing}, which no listed effect provides")
        if self.wall_bodies and not any(type(e).__name__ == "Walls" for e in effects):
            out.append("the scene has wall bodies but no wall treatment: list Walls()")
        for p in self.probes:
            missing = sorted(set(p.reads) - provided)
            if missing:
                out.append(f"probe {p.name!r} reads {missing}, which no listed effect provides")
        if not out and self.dim:
            for e in effects:
                out.extend(e.check(self))
        elif self.dim:
            for e in effects:
                try:
                    out.extend(e.check(self))
                except Exception as exc:  # a check may depend on what failed above
                    out.append(f"{e!r}: check failed ({exc})")
        o = self.output
        if o.every is not None and not o.every > 0:
            out.append(f"output.every must be positive, got {o.every!r}")
        if o.checkpoint_every is not None and not o.checkpoint_every > 0:
            out.append(f"output.checkpoint_every must be positive, got {o.checkpoint_every!r}")
        return out

    def validate(self) -> None:
        """Raise :class:`SceneError` listing every problem, or return if the scene can run."""
        problems = self.problems()
        if problems:
            lines = "\n".join(f"  - {p}" for p in problems)
            n = len(problems)
            raise SceneError(f"scene {self.name!r} has {n} problem{'s' if n > 1 else ''}:\n{lines}")
