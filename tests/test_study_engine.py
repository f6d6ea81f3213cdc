"""The study engine: grids, timing, schedulers (serial and Dask), records, fits, plot, errors.

One local Dask cluster (two worker processes, one thread each) serves the whole module; its
tests compare a cluster run with a serial run of the same grid: the records must be identical
except for the timing columns, and the worker column must name the cluster's workers.
"""

from __future__ import annotations

import functools
import itertools
import math
import threading

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from mlsgalerkin.analysis.convergence import fit_power_law, observed_order
from mlsgalerkin.studies.engine import (
    Grid,
    GridError,
    MeasurementError,
    SchedulerError,
    StudyResult,
    best_time,
    run_study,
)
from mlsgalerkin.studies.engine.schedulers import SINGLE_THREAD_ENV
from mlsgalerkin.studies.kernels import make_config, measure_point, warm_up
from mlsgalerkin.studies.kernels.study import study_grid

TIMING = ("wall_time_s", "worker", "wall_s")


@pytest.fixture(scope="module")
def client():
    distributed = pytest.importorskip("distributed")
    cluster = distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                                       dashboard_address=":0", env=dict(SINGLE_THREAD_ENV))
    with distributed.Client(cluster) as c:
        yield c
    cluster.close()


def _kernel_study_subset():
    """A small slice of the kernel study: SPH sums (numpy) and 2D MLS points (numba)."""
    cfg = make_config(quick=True)
    points = list(study_grid(cfg))
    sph = [p for p in points if p["part"] == "sph" and p["kernel"] == "cubic_spline"]
    mls2d = [p for p in points if p["part"] == "mls2d" and p["n_side"] <= 21][:6]
    return cfg, Grid.from_points(sph + mls2d)


def _without_timing(records):
    return [{k: v for k, v in r.items() if k not in TIMING} for r in records]


# ======================================================================================
# serial vs Dask
# ======================================================================================


def test_local_cluster_gives_the_same_records_as_serial(client):
    cfg, grid = _kernel_study_subset()
    kwargs = dict(warm_up=functools.partial(warm_up, cfg), progress=False)
    serial = run_study(grid, functools.partial(measure_point, cfg), scheduler="serial", **kwargs)
    dask = run_study(grid, functools.partial(measure_point, cfg), scheduler=client, **kwargs)
    assert len(serial.records) == len(dask.records) > 2 * len(grid)  # several rows per point
    # bit-identical (NaN equal to NaN: the SPH rows have no gradient errors)
    np.testing.assert_equal(_without_timing(dask.records), _without_timing(serial.records))
    workers = set(client.scheduler_info()["workers"])
    assert {r["worker"] for r in dask.records} <= workers
    assert len(dask.workers) == 2  # both workers measured
    assert all(r["worker"].startswith("serial@") for r in serial.records)
    for result in (serial, dask):
        assert all(r["wall_time_s"] > 0 and r["wall_s"] > 0 for r in result.records)
    assert "local" not in dask.scheduler and "serial" in serial.scheduler


def test_scheduler_address_fans_out_and_user_functions_are_shipped(client):
    def interpolation_error(kernel, spacing):  # defined here: travels by value (cloudpickle)
        from mlsgalerkin import shape_functions

        x = np.arange(0.0, 1.0 + spacing / 2, spacing)
        midpoints = 0.5 * (x[1:] + x[:-1])
        t = shape_functions(midpoints, x, 2.0 * spacing, kernel=kernel)
        return {"error": float(np.abs(t.interpolate(np.sin(x)) - np.sin(midpoints)).max())}

    grid = Grid.product(kernel=["cubic_spline", "wendland_c2"], spacing=[0.1, 0.05])
    address = client.scheduler.address
    remote = run_study(grid, interpolation_error, scheduler=address, progress=False)
    local = run_study(grid, interpolation_error, scheduler="serial", progress=False)
    np.testing.assert_equal(_without_timing(remote.records), _without_timing(local.records))
    assert set(remote.workers) <= set(client.scheduler_info()["workers"])
    assert address in remote.scheduler


def test_a_failing_measurement_names_its_point_on_a_cluster_and_in_serial(client):
    def fragile(spacing):
        if spacing < 0.03:
            raise FloatingPointError(f"diverged at {spacing}")
        return {"error": spacing**2}

    grid = Grid.product(spacing=[0.1, 0.05, 0.025])
    for scheduler in ("serial", client):
        with pytest.raises(MeasurementError, match=r"grid point #2 \{'spacing': 0.025\}") as info:
            run_study(grid, fragile, scheduler=scheduler, progress=False)
        assert info.value.index == 2 and info.value.params == {"spacing": 0.025}
        assert "FloatingPointError: diverged at 0.025" in str(info.value)


def test_a_measurement_that_cannot_travel_is_refused_before_work(client):
    lock = threading.Lock()
    calls = []

    def locked(n):
        calls.append(n)
        with lock:
            return {"value": n}

    with pytest.raises(TypeError, match="cannot be sent to Dask workers"):
        run_study({"n": [1, 2]}, locked, scheduler=client, progress=False)
    assert calls == []
    assert [r["value"] for r in run_study({"n": [1, 2]}, locked, scheduler="serial",
                                          progress=False).records] == [1, 2]


# ======================================================================================
# checks before any work
# ======================================================================================


def _counting_measure():
    calls = []

    def measure(kernel, spacing):
        calls.append((kernel, spacing))
        return {"error": spacing}

    return measure, calls


@pytest.mark.parametrize("grid, match", [
    ({"kernel": ["cubic_spline"], "spaceing": [0.1]}, "spaceing"),
    ({"kernel": ["cubic_spline"]}, "missing a required argument: 'spacing'"),
    ({"kernel": "cubic_spline", "spacing": [0.1]}, r"write kernel=\['cubic_spline'\]"),
    ({"kernel": [], "spacing": [0.1]}, "axis 'kernel' is empty"),
    ({"kernel": ["a"], "spacing": [0.1], "worker": ["me"]}, "reserved"),
    ([{"kernel": "a", "spacing": 0.1}, ("a", 0.2)], "not a mapping"),
    ([], "no points"),
])
def test_bad_grids_are_refused_before_any_work(grid, match):
    measure, calls = _counting_measure()
    with pytest.raises(GridError, match=match):
        run_study(grid, measure, scheduler="serial", progress=False)
    assert calls == []


@pytest.mark.parametrize("kwargs, error, match", [
    (dict(repeats=0), ValueError, "repeats"),
    (dict(min_time=-1.0), ValueError, "min_time"),
    (dict(numba_threads=0), ValueError, "numba_threads"),
    (dict(scheduler=42), SchedulerError, "scheduler must be"),
    (dict(scheduler=""), SchedulerError, "empty"),
    (dict(scheduler="serial", n_workers=2), SchedulerError, "local cluster only"),
    (dict(n_workers=0), SchedulerError, "n_workers"),
    (dict(scheduler="garbage"), SchedulerError, "neither 'local', 'serial' nor a Dask scheduler address"),
    (dict(scheduler="tcp://host-without-port"), SchedulerError, "Dask scheduler address"),
    (dict(warm_up="compile"), TypeError, "warm_up"),
])
def test_bad_options_are_refused_before_any_work(kwargs, error, match):
    measure, calls = _counting_measure()
    with pytest.raises(error, match=match):
        run_study({"kernel": ["a"], "spacing": [0.1]}, measure, progress=False, **kwargs)
    assert calls == []


@pytest.mark.parametrize("returned, match", [
    (0.1, "returned a float"),
    ([{"error": 1.0}, 2.0], "returned a list"),
    ({"worker": "me"}, "reserved|other than"),
    ({"spacing": 0.2}, "repeat a parameter only with its value"),
])
def test_a_measurement_must_return_records(returned, match):
    with pytest.raises(MeasurementError, match=match):
        run_study({"spacing": [0.1]}, lambda spacing: returned, scheduler="serial",
                  progress=False)


def test_records_echo_parameters_list_several_rows_and_keep_grid_order():
    def measure(h, n):
        return [{"h": h, "region": region, "error": h * n * k} for k, region in
                enumerate(("interior", "all"), start=1)]

    result = run_study(Grid.product(h=[0.2, 0.1], n=[3, 1]), measure, scheduler="serial",
                       progress=False)
    assert [(r["h"], r["n"], r["region"]) for r in result.records] == [
        (0.2, 3, "interior"), (0.2, 3, "all"), (0.2, 1, "interior"), (0.2, 1, "all"),
        (0.1, 3, "interior"), (0.1, 3, "all"), (0.1, 1, "interior"), (0.1, 1, "all")]
    assert list(result.records[0]) == ["h", "n", "region", "error", "wall_time_s", "worker"]
    assert result.parameters == ("h", "n")


# ======================================================================================
# timing
# ======================================================================================


def test_timing_policy_repeats_and_keeps_the_first_result():
    calls = []

    def measure(x):
        calls.append(x)
        return {"call": len(calls)}

    result = run_study({"x": [1]}, measure, scheduler="serial", repeats=3, progress=False)
    assert len(calls) == 4  # the recorded call, then three timed groups of one call
    assert result.records[0]["call"] == 1
    calls.clear()
    run_study({"x": [1]}, measure, scheduler="serial", progress=False)
    assert len(calls) == 1  # default: exactly one call


def test_best_time_groups_fast_calls_to_min_time():
    n = []
    out, seconds = best_time(lambda: n.append(1) or len(n), min_time=2e-3, repeats=2)
    assert out == 1 and seconds > 0
    assert len(n) > 3  # fast calls are grouped to last about min_time


def test_warm_up_runs_once_per_process_before_timing():
    warmed = []

    def warm():
        warmed.append(1)

    result = run_study({"x": [1, 2, 3]}, lambda x: {"warm": len(warmed)}, warm_up=warm,
                       scheduler="serial", progress=False)
    assert warmed == [1] and [r["warm"] for r in result.records] == [1, 1, 1]


# ======================================================================================
# fits, CSV, plot
# ======================================================================================


def test_fit_agrees_with_analysis_convergence(rng):
    h = np.array([0.2, 0.1, 0.05, 0.025])
    records = []
    for kernel, p, c in (("a", 2.0, 3.0), ("b", 1.0, 0.5)):
        err = c * h**p * (1 + 0.02 * rng.standard_normal(h.size))
        records += [{"kernel": kernel, "spacing": s, "error": e, "wall_time_s": 1e-3 / s,
                     "worker": "w"} for s, e in zip(h, err)]
    result = StudyResult(records=records, parameters=("kernel", "spacing"))
    fits = result.fit(x="spacing", y="error", by=["kernel"])
    assert [f["kernel"] for f in fits] == ["a", "b"]
    for f in fits:
        series = result.select(kernel=f["kernel"])
        ref = fit_power_law([r["spacing"] for r in series], [r["error"] for r in series])
        assert (f["exponent"], f["coefficient"], f["r2"], f["n_points"]) == (
            ref.exponent, ref.coefficient, ref.r2, ref.n_points)
        ls, _ = observed_order([r["spacing"] for r in series], [r["error"] for r in series])
        assert ls == pytest.approx(ref.exponent, abs=1e-11)
    assert fits[0]["exponent"] == pytest.approx(2.0, abs=0.1)
    with pytest.raises(KeyError, match="no column 'eror'"):
        result.fit(x="spacing", y="eror")


def test_csv_and_work_precision_plot_are_written_atomically(tmp_path):
    def measure(kernel, spacing):
        return {"error": spacing**2 * (2 if kernel == "b" else 1), "modes": np.arange(3)}

    result = run_study(Grid.product(kernel=["a", "b"], spacing=[0.1, 0.05, 0.025]), measure,
                       scheduler="serial", progress=False)
    csv_path = result.to_csv(tmp_path / "study.csv")
    lines = csv_path.read_text().splitlines()
    assert lines[0] == "kernel,spacing,error,wall_time_s,worker"  # the array column is left out
    assert len(lines) == 7 and lines[1].startswith("a,0.1,0.01,")
    png = result.work_precision_plot(tmp_path / "wp.png", error="error", by=["kernel"])
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert not list(tmp_path.glob(".*.tmp"))
    with pytest.raises(ValueError, match="no record matches"):
        result.work_precision_plot(tmp_path / "none.png", error="error", where={"kernel": "c"})


# ======================================================================================
# properties
# ======================================================================================


@settings(max_examples=30, deadline=None)
@given(st.lists(st.integers(1, 4), min_size=1, max_size=3))
def test_grid_product_visits_every_combination_once_in_itertools_order(sizes):
    axes = {f"p{i}": list(range(10 * i, 10 * i + n)) for i, n in enumerate(sizes)}
    grid = Grid.product(**axes)
    expected = [dict(zip(axes, combo)) for combo in itertools.product(*axes.values())]
    assert list(grid) == expected and len(grid) == math.prod(sizes)
    result = run_study(grid, lambda **p: {"sum": sum(p.values())}, scheduler="serial",
                       progress=False)
    assert [r["sum"] for r in result.records] == [sum(p.values()) for p in expected]


@settings(max_examples=50, deadline=None)
@given(order=st.floats(0.5, 6.0), prefactor=st.floats(1e-3, 1e3),
       coarse=st.floats(0.05, 1.0), levels=st.integers(2, 6))
def test_observed_order_recovers_an_exact_power_law(order, prefactor, coarse, levels):
    h = coarse / 2.0 ** np.arange(levels)
    err = prefactor * h**order
    if err.min() <= 1e-12:  # below the round-off floor those levels are (rightly) dropped
        return
    fit, finest = observed_order(h[::-1], err[::-1])  # input order does not matter
    assert fit == pytest.approx(order, abs=1e-8) and finest == pytest.approx(order, abs=1e-8)


# ------------------------------------------------------------------ rows on disk as measured
def test_rows_are_on_disk_as_they_are_measured_and_kept_when_the_study_fails(tmp_path):
    """Each point's records reach the row log when the point is measured: a measurement that fails
    at the fourth point leaves the first three points' rows in the file."""
    from mlsgalerkin.studies.engine import MeasurementError, read_rows

    log = tmp_path / "rows.jsonl"
    seen_on_disk = []

    def measure(n):
        seen_on_disk.append(len(read_rows(log)))
        if n == 3:
            raise RuntimeError("the solver diverged")
        return {"square": n * n, "values": np.arange(n)}  # an array: left out of the log

    with pytest.raises(MeasurementError, match="the solver diverged"):
        run_study({"n": [0, 1, 2, 3, 4]}, measure, scheduler="serial", progress=False, rows_log=log)
    assert seen_on_disk == [0, 1, 2, 3]  # every earlier point was on disk before the next started
    rows = read_rows(log)
    assert [(r["n"], r["square"]) for r in rows] == [(0, 0), (1, 1), (2, 4)]
    assert "values" not in rows[0] and {"wall_time_s", "worker"} <= set(rows[0])


def test_a_full_disk_stops_the_study_and_keeps_the_rows_written_before(tmp_path, monkeypatch):
    import errno

    from mlsgalerkin.studies.engine import RowLog, read_rows

    real_append = RowLog.append

    def append(self, index, records):
        if self.rows >= 2:
            raise OSError(errno.ENOSPC, "No space left on device")
        real_append(self, index, records)

    monkeypatch.setattr(RowLog, "append", append)
    log = tmp_path / "rows.jsonl"
    with pytest.raises(OSError, match="No space left on device.*the 2 rows measured before are in that file"):
        run_study({"n": [1, 2, 3, 4]}, lambda n: {"twice": 2 * n}, scheduler="serial", progress=False,
                  rows_log=log)
    assert [r["twice"] for r in read_rows(log)] == [2, 4]


def test_an_unwritable_row_log_is_refused_before_any_work(tmp_path):
    measure, calls = _counting_measure()
    blocker = tmp_path / "a_file"
    blocker.write_text("")
    with pytest.raises(OSError):
        run_study({"kernel": ["a"], "spacing": [0.1]}, measure, scheduler="serial", progress=False,
                  rows_log=blocker / "rows.jsonl")
    assert calls == []
