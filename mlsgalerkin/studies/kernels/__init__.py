r"""Kernel accuracy study (Xing 2019, §12.2.3) and its meshfree extension.

Part 1 reproduces Xing's (2019) SPH study; part 2 asks the same questions of the MLS,
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

Errors are RMS (Xing 2019, eq. 12.67) over two regions: ``interior`` (evaluation points whose
support ``[x - κh, x + κh]`` lies inside the domain) and ``all``. Every measured row records its
wall time ``wall_s`` (``time.perf_counter`` around building the approximation plus applying it to
one function; short calls are repeated, best time kept) and its neighbour count; the grid runs on
the study engine (:mod:`mlsgalerkin.studies.engine`), so ``worker`` says who measured it.

This package computes the numbers (rows, fits, key numbers); the report with Xing's (2019) claims,
the findings and the figures is written by ``verification/kernel_study.py``.

Modules
-------
``config``    output columns, test functions, :class:`StudyConfig`, :func:`make_config`
``measure``   RMS errors, interior masks, the rows of one point per region
``sph``       integral and particle approximations, the points and measurement of part 1
``layouts``   jittered 1D particles and their volumes, 2D node sets
``meshfree``  MLS/RKPM/Shepard: points and measurement of part 2, numba warm-up
``fits``      power-law fits of every series (:mod:`mlsgalerkin.analysis.convergence`)
``headline``  the key numbers (slopes, 5-neighbour errors, 2D orders)
``output``    CSV number formats
``result``    :class:`KernelStudyResult` and its console report
``study``     :func:`run_kernel_study`, the entry point

Example
-------
>>> from mlsgalerkin.studies.kernels import make_config, study_grid
>>> len(study_grid(make_config(quick=True)))
538

Run the study with ``mlsgalerkin study kernels --quick --out results/demo`` or
:func:`run_kernel_study`; the full report with ``python verification/kernel_study.py``.
"""

from __future__ import annotations

from mlsgalerkin.studies.kernels.config import (
    CLAIM_FUNCTIONS,
    COLUMNS,
    DOMAIN_1D,
    FIT_COLUMNS,
    FUNCTIONS,
    FUNCTIONS_BY_LABEL,
    METHOD_SPECS,
    SMOOTH_FUNCTIONS,
    U2D_LABEL,
    U2D_TEXT,
    StudyConfig,
    StudyFunction,
    grad_u2d,
    make_config,
    u2d,
)
from mlsgalerkin.studies.kernels.fits import compute_fits, fit_lookup
from mlsgalerkin.studies.kernels.headline import (
    five_neighbour_errors,
    headline,
    orders_2d,
    sph_slopes,
)
from mlsgalerkin.studies.kernels.layouts import jittered_particles_1d, local_spacing, nodes_2d
from mlsgalerkin.studies.kernels.measure import interior_mask, region_rows, rms_error
from mlsgalerkin.studies.kernels.meshfree import (
    build_shapes,
    measure_mls_1d,
    measure_mls_2d,
    mls_points,
    warm_up,
)
from mlsgalerkin.studies.kernels.result import KernelStudyResult
from mlsgalerkin.studies.kernels.sph import (
    ParticleSum,
    integral_approximation,
    measure_integral,
    measure_particle,
    neighbors_1d,
    particle_approximation,
    particle_sum,
    quadrature_offsets,
    sph_points,
)
from mlsgalerkin.studies.kernels.study import measure_point, run_kernel_study, study_grid

__all__ = [
    "CLAIM_FUNCTIONS",
    "COLUMNS",
    "DOMAIN_1D",
    "FIT_COLUMNS",
    "FUNCTIONS",
    "FUNCTIONS_BY_LABEL",
    "METHOD_SPECS",
    "SMOOTH_FUNCTIONS",
    "U2D_LABEL",
    "U2D_TEXT",
    "KernelStudyResult",
    "ParticleSum",
    "StudyConfig",
    "StudyFunction",
    "build_shapes",
    "compute_fits",
    "fit_lookup",
    "five_neighbour_errors",
    "grad_u2d",
    "headline",
    "integral_approximation",
    "interior_mask",
    "jittered_particles_1d",
    "local_spacing",
    "make_config",
    "measure_integral",
    "measure_mls_1d",
    "measure_mls_2d",
    "measure_particle",
    "measure_point",
    "mls_points",
    "neighbors_1d",
    "nodes_2d",
    "orders_2d",
    "particle_approximation",
    "particle_sum",
    "quadrature_offsets",
    "region_rows",
    "rms_error",
    "run_kernel_study",
    "sph_points",
    "sph_slopes",
    "study_grid",
    "u2d",
    "warm_up",
]
