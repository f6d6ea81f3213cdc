"""Part 2 of the kernel study: MLS, RKPM and Shepard shape functions in 1D and 2D.

:class:`Shapes` maps the study's method names onto :func:`mlsgalerkin.shape_functions`;
:func:`run_mls_1d` and :func:`run_mls_2d` run the sweeps. numba code is compiled before any
timing: :func:`start_prewarm` compiles the general kernel in a second process while the SPH part
runs, :func:`warm_up_2d_linear` and :func:`warm_up` call every remaining path on tiny inputs.
"""

from __future__ import annotations

import inspect
import logging
import subprocess
import sys
import warnings
from typing import Callable

import numpy as np

from mlsgalerkin.kernels import get_kernel
from mlsgalerkin.studies.kernels.config import (
    DOMAIN_1D,
    FUNCTIONS_BY_LABEL,
    METHOD_SPECS,
    U2D_LABEL,
    StudyConfig,
    grad_u2d,
    u2d,
)
from mlsgalerkin.studies.kernels.layouts import jittered_particles_1d, local_spacing, nodes_2d
from mlsgalerkin.studies.kernels.measure import interior_mask, timed
from mlsgalerkin.studies.kernels.records import Recorder
from mlsgalerkin.studies.kernels.sph import neighbors_1d

__all__ = [
    "Shapes",
    "get_shape_functions",
    "prewarm_worker",
    "run_mls_1d",
    "run_mls_2d",
    "start_prewarm",
    "wait_prewarm",
    "warm_up",
    "warm_up_2d_linear",
]

logger = logging.getLogger(__name__)


def get_shape_functions() -> Callable | None:
    """``mlsgalerkin.shape_functions``, or ``None`` (logged) when it cannot be imported."""
    try:
        import mlsgalerkin

        sf = getattr(mlsgalerkin, "shape_functions", None)
        if sf is None:
            from mlsgalerkin.approximation import shape_functions as sf  # type: ignore
        return sf
    except Exception as exc:  # the module may be mid-edit in a shared tree
        logger.warning("mlsgalerkin.shape_functions unavailable (%s): part 2 skipped", exc)
        return None


class Shapes:
    """Wrapper: maps study method names onto ``shape_functions`` and silences fallback warnings."""

    def __init__(self, sf: Callable):
        self.sf = sf
        try:
            params = inspect.signature(sf).parameters
        except (TypeError, ValueError):
            params = {}
        self.quiet = "on_fallback" in params
        self.accepts_neighbors = "neighbors" in params

    def __call__(self, points, nodes, h, kernel: str, method: str, volumes=None, neighbors=None):
        """Shape functions of ``method`` (a :data:`METHOD_SPECS` key) at ``points``."""
        meth, basis, needs_vol = METHOD_SPECS[method]
        kw = dict(kernel=kernel, basis=basis, method=meth)
        if needs_vol:
            kw["volumes"] = volumes
        if self.quiet:
            kw["on_fallback"] = "ignore"
        if neighbors is not None and self.accepts_neighbors:
            kw["neighbors"] = neighbors
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            return self.sf(points, nodes, h, **kw)


# --------------------------------------------------------------------------------------
# numba warm-up
# --------------------------------------------------------------------------------------


_PREWARM_CODE = "from mlsgalerkin.studies.kernels.meshfree import prewarm_worker; prewarm_worker()"


def prewarm_worker() -> None:
    """Entry point of the background process: compile the general shape-function kernel.

    numba writes the compiled code to its on-disk cache (``cache=True``); the main process then
    loads it instead of compiling. Only the 1D path is called, with a precomputed neighbour
    table, so this process compiles exactly the code the main process does not compile itself.
    """
    sf = get_shape_functions()
    if sf is None:
        return
    x1 = np.linspace(0.0, 1.0, 12)
    Shapes(sf)(x1, x1, 0.25, "cubic_spline", "mls_linear", neighbors=neighbors_1d(x1, x1, 0.5))


def start_prewarm() -> subprocess.Popen | None:
    """Compile the general MLS kernel in a second process while this one works (2 cores)."""
    try:
        return subprocess.Popen(
            [sys.executable, "-c", _PREWARM_CODE],
            stdin=subprocess.DEVNULL,
            stdout=subprocess.DEVNULL,
            stderr=subprocess.DEVNULL,
        )
    except OSError as exc:
        logger.info("background JIT warm-up not started: %s", exc)
        return None


def wait_prewarm(proc: subprocess.Popen | None, timeout: float = 900.0) -> None:
    """Wait for the background warm-up (killed after ``timeout`` s; failures only logged)."""
    if proc is None:
        return
    try:
        rc = proc.wait(timeout=timeout)
        if rc != 0:
            logger.info("background JIT warm-up exited with %s; compiling here instead", rc)
    except subprocess.TimeoutExpired:
        proc.kill()
        proc.wait()
        logger.warning("background JIT warm-up timed out; compiling here instead")


def warm_up_2d_linear(shapes: Shapes, cfg: StudyConfig) -> None:
    """Compile the neighbour search and the fused 2D-linear kernel (not the general kernel)."""
    if "mls_linear" not in cfg.methods_2d:
        return
    g = np.linspace(0.0, 1.0, 6)
    x2 = np.stack(np.meshgrid(g, g, indexing="ij"), axis=-1).reshape(-1, 2)
    t = shapes(x2, x2, 0.4, cfg.kernels_2d[0], "mls_linear")
    t.interpolate(x2[:, 0])
    t.gradient(x2[:, 0])


def warm_up(shapes: Shapes, cfg: StudyConfig) -> None:
    """Call every numba path once on tiny inputs, so no measured point includes JIT time."""
    x1 = np.linspace(0.0, 1.0, 12)
    g = np.linspace(0.0, 1.0, 6)
    x2 = np.stack(np.meshgrid(g, g, indexing="ij"), axis=-1).reshape(-1, 2)
    nb1 = neighbors_1d(x1, x1, 0.5)
    for m in cfg.mls_methods:
        t = shapes(x1, x1, 0.25, "cubic_spline", m, volumes=local_spacing(x1), neighbors=nb1)
        t.interpolate(x1)
    for kname in cfg.kernels_2d:
        for m in cfg.methods_2d:
            t = shapes(x2, x2, 0.4, kname, m)
            t.interpolate(x2[:, 0])
            t.gradient(x2[:, 0])


# --------------------------------------------------------------------------------------
# part 2: 1D and 2D sweeps
# --------------------------------------------------------------------------------------


def run_mls_1d(cfg: StudyConfig, rec: Recorder, shapes: Shapes) -> None:
    """1D sweeps (h, N, refinement at fixed h/Δx) of every method and kernel on jittered
    particles, evaluated at the particles."""
    lo, hi = DOMAIN_1D
    funcs = [FUNCTIONS_BY_LABEL[f] for f in cfg.mls_functions]
    for kname in cfg.mls_kernels:
        k = get_kernel(kname)
        sweeps = [("h", h, cfg.part_n_fixed) for h in cfg.part_h]
        sweeps += [("n_particles", cfg.part_h_fixed, n) for n in cfg.mls_part_n]
        sweeps += [("refine", None, n) for n in cfg.refine_n]
        for method in cfg.mls_methods:
            for sweep, h, n in sweeps:
                dx = (hi - lo) / (n - 1)
                if h is None:
                    h = cfg.refine_ratio * dx
                x = jittered_particles_1d(n, cfg.jitter_1d, cfg.seed)
                vol = local_spacing(x)
                masks = {
                    "interior": interior_mask(x, k.support * h, lo, hi),
                    "all": np.ones(x.shape, bool),
                }
                table, t_build = timed(
                    lambda: shapes(
                        x,
                        x,
                        h,
                        kname,
                        method,
                        volumes=vol,
                        neighbors=neighbors_1d(x, x, k.support * h),
                    ),
                    cfg.min_time,
                    cfg.repeats,
                )
                for fn in funcs:
                    fx = fn.f(x)
                    approx, t = timed(lambda: table.interpolate(fn.f(x)), cfg.min_time, cfg.repeats)
                    base = dict(
                        part="mls1d",
                        approximation=method,
                        layout="jittered",
                        kernel=kname,
                        function=fn.label,
                        sweep=sweep,
                        h=h,
                        h_over_dx=h / dx,
                        n_particles=n,
                        spacing=dx,
                        n_fallback=int(table.n_fallback),
                    )
                    rec.add(
                        base, masks, approx, fx, wall_s=t_build + t, counts=np.diff(table.indptr)
                    )
                rec.tick()


def run_mls_2d(cfg: StudyConfig, rec: Recorder, shapes: Shapes) -> None:
    """2D sweeps (h/Δx, resolution) of value and gradient errors of :func:`u2d` per layout."""
    grids: dict[int, tuple] = {}

    def eval_grid(n: int):
        # evaluation points on a grid of spacing Δx / eval_per_dx_2d: the cost grows with n
        if n not in grids:
            ge = np.linspace(0.0, 1.0, cfg.eval_per_dx_2d * (n - 1) + 1)
            pts = np.stack(np.meshgrid(ge, ge, indexing="ij"), axis=-1).reshape(-1, 2)
            grids[n] = (pts, u2d(pts), grad_u2d(pts))
        return grids[n]

    for kname in cfg.kernels_2d:
        k = get_kernel(kname)
        for layout in cfg.layouts_2d:
            sweeps = [("h_over_dx", r, cfg.n_fixed_2d) for r in cfg.ratios_2d]
            sweeps += [("resolution", cfg.ratio_fixed_2d, n) for n in cfg.levels_2d]
            for method in cfg.methods_2d:
                for sweep, ratio, n in sweeps:
                    pts, u_ex, g_ex = eval_grid(n)
                    nodes = nodes_2d(layout, n, cfg.jitter_2d, cfg.seed)
                    dx = 1.0 / (n - 1)
                    h = ratio * dx
                    masks = {
                        "interior": interior_mask(pts, k.support * h),
                        "all": np.ones(pts.shape[0], bool),
                    }
                    un = u2d(nodes)
                    base = dict(
                        part="mls2d",
                        approximation=method,
                        layout=layout,
                        kernel=kname,
                        function=U2D_LABEL,
                        sweep=sweep,
                        h=h,
                        h_over_dx=ratio,
                        n_particles=int(nodes.shape[0]),
                        spacing=dx,
                    )

                    def work():
                        tab = shapes(pts, nodes, h, kname, method)
                        return tab, tab.interpolate(un), tab.gradient(un)

                    try:
                        (table, approx, grad), t = timed(work, cfg.min_time, cfg.repeats)
                    except ValueError as exc:  # e.g. an evaluation point without neighbours
                        logger.warning(
                            "2D %s %s %s n=%d h/dx=%.2f failed: %s",
                            layout,
                            method,
                            kname,
                            n,
                            ratio,
                            exc,
                        )
                        rec.tick()
                        continue
                    base["n_fallback"] = int(table.n_fallback)
                    # a point cannot have a full-rank moment matrix of order p with fewer
                    # neighbours than basis terms (3 linear, 6 quadratic in 2D); count violations
                    order = getattr(table, "order", None)
                    if order is not None:
                        nterms = np.array([1, 3, 6])[np.clip(order.astype(int), 0, 2)]
                        bad = np.flatnonzero(np.diff(table.indptr) < nterms)
                        if bad.size:
                            j = int(bad[0])
                            rec.notes.append(
                                f"{layout} {method} {kname}, n = {n}² nodes, h/Δx = {ratio:g}: "
                                f"{bad.size} point(s) accepted at order {int(order[j])} with fewer "
                                f"neighbours than basis terms, e.g. "
                                f"({pts[j, 0]:.4g}, {pts[j, 1]:.4g}) "
                                f"with {int(np.diff(table.indptr)[j])} neighbour(s), condition "
                                f"{float(table.condition[j]):.3g}, gradient error "
                                f"{float(np.linalg.norm(grad[j] - g_ex[j])):.3g}"
                            )
                    rec.add(
                        base,
                        masks,
                        approx,
                        u_ex,
                        wall_s=t,
                        counts=np.diff(table.indptr),
                        grad=grad,
                        grad_exact=g_ex,
                        cond=getattr(table, "condition", None),
                    )
                    rec.tick()
