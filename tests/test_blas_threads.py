"""No multi-threaded BLAS call runs inside a step: numba's threads own the cores, and OpenBLAS
worker threads that busy-wait after a call on a large array would fight them (above about 10⁴
particles a 2-thread run was slower than a 1-thread one). The run loop holds every BLAS library
to one thread while it steps, and gives the caller's setting back afterwards."""

from __future__ import annotations

from threadpoolctl import threadpool_info

from mlsgalerkin.monitors import Probe
from mlsgalerkin.problem import load_problem, prepare_problem
from mlsgalerkin.simulation import Simulation


def _blas_threads() -> list[int]:
    return [p["num_threads"] for p in threadpool_info() if p["user_api"] == "blas"]


def test_every_step_runs_with_one_blas_thread(tmp_path):
    seen: list[int] = []

    def record(state) -> float:
        seen.extend(_blas_threads())
        return float(max(_blas_threads(), default=1))

    mod = load_problem("hydrostatic")
    scene = prepare_problem("hydrostatic", dict(mod.SMOKE)).scene
    scene.probes = (*scene.probes, Probe("blas_threads", record))
    before = _blas_threads()
    result = Simulation(scene).run(progress=False)
    assert result.summary["status"] == "completed"
    assert seen, "the probe never ran inside the loop"
    assert set(seen) == {1}, f"BLAS ran with {sorted(set(seen))} threads inside a step"
    assert _blas_threads() == before  # the caller's setting is back
