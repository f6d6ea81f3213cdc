"""``docs/getting_started.md`` and the README describe what ``make demo`` does.

The command they show is the Makefile's demo recipe, and the numbers they quote for it
(particles, steps, head speed) are those of the committed fluid validation's run of the same
case (``verification/results/fluid_validation/results.json``, gravity current ``dx=0.004``).
"""

from __future__ import annotations

import json
import re
from pathlib import Path

from howto_pages import missing_links

ROOT = Path(__file__).resolve().parents[1]
PAGE = ROOT / "docs" / "getting_started.md"
README = ROOT / "README.md"


def _demo_recipe() -> list[str]:
    """The argument list of the ``demo`` target's command (after the interpreter)."""
    text = (ROOT / "Makefile").read_text(encoding="utf-8")
    recipe = re.search(r"^demo:.*\n\t(.+)$", text, flags=re.MULTILINE).group(1).split()
    assert recipe[0] == "$(PY)" and recipe[1:3] == ["-m", "mlsgalerkin.cli"]
    return recipe[3:]


def _demo_row() -> dict:
    rows = json.loads((ROOT / "verification" / "results" / "fluid_validation" / "results.json").read_text())
    return next(r for r in rows if r["problem"] == "gravity_current" and r["case"] == "dx=0.004")


def test_the_pages_show_the_makefiles_demo_command():
    args = " ".join(_demo_recipe())
    assert f".venv/bin/python -m mlsgalerkin.cli {args}" in PAGE.read_text(encoding="utf-8")
    assert f"`mlsgalerkin {args}`" in README.read_text(encoding="utf-8")


def test_the_demos_numbers_are_the_validation_runs():
    row = _demo_row()
    args = _demo_recipe()
    assert row["dx_m"] == float(args[args.index("--dx") + 1])
    speed = f"{row['results']['head_speed_m_s']:.4f} m/s"
    for page in (PAGE, README):
        text = page.read_text(encoding="utf-8")
        assert f"{row['particles']:,} particles" in text, page.name
        assert f"{row['fluid_particles']:,} fluid" in text, page.name
        assert speed in text, page.name
    text = PAGE.read_text(encoding="utf-8")
    assert f"{row['steps']:,} steps" in text
    assert f"{row['particles'] - row['fluid_particles']} wall" in text
    # the sample output block
    assert f"{row['particles']} particles ({row['fluid_particles']} fluid), {row['steps']} steps" in text


def test_links_resolve():
    assert not missing_links(PAGE), missing_links(PAGE)
    assert not missing_links(README), missing_links(README)


def _commands(page: Path) -> list[str]:
    """The ``mlsgalerkin ...`` lines of the page's bash blocks, comments dropped and optional
    ``[...]`` arguments spelled out."""
    out = []
    for block in re.findall(r"```bash\n(.*?)```", page.read_text(encoding="utf-8"), flags=re.DOTALL):
        for line in block.splitlines():
            line = line.split("#", 1)[0].strip()
            if line.startswith("mlsgalerkin "):
                out.append(re.sub(r"\[([^\]]+)\]", r"\1", line))
    return out


def test_every_command_shown_parses_and_names_real_problems_and_parameters():
    """Each ``mlsgalerkin`` command of the README and the getting-started page is accepted by
    the command line, and a ``run`` names a shipped problem (or a user's file) and parameters
    that problem has."""
    import shlex

    from mlsgalerkin.cli import _parse_sets, build_parser
    from mlsgalerkin.problem import load_problem, parse_overrides

    commands = _commands(README) + _commands(PAGE)
    assert len(commands) >= 8
    parser = build_parser()
    for command in commands:
        args = parser.parse_args(shlex.split(command)[1:])
        if args.command == "run" and not args.problem.endswith(".py"):
            mod = load_problem(ROOT / "problems" / f"{args.problem}.py")
            parse_overrides(mod.Parameters, _parse_sets(args.set or []))
        if args.command == "problems" and args.problem:
            load_problem(ROOT / "problems" / f"{args.problem}.py")
