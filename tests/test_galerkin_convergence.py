"""Galerkin convergence study: the quick run's claims, its files, and its building blocks.

The quick study (three levels, cubic spline; about 15-40 s with a warm numba cache) runs once
per module into a temporary directory, serially (the Dask path is tested in
``test_study_engine.py``); its report (``verification/galerkin_report``, imported from the
repository root) is written next to it. Measured on the reference machine (relative errors):
SCNI + Nitsche patch tests 5e-14 – 5e-13 (L2), DNI on perturbed nodes 1.3e-2 (elasticity) and
3.1e-2 (Poisson); Poisson MMS with SCNI and a linear basis: L2 order 2.21, H1 order 1.26.
"""

from __future__ import annotations

import csv
import math

import numpy as np
import pytest
from scipy.sparse.linalg import spsolve

from mlsgalerkin.analysis import ErrorNorms, rectangle_quadrature
from mlsgalerkin.analysis.convergence import observed_order
from mlsgalerkin.integration import boundary_basis, meshfree_basis
from mlsgalerkin.integration.vci import integration_constraint_residual, vci_test_basis
from mlsgalerkin.models import elasticity, nitsche, poisson
from mlsgalerkin.studies.galerkin import COLUMNS, run_galerkin_study
from mlsgalerkin.studies.galerkin.problems import (
    PROBLEMS,
    elastic_patch,
    get_problem,
    node_grid,
    poisson_mms,
    timoshenko,
)
from mlsgalerkin.studies.galerkin.runner import SolveSpec, measure, spectrum
from verification.galerkin_report import write_report
from verification.galerkin_report.summary import time_to_error

REQUIRED = ["problem", "rule", "basis", "kernel", "support_ratio", "spacing", "n_nodes",
            "error_l2", "error_h1", "wall_s", "wall_shape_s", "wall_assembly_s", "wall_solve_s",
            "bc", "nodes"]
NUMERIC = ["support_ratio", "spacing", "n_nodes", "error_l2", "error_h1", "error_energy",
           "wall_s", "wall_shape_s", "wall_assembly_s", "wall_solve_s"]


# ======================================================================================
# the quick study
# ======================================================================================


@pytest.fixture(scope="module")
def quick(tmp_path_factory):
    out = tmp_path_factory.mktemp("galerkin_quick")
    result = run_galerkin_study(out=out, quick=True, scheduler="serial", progress=False)
    write_report(result)
    with open(result.csv_path, newline="") as fh:
        rows = list(csv.DictReader(fh))
    return result, rows


def _patch(rows, rule, nodes, problem=None):
    return [r for r in rows if r["study"] == "patch" and r["rule"] == rule and r["nodes"] == nodes
            and r["bc"] == "nitsche" and (problem is None or r["problem"] == problem)]


def test_files_exist(quick):
    result, _ = quick
    names = {p.name for p in result.out.iterdir()}
    for name in ("galerkin_convergence.csv", "galerkin_orders.csv", "summary.md",
                 "provenance.json", "work_precision.png", "convergence_poisson_mms.png",
                 "convergence_timoshenko.png", "h_sweep_poisson_mms.png", "spectra.png"):
        assert name in names
        assert (result.out / name).stat().st_size > 0
    assert not [n for n in names if n.endswith(".tmp")]  # atomic writes leave nothing behind
    summary = (result.out / "summary.md").read_text()
    for heading in ("## Patch tests", "observed orders", "What accuracy costs",
                    "spurious zero-energy modes", "## Observations"):
        assert heading in summary
    assert "patch tests" in result.report()


def test_csv_columns_present_and_finite(quick):
    _, rows = quick
    assert rows
    assert set(REQUIRED) <= set(rows[0]) and list(rows[0]) == COLUMNS
    for r in rows:
        for c in NUMERIC:
            v = float(r[c])
            assert math.isfinite(v), (c, r)
        assert float(r["wall_s"]) == pytest.approx(
            float(r["wall_shape_s"]) + float(r["wall_assembly_s"]) + float(r["wall_solve_s"]),
            rel=1e-4, abs=1e-5)
        assert r["nodes"] in ("regular", "perturbed") and r["bc"] in ("nitsche", "penalty")
        assert r["worker"].startswith("serial@")  # who measured the wall times
    assert {r["study"] for r in rows} == {"patch", "convergence", "h_sweep"}


@pytest.mark.parametrize("nodes", ["regular", "perturbed"])
@pytest.mark.parametrize("rule", ["scni", "vci"])
def test_consistent_rules_pass_the_patch_tests(quick, rule, nodes):
    _, rows = quick
    rs = _patch(rows, rule, nodes)
    assert {r["problem"] for r in rs} == {"poisson_patch", "elastic_patch"}
    for r in rs:
        assert float(r["error_l2"]) < 1e-10, r  # measured 3e-14 - 5e-13
        assert float(r["error_energy"]) < 1e-10, r  # measured <= 7e-12


def test_dni_fails_the_patch_tests_on_perturbed_nodes(quick):
    _, rows = quick
    rs = _patch(rows, "dni", "perturbed")
    assert {r["problem"] for r in rs} == {"poisson_patch", "elastic_patch"}
    for r in rs:
        assert float(r["error_l2"]) > 1e-4, r  # measured 1.3e-2 (elasticity), 3.1e-2 (Poisson)


def test_scni_linear_mms_orders(quick):
    _, rows = quick
    rs = sorted((r for r in rows if r["study"] == "convergence" and r["problem"] == "poisson_mms"
                 and r["rule"] == "scni" and r["basis"] == "linear" and r["nodes"] == "regular"),
                key=lambda r: -float(r["spacing"]))
    assert len(rs) == 3
    h = [float(r["spacing"]) for r in rs]
    l2, _ = observed_order(h, [float(r["error_l2"]) for r in rs])
    h1, _ = observed_order(h, [float(r["error_h1"]) for r in rs])
    assert l2 > 1.7  # measured 2.21
    assert h1 > 0.8  # measured 1.26
    result, _ = quick
    o = [o for o in result.orders if (o["problem"], o["rule"], o["basis"], o["nodes"])
         == ("poisson_mms", "scni", "linear", "regular")]
    assert o and o[0]["order_l2"] == pytest.approx(l2, abs=1e-5)


def test_h_sweep_records_modes_and_gap(quick):
    _, rows = quick
    sw = [r for r in rows if r["study"] == "h_sweep"]
    assert sw
    for r in sw:
        n_rigid = 3 if r["problem"] == "timoshenko" else 1
        assert int(r["n_rigid"]) == n_rigid
        assert int(r["n_spurious_modes"]) == int(r["n_zero_modes"]) - n_rigid
        assert int(r["n_zero_modes"]) >= n_rigid  # the rigid modes are always found
        assert float(r["eig_below"]) < float(r["eig_tol"]) <= float(r["eig_above"])


# ======================================================================================
# building blocks
# ======================================================================================


def _fd_gradient(f, x, eps=1e-6):
    cols = []
    for d in range(2):
        e = np.zeros((2, 1))
        e[d] = eps
        cols.append((f(x + e) - f(x - e)) / (2 * eps))
    return np.stack(cols, axis=-2)  # [..., d, n]


@pytest.mark.parametrize("name", list(PROBLEMS))
def test_exact_gradients_match_finite_differences(name, rng):
    p = get_problem(name)
    x = np.asarray(p.lower)[:, None] + rng.random((2, 40)) * p.size[:, None]
    g = p.grad_exact(x)
    fd = _fd_gradient(p.exact, x, eps=1e-6 * float(p.size.max()))
    assert np.abs(fd - g).max() < 1e-6 * np.abs(g).max()


def test_poisson_mms_source_is_minus_laplacian(rng):
    p = poisson_mms()
    x = rng.random((2, 30))
    lap = sum(_fd_gradient(lambda y: p.grad_exact(y)[d], x, 1e-5)[d] for d in range(2))
    np.testing.assert_allclose(-lap, p.source(x), atol=1e-6)


def test_timoshenko_solution_is_the_classic_one(rng):
    p = timoshenko()
    L, D, P, inertia = (p.meta[k] for k in ("L", "D", "P", "I"))
    assert p.plane_stress and (L, D, p.E, p.nu, P) == (48.0, 12.0, 3e7, 0.3, 1000.0)
    x = np.asarray(p.lower)[:, None] + rng.random((2, 50)) * p.size[:, None]
    # plane-stress Hooke's law applied to the exact strains gives the exact stresses
    np.testing.assert_allclose(p.flux_exact(x), p.meta["stress"](x), rtol=1e-10,
                               atol=1e-10 * P / D)
    # equilibrium without body force
    div = sum(_fd_gradient(lambda y: p.meta["stress"](y)[:, d], x, 1e-4)[:, d] for d in range(2))
    assert np.abs(div).max() < 1e-6 * P / D
    # free top and bottom, the end shear integrates to P
    t, w = np.polynomial.legendre.leggauss(8)
    for y0, n in ((D / 2, (0.0, 1.0)), (-D / 2, (0.0, -1.0))):
        xs = np.stack([L / 2 * (t + 1), np.full(8, y0)])
        normals = np.repeat(np.array(n)[:, None], 8, axis=1)
        assert np.abs(p.boundary_flux(xs, normals)).max() < 1e-9
    ys = np.stack([np.full(8, L), D / 2 * t])
    traction = p.boundary_flux(ys, np.repeat(np.array([[1.0], [0.0]]), 8, axis=1))
    assert float(traction[1] @ w) * D / 2 == pytest.approx(P, rel=1e-12)
    # tip deflection P L³/(3EI) + (4 + 5ν) P D² L / (24 EI)
    EI = p.E * inertia
    tip = P * L**3 / (3 * EI) + (4 + 5 * p.nu) * P * D**2 * L / (24 * EI)
    assert p.exact(np.array([[L], [0.0]]))[1, 0] == pytest.approx(tip, rel=1e-12)


def test_perturbed_nodes_keep_the_boundary(rng):
    p = timoshenko()
    reg = node_grid(p, 2.0)
    per = node_grid(p, 2.0, "perturbed", rng)
    assert reg.shape == per.shape == (25 * 7, 2)
    lo, hi = np.asarray(p.lower), np.asarray(p.upper)
    on = (np.isclose(reg, lo) | np.isclose(reg, hi)).any(axis=1)
    np.testing.assert_array_equal(per[on], reg[on])
    assert 0 < np.abs(per[~on] - reg[~on]).max() <= 0.3 * 2.0
    with pytest.raises(ValueError, match="does not divide"):
        node_grid(p, 5.0)
    with pytest.raises(ValueError, match="rng"):
        node_grid(p, 2.0, "perturbed")


@pytest.mark.parametrize("correction", ["constant", "shape"])
def test_vci_restores_the_integration_constraint(correction):
    p = elastic_patch()
    nodes = node_grid(p, 1 / 8, "perturbed", np.random.default_rng(3))
    dni = meshfree_basis(nodes, 1.5 / 8, rule="dni", domain=p.domain)
    vci = vci_test_basis(dni, p.domain, correction=correction)
    assert integration_constraint_residual(dni, p.domain).max() > 1e-3
    assert integration_constraint_residual(vci, p.domain).max() < 1e-13
    np.testing.assert_array_equal(vci.table.values, dni.table.values)
    np.testing.assert_array_equal(vci.weights, dni.weights)
    K = poisson.laplace.assemble(dni, vci)  # Petrov-Galerkin: unsymmetric
    assert abs(K @ np.ones(dni.n_dofs)).max() < 1e-12 * abs(K).max()  # constants: zero energy
    assert abs(K - K.T).max() > 1e-6 * abs(K).max()


@pytest.mark.parametrize("correction", ["constant", "shape"])
def test_vci_passes_the_elastic_patch_test(correction):
    p = elastic_patch()
    lam, mu = p.lame
    nodes = node_grid(p, 1 / 8, "perturbed", np.random.default_rng(5))
    dni = meshfree_basis(nodes, 1.5 / 8, rule="dni", domain=p.domain, n_components=2)
    vci = vci_test_basis(dni, p.domain, correction=correction)
    K = elasticity.linear_elasticity(lam, mu).assemble(dni, vci)
    Kb, fb = nitsche(boundary_basis(dni, p.domain), p.exact, flux=elasticity.stress(lam, mu),
                     modulus=p.E)
    u = spsolve((K + Kb).tocsc(), fb)
    norms = ErrorNorms(dni, rectangle_quadrature((0, 0), (1, 1), 8, 4))
    assert norms.l2(u, p.exact, relative=True) < 1e-11  # measured ~1e-13
    # the same solve with DNI test functions fails
    u_dni = spsolve((elasticity.linear_elasticity(lam, mu).assemble(dni) + Kb).tocsc(), fb)
    assert norms.l2(u_dni, p.exact, relative=True) > 1e-3


def test_vci_rejects_bad_input():
    p = elastic_patch()
    nodes = node_grid(p, 1 / 4)
    dni = meshfree_basis(nodes, 1.5 / 4, rule="dni", domain=p.domain)
    with pytest.raises(ValueError, match="correction"):
        vci_test_basis(dni, p.domain, correction="linear")
    with pytest.raises(ValueError, match="MeshfreeBasis"):
        vci_test_basis(dni.table, p.domain)


def test_measure_splits_the_wall_time():
    row = measure(SolveSpec("poisson_patch", "scni", "linear", "cubic_spline", 3.0, 1 / 4),
                  min_time=0.0, max_repeats=1)
    assert row["error_l2"] < 1e-10 and row["n_nodes"] == 25 and row["dilation"] == 1.5
    parts = row["wall_shape_s"] + row["wall_assembly_s"] + row["wall_solve_s"]
    assert row["wall_s"] == pytest.approx(parts) and min(
        row["wall_shape_s"], row["wall_assembly_s"], row["wall_solve_s"]) > 0
    with pytest.raises(ValueError, match="unknown rule"):
        SolveSpec("poisson_patch", "gauss", "linear", "cubic_spline", 3.0, 0.25)


@pytest.mark.parametrize("problem, n_rigid", [("poisson_mms", 1), ("timoshenko", 3)])
def test_spectrum_finds_exactly_the_rigid_modes(problem, n_rigid):
    spacing = 1 / 6 if problem == "poisson_mms" else 4.0
    row, vals = spectrum(SolveSpec(problem, "scni", "linear", "cubic_spline", 3.0, spacing))
    assert row["n_rigid"] == n_rigid and row["n_zero_modes"] == n_rigid
    assert row["n_spurious_modes"] == 0 and row["eig_gap"] > 1e4
    assert np.all(np.diff(vals) >= 0) and vals[-1] == 1.0
    assert row["energy_ratio_max"] >= 1.0 - 1e-9  # SCNI never overestimates the energy
    assert 0 < row["nitsche_ci"] < 50  # β = 100 is coercive


def test_observed_order_and_time_to_error():
    p, last = observed_order([0.4, 0.2, 0.1], [1.6e-2, 4e-3, 1e-3])
    assert p == pytest.approx(2.0) and last == pytest.approx(2.0)
    assert math.isnan(observed_order([0.1], [1.0])[0])
    assert math.isnan(observed_order([0.2, 0.1], [1e-14, 1e-15])[0])  # round-off is not fitted
    rs = [{"wall_s": 1.0, "e": 1e-1}, {"wall_s": 10.0, "e": 1e-3}]
    assert time_to_error(rs, "e", 1e-2) == pytest.approx(math.sqrt(10.0))
    assert math.isnan(time_to_error(rs, "e", 1e-4))
    assert time_to_error(rs, "e", 1.0) == 1.0
