"""Cost of the structures in a coupled run: the sub-cycles, the nonlinear internal force, and the
share of a coupled step spent in contact and in the structure.

1. **Sub-cycles of a linear elastic body.** ``k`` central-difference sub-steps of the clamped
   beam of ``beam_clamped`` (Q2, 1 × 38 elements) and of the plate of ``hydrostatic_plate``
   (Q2, 2 × 40): in one numba call (:func:`~mlsgalerkin.structure.explicit.subcycle_linear`)
   against a Python loop of scipy sparse products (the numpy reference), per sub-step.
2. **Total-Lagrangian internal force** of the rubber gate of ``elastic_gate`` (neo-Hookean, Q2,
   2 × 32): the numba kernel against scikit-fem's ``LinearForm`` assembly of ``P : ∇δu``.
3. **Coupled steps.** Each coupled problem run for a fixed number of steps: wall time per step,
   split into the fluid (its own stage timer), the structure (with its sub-steps) and the
   coupling (riding wall particles, penalty contact, the reaction), and the contact's time per
   step against the fluid's at the same particle count.

Timing as in the other benchmarks (``bench_neighbors.measure``: best of several calls). Nothing
is asserted.

Run::

    NUMBA_NUM_THREADS=1 .venv/bin/python benchmarks/bench_structure.py --out benchmarks/results/structure.md
"""

from __future__ import annotations

import argparse
import sys
import time
import warnings
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from bench_neighbors import measure, provenance_line


def subcycles(rows: list[str]) -> None:
    from mlsgalerkin.problem import load_problem
    from mlsgalerkin.structure.explicit import subcycle_linear, subcycle_linear_reference

    rows += ["", "## 1. Sub-cycles of a linear elastic body (one call of k sub-steps)", "",
             "| body | dofs | k | numba (µs/sub-step) | Python + scipy (µs/sub-step) | speed-up |", "|---|---|---|---|---|---|"]
    for name, body in (("beam_clamped beam", load_problem("beam_clamped")._beam(load_problem("beam_clamped").Parameters())),
                       ("hydrostatic_plate plate", load_problem("hydrostatic_plate")._plate(
                           load_problem("hydrostatic_plate").Parameters()))):
        K = body.stiffness.tocsr()
        K.sort_indices()
        n = body.n_dofs
        inv_m = 1.0 / body.lumped_mass
        fixed = np.zeros(n, dtype=bool)
        fixed[body.clamped_dofs] = True
        f = body.weight.copy()
        df = np.zeros(n)
        dt = 0.5 * body.stable_time_step()
        k = 20
        state = [np.zeros(n), np.zeros(n), np.zeros(n)]
        fast = measure(lambda: subcycle_linear(K, inv_m, fixed, f, df, *state, dt, k))[0]
        slow = measure(lambda: subcycle_linear_reference(K, inv_m, fixed, f, df, *state, dt, k))[0]
        rows.append(f"| {name} | {n} | {k} | {1e6 * fast / k:.1f} | {1e6 * slow / k:.1f} | {slow / fast:.1f}× |")


def nonlinear(rows: list[str]) -> None:
    from mlsgalerkin.problem import load_problem
    from mlsgalerkin.structure.hyperelastic import (
        QuadratureData,
        internal_force,
        internal_force_reference,
    )

    mod = load_problem("elastic_gate")
    gate = mod._gate(mod.Parameters())
    data = QuadratureData.from_basis(gate.basis)
    lam, mu = gate.material.lame()
    rng = np.random.default_rng(0)
    u = rng.normal(scale=1e-4, size=gate.n_dofs)
    fast = measure(lambda: internal_force(data, u, lam, mu, "neo_hookean"))[0]
    slow = measure(lambda: internal_force_reference(gate.basis, u, lam, mu, "neo_hookean"))[0]
    rows += ["", "## 2. Total-Lagrangian internal force (neo-Hookean, per call)", "",
             "| body | dofs | elements | numba (µs) | scikit-fem LinearForm (µs) | speed-up |",
             "|---|---|---|---|---|---|",
             f"| elastic_gate (2D Q2) | {gate.n_dofs} | {gate.mesh.t.shape[1]} | {1e6 * fast:.0f} | {1e6 * slow:.0f} | "
             f"{slow / fast:.0f}× |"]
    from skfem import Basis, MeshHex

    from mlsgalerkin.structure import ElasticBody, ElasticMaterial
    from mlsgalerkin.structure.hyperelastic import lame_for_dimension
    from mlsgalerkin.structure.steppers.central_difference import NONLINEAR_ORDER

    mesh = MeshHex.init_tensor(*(np.linspace(0.0, a, n + 1) for a, n in ((0.1, 4), (0.1, 4), (0.4, 16))))
    block = ElasticBody("block", mesh, ElasticMaterial(1e7, 0.3, 1000.0), "Hex2", model="neo_hookean")
    basis = Basis(mesh, block.basis.elem, intorder=NONLINEAR_ORDER)
    data = QuadratureData.from_basis(basis)
    lam, mu = lame_for_dimension(block.material, 3)
    u = rng.normal(scale=1e-4, size=block.n_dofs)
    fast = measure(lambda: internal_force(data, u, lam, mu, "neo_hookean"))[0]
    slow = measure(lambda: internal_force_reference(basis, u, lam, mu, "neo_hookean"))[0]
    rows.append(f"| 3D Hex2 block 4 × 4 × 16 | {block.n_dofs} | {mesh.t.shape[1]} | {1e6 * fast:.0f} | "
                f"{1e6 * slow:.0f} | {slow / fast:.0f}× |")


def coupled(rows: list[str], steps: int) -> None:
    from mlsgalerkin.problem import load_problem
    from mlsgalerkin.simulation import Simulation

    cases = [("hydrostatic_plate", {"dx": 0.025}), ("elastic_gate", {"dx": 0.002}), ("wedge_drop", {"dx": 0.01}),
             ("beam_clamped", {"dx": 0.004}), ("beam_on_spring", {"dx": 0.015})]
    rows += ["", f"## 3. Coupled steps ({steps} steps from the start)", "",
             "| problem | particles | structure | sub-steps per step | ms per step | fluid | structure | coupling: walls | "
             "contact | reaction | contact / fluid step |", "|---|---|---|---|---|---|---|---|---|---|---|"]
    for problem, overrides in cases:
        mod = load_problem(problem)
        p = mod.Parameters(**overrides)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            sim = Simulation(mod.make_scene(p))
            sim.start()
            for _ in range(10):          # warm-up (compilation)
                sim.step(sim.time_step())
            fluid = sim.solver("fluid")
            structure = sim.solver("structure")
            coupling = sim.scene.interactions[0]
            f0 = sum(fluid.timer.seconds.values())
            s0 = structure.summary()["time_s"]
            c0 = dict(coupling.seconds)
            t0 = time.perf_counter()
            for _ in range(steps):
                sim.step(sim.time_step())
            wall = time.perf_counter() - t0
        f = sum(fluid.timer.seconds.values()) - f0
        s = structure.summary()["time_s"] - s0
        c = {k: coupling.seconds[k] - c0[k] for k in c0}
        body = next(iter(structure.summary()["bodies"].values()))
        sub = body.get("substeps_per_step_mean") or body["substeps"] / max(body["outer_steps"], 1)
        kind = body["kind"] + (f" {body['integrator']}" if body["kind"] == "elastic" else "")
        share = lambda x: f"{100 * x / wall:.1f} %"
        rows.append(f"| {problem} | {fluid.state.n} | {kind} | {sub:.1f} | {1e3 * wall / steps:.2f} | {share(f)} | "
                    f"{share(s)} | {share(c['walls'])} | {share(c['contact'])} | {share(c['reaction'])} | "
                    f"{c['contact'] / max(f, 1e-12):.3f} |")


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", default=None, help="write the table here (markdown)")
    ap.add_argument("--steps", type=int, default=200)
    args = ap.parse_args(argv)
    rows = ["# Structures in a coupled run: what they cost", "",
            provenance_line("benchmarks/bench_structure.py", sys.argv[1:] if argv is None else argv)]
    subcycles(rows)
    nonlinear(rows)
    coupled(rows, args.steps)
    text = "\n".join(rows) + "\n"
    print(text)
    if args.out:
        from mlsgalerkin.io import atomic_write

        atomic_write(Path(args.out), text)
    return 0


if __name__ == "__main__":
    sys.exit(main())
