"""Kernel accuracy study: its helpers, and the pass criteria of Xing's (2019) study in quick mode.

The measurements are the package's (:mod:`mlsgalerkin.studies.kernels`); the report (claims,
``summary.md``, figures) is ``verification/kernel_report``, imported from the repository root.
The quick study runs once per module, serially (the Dask path is tested in
``test_study_engine.py``), then its report is written.
"""

from __future__ import annotations

import csv
import json
import math

import numpy as np
import pytest

from mlsgalerkin.analysis.convergence import fit_power_law
from mlsgalerkin.cli import main as cli_main
from mlsgalerkin.kernels import SPH_STUDY_KERNELS, get_kernel
from mlsgalerkin.neighbors import brute_force_neighbors
from mlsgalerkin.studies import kernels as ks
from verification.kernel_report import kernel_diagnostics, write_report

# ----------------------------------------------------------------------------------------
# small helpers
# ----------------------------------------------------------------------------------------


def test_fit_power_law_recovers_a_known_slope(rng):
    h = np.geomspace(0.01, 0.3, 9)
    err = 0.7 * h**2.0 * (1.0 + 0.01 * rng.standard_normal(h.size))
    fit = fit_power_law(h, err)
    assert fit.exponent == pytest.approx(2.0, abs=0.02)
    assert fit.coefficient == pytest.approx(0.7, rel=0.05)
    assert fit.n_points == 9 and fit.r2 > 0.999


def test_fit_power_law_skips_round_off_and_reports_no_fit():
    n = np.array([10.0, 20.0, 40.0, 80.0, 160.0])
    err = np.array([1e-2, 2.5e-3, 6.25e-4, 1e-16, 0.0])  # last two at round-off
    fit = fit_power_law(n, err)
    assert fit.n_points == 3
    assert fit.exponent == pytest.approx(-2.0, abs=1e-9)
    none = fit_power_law(n, np.full(5, 1e-15))
    assert math.isnan(none.exponent) and not none.ok


def test_rms_error_absolute_relative_and_vector():
    exact = np.array([1.0, -1.0, 1.0, -1.0])
    approx = exact + np.array([0.1, -0.1, 0.1, -0.1])
    assert ks.rms_error(approx, exact) == pytest.approx((0.1, 0.1))
    mask = np.array([True, False, False, False])
    assert ks.rms_error(approx, exact, mask) == pytest.approx((0.1, 0.1))
    g = np.array([[3.0, 4.0], [0.0, 0.0]])
    assert ks.rms_error(g, np.zeros_like(g))[0] == pytest.approx(math.sqrt(25.0 / 2.0))


def test_midpoint_quadrature_has_exactly_n_points_in_the_support():
    for name in SPH_STUDY_KERNELS:
        k = get_kernel(name)
        for n in (2, 5, 20, 100):
            s, w = ks.quadrature_offsets(k, 0.1, n)
            assert s.size == n
            assert np.all(np.abs(s) < k.support * 0.1)
            assert np.allclose(s, -s[::-1], atol=1e-15)  # symmetric about the point
            assert np.diff(s) == pytest.approx(np.full(n - 1, 2 * k.support * 0.1 / n))


def test_integral_approximation_extends_outside_the_domain():
    # quadrature points left of x = 0 are used (F analytic), so x is reproduced at the boundary
    x = np.array([0.0, 1.0, 2.0])
    approx = ks.integral_approximation(lambda y: y, x, "quartic_spline", 0.1, 100)
    assert np.max(np.abs(approx - x)) < 1e-13


def test_neighbors_1d_matches_brute_force(rng):
    x = np.sort(rng.uniform(0.0, 2.0, 200))
    mine = ks.neighbors_1d(x, x, 0.07).sorted()
    ref = brute_force_neighbors(x[:, None], x[:, None], radius=0.07).sorted()
    assert np.array_equal(mine.indptr, ref.indptr)
    assert np.array_equal(mine.indices, ref.indices)


@pytest.mark.parametrize("kernel", SPH_STUDY_KERNELS)
def test_particle_sum_reproduces_linear_on_a_uniform_lattice(kernel):
    k = get_kernel(kernel)
    for n, h in ((100, 0.05), (61, 0.1), (121, 0.1)):  # 61, 121: neighbours exactly at κh
        x = np.linspace(0.0, 2.0, n)
        inner = ks.interior_mask(x, k.support * h, 0.0, 2.0)
        approx = ks.particle_approximation(lambda y: y, x, k, h)
        assert inner.any()
        assert np.max(np.abs(approx[inner] - x[inner])) < 1e-12


def test_super_gaussian_unity_defect_matches_the_closed_form():
    # ∫_{-2}^{2} (3/2 - q²) e^{-q²} dq / √π = erf(2) + 2 e^{-4} / √π
    d = kernel_diagnostics("super_gaussian")
    assert d["unity"] == pytest.approx(
        math.erf(2.0) + 2.0 * math.exp(-4.0) / math.sqrt(math.pi), rel=1e-10
    )


# ----------------------------------------------------------------------------------------
# the quick study
# ----------------------------------------------------------------------------------------


@pytest.fixture(scope="module")
def quick(tmp_path_factory):
    out = tmp_path_factory.mktemp("kernel_study")
    result = ks.run_kernel_study(out, quick=True, scheduler="serial", progress=False)
    write_report(result)
    with open(result.csv_path, newline="") as fh:
        rows = list(csv.DictReader(fh))
    with open(result.fits_path, newline="") as fh:
        fits = list(csv.DictReader(fh))
    return result, rows, fits


def _num(v: str) -> float:
    return float(v) if v != "" else math.nan


def _sel(rows, **kw):
    return [r for r in rows if all(r[k] == str(v) for k, v in kw.items())]


def test_files_exist_and_csv_has_the_columns(quick):
    result, rows, _ = quick
    out = result.out
    for name in (
        "kernel_study.csv",
        "kernel_study_fits.csv",
        "summary.md",
        "provenance.json",
        "sph_error_vs_h.png",
        "sph_error_vs_neighbors.png",
        "work_precision.png",
    ):
        assert (out / name).is_file() and (out / name).stat().st_size > 0, name
    assert not list(out.glob(".*.tmp")), "atomic writes left temporary files"
    assert list(rows[0].keys()) == ks.COLUMNS
    assert all(r["worker"].startswith("serial@") for r in rows)  # who measured the wall time
    assert {r["part"] for r in rows} >= {"sph"}
    assert {r["region"] for r in rows} == {"interior", "all"}
    for r in rows:
        assert math.isfinite(_num(r["error_abs"])) and math.isfinite(_num(r["error_rel"]))
        assert _num(r["wall_s"]) > 0 and _num(r["n_neighbors"]) >= 1


def test_provenance_and_report(quick):
    result, rows, _ = quick
    prov = json.loads(result.provenance_path.read_text())
    for key in (
        "command",
        "mlsgalerkin_version",
        "git_commit",
        "date_utc",
        "machine",
        "python",
        "numpy",
    ):
        assert prov[key], key
    assert prov["mode"] == "quick" and prov["n_rows"] == len(rows)
    assert prov["scheduler"] == result.study.scheduler and prov["workers"]
    summary = (result.out / "summary.md").read_text()
    assert "## Provenance" in summary and prov["git_commit"] in summary
    for claim in ("**(a)", "**(b)", "**(c)", "**(d)"):
        assert claim in summary
    text = result.report()
    assert str(result.csv_path) in text and "cubic_spline" in text


def test_cli_writes_the_tables_plot_and_key_numbers(tmp_path, capsys, quick):
    out = tmp_path / "cli"
    assert cli_main(["study", "kernels", "--quick", "--scheduler", "serial", "--no-progress",
                     "--out", str(out)]) == 0
    printed = capsys.readouterr().out
    assert "kernels above 5%: johnson_quadratic" in printed
    assert "verification/kernel_study.py" in printed  # where the full report comes from
    names = {p.name for p in out.iterdir()}
    assert names == {"kernel_study.csv", "kernel_study_fits.csv", "work_precision.png",
                     "provenance.json"}
    # the same numbers as the module's run (the CLI run is another process-level repetition)
    result = quick[0]
    fresh = (out / "kernel_study_fits.csv").read_text()
    assert fresh == result.fits_path.read_text()


@pytest.mark.parametrize("kernel", ["cubic_spline", "quartic_spline"])
@pytest.mark.parametrize("function", ["x^3", "exp(-x)", "sin(x)"])
def test_integral_approximation_is_second_order_in_h(quick, kernel, function):
    """Xing (2019), claim (a): slope β ≈ 2 (here within [1.6, 2.4]) with N_nb = 100, interior points."""
    _, rows, fits = quick
    series = _sel(
        rows,
        part="sph",
        approximation="integral",
        kernel=kernel,
        function=function,
        sweep="h",
        region="interior",
    )
    fit = fit_power_law([_num(r["h"]) for r in series], [_num(r["error_abs"]) for r in series])
    assert fit.n_points >= 5
    assert 1.6 <= fit.exponent <= 2.4
    recorded = _sel(
        fits,
        part="sph",
        approximation="integral",
        kernel=kernel,
        function=function,
        sweep="h",
        region="interior",
        quantity="error_abs",
    )
    assert _num(recorded[0]["exponent"]) == pytest.approx(fit.exponent, abs=1e-3)


def _five_neighbour_errors(rows, kernel):
    rs = _sel(
        rows,
        part="sph",
        approximation="integral",
        kernel=kernel,
        sweep="n_neighbors",
        region="interior",
    )
    rs = [r for r in rs if _num(r["n_neighbors"]) == 5 and _num(r["h"]) == 0.1]
    return {r["function"]: _num(r["error_rel"]) for r in rs}


@pytest.mark.parametrize("kernel", [k for k in SPH_STUDY_KERNELS if k != "johnson_quadratic"])
def test_five_neighbours_give_under_5_percent(quick, kernel):
    """Xing (2019), claim (b): < 5 % with 5 neighbours at h = 0.1 for F1-F4 (integral, interior)."""
    errs = _five_neighbour_errors(quick[1], kernel)
    assert set(errs) >= set(ks.CLAIM_FUNCTIONS)
    for f in ks.CLAIM_FUNCTIONS:
        assert errs[f] < 0.05, (kernel, f, errs[f])


def test_johnson_quadratic_misses_5_percent_because_of_its_cusp(quick):
    """The one measured exception to the 5 % claim, pinned to its cause.

    The Johnson kernel has a cusp at q = 0. With 5 midpoints one quadrature point sits on it and
    the discrete unity Σ W δx' is 1.08, so every function carries an 8 % error; for F1 = x the
    relative error *is* that defect, |Σ W δx' - 1|.
    """
    errs = _five_neighbour_errors(quick[1], "johnson_quadratic")
    _, w = ks.quadrature_offsets(get_kernel("johnson_quadratic"), 0.1, 5)
    assert w.sum() == pytest.approx(1.08, abs=1e-12)
    assert errs["x"] == pytest.approx(abs(w.sum() - 1.0), rel=1e-3)
    assert max(errs[f] for f in ks.CLAIM_FUNCTIONS) > 0.05


def test_particle_sum_reproduces_linear_in_the_interior(quick):
    """The Shepard-normalised particle sum reproduces F1 = x to round-off on a uniform lattice."""
    rs = _sel(quick[1], part="sph", approximation="particle", function="x", region="interior")
    assert len(rs) >= len(SPH_STUDY_KERNELS) * 10
    assert max(_num(r["error_abs"]) for r in rs) < 1e-12


def test_mls_linear_reproduces_linear_everywhere(quick):
    """MLS (and RKPM) with a linear basis reproduce F1 = x up to and including the boundary."""
    rows = quick[1]
    if not _sel(rows, part="mls1d"):
        pytest.fail("part 2 did not run: mlsgalerkin.shape_functions is unavailable")
    for method in ("mls_linear", "mls_quadratic", "rkpm_linear"):
        rs = _sel(rows, part="mls1d", approximation=method, function="x", region="all")
        assert rs and max(_num(r["error_abs"]) for r in rs) < 1e-12, method
    shepard = _sel(rows, part="mls1d", approximation="shepard", function="x", region="all")
    assert max(_num(r["error_abs"]) for r in shepard) > 1e-4  # zeroth order: it cannot


def test_2d_rows_have_gradient_errors_and_mls_beats_shepard(quick):
    rows = _sel(quick[1], part="mls2d", sweep="resolution", layout="jittered", region="interior")
    assert rows
    for r in rows:
        assert math.isfinite(_num(r["error_grad"])) and math.isfinite(_num(r["error_grad_rel"]))
    finest = max(_num(r["spacing"]) for r in rows), min(_num(r["spacing"]) for r in rows)
    at = {r["approximation"]: r for r in rows if _num(r["spacing"]) == finest[1]}
    assert _num(at["mls_quadratic"]["error_abs"]) < _num(at["mls_linear"]["error_abs"])
    assert _num(at["mls_linear"]["error_grad"]) < _num(at["shepard"]["error_grad"])
