"""Every parameter of every shipped problem says what it means and in which unit, and
``mlsgalerkin problems [NAME]`` prints them.

The shipped problems are read from the repository's ``problems/`` folder by path (the files a
user copies), so the checks hold for the files in this tree whichever copy is installed.
"""

from __future__ import annotations

import dataclasses
import textwrap
from pathlib import Path

import pytest

from mlsgalerkin.cli import main
from mlsgalerkin.problem import (
    ParameterHelp,
    ProblemError,
    load_problem,
    parameter_help,
    parameter_table,
    problem_description,
    shipped_problems,
    split_unit,
)

ROOT = Path(__file__).resolve().parents[1]
PROBLEM_FILES = sorted(p for p in (ROOT / "problems").glob("*.py") if not p.name.startswith("_"))

#: The units the shipped problems use: SI, "–" for a dimensionless number, "bool" for a
#: switch, "choice" for one of the named options the meaning lists.
UNITS = {"deg", "Pa", "N m/rad", "kg", "kg/m", "m", "s", "m/s", "m/s²", "kg/m³", "Pa s", "–", "bool", "choice"}


def test_the_repository_ships_the_listed_problems():
    assert [p.stem for p in PROBLEM_FILES] == list(shipped_problems())


@pytest.mark.parametrize("path", PROBLEM_FILES, ids=lambda p: p.stem)
def test_every_shipped_parameter_has_a_meaning_and_a_unit(path):
    mod = load_problem(path)
    helps = parameter_help(mod.Parameters)
    assert [h.name for h in helps] == [f.name for f in dataclasses.fields(mod.Parameters)]
    for h in helps:
        assert h.meaning, f"{path.name}: parameter {h.name} has no `#: meaning (unit)` comment"
        assert h.unit in UNITS, f"{path.name}: parameter {h.name} has unit {h.unit!r}, not one of {UNITS}"
        assert h.default == getattr(mod.Parameters(), h.name)
        if isinstance(h.default, bool):
            assert h.unit == "bool", h.name
        elif isinstance(h.default, str):
            assert h.unit == "choice" and h.default in h.meaning, h.name
        else:
            assert h.unit not in ("bool", "choice"), h.name


def _write(tmp_path: Path, code: str) -> Path:
    path = tmp_path / "my_case.py"
    path.write_text(textwrap.dedent(code), encoding="utf-8")
    return path


def test_comment_forms_defaults_and_inheritance(tmp_path):
    """A trailing comment, ``#:`` lines above the field, none at all, a value over two lines,
    a parenthesised expression before the unit, and a field inherited from a base class."""
    path = _write(tmp_path, '''
        """Test case."""
        from dataclasses import dataclass, field

        @dataclass(frozen=True)
        class Base:
            g: float = 9.81   #: gravitational acceleration (m/s²)

        @dataclass(frozen=True)
        class Parameters(Base):
            c0_factor: float = 10.0   #: sound speed / sqrt(2 g H) (–)
            #: a meaning too long for one line,
            #: continued on a second (m)
            depth: float = 0.4
            plain: int = 3            # an ordinary comment is not help
            nothing: bool = False
            shape: tuple = field(
                default=(1.0, 2.0))   #: box size (m)

        def make_scene(p):
            raise NotImplementedError
        ''')
    helps = {h.name: h for h in parameter_help(load_problem(path).Parameters)}
    assert list(helps) == ["g", "c0_factor", "depth", "plain", "nothing", "shape"]
    assert helps["g"] == ParameterHelp("g", 9.81, "m/s²", "gravitational acceleration")
    assert helps["c0_factor"] == ParameterHelp("c0_factor", 10.0, "–", "sound speed / sqrt(2 g H)")
    assert helps["depth"].meaning == "a meaning too long for one line, continued on a second"
    assert helps["depth"].unit == "m"
    assert helps["plain"] == ParameterHelp("plain", 3, "", "")
    assert helps["nothing"] == ParameterHelp("nothing", False, "", "")
    assert helps["shape"] == ParameterHelp("shape", (1.0, 2.0), "m", "box size")


def test_split_unit_rules():
    assert split_unit("  water   depth H (m)  ") == ("water depth H", "m")
    assert split_unit("Monaghan viscosity α; 0.1 let a mode grow (–)") == ("Monaghan viscosity α; 0.1 let a mode grow", "–")
    # a group that does not close the comment, or is a phrase, is not a unit
    assert split_unit("a (m); the column is a wide") == ("a (m); the column is a wide", "")
    assert split_unit("viscosity (0.02 let a lattice mode grow)") == ("viscosity (0.02 let a lattice mode grow)", "")
    assert split_unit("") == ("", "")


def test_classes_without_source_and_non_dataclasses():
    made = dataclasses.make_dataclass("Made", [("dx", float, dataclasses.field(default=0.1))])
    assert parameter_help(made) == [ParameterHelp("dx", 0.1, "", "")]
    assert "?" in parameter_table(made).splitlines()[-1]
    with pytest.raises(ProblemError, match="needs a dataclass"):
        parameter_help(dict)


def test_problem_description_is_plain_text(tmp_path):
    path = _write(tmp_path, '''
        """A :class:`~mlsgalerkin.fluid.WallBody` moving with ``X(t)``
        over two lines.

        Second paragraph.
        """
        from dataclasses import dataclass

        @dataclass
        class Parameters:
            dx: float = 0.01  #: particle spacing (m)

        def make_scene(p):
            raise NotImplementedError
        ''')
    assert problem_description(load_problem(path)) == "A WallBody moving with X(t) over two lines."


# ------------------------------------------------------------------ the command line
def _table_rows(out: str) -> dict[str, tuple[str, str, str, str]]:
    """Parameter name -> (name, default, unit, meaning) of the table in ``out``, cut at the
    columns of its header line; wrapped meanings are joined."""
    lines = out.splitlines()
    head = next(line for line in lines if line.split()[:1] == ["parameter"])
    cols = [head.index(w) for w in ("parameter", "default", "unit", "meaning")]
    rows: dict[str, tuple[str, str, str, str]] = {}
    last = None
    for line in lines[lines.index(head) + 2:]:
        if not line.startswith(" " * cols[0]) or not line.strip():
            break
        cells = [line[a:b].strip() for a, b in zip(cols, cols[1:] + [None])]
        if cells[0]:
            last = cells[0]
            rows[last] = tuple(cells)
        else:  # a wrapped meaning
            rows[last] = rows[last][:3] + (rows[last][3] + " " + cells[3],)
    return rows


@pytest.mark.parametrize("path", PROBLEM_FILES, ids=lambda p: p.stem)
def test_cli_shows_one_problem_with_units_and_meanings(path, capsys):
    assert main(["problems", str(path)]) == 0
    out = capsys.readouterr().out
    mod = load_problem(path)
    assert out.startswith(f"{path}: {problem_description(mod)[:40]}")
    rows = _table_rows(out)
    helps = parameter_help(mod.Parameters)
    assert list(rows) == [h.name for h in helps]
    for h in helps:
        _, default, unit, meaning = rows[h.name]
        assert (unit, meaning) == (h.unit, h.meaning)
        if isinstance(h.default, float):
            assert float(default) == pytest.approx(h.default, rel=1e-5)
        else:
            assert default == str(h.default)
    assert f"\nfile: {path}\n" in out
    assert f"mlsgalerkin run {path} --set PARAMETER=VALUE" in out


def test_cli_shows_one_problem_with_what_its_numbers_were_measured_in(capsys):
    """``mlsgalerkin problems NAME`` prints the docstring after its first paragraph below the table:
    the reference and the configuration the problem's numbers were measured in."""
    assert main(["problems", "beam_clamped"]) == 0
    out = capsys.readouterr().out
    table_end = out.index("render animation.gif")
    assert out.index("Reference: Sun (2016)") > table_end
    assert "Measured at the defaults" in out and "StructureCoupling" in out and ":class:" not in out
    assert out.index("Measured at the defaults") < out.index("\nfile: ")


def test_cli_output_does_not_depend_on_where_the_problem_file_lives(tmp_path, capsys):
    """The same problem file, copied into a short path and into a long one with spaces, prints the
    same description and table: only the path itself differs."""
    import shutil

    src = ROOT / "problems" / "dam_break.py"
    short = tmp_path / "d.py"
    deep = tmp_path.joinpath("a folder with spaces", "x" * 60, "and another level of nesting", "dam_break.py")
    assert len(str(deep)) > 120 and " " in str(deep)
    deep.parent.mkdir(parents=True)
    shutil.copyfile(src, short)
    shutil.copyfile(src, deep)
    texts = {}
    for path in (short, deep):
        assert main(["problems", str(path)]) == 0
        out = capsys.readouterr().out
        assert out.startswith(f"{path}: {problem_description(load_problem(path))[:40]}")
        assert f"\nfile: {path}\n" in out
        texts[path] = out.replace(str(path), "PATH")
    assert texts[short] == texts[deep]
    rows = _table_rows(out)
    assert list(rows) == [h.name for h in parameter_help(load_problem(deep).Parameters)]


def test_cli_lists_every_problem_with_its_table(capsys):
    assert main(["problems"]) == 0
    out = capsys.readouterr().out
    for name in shipped_problems():
        mod = load_problem(name)
        assert f"\n{name}: " in "\n" + out
        for h in parameter_help(mod.Parameters):
            assert f" {h.name} " in out
    assert out.count("parameter  ") == len(shipped_problems())
    assert "mlsgalerkin problems NAME" in out and "my_case.py" in out


def test_cli_shows_a_shipped_problem_by_name(capsys):
    name = shipped_problems()[0]
    assert main(["problems", name]) == 0
    out = capsys.readouterr().out
    assert out.startswith(f"{name}: ") and "(copy it to start your own case)" in out
    assert f"mlsgalerkin run {name} --set PARAMETER=VALUE" in out


def test_cli_unknown_problem(capsys):
    assert main(["problems", "no_such_problem"]) == 2
    assert "unknown problem 'no_such_problem'" in capsys.readouterr().err
