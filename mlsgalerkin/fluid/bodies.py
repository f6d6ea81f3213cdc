r"""Bodies of a fluid scene: :class:`FluidBody` (moving particles, one or more phases) and
:class:`WallBody` (wall particles and/or a penalty contact surface, fixed or moving with a
prescribed motion), plus lattice builders. Both are advanced by :class:`~mlsgalerkin.fluid.solver.FluidSolver`: wall particles
are nodes of the fluid's approximation.

A particle carries a constant physical mass ``M = ρ_init · Δx^d`` (kg/m^(3-d) per unit depth
in 2D); its volume follows the density, ``V = M/ρ``. Wall particles are integration points of
the fictitious fluid beyond the wall: their volume stays ``Δx^d`` and their density, pressure
and velocity are extrapolated from the fluid every step (see :mod:`mlsgalerkin.fluid.walls`).

>>> water = Phase("water", density=1000.0, viscosity=1e-3)
>>> body = FluidBody.block("water", lower=(0, 0), upper=(0.1, 0.05), spacing=0.01, phases=[water])
>>> body.n, body.dim
(50, 2)
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import ClassVar

import numpy as np
from numpy.typing import ArrayLike, NDArray

from mlsgalerkin.contact.surface import (
    ContactSurface,
    SurfacePoints,
    TrianglePoints,
    surface_points,
)
from mlsgalerkin.dynamics import Body
from mlsgalerkin.limits import ParticleLimitError, check_size, particle_limit
from mlsgalerkin.motion import Motion
from mlsgalerkin.neighbors import as_coordinates

#: The solver of fluid and wall bodies (resolved by the run loop; a string avoids an import cycle).
FLUID_SOLVER = "mlsgalerkin.fluid.solver:FluidSolver"

__all__ = ["FluidBody", "ParticleLimitError", "Phase", "WallBody", "lattice", "particle_limit", "wall_box"]

@dataclass(frozen=True)
class Phase:
    """A fluid phase: reference density ``density`` (kg/m³) and dynamic ``viscosity`` (Pa s)."""

    name: str
    density: float
    viscosity: float = 0.0

    def __post_init__(self) -> None:
        if not (np.isfinite(self.density) and self.density > 0):
            raise ValueError(f"phase {self.name!r}: density must be positive, got {self.density!r}")
        if not (np.isfinite(self.viscosity) and self.viscosity >= 0):
            raise ValueError(f"phase {self.name!r}: viscosity must be >= 0, got {self.viscosity!r}")


def lattice(lower: ArrayLike, upper: ArrayLike, spacing: float) -> NDArray[np.float64]:
    """Cell-centred square lattice filling the box ``[lower, upper]``: ``(n, d)`` positions.

    Points sit at ``lower + (k + 1/2) spacing`` so that each owns a ``spacing^d`` cell inside
    the box. The number of points per axis is ``round((upper - lower)/spacing)``.
    """
    lo = np.asarray(lower, dtype=float)
    hi = np.asarray(upper, dtype=float)
    if lo.shape != hi.shape or lo.ndim != 1 or not np.all(hi > lo) or not np.all(np.isfinite(hi - lo)):
        raise ValueError(f"lattice: need finite lower < upper componentwise, got {lo} and {hi}")
    if not (math.isfinite(spacing) and spacing > 0):
        raise ValueError(f"lattice: spacing must be positive and finite, got {spacing}")
    ratio = (hi - lo) / spacing
    if np.any(ratio < 0.5):
        a = int(np.argmin(ratio))
        raise ValueError(
            f"lattice: the spacing {spacing:g} m is larger than twice the box's size {hi[a] - lo[a]:g} m along "
            f"axis {a}: not one particle fits; choose a spacing below {(hi[a] - lo[a]) / 2:g} m (a few particles "
            "across the smallest feature)")
    with np.errstate(over="ignore"):  # a product beyond 1e308 is inf: above any limit
        count = float(np.prod(np.maximum(np.round(ratio), 1.0)))
    check_size(count, f"a lattice (box {np.round(hi - lo, 6).tolist()} m", spacing)
    counts = np.maximum(np.round(ratio).astype(int), 1)
    axes = [lo[a] + (np.arange(counts[a]) + 0.5) * spacing for a in range(lo.size)]
    grid = np.meshgrid(*axes, indexing="ij")
    return np.ascontiguousarray(np.stack([g.ravel() for g in grid], axis=1))


@dataclass
class FluidBody(Body):
    """Fluid particles.

    Parameters
    ----------
    name : str
    positions : (n, d) array, m
    spacing : float
        Initial particle spacing ``Δx`` (m); sets the particle volume ``Δx^d`` and ``h``.
    phases : list of Phase
    phase : (n,) int array, optional
        Index into ``phases`` of each particle (default all 0).
    velocity : (n, d) array or (d,), m/s, optional
    density : (n,) array, kg/m³, optional
        Initial density (e.g. hydrostatic); default the phase reference density.
    """

    solver: ClassVar[str] = FLUID_SOLVER
    #: What a particle of this body is, for the counts a run reports ("12,000 particles (9,000 fluid)").
    particle_kind: ClassVar[str] = "fluid"
    name: str
    positions: NDArray[np.float64]
    spacing: float
    phases: list[Phase]
    phase: NDArray[np.int64] | None = None
    velocity: NDArray[np.float64] | None = None
    density: NDArray[np.float64] | None = None

    def __post_init__(self) -> None:
        self.positions = as_coordinates(f"fluid body {self.name!r} positions", self.positions)
        n, d = self.positions.shape
        if d not in (2, 3):
            raise ValueError(f"fluid body {self.name!r}: positions must be 2D or 3D, got d={d}")
        if not self.spacing > 0:
            raise ValueError(f"fluid body {self.name!r}: spacing must be positive")
        if not self.phases:
            raise ValueError(f"fluid body {self.name!r}: give at least one Phase")
        self.phase = np.zeros(n, dtype=np.int64) if self.phase is None else np.asarray(self.phase, dtype=np.int64)
        if self.phase.shape != (n,) or self.phase.min(initial=0) < 0 or self.phase.max(initial=0) >= len(self.phases):
            raise ValueError(
                f"fluid body {self.name!r}: phase must be (n,) integers in [0, {len(self.phases)})"
            )
        v = np.zeros((n, d)) if self.velocity is None else np.asarray(self.velocity, dtype=float)
        self.velocity = np.array(np.broadcast_to(v, (n, d)), dtype=float, order="C")
        ref = np.array([p.density for p in self.phases])[self.phase]
        rho = ref if self.density is None else np.asarray(self.density, dtype=float)
        self.density = np.array(np.broadcast_to(rho, (n,)), dtype=float, order="C")
        for name, arr in (("velocity", self.velocity), ("density", self.density)):
            if not np.all(np.isfinite(arr)):
                raise ValueError(f"fluid body {self.name!r}: {name} has non-finite values")
        if np.any(self.density <= 0):
            raise ValueError(f"fluid body {self.name!r}: density must be positive")

    @classmethod
    def block(
        cls, name: str, lower: ArrayLike, upper: ArrayLike, spacing: float, phases: list[Phase], **kw
    ) -> "FluidBody":
        """A rectangular block of lattice particles (see :func:`lattice`)."""
        return cls(name, lattice(lower, upper, spacing), spacing, phases, **kw)

    @property
    def n(self) -> int:
        return self.positions.shape[0]

    @property
    def dim(self) -> int:
        return self.positions.shape[1]

    @property
    def reference_density(self) -> NDArray[np.float64]:
        """``(n,)`` reference density ``ρ0`` of each particle's phase."""
        return np.array([p.density for p in self.phases])[self.phase]

    @property
    def viscosity(self) -> NDArray[np.float64]:
        """``(n,)`` dynamic viscosity of each particle's phase (Pa s)."""
        return np.array([p.viscosity for p in self.phases])[self.phase]


@dataclass
class WallBody(Body):
    """A rigid wall: wall particles (several layers) with fluid-side normals, a penalty contact
    surface, or both; fixed or moving rigidly.

    Parameters
    ----------
    name : str
    positions : (n, d) array, m, optional
        Wall particle positions at ``t = 0`` (the reference configuration of ``motion``).
        Omit (with ``spacing``) for a wall that is only a penalty ``surface``.
    spacing : float, optional
        Wall particle spacing (m); each wall particle integrates a ``spacing^d`` volume.
        Required with ``positions``.
    normals : (n, d) array, optional
        Unit normal pointing from the wall into the fluid; required for free-slip walls.
    velocity : (d,) array, m/s, optional
        Tangential velocity of the surface of a wall that stays in place (a belt, a lid
        driving a cavity); zero by default. Not with ``motion``.
    motion : :class:`~mlsgalerkin.motion.Motion`, optional
        Prescribed rigid motion (translation and rotation about a point as functions of time,
        e.g. :class:`~mlsgalerkin.motion.Oscillation` for a piston wave maker). The wall
        particles, their velocity, acceleration and normals, and the nodes of ``surface``
        follow it; the wall pressure sees ``g − a_wall``.
    reference_density : float
        Density given to wall particles with no fluid in reach (kg/m³).
    surface : :class:`~mlsgalerkin.contact.surface.ContactSurface`, optional
        A penalty contact surface of the wall (normals toward the fluid), in the reference
        configuration of ``motion``. Used by the ``PenaltyWalls`` effect, which must then be
        listed (:mod:`mlsgalerkin.fluid.penalty_walls`).
    follows : str, optional
        The name of another body (a structure) whose surface carries these wall particles: an
        interaction (:class:`~mlsgalerkin.interactions.StructureCoupling`) sets their
        positions, velocities, accelerations and normals every step. Built by
        :meth:`on_surface`, which also sets ``anchors``.
    anchors : (n, 4) array, optional
        For a wall that ``follows`` a surface: the facet of the surface each particle rides on
        (2D: a segment; 3D: a triangle), its position ``ξ`` along a 2D segment (0 at the
        segment's first node, 1 at the second; 0 in 3D, where ``footprints.barycentric`` holds
        the position), its depth behind the surface (m) and the index of its point in
        ``footprints``.
    footprints : SurfacePoints or TrianglePoints, optional
        The points on the surface the layers of particles stand on, each with the piece of
        surface it represents (the maps from the surface's nodes to the particles):
        :class:`~mlsgalerkin.contact.surface.SurfacePoints` in 2D,
        :class:`~mlsgalerkin.contact.surface.TrianglePoints` in 3D.
    volumes : (n,) array, optional
        The volume each wall particle integrates (m³; m² per unit depth in 2D), by default
        ``spacing^d``. :meth:`on_surface` in 3D sets each particle's footprint area times the
        spacing (a triangle's pieces need not cover ``spacing²`` each).
    """

    solver: ClassVar[str] = FLUID_SOLVER
    #: What a particle of this body is, for the counts a run reports.
    particle_kind: ClassVar[str] = "wall"
    name: str
    positions: NDArray[np.float64] | None = None
    spacing: float | None = None
    normals: NDArray[np.float64] | None = None
    velocity: NDArray[np.float64] | None = None
    motion: Motion | None = None
    reference_density: float = 1000.0
    surface: ContactSurface | None = None
    follows: str | None = None
    anchors: NDArray[np.float64] | None = None
    footprints: SurfacePoints | TrianglePoints | None = None
    volumes: NDArray[np.float64] | None = None

    def __post_init__(self) -> None:
        if self.surface is not None and not isinstance(self.surface, ContactSurface):
            raise ValueError(f"wall body {self.name!r}: surface must be a mlsgalerkin.contact.ContactSurface "
                             f"(e.g. ContactSurface.tank or ContactSurface.polyline), got {type(self.surface).__name__}")
        if self.positions is None:
            if self.surface is None:
                raise ValueError(f"wall body {self.name!r}: give wall particles (positions and spacing), a penalty "
                                 "surface (surface=ContactSurface...), or both")
            if self.normals is not None:
                raise ValueError(f"wall body {self.name!r}: normals belong to wall particles, and this wall has none")
            self.positions = np.zeros((0, self.surface.dim))
        else:
            self.positions = as_coordinates(f"wall body {self.name!r} positions", self.positions)
            if not (isinstance(self.spacing, (int, float)) and math.isfinite(self.spacing) and self.spacing > 0):
                raise ValueError(f"wall body {self.name!r}: spacing must be positive (the wall particle spacing, m), "
                                 f"got {self.spacing!r}")
        n, d = self.positions.shape
        if self.surface is not None and self.surface.dim != d:
            raise ValueError(f"wall body {self.name!r}: its penalty surface is {self.surface.dim}D but its particles "
                             f"are {d}D; build both in the same space")
        if self.normals is not None:
            nrm = np.asarray(self.normals, dtype=float)
            if nrm.shape != (n, d):
                raise ValueError(f"wall body {self.name!r}: normals must be ({n}, {d}), got {nrm.shape}")
            length = np.linalg.norm(nrm, axis=1)
            if np.any(np.abs(length - 1) > 1e-6):
                raise ValueError(f"wall body {self.name!r}: normals must be unit vectors")
            self.normals = np.ascontiguousarray(nrm)
        v = np.zeros(d) if self.velocity is None else np.asarray(self.velocity, dtype=float)
        if v.shape != (d,):
            raise ValueError(f"wall body {self.name!r}: velocity must be a ({d},) vector")
        if self.motion is not None:
            if not isinstance(self.motion, Motion):
                raise ValueError(f"wall body {self.name!r}: motion must be a mlsgalerkin.motion.Motion "
                                 f"(PrescribedMotion, Oscillation), got {type(self.motion).__name__}")
            if np.any(v != 0):
                raise ValueError(f"wall body {self.name!r}: give either a surface velocity (a wall that "
                                 "stays in place) or a motion, not both")
        self.velocity = v
        if self.volumes is not None:
            vol = np.asarray(self.volumes, dtype=float)
            if vol.shape != (n,) or not np.all(np.isfinite(vol)) or np.any(vol <= 0):
                raise ValueError(f"wall body {self.name!r}: volumes must be ({n},) positive finite volumes (m^{d}), "
                                 f"got shape {vol.shape}")
            self.volumes = np.ascontiguousarray(vol)
        if self.follows is not None:
            if self.motion is not None or self.surface is not None:
                raise ValueError(f"wall body {self.name!r}: a wall that follows the surface of {self.follows!r} moves "
                                 "with it; give it no motion and no penalty surface of its own (the coupling's "
                                 "contact uses the structure's surface)")
            anchors = None if self.anchors is None else np.asarray(self.anchors, dtype=float)
            if anchors is None or anchors.shape != (n, 4) or self.normals is None or self.footprints is None:
                raise ValueError(f"wall body {self.name!r}: a wall that follows a surface needs anchors (n, 4), "
                                 "footprints and normals; build it with WallBody.on_surface(...)")
            self.anchors = anchors

    @classmethod
    def on_surface(cls, name: str, surface: ContactSurface, spacing: float, follows: str, layers: int = 3,
                   reference_density: float = 1000.0) -> "WallBody":
        """Wall particles riding on the 2D or 3D ``surface`` of the body ``follows`` (its surface
        at rest, normals out of that body, into the fluid), in points each standing for a piece
        of surface (:func:`~mlsgalerkin.contact.surface.surface_points`):

        - 2D: along each chain of connected segments of total length ``S``, ``k = max(1,
          round(S/spacing))`` points at arc lengths ``(j + ½) S/k``, each standing for ``S/k``
          of surface;
        - 3D: each triangle of area ``A`` split into ``m²`` equal sub-triangles, ``m = max(1,
          round(√A/spacing))``, a point at each one's centroid standing for ``A/m²`` of surface
          (:class:`~mlsgalerkin.contact.surface.TrianglePoints`). The particles are about
          ``area/spacing²`` a layer: exactly when each ``√A/spacing`` is a whole number; the
          triangles of a square face cut in two (``√A = side/√2``) never are, so each particle
          integrates its own footprint area times ``spacing`` (``volumes``) instead of
          ``spacing³``; faces of sides ``spacing·(1, 2)``, ``(2, 4)``... cover evenly.

        A particle sits at the mean of its piece, ``(l + ½) spacing`` behind it along the
        normal of the piece (2D: of its chord; 3D: of its triangle), for ``layers`` layers ``l``.

        >>> plate = ContactSurface.polyline([(1.0, 0.0), (0.0, 0.0)])     # normal up
        >>> w = WallBody.on_surface("plate_walls", plate, 0.25, follows="plate", layers=2)
        >>> w.n, w.positions[:2].tolist(), w.normals[0].tolist()
        (8, [[0.875, -0.125], [0.625, -0.125]], [0.0, 1.0])
        >>> top = ContactSurface(np.array([[0.0, 0, 0], [0.5, 0, 0], [0, 0.25, 0]]), np.array([[0, 1, 2]]))
        >>> w = WallBody.on_surface("plate_walls", top, 0.25, follows="plate", layers=2)   # m = 1
        >>> w.n, w.positions[1].round(4).tolist(), w.normals[0].tolist()
        (2, [0.1667, 0.0833, -0.375], [0.0, 0.0, 1.0])
        """
        if not isinstance(surface, ContactSurface) or surface.dim not in (2, 3):
            raise ValueError(f"wall body {name!r}: on_surface needs a 2D or 3D ContactSurface")
        if not (isinstance(spacing, (int, float)) and math.isfinite(spacing) and spacing > 0):
            raise ValueError(f"wall body {name!r}: spacing must be positive (m), got {spacing!r}")
        if not (isinstance(layers, int) and layers >= 1):
            raise ValueError(f"wall body {name!r}: layers must be a positive integer, got {layers!r}")
        total = float(surface.measures().sum())
        if surface.dim == 2:
            check_size((total / spacing + surface.n_facets) * layers, f"wall particles on a surface "
                         f"({surface.n_facets} segments", spacing)
        else:  # each triangle has at most (√A/spacing + ½)² points
            per = (np.sqrt(surface.measures()) / spacing + 0.5) ** 2
            check_size(float(np.maximum(per, 1.0).sum()) * layers, f"wall particles on a surface "
                         f"({surface.n_facets} triangles", spacing)
        pts = surface_points(surface, spacing)
        k = pts.average.shape[0]
        x0, _, n0, _ = pts.kinematics(surface.nodes, np.zeros_like(surface.nodes))
        depth = np.repeat((np.arange(layers) + 0.5) * spacing, k)
        facet, xi = (pts.segment, pts.xi) if surface.dim == 2 else (pts.triangle, np.zeros(k))
        anchors = np.column_stack([np.tile(facet, layers), np.tile(xi, layers), depth,
                                   np.tile(np.arange(k), layers)]).astype(float)
        nrm = np.tile(n0, (layers, 1))
        x = np.tile(x0, (layers, 1)) - depth[:, None] * nrm
        # 3D: each particle integrates its footprint times the spacing (2D footprints are S/k,
        # within the rounding of k of the spacing, and keep the default spacing²)
        volumes = None if surface.dim == 2 else np.tile(pts.area * spacing, layers)
        return cls(name, np.ascontiguousarray(x), spacing, normals=np.ascontiguousarray(nrm),
                   reference_density=reference_density, follows=follows, anchors=anchors, footprints=pts,
                   volumes=volumes)

    @property
    def n(self) -> int:
        """Number of wall particles (0 for a wall that is only a penalty surface)."""
        return self.positions.shape[0]

    @property
    def dim(self) -> int:
        return self.positions.shape[1]


def wall_box(
    lower: ArrayLike, upper: ArrayLike, spacing: float, layers: int = 3, *,
    open_top: bool = True, name: str = "walls", reference_density: float = 1000.0, surface: bool = False,
) -> WallBody:
    """Wall particles around the 2D box ``[lower, upper]`` (the fluid region), ``layers`` deep,
    and with ``surface=True`` the box's inner penalty surface
    (:meth:`~mlsgalerkin.contact.surface.ContactSurface.tank`, normals into the box; used by
    ``PenaltyWalls``). ``layers=0`` with ``surface=True`` builds a wall that is only the surface.

    Wall particles sit at ``(k + 1/2) spacing`` outside each side (``k < layers``); along a
    side they follow the lattice of :func:`lattice` when the box is a whole number of
    spacings (otherwise the side-wall rows are spread evenly over the height). The normal of each wall particle
    points into the box (corner particles get the diagonal). ``open_top`` leaves the top side
    open. With support ``2h = 2.6 Δx`` three layers cover a full kernel support.
    """
    lo = np.asarray(lower, dtype=float)
    hi = np.asarray(upper, dtype=float)
    if lo.shape != (2,) or hi.shape != (2,):
        raise ValueError("wall_box is 2D: lower and upper must be (2,) points")
    if layers < (0 if surface else 1):
        raise ValueError("wall_box: need at least one layer of wall particles (or layers=0 with surface=True, a "
                         f"wall of only a penalty surface), got layers={layers!r}")
    if not (math.isfinite(spacing) and spacing > 0) or not np.all(hi > lo) or not np.all(np.isfinite(hi - lo)):
        raise ValueError(f"wall_box: need a positive spacing and lower < upper, got {spacing!r}, {lo}, {hi}")
    tank = ContactSurface.tank(lo, hi, open_top=open_top) if surface else None
    if layers == 0:
        return WallBody(name, reference_density=reference_density, surface=tank)
    size = (hi - lo) / spacing
    check_size(layers * (2.0 * (size[0] + 2 * layers) + 2.0 * size[1]), f"a wall box ({np.round(hi - lo, 6).tolist()} m",
                 spacing)
    # layers k = 0..layers-1 at (k + 1/2) spacing outside each side; the bottom (and top)
    # rows run under the side walls to fill the corners. Built side by side, so a box whose
    # size is not a multiple of the spacing still gets exactly `layers` layers everywhere.
    off = (np.arange(layers) + 0.5) * spacing
    t = layers * spacing
    xs = np.arange(lo[0] - t + 0.5 * spacing, hi[0] + t, spacing)
    xs = xs[xs < hi[0] + t - 1e-9 * spacing]
    n_y = max(int(np.round((hi[1] - lo[1]) / spacing)), 1)
    ys = lo[1] + (np.arange(n_y) + 0.5) * (hi[1] - lo[1]) / n_y
    parts = [np.column_stack([np.tile(xs, layers), np.repeat(lo[1] - off, xs.size)])]
    if not open_top:
        parts.append(np.column_stack([np.tile(xs, layers), np.repeat(hi[1] + off, xs.size)]))
    parts.append(np.column_stack([np.repeat(lo[0] - off, ys.size), np.tile(ys, layers)]))
    parts.append(np.column_stack([np.repeat(hi[0] + off, ys.size), np.tile(ys, layers)]))
    pts = np.ascontiguousarray(np.vstack(parts))
    # inward normal: direction from the particle to the closest point of the box
    closest = np.clip(pts, lo, hi)
    nrm = closest - pts
    nrm /= np.linalg.norm(nrm, axis=1, keepdims=True)
    return WallBody(name, pts, spacing, normals=nrm, reference_density=reference_density, surface=tank)
