"""Configuration of the kernel study: output columns, test functions and sweep parameters."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

import numpy as np

from mlsgalerkin.analysis.convergence import ROUNDOFF
from mlsgalerkin.kernels import SPH_STUDY_KERNELS

__all__ = [
    "CLAIM_FUNCTIONS",
    "COLUMNS",
    "DOMAIN_1D",
    "FIT_COLUMNS",
    "FUNCTIONS",
    "FUNCTIONS_BY_LABEL",
    "METHOD_SPECS",
    "ROUNDOFF",
    "SMOOTH_FUNCTIONS",
    "U2D_LABEL",
    "U2D_TEXT",
    "StudyConfig",
    "StudyFunction",
    "grad_u2d",
    "make_config",
    "u2d",
]

DOMAIN_1D = (0.0, 2.0)

COLUMNS = [
    "part",
    "approximation",
    "layout",
    "kernel",
    "function",
    "sweep",
    "h",
    "h_over_dx",
    "n_neighbors",
    "n_particles",
    "spacing",
    "region",
    "n_eval",
    "error_abs",
    "error_rel",
    "error_grad",
    "error_grad_rel",
    "error_grad_max",
    "cond_max",
    "n_fallback",
    "wall_s",
    "worker",
]
FIT_COLUMNS = [
    "part",
    "approximation",
    "layout",
    "kernel",
    "function",
    "sweep",
    "region",
    "quantity",
    "x",
    "exponent",
    "coefficient",
    "r2",
    "n_points",
    "x_min",
    "x_max",
]


# --------------------------------------------------------------------------------------
# test functions
# --------------------------------------------------------------------------------------


@dataclass(frozen=True)
class StudyFunction:
    """A 1D test function with its second derivative (for the leading-error estimate)."""

    key: str
    label: str
    f: Callable[[np.ndarray], np.ndarray]
    d2f: Callable[[np.ndarray], np.ndarray]


FUNCTIONS: tuple[StudyFunction, ...] = (
    StudyFunction("F1", "x", lambda x: np.asarray(x, dtype=float) * 1.0, lambda x: 0.0 * x),
    StudyFunction("F2", "x^3", lambda x: x**3, lambda x: 6.0 * x),
    StudyFunction("F3", "exp(-x)", lambda x: np.exp(-x), lambda x: np.exp(-x)),
    StudyFunction("F4", "sin(x)", np.sin, lambda x: -np.sin(x)),
    StudyFunction("F5", "tan(x)", np.tan, lambda x: 2.0 * np.tan(x) / np.cos(x) ** 2),
)
FUNCTIONS_BY_LABEL = {f.label: f for f in FUNCTIONS}
#: Functions of Xing's (2019) claims (tan x is singular at pi/2 inside the domain).
CLAIM_FUNCTIONS = ("x", "x^3", "exp(-x)", "sin(x)")
SMOOTH_FUNCTIONS = ("x^3", "exp(-x)", "sin(x)")


def u2d(p: np.ndarray) -> np.ndarray:
    """2D test field ``u = sin(pi x) cos(pi y) + x y^2``."""
    x, y = p[:, 0], p[:, 1]
    return np.sin(np.pi * x) * np.cos(np.pi * y) + x * y**2


def grad_u2d(p: np.ndarray) -> np.ndarray:
    """Exact gradient of :func:`u2d`, ``(n, 2)``."""
    x, y = p[:, 0], p[:, 1]
    gx = np.pi * np.cos(np.pi * x) * np.cos(np.pi * y) + y**2
    gy = -np.pi * np.sin(np.pi * x) * np.sin(np.pi * y) + 2.0 * x * y
    return np.column_stack([gx, gy])


U2D_LABEL = "u2d"
U2D_TEXT = "sin(πx)cos(πy) + x y²"


# --------------------------------------------------------------------------------------
# configuration
# --------------------------------------------------------------------------------------


#: name -> (method, basis, needs volumes) for :func:`mlsgalerkin.shape_functions`.
METHOD_SPECS: dict[str, tuple[str, str, bool]] = {
    "shepard": ("shepard", "constant", False),
    "mls_linear": ("mls", "linear", False),
    "mls_quadratic": ("mls", "quadratic", False),
    "rkpm_linear": ("rkpm", "linear", True),
}


def _geom(lo: float, hi: float, n: int) -> tuple[float, ...]:
    return tuple(float(v) for v in np.round(np.geomspace(lo, hi, n), 5))


@dataclass(frozen=True)
class StudyConfig:
    """All sweep parameters (see :func:`make_config`)."""

    quick: bool
    # part 1
    sph_kernels: tuple[str, ...]
    n_eval_1d: int
    int_h: tuple[float, ...]
    int_nnb_fixed: int
    int_nnb: tuple[int, ...]
    int_h_fixed: float
    part_h: tuple[float, ...]
    part_n_fixed: int
    part_n: tuple[int, ...]
    part_h_fixed: float
    # part 2, 1D
    mls_kernels: tuple[str, ...]
    mls_methods: tuple[str, ...]
    mls_functions: tuple[str, ...]
    mls_part_n: tuple[int, ...]
    jitter_1d: float
    refine_n: tuple[int, ...]
    refine_ratio: float
    # part 2, 2D
    kernels_2d: tuple[str, ...]
    methods_2d: tuple[str, ...]
    layouts_2d: tuple[str, ...]
    ratios_2d: tuple[float, ...]
    n_fixed_2d: int
    levels_2d: tuple[int, ...]
    ratio_fixed_2d: float
    eval_per_dx_2d: int
    jitter_2d: float
    # misc
    seed: int
    min_time: float
    repeats: int = 1
    threads: int = 1


def make_config(quick: bool = False) -> StudyConfig:
    """Sweep parameters; ``quick`` keeps every sweep but with fewer points (< 30 s in total)."""
    common = dict(
        quick=quick,
        sph_kernels=tuple(SPH_STUDY_KERNELS),
        n_eval_1d=201,
        int_nnb_fixed=100,
        int_h_fixed=0.1,
        part_n_fixed=100,
        part_h_fixed=0.1,
        mls_kernels=("cubic_spline", "quartic_spline", "quintic_spline", "wendland_c2"),
        mls_methods=("shepard", "mls_linear", "mls_quadratic", "rkpm_linear"),
        mls_functions=CLAIM_FUNCTIONS,
        mls_part_n=(30, 45, 60, 90, 120),
        jitter_1d=0.2,
        refine_ratio=1.5,
        methods_2d=("shepard", "mls_linear", "mls_quadratic"),
        layouts_2d=("jittered", "random"),
        ratio_fixed_2d=1.5,
        jitter_2d=0.3,
        seed=20240611,
    )
    if quick:
        return StudyConfig(
            **common,
            int_h=_geom(0.018, 0.22, 6),
            int_nnb=(2, 3, 4, 5, 6, 8, 10, 14, 20),
            part_h=_geom(0.033, 0.25, 6),
            part_n=(30, 45, 60, 90, 120),
            refine_n=(21, 41, 81, 161, 321),
            kernels_2d=("cubic_spline",),
            ratios_2d=(1.2, 1.5, 2.0, 3.0),
            n_fixed_2d=21,
            levels_2d=(11, 16, 21, 31),
            eval_per_dx_2d=2,
            min_time=2e-4,
        )
    return StudyConfig(
        **common,
        int_h=_geom(0.018, 0.22, 12),
        int_nnb=(2, 3, 4, 5, 6, 7, 8, 9, 10, 12, 14, 16, 18, 20),
        part_h=_geom(0.033, 0.25, 12),
        part_n=tuple(range(30, 121, 10)),
        refine_n=(21, 41, 81, 161, 321, 641, 1281, 2561),
        kernels_2d=("cubic_spline", "wendland_c2"),
        ratios_2d=(1.2, 1.35, 1.5, 1.75, 2.0, 2.5, 3.0),
        n_fixed_2d=41,
        levels_2d=(11, 16, 21, 31, 41, 61, 81, 121, 161),
        eval_per_dx_2d=2,
        min_time=2e-3,
        repeats=3,
    )
