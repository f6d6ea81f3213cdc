"""Kernel accuracy study (seed digest §6, §9.9) and its MLS/RKPM/Shepard extension.

Compatibility facade: the study lives in the package :mod:`mlsgalerkin.studies.kernels` (one
module per purpose); this module re-exports its public names, so
``from mlsgalerkin.studies.kernel_study import run_kernel_study`` keeps working.

>>> from mlsgalerkin.studies.kernel_study import fit_power_law
>>> fit = fit_power_law([0.1, 0.2, 0.4], [0.02, 0.08, 0.32])
>>> round(fit.exponent, 6)
2.0
"""

from __future__ import annotations

from mlsgalerkin.studies.kernels import (
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
    KernelStudyResult,
    ParticleSum,
    PowerLawFit,
    StudyConfig,
    StudyFunction,
    compute_fits,
    fit_power_law,
    grad_u2d,
    integral_approximation,
    interior_mask,
    jittered_particles_1d,
    kernel_diagnostics,
    local_spacing,
    make_config,
    neighbors_1d,
    nodes_2d,
    particle_approximation,
    particle_sum,
    provenance,
    quadrature_offsets,
    rms_error,
    run_kernel_study,
    u2d,
)

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
