r"""The particles' volumes kept consistent with the space they fill: the :class:`VolumeConsistency`
effect and its kernel.

**Why.** The collocated continuity equation ``ρ̇_i = −ρ_i tr L_i`` sees the divergence of the MLS
fit of the velocity, which is smooth over a support of about five spacings. A rearrangement of
the particles at the scale of one spacing (a square lattice that shears into a denser, disordered
packing; layers that slide into each other's gaps) has no smooth divergence: the particles pack
tighter while each keeps its density, so the volumes ``M/ρ`` add up to more than the space the
fluid fills. Measured in the wave maker (20 rows, 14.2 s, the recommended set): the Shepard sum of
the interior particles, ``c_i = Σ_j W(x_i − x_j, h_j) V_j`` with ``V_j = M_j/ρ_j`` (1 when the
volumes tile space), rose from 1.000 at 3 s to 1.011 at 6 s, 1.066 at 10 s and 1.111 at 14 s,
uniformly in depth, while ``ρ/ρ0`` stayed at 1.005; the geometric volume fell by 6.7 %. The deep
exchange flow with a free surface lost 3.3 % in 1.15 s the same way. Under a lid
:class:`~mlsgalerkin.fluid.closed_volume.ClosedVolume` holds the tank's volume, but an open surface
has nothing that does.

**What.** The Shepard sum sees this packing where the continuity equation does not, so the
density relaxes towards it. With the mean gap of the deep fluid particles
:math:`\langle g\rangle` (below; ``c_ref`` the sum on the square or cubic lattice of the scene's
spacing, :func:`lattice_shepard_sum`),

.. math::
    \dot\rho_i \mathrel{+}= \varepsilon\,\frac{c_0}{h_i}\,\rho_i\,
        \operatorname{sign}\langle g\rangle\,\max(|\langle g\rangle| - g_0,\ 0)

at the deep fluid particles ``i``. A particle is *deep* when its table row lists no wall particle
and its own sum and that of every node of its row are at least ``surface · c_ref`` (default 0.9).
The top row of a free surface (0.76 on a lattice) and splashes fall below it, so they and the row
under them keep their density: there the sum is short because the support is cut, not because
the particles spread (0.9904 on the row under a flat surface). Wall particles need not tile space
with the fluid (a structure's riding particles beside the tank's own made the fluid's column at
the gate of ``elastic_gate`` read 1.22, and the floor's first row reads 1.0017), so the rows
that reach them are left out too. A fluid packed tighter than its volumes say gains density, so
pressure, below its surface rows, and rises; one that has spread loses it and settles.

*Why one mean, not a field.* The sum of each particle carries the noise of its neighbourhood
(a standard deviation of 1.5–2 % in a disordered flow, 5 % or more in a lattice jittered by
± 0.25 Δx), and the pressure answers a density gap with ``ρ0 c0²`` times it: about 100 ``ρ g H``
per unit gap at ``c0 = 10 √(gH)``. Relaxed particle by particle (averaged over each MLS row), the
noise of a jittered two-layer tank drove a flow of 0.34 m/s within 0.1 s (0.0017 m/s without the
effect). The compaction this corrects is a drift of the whole fluid (uniform in depth in the wave
maker), which the mean sees and the noise averages out of.

*The disorder's share.* The sum reads a disordered packing as tighter than it is, at second
order: on a lattice jittered by ± 0.05 / 0.1 / 0.15 / 0.25 Δx the mean gap is 0.07 / 0.28 / 0.63 /
1.7 %, and it is ``k`` times the variance of ``c/c_ref`` at every jitter (``k`` = 3.4–3.7 for the
cubic spline at ``h = 1.3 Δx`` in 2D, 5.1–5.5 in 3D). The gap relaxed is therefore the mean less
that share, :math:`\langle g\rangle = \langle c/c_\mathrm{ref}\rangle - 1 - k\,\mathrm{var}(c/c_\mathrm{ref})`,
with ``k`` measured at set-up on a jittered periodic lattice of the scene's kernel
(:func:`disorder_bias_coefficient`): a tank at rest started jittered is not expanded.

*A band* ``g_0`` (default 0.005). Inside it nothing is added, so a run whose packing stays
consistent is the run without the effect, bit for bit; ``summary.json`` reports the share of
evaluations in which it acted. The band sits above what the sum reads in a flow whose volume
holds: the bulk of the dam break with impact at H/Δx = 40 reads up to 0.31 % (its disorder's share
taken out) while its geometric volume stays within 0.4 % of Σ M/ρ. Relaxed at a band of 0.25 %,
that run expanded by 1.0 % and its sensors' RMS deviation rose from 0.283 / 0.459 / 0.191 / 0.158
to 0.351 / 0.492 / 0.245 / 0.237 (a density change of 10⁻³ is ``0.2 ρ g H`` of pressure at
``c0 = 10 √(2gH)``).

The relaxation time is :math:`\tau = h/(\varepsilon c_0)`: 50 acoustic times ``h/c0`` at the
default ``ε = 0.02`` (0.046 s in the wave maker at 20 rows, 0.093 s at 10), long against the
sound and short against the drift it corrects (a 10 % compaction over about 8 s). At a steady compaction rate
``ṙ`` the packing settles at the gap ``g_0 + ṙ τ``. Like the error-compensating source of Khayyer &
Gotoh (2011) and the density-invariance relaxation of Asai et al. (2012) in projection methods,
it acts on the error of the particle number density.

*Only where there is a free surface.* A fluid that fills its domain (a periodic box, a full
channel) cannot pack tighter as a whole: its volume is the domain's. There the mean sum drifts
only with the anisotropy of a sheared packing, which the disorder's share (calibrated on isotropic
jitter) does not remove: the Taylor–Green vortex at 32 rows read a gap of up to 1.2 %, and relaxing
it raised its kinetic-energy error from 2.75 to 2.98 %. So the effect acts only in evaluations in
which some fluid particle's sum is below ``surface · c_ref`` (a free surface, a splash);
``summary.json`` reports the share of evaluations that had one.

*The loose side* (``loose_band``, 0.005 in the recommended set). Below the surface rows the sum is cut by the surface,
so the deep mean cannot see a packing that has spread there. In ``beam_clamped`` the water thrown
over the beam falls back and settles as a layer whose particles stand 1.2–2 spacings apart at
the density their continuity gives them: :math:`\sum M/\rho` holds (0.01922 → 0.01915 m² from
0.5 to 4 s at Δx = 8 mm) while the geometric volume grows by 8.5 %. Their pressure holds the layer
up at any packing. The loose side measures the fluid's volume error
:math:`e = V_\mathrm{geo}/\sum M/\rho - 1` (:func:`~mlsgalerkin.fluid.distribution.volume_error`,
the run checks' measure; a few milliseconds, so every ``loose_every`` evaluations) and, past the
band ``e_0``, relaxes the particles that are neither deep nor splashes (sum at least
``splash · c_ref``, :func:`loose_particles`):

.. math::
    \dot\rho_i \mathrel{-}= \varepsilon\,\frac{c_0}{h_i}\,\rho_i\,\max(e - e_0,\ 0).

They lose their pressure, and gravity closes the gaps until the error is back within the band.
Measured in ``beam_clamped`` at its default Δx = 4 mm with ``e_0 = 0.005``
(``docs/theory/stabilisation.md`` §10): the largest error is 2.05 % (6.52 % without), and 0.87 %
on average after 1.5 s; with the droplets below, 2.27 % and 0.67 %. Both are in the recommended
set since 2026-12-04.

*Its local part* (``loose_local`` ``w``, 2 in the recommended set; ``loose_local_band`` ``b``,
0.05). The whole fluid's error drives every loose particle alike, so the few that carry a breaking
wave's excess (a collapsing run-up whose particles stand 1.06 spacings apart at 100–170 Pa) relax
no faster than the rest. While ``e > e_0``, each measurement also gives every particle its
neighbourhood's excess ``e_i`` (:func:`~mlsgalerkin.fluid.distribution.neighbourhood_excess` of the
:func:`~mlsgalerkin.fluid.distribution.cell_volumes` shares: the particle and those within 1.5
spacings; in ``state.extra["loose_local_excess"]``, so in the frames), and the loose particles
whose table row lists no wall node relax by

.. math::
    \dot\rho_i \mathrel{-}= \varepsilon\,\frac{c_0}{h_i}\,\rho_i\,
        \bigl[(e - e_0) + w\,\max(e_i - b,\ 0)\bigr].

The rows within a support of a wall keep the global drive only: there the fluid–wall gap reads as
looseness, and relaxing it took the water's pressure off ``beam_clamped``'s beam (its tip swung
9 mm instead of 14–17 mm at 1.3 s). Measured in ``beam_clamped`` at 4 mm
(``docs/theory/stabilisation.md`` §10): the largest error 2.27 → 1.33 %, its largest 50 ms mean
1.80 → 0.88 %, the tip's motion as before (``beam_on_spring``: 1.64 → 1.22 %). What is left sits at the cavitation floor: the jet
that climbs the beam at its first load stretches at ``ρ0``, where no density relaxation can give
it volume.

*Droplets* (``droplet_rate``). A particle whose Shepard sum is below ``splash · c_ref`` (0.5 of
the lattice's: fewer neighbours than a line of particles has) is a droplet in air, whose pressure
is the air's. Its continuity cannot say so: with so few neighbours its shape functions fall back
to a lower order, two droplets that meet compress each other and keep the density when they part,
and the cavitation floor keeps it from falling below ``ρ0``. In ``beam_clamped`` such droplets
collected into a cloud of 100–180 particles above the water (8–14 % of it) at 2–4 kPa, which held
itself up against gravity for seconds. Every evaluation with a free surface, the droplets above
the rest density relax towards it,

.. math::
    \dot\rho_i \mathrel{-}= r_d\,\frac{c_0}{h_i}\,(\rho_i - \rho_{0,i})^+ ,

with ``r_d = droplet_rate`` (0.1: a relaxation time of ten acoustic times ``h/c0``, 1.9 ms in
``beam_clamped``, against the 28 ms a droplet takes to fall its own spacing). They lose their
pressure and fall. In ``beam_clamped`` at its default spacing, 6 particles (10 Pa) are left above
the water at 4 s instead of 100 (2 kPa) (``docs/theory/stabilisation.md`` §10).

**What it is not.** It adds no viscosity and no momentum; it moves no particle. On a lattice
(still water) the deep particles' gap is zero to ``10⁻⁴``, so a fluid at rest is left at rest. In a tank closed by
:class:`~mlsgalerkin.fluid.closed_volume.ClosedVolume` the effect stays idle: the divergence
correction holds that volume exactly, and a relaxation on top of it would raise the pressure of a
fluid that cannot expand.

``c`` comes with the shape-function table (the solver fills it when an effect reads
``kernel_sum``, as :class:`~mlsgalerkin.fluid.linear_consistency.LinearConsistentPressure` does);
one compiled pass over the table's fluid rows finds the deep particles (:func:`deep_particles`,
with a numpy reference :func:`deep_particles_reference`).
"""

from __future__ import annotations

import functools
import itertools
import math
from typing import Any

import numba
import numpy as np
from numba import prange
from numpy.typing import NDArray

from mlsgalerkin.approximation.table import ShapeTable
from mlsgalerkin.fluid.closed_volume import ClosedVolume
from mlsgalerkin.fluid.distribution import cell_volumes, neighbourhood_excess, volume_error
from mlsgalerkin.fluid.domain_exit import still_in_run
from mlsgalerkin.fluid.effect import Effect, EffectContext, check_positive
from mlsgalerkin.fluid.state import FluidState
from mlsgalerkin.kernels import get_kernel
from mlsgalerkin.neighbors import find_neighbors
from mlsgalerkin.periodic import minimum_image

__all__ = [
    "LOOSE_LOCAL_FIELD",
    "VolumeConsistency",
    "deep_particles",
    "deep_particles_reference",
    "disorder_bias_coefficient",
    "droplets",
    "lattice_shepard_sum",
    "loose_particles",
    "volume_consistency_rate",
    "wall_rows",
    "wall_rows_reference",
]

#: ``state.extra`` key of the loose side's last neighbourhood excess per particle (``(n,)``, –; 0
#: on the wall rows and while the loose side is idle), in the frames and checkpoints.
LOOSE_LOCAL_FIELD = "loose_local_excess"

FloatArray = NDArray[np.float64]


@functools.lru_cache(maxsize=32)
def lattice_shepard_sum(kernel: str, h_factor: float, dim: int) -> float:
    """The Shepard sum ``Σ_n W(|n| Δx, h) Δx^d`` of a node of the infinite square (cubic) lattice
    of spacing ``Δx`` with ``h = h_factor Δx`` (dimensionless; 0.9999 for the cubic spline at
    ``h = 1.3 Δx`` in 2D)."""
    k = get_kernel(kernel)
    reach = math.ceil(k.support * h_factor)
    axis = range(-reach, reach + 1)
    r = np.array([math.sqrt(sum(c * c for c in n)) for n in itertools.product(axis, repeat=dim)])
    return float(np.sum(k.value(r, h_factor, dim)))


@functools.lru_cache(maxsize=32)
def disorder_bias_coefficient(kernel: str, h_factor: float, dim: int, *, jitter: float = 0.1,
                              seed: int = 0) -> float:
    """``k`` of the Shepard sum's disorder bias ``⟨c⟩/c_ref − 1 ≈ k var(c/c_ref)`` (dimensionless):
    measured on a periodic square (cubic) lattice of ``48²`` (``16³``) nodes jittered uniformly by
    ``± jitter Δx`` (a fixed seed, so every run gets the same ``k``; cached per set of arguments).
    3.7 for the cubic spline at ``h = 1.3 Δx`` in 2D (3.4–3.7 from ± 0.05 to ± 0.25 Δx), 5.4 in 3D."""
    k = get_kernel(kernel)
    n = 48 if dim <= 2 else 16
    axis = np.arange(n, dtype=float)
    x = np.stack(np.meshgrid(*([axis] * dim), indexing="ij"), axis=-1).reshape(-1, dim)
    x = (x + np.random.default_rng(seed).uniform(-jitter, jitter, x.shape)) % n
    period = np.full(dim, float(n))
    table = find_neighbors(x, x, radius=k.support * h_factor, period=period)
    rows = np.repeat(np.arange(x.shape[0]), np.diff(table.indptr))
    r = np.linalg.norm(minimum_image(x[table.indices] - x[rows], period), axis=1)
    c = np.bincount(rows, k.value(r, h_factor, dim), x.shape[0]) / lattice_shepard_sum(kernel, h_factor, dim)
    return float((c.mean() - 1.0) / c.var())


@numba.njit(parallel=True, cache=True)
def _deep(indptr, indices, c, n_fluid, least, out):
    for i in prange(n_fluid):
        ok = c[i] >= least
        for q in range(indptr[i], indptr[i + 1]):
            j = indices[q]
            if j >= n_fluid or c[j] < least:
                ok = False
        out[i] = ok


def deep_particles(table: ShapeTable, shepard_sum: FloatArray, n_fluid: int, least: float) -> NDArray[np.bool_]:
    """The mask ``(n_fluid,)`` of the deep fluid particles: their table row lists fluid nodes only
    (``j < n_fluid``), and their Shepard sum and that of every node of the row is at least ``least``
    (dimensionless)."""
    deep = np.empty(n_fluid, dtype=np.bool_)
    _deep(table.indptr, table.indices, np.ascontiguousarray(shepard_sum, dtype=float), n_fluid, float(least), deep)
    return deep


def deep_particles_reference(table: ShapeTable, shepard_sum: FloatArray, n_fluid: int,
                             least: float) -> NDArray[np.bool_]:
    """Numpy version of :func:`deep_particles` (tests), with a sparse pattern matrix."""
    from scipy.sparse import csr_array
    # the rows' entries, whatever their value (an entry may be outside its support, with N = 0)
    pattern = csr_array((np.ones(table.indices.size), table.indices, table.indptr),
                        shape=(table.n_points, table.n_nodes))[:n_fluid]
    shallow = np.asarray(shepard_sum, dtype=float) < least
    shallow[n_fluid:] = True                                 # a wall node in the row: not deep
    return ~shallow[:n_fluid] & ((pattern @ shallow.astype(float)) == 0.0)


@numba.njit(parallel=True, cache=True)
def _wall_rows(indptr, indices, n_fluid, out):
    for i in prange(n_fluid):
        touches = False
        for q in range(indptr[i], indptr[i + 1]):
            if indices[q] >= n_fluid:
                touches = True
        out[i] = touches


def wall_rows(table: ShapeTable, n_fluid: int) -> NDArray[np.bool_]:
    """The mask ``(n_fluid,)`` of the fluid particles whose table row lists a wall node
    (``j >= n_fluid``): those within a support of a wall, a structure's surface included."""
    out = np.empty(n_fluid, dtype=np.bool_)
    _wall_rows(table.indptr, table.indices, n_fluid, out)
    return out


def wall_rows_reference(table: ShapeTable, n_fluid: int) -> NDArray[np.bool_]:
    """Numpy version of :func:`wall_rows` (tests)."""
    rows = np.repeat(np.arange(table.indptr.size - 1), np.diff(table.indptr))
    hit = (rows < n_fluid) & (np.asarray(table.indices) >= n_fluid)
    out = np.zeros(n_fluid, dtype=bool)
    out[rows[hit]] = True
    return out


def volume_consistency_rate(shepard_sum: FloatArray, rho: FloatArray, h: FloatArray, deep: NDArray[np.bool_], *,
                            reference: float, rate: float, c0: float, band: float = 0.0,
                            bias: float = 0.0) -> tuple[FloatArray | None, float]:
    """The added continuity rate ``ρ̇ (n_fluid,)`` (kg/m^d/s) of the module docstring,
    ``ε (c0/h_i) ρ_i (⟨g⟩ ∓ g_0)`` at the deep particles (mask ``deep (n_fluid,)``) and 0
    elsewhere, or ``None`` while ``|⟨g⟩| ≤ band`` (``g_0``); and the mean gap ``⟨g⟩`` (–; 0
    without deep particles), ``⟨c/c_ref⟩ − 1 − k var(c/c_ref)`` with ``k = bias`` (the disorder's
    share taken out, :func:`disorder_bias_coefficient`). ``shepard_sum``, ``rho`` (kg/m^d) and
    ``h`` (m) of the fluid particles, ``reference`` the lattice's sum, ``rate`` ε (–), ``c0`` (m/s)."""
    n = deep.size
    if deep.any():
        ratio = shepard_sum[:n][deep] / reference
        gap = float(ratio.mean() - 1.0 - bias * ratio.var())
    else:
        gap = 0.0
    excess = math.copysign(max(abs(gap) - band, 0.0), gap)
    if excess == 0.0:
        return None, gap
    out = np.zeros(n)
    out[deep] = rate * c0 / h[:n][deep] * rho[:n][deep] * excess
    return out, gap


def droplets(shepard_sum: FloatArray, rho: FloatArray, rho0: FloatArray, *, reference: float,
             splash: float) -> NDArray[np.bool_]:
    """The mask ``(n,)`` of the droplets the volume consistency relaxes (module docstring): a
    Shepard sum below ``splash · reference`` (dimensionless) and a density ``rho`` above the rest
    density ``rho0`` (kg/m³; ``(n,)`` each)."""
    return (shepard_sum[: rho.size] < splash * reference) & (rho > rho0)


def loose_particles(shepard_sum: FloatArray, deep: NDArray[np.bool_], *, reference: float,
                    splash: float) -> NDArray[np.bool_]:
    """The mask ``(n_fluid,)`` of the particles the loose side relaxes (module docstring): not
    deep (``deep (n_fluid,)``), and with a Shepard sum of at least ``splash · reference`` (a
    splash's lone particles are left out)."""
    return ~deep & (shepard_sum[: deep.size] >= splash * reference)


class VolumeConsistency(Effect):
    """The density relaxed towards the particles' packing (module docstring):
    ``ρ̇_i += ε (c0/h_i) ρ_i sign⟨g⟩ max(|⟨g⟩| − g_0, 0)`` at the deep fluid particles, with
    ``ε = rate`` (default 0.02, a relaxation time of 50 ``h/c0``), ``g_0 = band`` (0.005) and
    ``surface`` the least Shepard sum, over the lattice's, of a deep particle and its row (0.9).
    Part of the recommended set (``water(volume_consistency=0)`` and every fluid problem's
    ``--set volume_consistency=0`` leave it out); it acts only while some fluid particle's sum is
    below ``surface`` (a free surface), and is idle under
    :class:`~mlsgalerkin.fluid.closed_volume.ClosedVolume`.

    ``loose_band`` ``e_0`` (default 0.005; 0: off) adds the loose side (module docstring): every
    ``loose_every`` (10) evaluations with a free surface the fluid's volume error ``e`` (geometric
    volume over ``Σ M/ρ``, minus one; :func:`~mlsgalerkin.fluid.distribution.volume_error`) is
    measured, and while ``e > e_0`` the particles that are neither deep nor splashes (Shepard sum
    at least ``splash`` (0.5) of the lattice's) relax ``ρ̇_i −= ε (c0/h_i) ρ_i (e − e_0)``.
    ``loose_local`` ``w`` (default 2; 0: off) adds its local part: those whose table row lists no
    wall node relax by ``w max(e_i − b, 0)`` more, with ``e_i`` their neighbourhood's volume excess
    at the last measurement and ``b = loose_local_band`` (0.05).

    ``droplet_rate`` ``r_d`` (default 0.1; 0: off): every evaluation with a free surface, the
    droplets (Shepard sum below ``splash`` of the lattice's) above their rest density relax
    ``ρ̇_i −= r_d (c0/h_i) (ρ_i − ρ0_i)`` (module docstring)."""

    name = "volume_consistency"
    stabilising = True
    stages = ("continuity",)
    reads = ("shape_functions", "kernel_sum")

    def __init__(self, rate: float = 0.02, *, band: float = 0.005, surface: float = 0.9,
                 loose_band: float = 0.005, loose_every: int = 10, splash: float = 0.5,
                 droplet_rate: float = 0.1, loose_local: float = 2.0, loose_local_band: float = 0.05) -> None:
        self.rate, self.band, self.surface = float(rate), float(band), float(surface)
        self.loose_band, self.loose_every, self.splash = float(loose_band), loose_every, float(splash)
        self.loose_local, self.loose_local_band = float(loose_local), float(loose_local_band)
        self.loose_local_largest = 0.0   # the largest neighbourhood excess the local part measured (–)
        self.droplet_rate = float(droplet_rate)
        self.droplet_evaluations = 0     # evaluations in which some droplet was relaxed
        self.droplets_largest = 0        # the most droplets relaxed in one evaluation
        self.loose_error = 0.0           # the volume error last measured by the loose side (–)
        self.loose_error_largest = 0.0
        self.loose_evaluations = 0       # evaluations in which the loose side acted
        self.evaluations = 0
        self.active_evaluations = 0
        self.surface_evaluations = 0
        self.reference = math.nan
        self.bias = math.nan
        self.c0 = math.nan
        self._h = math.nan
        self.gap_mean = math.nan
        self.gap_mean_largest = 0.0
        self.idle = False

    def __repr__(self) -> str:
        loose = f", loose_band={self.loose_band:g}" if self.loose_band else ""
        if self.loose_band and self.loose_local:
            loose += f", loose_local={self.loose_local:g}, loose_local_band={self.loose_local_band:g}"
        droplet = f", droplet_rate={self.droplet_rate:g}" if self.droplet_rate else ""
        return f"VolumeConsistency({self.rate:g}, band={self.band:g}, surface={self.surface:g}{loose}{droplet})"

    def check(self, ctx: EffectContext) -> list[str]:
        out: list[str] = []
        check_positive("VolumeConsistency", "rate", self.rate, out)
        if np.isfinite(self.rate) and self.rate > 0.05:
            out.append(f"VolumeConsistency: rate {self.rate:g} relaxes the density within {1 / self.rate:.0f} "
                       "acoustic times h/c0 and fights the sound; use at most 0.05 (the default is 0.02)")
        if not (np.isfinite(self.band) and 0.0 <= self.band < 0.1):
            out.append(f"VolumeConsistency: band must be a gap in [0, 0.1), got {self.band:g}; the default is 0.005")
        if not 0.0 < self.surface < 1.0:
            out.append(f"VolumeConsistency: surface must be a Shepard sum in (0, 1), got {self.surface:g}; "
                       "the default is 0.9")
        if not (np.isfinite(self.loose_band) and 0.0 <= self.loose_band < 0.1):
            out.append(f"VolumeConsistency: loose_band must be a volume error in [0, 0.1) (0: off), got "
                       f"{self.loose_band:g}; 0.005 is the measured choice")
        if not (np.isfinite(self.loose_local) and 0.0 <= self.loose_local <= 10.0):
            out.append(f"VolumeConsistency: loose_local must be a weight in [0, 10] (0: off), got "
                       f"{self.loose_local:g}; 2 is the measured choice")
        if not (np.isfinite(self.loose_local_band) and 0.0 <= self.loose_local_band < 1.0):
            out.append(f"VolumeConsistency: loose_local_band must be a neighbourhood excess in [0, 1), got "
                       f"{self.loose_local_band:g}; 0.05 is the measured choice")
        if not (isinstance(self.loose_every, int) and self.loose_every >= 1):
            out.append(f"VolumeConsistency: loose_every must be a whole number of evaluations >= 1, got "
                       f"{self.loose_every!r}")
        if not (np.isfinite(self.droplet_rate) and 0.0 <= self.droplet_rate <= 1.0):
            out.append(f"VolumeConsistency: droplet_rate must be in [0, 1] (a relaxation time of at least one "
                       f"acoustic time h/c0; 0: off), got {self.droplet_rate:g}; the default is 0.1")
        if not 0.0 < self.splash < self.surface:
            out.append(f"VolumeConsistency: splash must be a Shepard sum in (0, surface = {self.surface:g}), got "
                       f"{self.splash:g}; the default is 0.5")
        if ctx.sound_speed() is None:
            out.append("VolumeConsistency needs a pressure model with a sound speed c0 (TaitPressure)")
        return out

    def setup(self, state: FluidState, ctx: EffectContext) -> None:
        ap = ctx.approximation
        self.reference = lattice_shepard_sum(ap.kernel, ap.h_factor, state.x.shape[1])
        self.bias = disorder_bias_coefficient(ap.kernel, ap.h_factor, state.x.shape[1])
        self.c0 = state.c0
        self._h = float(state.h[state.fluid].max()) if state.n_fluid else math.nan
        self.idle = any(isinstance(e, ClosedVolume) for e in ctx.effects)
        if self.loose_band > 0.0 and self.loose_local > 0.0:
            field = state.extra.get(LOOSE_LOCAL_FIELD)
            if field is None or np.shape(field) != (state.n,):
                state.extra[LOOSE_LOCAL_FIELD] = np.zeros(state.n)

    def continuity(self, s: FluidState) -> None:
        if self.idle:
            return
        t = s.table
        if t.kernel_sum is None:
            raise ValueError("VolumeConsistency: the shape-function table carries no Shepard sums (the solver "
                             "fills them when an effect reads 'kernel_sum')")
        nf = s.n_fluid
        least = self.surface * self.reference
        self.evaluations += 1
        if nf == 0 or float(t.kernel_sum[:nf].min()) >= least:
            return                          # no free surface: the fluid fills its domain, whose volume is fixed
        self.surface_evaluations += 1
        deep = deep_particles(t, t.kernel_sum, nf, least)
        rate, self.gap_mean = volume_consistency_rate(t.kernel_sum, s.rho, s.h, deep, reference=self.reference,
                                                      rate=self.rate, c0=self.c0, band=self.band, bias=self.bias)
        if rate is not None:
            s.drho[s.fluid] += rate
            self.active_evaluations += 1
        if abs(self.gap_mean) > abs(self.gap_mean_largest):
            self.gap_mean_largest = self.gap_mean
        if self.loose_band > 0.0:
            self._loose_side(s, deep)
        if self.droplet_rate > 0.0:
            self._droplets(s)

    def _droplets(self, s: FluidState) -> None:
        """The droplets (module docstring): the fluid particles whose Shepard sum is below
        ``splash · c_ref`` and whose density is above their rest density relax towards it."""
        nf = s.n_fluid
        over = droplets(s.table.kernel_sum[:nf], s.rho[:nf], s.rho0[:nf], reference=self.reference,
                        splash=self.splash)
        count = int(np.count_nonzero(over))
        if count == 0:
            return
        s.drho[:nf][over] -= self.droplet_rate * self.c0 / s.h[:nf][over] * (s.rho[:nf][over] - s.rho0[:nf][over])
        self.droplet_evaluations += 1
        self.droplets_largest = max(self.droplets_largest, count)

    def _loose_side(self, s: FluidState, deep: NDArray[np.bool_]) -> None:
        """The loose side (module docstring): the volume error measured every ``loose_every``
        evaluations with a free surface (the first included), and past ``loose_band`` the density
        of the particles of :func:`loose_particles` relaxed down."""
        nf = s.n_fluid
        local = self.loose_local > 0.0
        if (self.surface_evaluations - 1) % self.loose_every == 0:
            in_run = still_in_run(s)
            _, self.loose_error = volume_error(s.x[:nf], s.M[:nf], s.rho[:nf], s.spacing, in_run)
            self.loose_error_largest = max(self.loose_error_largest, self.loose_error)
            if local:
                self._measure_local(s, in_run)
        excess = self.loose_error - self.loose_band
        if excess <= 0.0:
            return
        loose = loose_particles(s.table.kernel_sum[:nf], deep, reference=self.reference, splash=self.splash)
        drive: float | FloatArray = excess
        if local:                           # the wall rows keep the global drive only
            field = excess + self.loose_local * np.maximum(s.extra[LOOSE_LOCAL_FIELD][:nf] - self.loose_local_band, 0.0)
            field[wall_rows(s.table, nf)] = excess
            drive = field[loose]
        s.drho[:nf][loose] -= self.rate * self.c0 / s.h[:nf][loose] * s.rho[:nf][loose] * drive
        self.loose_evaluations += 1

    def _measure_local(self, s: FluidState, in_run: NDArray[np.bool_]) -> None:
        """The local part's field (module docstring): while the volume error is past the loose
        band, each fluid particle still in the run gets its neighbourhood's excess
        (:func:`~mlsgalerkin.fluid.distribution.neighbourhood_excess` of the
        :func:`~mlsgalerkin.fluid.distribution.cell_volumes` shares); 0 elsewhere and otherwise."""
        nf = s.n_fluid
        field = s.extra[LOOSE_LOCAL_FIELD]
        field[:] = 0.0
        if self.loose_error <= self.loose_band or not in_run.any():
            return
        x = np.ascontiguousarray(s.x[:nf][in_run])
        volume = s.M[:nf][in_run] / s.rho[:nf][in_run]
        measured = neighbourhood_excess(x, cell_volumes(x, s.spacing), volume, s.spacing)
        field[np.flatnonzero(in_run)] = measured
        self.loose_local_largest = max(self.loose_local_largest, float(measured.max()))

    def summary(self) -> dict[str, Any]:
        if self.idle:
            return {"rate": self.rate, "idle": "ClosedVolume holds the closed tank's volume"}
        if self.evaluations and not self.surface_evaluations:
            return {"rate": self.rate, "idle": "no free surface: the fluid fills its domain, whose volume is fixed"}
        return {"rate": self.rate, "band": self.band, "surface": self.surface,
                "lattice_shepard_sum": self.reference, "disorder_bias_coefficient": self.bias,
                "relaxation_time_s": self._h / (self.rate * self.c0) if self.c0 > 0 else None,
                "packing_gap_mean_at_end": self.gap_mean, "packing_gap_mean_largest": self.gap_mean_largest,
                "active_share": self.active_evaluations / self.evaluations if self.evaluations else 0.0,
                "free_surface_share": self.surface_evaluations / self.evaluations if self.evaluations else 0.0,
                **self._loose_summary(), **self._droplet_summary()}

    def _loose_summary(self) -> dict[str, Any]:
        if not self.loose_band:
            return {}
        out = {"loose_band": self.loose_band, "loose_every": self.loose_every, "splash": self.splash,
               "loose_volume_error_largest": self.loose_error_largest,
               "loose_active_share": self.loose_evaluations / self.evaluations if self.evaluations else 0.0}
        if self.loose_local:
            out.update(loose_local=self.loose_local, loose_local_band=self.loose_local_band,
                       loose_local_excess_largest=self.loose_local_largest)
        return out

    def _droplet_summary(self) -> dict[str, Any]:
        if not self.droplet_rate:
            return {}
        return {"droplet_rate": self.droplet_rate, "droplets_largest": self.droplets_largest,
                "droplet_active_share": self.droplet_evaluations / self.evaluations if self.evaluations else 0.0}

    def state_dict(self) -> dict[str, Any]:
        return {"gap_mean_largest": self.gap_mean_largest, "evaluations": self.evaluations,
                "active_evaluations": self.active_evaluations, "surface_evaluations": self.surface_evaluations,
                "loose_error": self.loose_error, "loose_error_largest": self.loose_error_largest,
                "loose_evaluations": self.loose_evaluations, "droplet_evaluations": self.droplet_evaluations,
                "droplets_largest": self.droplets_largest, "loose_local_largest": self.loose_local_largest}

    def load_state_dict(self, d: dict[str, Any]) -> None:
        self.gap_mean_largest = float(d.get("gap_mean_largest", 0.0))
        self.evaluations = int(d.get("evaluations", 0))
        self.active_evaluations = int(d.get("active_evaluations", 0))
        self.surface_evaluations = int(d.get("surface_evaluations", self.evaluations))
        self.loose_error = float(d.get("loose_error", 0.0))
        self.loose_error_largest = float(d.get("loose_error_largest", 0.0))
        self.loose_evaluations = int(d.get("loose_evaluations", 0))
        self.droplet_evaluations = int(d.get("droplet_evaluations", 0))
        self.droplets_largest = int(d.get("droplets_largest", 0))
        self.loose_local_largest = float(d.get("loose_local_largest", 0.0))
