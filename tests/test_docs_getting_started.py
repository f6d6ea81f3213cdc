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
    recipe = re.search(r"^demo:.*\n\t(.+)$", text, flags=re.M).group(1).split()
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
