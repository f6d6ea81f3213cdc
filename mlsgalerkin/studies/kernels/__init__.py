r"""Kernel accuracy study (seed digest §6 and §9.9) and its meshfree extension.

Part 1 reproduces the source chapter's SPH study; part 2 asks the same questions of the MLS,
RKPM and Shepard shape functions of :func:`mlsgalerkin.shape_functions`.

Part 1 — SPH sums, 1D, on :math:`[0, 2]`
    Five functions :math:`F_1 = x,\ F_2 = x^3,\ F_3 = e^{-x},\ F_4 = \sin x,\ F_5 = \tan x` and the
    nine kernels of :data:`~mlsgalerkin.kernels.SPH_STUDY_KERNELS`.

    * *Integral approximation* :math:`\langle F(x_a)\rangle = \sum_b F(x_b) W(x_a - x_b, h)\,
      \delta x'`. The ``N_nb`` quadrature points of each evaluation point are the midpoints of
      ``N_nb`` equal cells covering the support :math:`[x_a - \kappa h, x_a + \kappa h]`, so
      :math:`\delta x' = 2\kappa h / N_{nb}`, the set is symmetric about :math:`x_a` and exactly
      ``N_nb`` points lie inside the support. :math:`F` is analytic, so quadrature points are
      allowed outside :math:`[0, 2]`: this approximation has no boundary deficiency.
    * *Particle approximation* :math:`\langle F(x_a)\rangle = \sum_b F(x_b) W_{ab} / \sum_b W_{ab}`
      (the Shepard-normalised sum) on ``N`` equally spaced particles covering :math:`[0, 2]`,
      evaluated at the particles.

Part 2 — shape functions
    1D particle sweeps with Shepard, MLS linear, MLS quadratic and RKPM linear (volumes = local
    spacing) on slightly non-uniform particles, plus a refinement sweep at fixed ``h/Δx``; 2D on
    a jittered lattice and on uniformly random nodes in the unit square, value and gradient
    errors against ``h/Δx`` and against ``Δx``.

Errors are RMS (seed eq. 12.67) over two regions: ``interior`` (evaluation points whose
support ``[x - κh, x + κh]`` lies inside the domain) and ``all``. Every measured point records
its wall time (``time.perf_counter`` around building the approximation plus applying it to one
function; short calls are repeated and averaged) and its neighbour count.

Modules
-------
``config``           output columns, test functions, :class:`StudyConfig`, :func:`make_config`
``measure``          RMS errors, interior masks, timing of one point
``sph``              integral and particle approximations, the SPH sweep (part 1)
``layouts``          jittered 1D particles and their volumes, 2D node sets
``meshfree``         MLS/RKPM/Shepard sweeps in 1D and 2D, numba warm-up (part 2)
``records``          :class:`KernelStudyResult`, the row recorder, row selection
``fits``             power-law fits of every series (:mod:`mlsgalerkin.analysis.convergence`)
``claims``           the numbers behind the source's claims and the MLS comparison
``plot_style``       colours, markers and axes shared by the figures
``plots``            the PNG figures
``markdown``         number and table formatting of ``summary.md``
``report``           ``summary.md``: provenance, set-up, part 1 and the claims
``report_meshfree``  ``summary.md``: part 2 tables and findings
``output``           CSV formatting and the provenance record
``study``            :func:`run_kernel_study`, the entry point

Example
-------
>>> from mlsgalerkin.studies.kernels import fit_power_law
>>> fit = fit_power_law([0.1, 0.2, 0.4], [0.02, 0.08, 0.32])
>>> round(fit.exponent, 6)
2.0

Run the study with ``mlsgalerkin study kernels --quick --out results/demo`` or
:func:`run_kernel_study`.
"""

from __future__ import annotations

from mlsgalerkin.analysis.convergence import PowerLawFit, fit_power_law
from mlsgalerkin.studies.kernels.claims import kernel_diagnostics
from mlsgalerkin.studies.kernels.config import (
    CLAIM_FUNCTIONS,
    COLUMNS,
    DOMAIN_1D,
    FIT_COLUMNS,
    FUNCTIONS,
    METHOD_SPECS,
    ROUNDOFF,
    SMOOTH_FUNCTIONS,
    U2D_LABEL,
    U2D_TEXT,
    StudyConfig,
    StudyFunction,
    grad_u2d,
    make_config,
    u2d,
)
from mlsgalerkin.studies.kernels.fits import compute_fits
from mlsgalerkin.studies.kernels.layouts import jittered_particles_1d, local_spacing, nodes_2d
from mlsgalerkin.studies.kernels.measure import interior_mask, rms_error
from mlsgalerkin.studies.kernels.output import provenance
from mlsgalerkin.studies.kernels.records import KernelStudyResult
from mlsgalerkin.studies.kernels.sph import (
    ParticleSum,
    integral_approximation,
    neighbors_1d,
    particle_approximation,
    particle_sum,
    quadrature_offsets,
)
from mlsgalerkin.studies.kernels.study import run_kernel_study

__all__ = [
    "CLAIM_FUNCTIONS",
    "COLUMNS",
    "DOMAIN_1D",
    "FIT_COLUMNS",
    "FUNCTIONS",
    "KernelStudyResult",
    "METHOD_SPECS",
    "ParticleSum",
    "PowerLawFit",
    "ROUNDOFF",
    "SMOOTH_FUNCTIONS",
    "StudyConfig",
    "StudyFunction",
    "U2D_LABEL",
    "U2D_TEXT",
    "compute_fits",
    "fit_power_law",
    "grad_u2d",
    "integral_approximation",
    "interior_mask",
    "jittered_particles_1d",
    "kernel_diagnostics",
    "local_spacing",
    "make_config",
    "neighbors_1d",
    "nodes_2d",
    "particle_approximation",
    "particle_sum",
    "provenance",
    "quadrature_offsets",
    "rms_error",
    "run_kernel_study",
    "u2d",
]
