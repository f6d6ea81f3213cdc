"""mlsgalerkin's import graph has no cycles, between modules or between top-level packages.

Every module is parsed with :mod:`ast`; every ``import mlsgalerkin...`` / ``from mlsgalerkin...
import ...``, module-level or inside a function, is an edge. Importing ``a.b.c`` runs the
``__init__`` of ``a.b`` first, so it is also an edge to ``a.b``. Imports under
``if TYPE_CHECKING:`` count too: a type-only circle is still a circle in the design (the two
modules cannot be read, tested or moved apart). The package graph merges every module
into its top-level node (``mlsgalerkin.integration``, ``mlsgalerkin.basis``, ...): a layer that
imports another layer must not be imported by it, not even lazily.
"""

from __future__ import annotations

import ast
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
PACKAGE = ROOT / "mlsgalerkin"
#: Folders installed under another name (pyproject's package-dir): the shipped problems.
MAPPED = {ROOT / "problems": "mlsgalerkin.problems"}


def module_names() -> dict[str, Path]:
    out = {}
    for path in sorted(PACKAGE.rglob("*.py")):
        parts = list(path.relative_to(PACKAGE.parent).with_suffix("").parts)
        if parts[-1] == "__init__":
            parts = parts[:-1]
        out[".".join(parts)] = path
    for folder, package in MAPPED.items():
        for path in sorted(folder.rglob("*.py")):
            parts = [package] + list(path.relative_to(folder).with_suffix("").parts)
            if parts[-1] == "__init__":
                parts = parts[:-1]
            out[".".join(parts)] = path
    return out


def import_edges(modules: dict[str, Path]) -> set[tuple[str, str]]:
    """``(importer, imported)`` pairs of modules of the package (packages count as modules).
    A moved name forwarded by :mod:`mlsgalerkin.deprecation` imports its new home by name when
    read, not by an import statement, so it is no edge."""

    def known_prefix(name: str) -> str | None:
        while name and name not in modules:
            name = name.rpartition(".")[0]
        return name or None

    edges = set()
    for name, path in modules.items():
        tree = ast.parse(path.read_text(encoding="utf-8"), str(path))
        package = name if path.name == "__init__.py" else name.rpartition(".")[0]
        for node in ast.walk(tree):
            if isinstance(node, ast.Import):
                targets = [a.name for a in node.names]
            elif isinstance(node, ast.ImportFrom):
                if node.level:
                    base = package.split(".")[: len(package.split(".")) - node.level + 1]
                    source = ".".join(base + ([node.module] if node.module else []))
                else:
                    source = node.module or ""
                targets = [source] + [f"{source}.{a.name}" for a in node.names]
            else:
                continue
            for target in targets:
                found = known_prefix(target) if target.startswith("mlsgalerkin") else None
                if found is None:
                    continue
                chain = found.split(".")
                for k in range(2, len(chain) + 1):  # a.b.c also runs a.b's __init__
                    imported = ".".join(chain[:k])
                    if imported != name and not name.startswith(imported + "."):
                        edges.add((name, imported))
    return edges


def cycles(edges: set[tuple[str, str]]) -> list[list[str]]:
    """Strongly connected components with more than one node (Tarjan)."""
    graph: dict[str, set[str]] = {}
    for a, b in edges:
        graph.setdefault(a, set()).add(b)
        graph.setdefault(b, set())
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on_stack: set[str] = set()
    found: list[list[str]] = []

    def visit(v: str) -> None:
        index[v] = low[v] = len(index)
        stack.append(v)
        on_stack.add(v)
        for w in sorted(graph[v]):
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on_stack:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            component = []
            while True:
                w = stack.pop()
                on_stack.discard(w)
                component.append(w)
                if w == v:
                    break
            if len(component) > 1:
                found.append(sorted(component))

    for v in sorted(graph):
        if v not in index:
            visit(v)
    return found


def top_level(name: str) -> str:
    return ".".join(name.split(".")[:2])


def test_the_checker_finds_a_cycle():
    assert cycles({("a", "b"), ("b", "c"), ("c", "a"), ("c", "d")}) == [["a", "b", "c"]]
    assert cycles({("a", "b"), ("b", "c")}) == []


def test_the_graph_sees_the_known_layers():
    edges = import_edges(module_names())
    assert ("mlsgalerkin.integration.boundary", "mlsgalerkin.basis") in edges
    assert ("mlsgalerkin.models.boundary_conditions", "mlsgalerkin.integration") in edges
    assert ("mlsgalerkin.forms", "mlsgalerkin.basis") in edges


def test_moved_names_are_forwarded_by_the_one_helper():
    """Every module that forwards moved names does it through :mod:`mlsgalerkin.deprecation` (one
    way to warn, cache and name the new import), not with a hand-written ``__getattr__``."""
    bad = []
    for name, path in module_names().items():
        text = path.read_text(encoding="utf-8")
        if name != "mlsgalerkin.deprecation" and "warnings.warn(" in text and "def __getattr__" in text:
            bad.append(name)
    assert not bad, f"modules forwarding moved names by hand: {bad}"

def test_no_import_cycle_between_modules():
    found = cycles(import_edges(module_names()))
    assert not found, f"import cycles between modules: {found}"


def test_no_import_cycle_between_top_level_packages():
    edges = {(top_level(a), top_level(b)) for a, b in import_edges(module_names())}
    found = cycles({(a, b) for a, b in edges if a != b})
    assert not found, f"import cycles between mlsgalerkin's top-level modules/packages: {found}"


def test_io_is_a_bottom_layer():
    """io/ (files, checkpoints, frames) imports nothing from the solvers, the run loop, the
    studies or the pictures: everything can write files, files depend on nothing above them."""
    forbidden = ("mlsgalerkin.fluid", "mlsgalerkin.simulation", "mlsgalerkin.studies", "mlsgalerkin.scene",
                 "mlsgalerkin.monitors", "mlsgalerkin.dynamics", "mlsgalerkin.problem", "mlsgalerkin.plots")
    bad = sorted((a, b) for a, b in import_edges(module_names())
                 if a.startswith("mlsgalerkin.io") and b.startswith(forbidden))
    assert not bad, f"io imports from higher layers: {bad}"


def test_pictures_sit_on_the_files_only():
    """plots/ (the pictures of a run) reads files through io and imports nothing from the solvers,
    the run loop or the studies: a run directory is drawn from its files alone."""
    allowed = ("mlsgalerkin.plots", "mlsgalerkin.io")
    bad = sorted((a, b) for a, b in import_edges(module_names())
                 if a.startswith("mlsgalerkin.plots") and not b.startswith(allowed) and b != "mlsgalerkin")
    assert not bad, f"plots imports beyond io: {bad}"
    assert any(a.startswith("mlsgalerkin.plots") and b.startswith("mlsgalerkin.io") for a, b in
               import_edges(module_names())), "the check sees plots' imports of io"


def test_shipped_problems_use_only_the_public_api():
    """A problem copied out of the package must run: no private names of mlsgalerkin imported."""
    bad = []
    for name, path in module_names().items():
        if not name.startswith("mlsgalerkin.problems"):
            continue
        tree = ast.parse(path.read_text(encoding="utf-8"))
        for node in ast.walk(tree):
            if isinstance(node, ast.ImportFrom) and (node.module or "").startswith("mlsgalerkin"):
                mods = node.module.split(".")
                names = [a.name for a in node.names]
                if any(m.startswith("_") for m in mods) or any(n.startswith("_") for n in names):
                    bad.append(f"{path.name}: from {node.module} import {', '.join(names)}")
                if node.module.startswith("mlsgalerkin.problems"):
                    bad.append(f"{path.name}: imports another shipped problem ({node.module})")
    assert not bad, bad


def test_the_run_loop_knows_no_physics():
    """simulation, scene, dynamics, monitors and the problem runner import nothing from fluid (or a
    structure package)."""
    layer = ("mlsgalerkin.simulation", "mlsgalerkin.scene", "mlsgalerkin.dynamics", "mlsgalerkin.monitors",
             "mlsgalerkin.motion", "mlsgalerkin.problem", "mlsgalerkin.limits")
    bad = sorted((a, b) for a, b in import_edges(module_names())
                 if (a in layer or a.startswith(tuple(m + "." for m in layer)))
                 and b.startswith(("mlsgalerkin.fluid", "mlsgalerkin.problems")))
    assert not bad, f"the run loop imports physics: {bad}"


def test_type_only_imports_are_edges(tmp_path):
    """An import under ``if TYPE_CHECKING:`` is an edge (the checker would otherwise miss a circle)."""
    pkg = tmp_path / "pkg"
    pkg.mkdir()
    (pkg / "a.py").write_text("from typing import TYPE_CHECKING\nif TYPE_CHECKING:\n    from mlsgalerkin.scene import Scene\n")
    edges = import_edges({"mlsgalerkin.x": pkg / "a.py", "mlsgalerkin.scene": pkg / "a.py"})
    assert ("mlsgalerkin.x", "mlsgalerkin.scene") in edges


def test_solvers_effects_and_interactions_know_no_scene():
    """No solver, effect or interaction module imports the run layer (``scene``, ``simulation``,
    ``monitors``), not even for a type: they get their bodies, their scheme and a
    :class:`~mlsgalerkin.dynamics.SceneView`."""
    below = ("mlsgalerkin.fluid", "mlsgalerkin.structure", "mlsgalerkin.contact", "mlsgalerkin.interactions",
             "mlsgalerkin.dynamics", "mlsgalerkin.run_state")
    run_layer = ("mlsgalerkin.scene", "mlsgalerkin.simulation", "mlsgalerkin.monitors", "mlsgalerkin.problem")
    bad = sorted((a, b) for a, b in import_edges(module_names())
                 if a.startswith(below) and b.startswith(run_layer))
    assert not bad, f"solver, effect or interaction modules import the run layer: {bad}"


ARCHITECTURE = ROOT / "docs" / "architecture.md"
#: Top-level modules outside the layer table: the package itself, its ``python -m`` entry, and
#: the deprecation helper below every layer (it imports nothing of the package).
OUTSIDE_THE_TABLE = {"mlsgalerkin", "mlsgalerkin.__main__", "mlsgalerkin.deprecation"}


def layer_table() -> dict[str, tuple[int, str]]:
    """Each top-level module named in the layer table of ``docs/architecture.md`` -> (row, layer),
    rows from the bottom layer up."""
    import re

    tops = {top_level(m) for m in module_names()}
    layers: dict[str, tuple[int, str]] = {}
    rows = 0
    for line in ARCHITECTURE.read_text(encoding="utf-8").splitlines():
        m = re.match(r"^\| ([a-z][a-z ]*) \| (.*?) \| (.*) \|$", line)
        if not m or m.group(1) == "layer":
            continue
        for name in re.findall(r"`([a-z_]+)/?`", m.group(2)):
            full = f"mlsgalerkin.{name}"
            if full in tops and full not in layers:
                layers[full] = (rows, m.group(1))
        rows += 1
    return layers


def test_the_layer_table_of_the_architecture_page_holds():
    """Every top-level module is in the table of ``docs/architecture.md``, and no import (type-only
    ones included) goes from a layer to one above it."""
    layers = layer_table()
    assert len({k for k, _ in layers.values()}) >= 8, "the architecture page lost its layer table"
    missing = sorted({top_level(m) for m in module_names()} - set(layers) - OUTSIDE_THE_TABLE)
    assert not missing, f"modules the layer table of docs/architecture.md does not name: {missing}"
    edges = {(top_level(a), top_level(b)) for a, b in import_edges(module_names())}
    upward = sorted(f"{a} ({layers[a][1]}) imports {b} ({layers[b][1]})" for a, b in edges
                    if a in layers and b in layers and layers[a][0] < layers[b][0])
    assert not upward, f"imports against the layer table: {upward}"


def test_the_deprecation_helper_imports_nothing_of_the_package():
    assert not [b for a, b in import_edges(module_names()) if a == "mlsgalerkin.deprecation"]
