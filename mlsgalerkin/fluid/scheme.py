r"""The fluid's numerical settings: :class:`FluidScheme`, and :class:`FluidContext`, what an effect
sees of them and of the scene.

A scene lists the fluid's settings once, as a scheme beside the other solvers' schemes:

>>> from mlsgalerkin.fluid import FluidScheme, Gravity, TaitPressure, Walls
>>> scheme = FluidScheme([TaitPressure(20.0), Gravity((0.0, -9.81)), Walls()], dt_max=1e-3)
>>> scheme.problems()
[]
>>> FluidScheme([TaitPressure(20.0)], safety=3.0).problems()
['safety factor must be in (0, 1.5], got 3.0']

:func:`~mlsgalerkin.fluid.presets.water` returns the recommended scheme for water with a free
surface, so a problem lists only what it changes. A scheme that lists no stabilising effect at all
gets the recommended set (:mod:`~mlsgalerkin.fluid.recommended`) added, and says so; one that lists
part of it is warned; ``stabilisation="as_listed"`` runs exactly the list:

>>> [type(e).__name__ for e in FluidScheme([TaitPressure(20.0), Gravity((0.0, -9.81))]).effects]
... # doctest: +NORMALIZE_WHITESPACE
['TaitPressure', 'Gravity', 'MonaghanViscosity', 'DensityDiffusion', 'ParticleShifting',
 'LinearConsistentPressure', 'VolumeConsistency']
>>> len(FluidScheme([TaitPressure(20.0)], stabilisation="as_listed").effects)
1
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass, field
from typing import Any, ClassVar, Sequence

from mlsgalerkin.approximation.settings import Approximation
from mlsgalerkin.dynamics import SceneView, Scheme
from mlsgalerkin.fluid.effect import Effect
from mlsgalerkin.fluid.integrators import make_integrator
from mlsgalerkin.fluid.mass import MASS_OPTIONS
from mlsgalerkin.fluid.recommended import (
    STABILISATION_MODES,
    is_stabilising,
    missing_from_recommended,
    recommended_stabilisation,
)
from mlsgalerkin.io.files import to_jsonable
from mlsgalerkin.periodic import Periodic

__all__ = ["FluidContext", "FluidScheme", "PartialStabilisationWarning", "SPACING_TOLERANCE"]

#: Largest relative difference between a wall body's particle spacing and the fluid's: wall
#: particles are nodes of the fluid's approximation and each integrates a ``spacing^d`` volume,
#: so walls on another lattice leave the fluid's Galerkin sums wrong near the wall.
SPACING_TOLERANCE = 1e-6


class PartialStabilisationWarning(UserWarning):
    """A scheme lists some stabilising effects but not the whole recommended set."""


@dataclass
class FluidScheme(Scheme):
    """The fluid's effects and options: everything numerical about the particle solver.

    Parameters
    ----------
    effects : list of Effect
        The units of physics (:mod:`mlsgalerkin.fluid`; nothing unlisted is computed); exactly
        one pressure model.
    approximation : Approximation
        Kernel, ``h/Δx``, basis, method, neighbour skin.
    integrator : str or Integrator
        ``"kdk"`` (kick-drift-kick, default) or ``"predictor_corrector"``.
    mass : str
        ``"lumped"``, ``"particle"`` or ``"consistent"``.
    safety : float
        Factor on the stable time step, in ``(0, 1.5]``.
    dt_max : float, optional
        Largest time step (s).
    spacing : float, optional
        The particle spacing ``Δx`` (m) the fluid bodies were built with; checked against every
        fluid and wall body (``None``: the fluid bodies' own, which must agree).
    periodic : Periodic, optional
        The axes along which the domain repeats (:class:`~mlsgalerkin.periodic.Periodic`, e.g.
        ``Periodic(x=(0.0, L))``): neighbours, shape functions and every pair term see across
        the seam (minimum-image offsets) and the fluid particles wrap back into the box after
        each drift. ``None`` (default): no periodic axis.
    domain_exit : bool
        Take the fluid particles that leave the domain (the particles' starting bounding box
        widened by two search radii, open above) out of the run (default ``True``; a scene
        without wall particles has no domain; :mod:`mlsgalerkin.fluid.domain_exit`).
    """

    solver: ClassVar[str] = "mlsgalerkin.fluid.solver:FluidSolver"

    effects: Sequence[Effect] = ()
    approximation: Approximation = field(default_factory=Approximation)
    integrator: Any = "kdk"
    mass: str = "lumped"
    safety: float = 1.0
    dt_max: float | None = None
    spacing: float | None = None
    periodic: Periodic | None = None
    stabilisation: str = "auto"
    domain_exit: bool = True

    def __post_init__(self) -> None:
        listed = list(self.effects)
        #: what ``stabilisation="auto"`` appended to the listed effects (empty if nothing)
        self.added_stabilisation: list[Effect] = []
        #: the recommended stabilising effects a list with some stabilisation leaves out
        self.missing_stabilisation: list[str] = []
        if self.stabilisation == "auto":
            if not any(is_stabilising(e) for e in listed):
                self.added_stabilisation = recommended_stabilisation()
            else:
                self.missing_stabilisation = missing_from_recommended(listed)
                if self.missing_stabilisation:
                    warnings.warn(
                        "the fluid scheme lists its own stabilisation without "
                        f"{', '.join(self.missing_stabilisation)} of the recommended set: impacts and long quiet "
                        "runs are known to go unstable or drift without them (docs/theory/stabilisation.md). "
                        "Build the scheme with water(...) or list them; FluidScheme(..., stabilisation='as_listed') "
                        "runs exactly the list without this warning", PartialStabilisationWarning, stacklevel=3)
        self.effects = listed + self.added_stabilisation

    def problems(self) -> list[str]:
        """Problems with the options alone (the effects are checked with the bodies, by the solver)."""
        out: list[str] = []
        if self.dt_max is not None and not (isinstance(self.dt_max, (int, float)) and self.dt_max > 0):
            out.append(f"dt_max must be positive, got {self.dt_max!r}")
        if not isinstance(self.domain_exit, bool):
            out.append(f"domain_exit must be True or False, got {self.domain_exit!r}")
        if not (isinstance(self.safety, (int, float)) and 0 < self.safety <= 1.5):
            out.append(f"safety factor must be in (0, 1.5], got {self.safety!r}")
        try:
            make_integrator(self.integrator)
        except ValueError as err:
            out.append(str(err))
        if self.mass not in MASS_OPTIONS:
            out.append(f"mass must be 'lumped', 'particle' or 'consistent', got {self.mass!r}")
        if self.spacing is not None and not (isinstance(self.spacing, (int, float)) and self.spacing > 0):
            out.append(f"spacing must be positive (the particle spacing, m), got {self.spacing!r}")
        if self.stabilisation not in STABILISATION_MODES:
            out.append(f"stabilisation must be one of {', '.join(STABILISATION_MODES)}, got {self.stabilisation!r}")
        if self.periodic is not None and not isinstance(self.periodic, Periodic):
            out.append(f"periodic must be a Periodic (e.g. Periodic(x=(0.0, 1.0))) or None, got {self.periodic!r}")
        if isinstance(self.approximation, Approximation):
            out.extend(self.approximation.problems())
        else:
            out.append(f"approximation must be an Approximation, got {self.approximation!r}")
        return out

    def pressure_model(self) -> Effect | None:
        """The listed effect with role ``"pressure"`` (the first, if several are listed)."""
        return next((e for e in self.effects if getattr(e, "role", "") == "pressure"), None)

    def provides(self, quantity: str) -> bool:
        """Whether a listed effect provides ``quantity`` (``"gravity"``, ``"free_surface"``, ...)."""
        return any(quantity in getattr(e, "provides", ()) for e in self.effects)

    def identity(self) -> dict[str, Any]:
        """The settings that make a run this run (as a run's identity has always held them)."""
        out = {
            "effects": [repr(e) for e in self.effects],
            "approximation": to_jsonable(self.approximation.__dict__),
            "integrator": str(getattr(self.integrator, "name", self.integrator)),
            "mass": self.mass, "safety": self.safety, "dt_max": self.dt_max,
        }
        if self.periodic is not None:  # only then: the identity of a run without periodic axes is unchanged
            out["periodic"] = self.periodic.identity()
        return out  # the spacing is checked against the bodies, whose initial state the identity hashes

    def stabilisation_report(self) -> dict[str, Any]:
        """For ``summary.json``: the mode, the stabilising effects that ran, what the scheme
        added to the list, and what of the recommended set a listed stabilisation left out."""
        return {"mode": self.stabilisation,
                "effects": [repr(e) for e in self.effects if is_stabilising(e)],
                "added": [repr(e) for e in self.added_stabilisation],
                "missing_from_recommended": list(self.missing_stabilisation)}


@dataclass(frozen=True)
class FluidContext:
    """What an effect sees in :meth:`~mlsgalerkin.fluid.effect.Effect.check` and
    :meth:`~mlsgalerkin.fluid.effect.Effect.setup`: the fluid's scheme and a read-only view of
    the scene. Its attribute names are those an effect read from the scene before schemes
    existed (``effects``, ``approximation``, ``dim``, ``safety``, ``dt_max``, ``bodies_of``),
    so an effect written then keeps working.
    """

    scheme: FluidScheme
    scene: SceneView

    @property
    def dim(self) -> int:
        return self.scene.dim

    @property
    def effects(self) -> list[Effect]:
        return list(self.scheme.effects)

    @property
    def approximation(self) -> Approximation:
        return self.scheme.approximation

    @property
    def safety(self) -> float:
        return self.scheme.safety

    @property
    def dt_max(self) -> float | None:
        return self.scheme.dt_max

    @property
    def interactions(self) -> tuple:
        return self.scene.interactions

    @property
    def probes(self) -> tuple:
        return self.scene.probes

    def bodies_of(self, kind: type) -> list:
        """The scene's bodies that are instances of ``kind``, in scene order."""
        return self.scene.bodies_of(kind)

    def pressure_model(self) -> Effect | None:
        """The scheme's pressure model (``None`` if none is listed)."""
        return self.scheme.pressure_model()

    def sound_speed(self) -> float | None:
        """The pressure model's reference sound speed ``c0`` (m/s), ``None`` without one."""
        c0 = getattr(self.pressure_model(), "c0", None)
        return None if c0 is None else float(c0)

    def provides(self, quantity: str) -> bool:
        """Whether a listed effect provides ``quantity``."""
        return self.scheme.provides(quantity)
