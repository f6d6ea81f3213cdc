"""Pictures of runs: labelled frames (units, time, walls apart), the field table, the time-series
figure, ``mlsgalerkin render`` on a run directory and the gallery page.

The figures are checked as matplotlib objects (labels, titles, which collections are colour-mapped),
not as pixels.
"""

from __future__ import annotations

import importlib.util
import json
import re
import shutil
import sys
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest

from mlsgalerkin.cli import main
from mlsgalerkin.plots.fields import FIELDS, field_name_problem, resolve_field
from mlsgalerkin.plots.frames import WALL_COLOR, frame_figure, frame_view, time_text
from mlsgalerkin.plots.timeseries import timeseries_figure
from mlsgalerkin.monitors import Output, Pictures, RunInfo

Image = pytest.importorskip("PIL.Image")
ROOT = Path(__file__).resolve().parents[1]


def _tank(t: float = 0.1234, wide: bool = False):
    """A frame: a 6 x 4 block of fluid (two phases) in a U of wall particles."""
    dx = 0.01
    xs, ys = np.meshgrid(np.arange(6) * dx + dx / 2, np.arange(4) * dx + dx / 2)
    fluid = np.column_stack([xs.ravel(), ys.ravel()])
    if wide:
        fluid = fluid * np.array([20.0, 1.0])
    lo, hi = fluid.min(axis=0), fluid.max(axis=0)
    wall = np.vstack([np.column_stack([np.full(6, lo[0] - dx), np.linspace(lo[1], hi[1] + 2 * dx, 6)]),
                      np.column_stack([np.full(6, hi[0] + dx), np.linspace(lo[1], hi[1] + 2 * dx, 6)]),
                      np.column_stack([np.linspace(lo[0], hi[0], 8), np.full(8, lo[1] - dx)])])
    pts = np.vstack([fluid, wall])
    n_f, n = len(fluid), len(pts)
    p = np.concatenate([1000.0 * (hi[1] - fluid[:, 1]), np.full(len(wall), 9.9e9)])  # walls: absurd values
    data = {
        "pressure": p, "density": np.full(n, 1000.0), "density_ratio": np.full(n, 1.0),
        "speed": np.linspace(0.0, 1.0, n), "velocity": np.column_stack([np.linspace(-1, 1, n), np.zeros(n), np.zeros(n)]),
        "phase": np.concatenate([(np.arange(n_f) % 2), np.full(len(wall), -1)]).astype(np.int32),
        "is_wall": (np.arange(n) >= n_f).astype(np.int32),
        "mls_order": np.ones(n, dtype=np.int32),
    }
    return t, pts, data


@pytest.mark.parametrize("field, label", [
    ("pressure", "pressure (Pa)"), ("density", "density (kg/m³)"), ("density_ratio", "density ratio ρ/ρ0 (–)"),
    ("speed", "speed |v| (m/s)"), ("velocity", "velocity magnitude |v| (m/s)"),
    ("velocity_x", "horizontal velocity v_x (m/s)"),
])
def test_a_frame_has_axes_in_metres_the_time_in_seconds_and_a_colour_bar_with_the_unit(field, label):
    frame = _tank(t=0.1234)
    view = frame_view([frame], field, title="tank")
    fig = frame_figure(view, [frame])
    ax, cbar = fig.axes[0], fig.axes[1]
    assert (ax.get_xlabel(), ax.get_ylabel()) == ("x (m)", "y (m)")
    assert ax.get_title(loc="right") == "t = 0.1234 s"
    assert ax.get_title(loc="left") == "tank"
    assert cbar.get_ylabel() == label
    assert ax.get_aspect() == 1.0  # equal scales in x and y


def test_time_text_keeps_small_times_readable():
    assert time_text(0.0) == "t = 0.0000 s"
    assert time_text(2.5) == "t = 2.5000 s"
    assert time_text(5e-5) == "t = 5e-05 s"


def test_walls_are_grey_and_not_colour_mapped_and_do_not_set_the_colour_range():
    frame = _tank()
    data = frame[2]
    wall = data["is_wall"].astype(bool)
    view = frame_view([frame], "pressure")
    assert view.clim[1] < 1e6  # the walls' 9.9e9 Pa are not part of the colour range
    fig = frame_figure(view, [frame])
    collections = {c.get_label(): c for c in fig.axes[0].collections}
    walls, fluid = collections["wall particles"], collections["fluid particles"]
    assert walls.get_array() is None  # not colour-mapped
    np.testing.assert_allclose(walls.get_facecolor()[0][:3], [float(WALL_COLOR)] * 3)
    assert len(walls.get_offsets()) == wall.sum()
    np.testing.assert_allclose(fluid.get_array(), data["pressure"][~wall])
    assert walls.get_sizes()[0] < fluid.get_sizes()[0]  # smaller discs
    assert "wall particles" in [t.get_text() for t in fig.legends[0].get_texts()]


def test_a_categorical_field_gets_a_legend_of_its_categories_instead_of_a_colour_bar():
    frame = _tank()
    view = frame_view([frame], "phase")
    assert view.categories == (0, 1)  # the walls' -1 is not a category
    fig = frame_figure(view, [frame])
    assert len(fig.axes) == 1  # no colour bar
    texts = [t.get_text() for t in fig.legends[0].get_texts()]
    assert texts == ["phase 0", "phase 1", "wall particles"]
    assert fig.legends[0].get_title().get_text() == "phase"
    fluid = next(c for c in fig.axes[0].collections if c.get_label() == "fluid particles")
    assert len({tuple(c) for c in fluid.get_facecolor()}) == 2  # one colour per phase
    order = frame_view([frame], "mls_order")
    labels = [t.get_text() for t in frame_figure(order, [frame]).legends[0].get_texts()]
    assert labels[0] == "order 1 (linear)"


def test_a_flat_domain_gets_its_colour_bar_under_the_axes_and_a_panel_shares_one_colour_bar():
    frame = _tank(wide=True)
    view = frame_view([frame], "velocity_x")
    assert view.clim[0] == pytest.approx(-view.clim[1])  # centred on zero
    fig = frame_figure(view, [frame])
    cbar = fig.axes[1]
    assert cbar.get_xlabel() == "horizontal velocity v_x (m/s)"
    frames = [_tank(t=0.1 * k) for k in range(4)]
    panel = frame_figure(frame_view(frames, "pressure"), frames, columns=2, suptitle="tank: pressure (Pa)")
    assert len(panel.axes) == 5
    assert [ax.get_title(loc="right") for ax in panel.axes[:4]] == [time_text(0.1 * k) for k in range(4)]
    assert panel.axes[4].get_ylabel() == "pressure (Pa)"


def test_unknown_fields_are_refused_with_the_list_of_fields():
    with pytest.raises(ValueError, match=r"no field 'pressur'.*available: .*pressure.*velocity_x"):
        resolve_field(_tank()[2], "pressur")
    values, style = resolve_field(_tank()[2], "velocity_x")
    assert style is FIELDS["velocity_x"] and values.shape == (len(_tank()[1]),)
    assert field_name_problem("speed") is None
    problems = Output(color_by="pressur").problems()
    assert len(problems) == 1 and "output.color_by" in problems[0]
    assert "density_ratio" in problems[0] and "free_surface (with the FreeSurfaceDetection effect)" in problems[0]
    assert Output(color_by="velocity_y").problems() == []


def test_the_pictures_monitor_checks_its_field_against_the_frame_before_the_first_step(tmp_path, caplog):
    _, pts, data = _tank()
    fluid = SimpleNamespace(frame_name="particles", frame=lambda: (pts, data))
    state = SimpleNamespace(systems={"fluid": fluid})
    info = RunInfo(scene="tank", t_end=1.0, dim=2, out=tmp_path)
    Pictures(color_by="speed").start(state, info)
    assert caplog.records == []
    missing = Pictures(color_by="free_surface")
    with caplog.at_level("WARNING", logger="mlsgalerkin.monitors"):
        missing.start(state, info)  # the run is not lost: a warning, and no pictures
    assert "cannot be coloured by 'free_surface'" in caplog.text and "available: " in caplog.text
    assert "mlsgalerkin render" in caplog.text
    missing.finish(state, "completed")
    assert list(tmp_path.iterdir()) == []
    assert Pictures(color_by="nonsense").problems()


def test_the_time_series_figure_has_a_panel_per_group_with_units():
    n = 5
    t = np.linspace(0.0, 0.4, n)
    cols = {"time": t, "dt": np.full(n, 1e-4), "step": np.arange(n), "kinetic_energy": t**2,
            "potential_energy": 10.0 - t, "total_mass": np.full(n, 2.0), "momentum_x": t, "momentum_y": -t,
            "max_speed": t, "min_density_ratio": np.full(n, 0.99), "max_density_ratio": np.full(n, 1.01),
            "fallback_points": np.zeros(n, dtype=int), "front_x": 0.1 + t}
    fig = timeseries_figure(cols, title="demo", units={"front_x": "m"})
    labels = [ax.get_ylabel() for ax in fig.axes]
    assert labels == ["energy (J/m)", "(M − M0)/M0 (–)", "momentum (kg·m/s per m)", "speed (m/s)",
                      "ρ/ρ0 (–)", "dt (s)", "front_x (m)"]
    assert fig.axes[-1].get_xlabel() == "time t (s)"
    energy = fig.axes[0]
    np.testing.assert_allclose(energy.lines[1].get_ydata(), -t)  # potential energy: change since t = 0
    cols3 = dict(cols, momentum_z=t)
    assert timeseries_figure(cols3).axes[0].get_ylabel() == "energy (J)"
    with pytest.raises(ValueError, match="no rows"):
        timeseries_figure({"time": np.array([]), "dt": np.array([])})


# ------------------------------------------------------------------------------------------
# mlsgalerkin render on a run directory
# ------------------------------------------------------------------------------------------


@pytest.fixture(scope="module")
def run_dir(tmp_path_factory):
    """A tiny hydrostatic run (this checkout's problem file) with the run's own pictures."""
    import numba

    from mlsgalerkin.problem import run_problem

    out = tmp_path_factory.mktemp("run") / "hydrostatic"
    before = numba.get_num_threads()
    numba.set_num_threads(1)
    try:
        run_problem(ROOT / "problems" / "hydrostatic.py",
                    {"dx": 0.05, "t_end": 0.02, "frame_every": 0.01, "gif": True}, out=out, progress=False)
    finally:
        numba.set_num_threads(before)
    return out


def test_a_run_with_pictures_writes_them_with_the_new_renderer(run_dir):
    for name in ("final.png", "animation.gif"):
        assert (run_dir / name).stat().st_size > 1000
    with Image.open(run_dir / "animation.gif") as im:
        assert im.n_frames == 3  # t = 0, 0.01, 0.02


def test_render_draws_frames_animation_and_time_series_of_a_run(run_dir, tmp_path, capsys):
    out = tmp_path / "pictures"
    assert main(["render", str(run_dir), "--color-by", "density_ratio", "--out", str(out), "--snapshots", "2"]) == 0
    printed = capsys.readouterr().out
    assert "hydrostatic (completed): 3 frames" in printed
    for name in ("final.png", "frames.png", "animation.gif", "timeseries.png"):
        assert (out / name).is_file() and f"wrote {out / name}" in printed
    with Image.open(out / "animation.gif") as im:
        assert im.n_frames == 3
    with Image.open(out / "final.png") as im:
        assert im.format == "PNG" and np.asarray(im.convert("RGB")).std() > 0


def test_render_works_on_an_interrupted_run_without_summary(run_dir, tmp_path, capsys):
    partial = tmp_path / "partial"
    shutil.copytree(run_dir, partial)
    (partial / "summary.json").unlink()
    for name in ("final.png", "animation.gif"):
        (partial / name).unlink()
    assert main(["render", str(partial), "--no-gif", "--snapshots", "0"]) == 0
    printed = capsys.readouterr().out
    assert "partial (no summary.json: unfinished or interrupted): 3 frames" in printed
    assert (partial / "final.png").is_file() and not (partial / "animation.gif").exists()
    assert (partial / "timeseries.png").is_file()


def test_render_refuses_a_missing_directory_a_bad_field_and_a_directory_without_frames(run_dir, tmp_path, capsys):
    assert main(["render", str(tmp_path / "nowhere")]) == 2
    assert "does not exist" in capsys.readouterr().err
    assert main(["render", str(run_dir), "--color-by", "pressur", "--out", str(tmp_path / "x")]) == 2
    err = capsys.readouterr().err
    assert "cannot colour by 'pressur'" in err and "available:" in err and "density_ratio" in err
    assert not (tmp_path / "x").exists()  # refused before any work
    bare = tmp_path / "bare"
    bare.mkdir()
    shutil.copy(run_dir / "timeseries.csv", bare)
    assert main(["render", str(bare)]) == 2
    err = capsys.readouterr().err
    assert "has no frames to draw" in err and "--no-gif --no-png" in err
    assert main(["render", str(bare), "--no-gif", "--no-png"]) == 0
    assert (bare / "timeseries.png").is_file()


# ------------------------------------------------------------------------------------------
# the gallery page
# ------------------------------------------------------------------------------------------


def _gallery_module():
    spec = importlib.util.spec_from_file_location("make_gallery", ROOT / "docs" / "make_gallery.py")
    mod = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = mod  # dataclasses look their module up by name
    spec.loader.exec_module(mod)
    return mod


def test_the_gallery_page_shows_one_small_picture_per_shipped_problem():
    from mlsgalerkin.problem import shipped_problems

    gallery = _gallery_module()
    meta = json.loads(gallery.META.read_text(encoding="utf-8"))
    page = gallery.build_page(meta)
    assert page == (ROOT / "docs" / "gallery.md").read_text(encoding="utf-8"), \
        "docs/gallery.md is not the page of docs/gallery/gallery.json: run python docs/make_gallery.py --dry-run"
    assert sorted(e.problem for e in gallery.ENTRIES) == sorted(shipped_problems())
    for name in shipped_problems():
        assert page.count(f"](gallery/{name}.png)") == 1
        png = ROOT / "docs" / "gallery" / f"{name}.png"
        assert 0 < png.stat().st_size < 200_000
        assert f"mlsgalerkin run {name} " in page and f"mlsgalerkin render results/{name} " in page
    for style in {FIELDS[e.color_by] for e in gallery.ENTRIES}:
        assert f"**Colour:** {style.axis_label}" in page
    # the whole gallery or some pictures of it (``--only``) regenerated, with the command that did it
    assert re.search(r"Generated by `python docs/make_gallery\.py( --only [a-z_ ]+)?` at commit", page)
    assert "/work/" not in page and "/tmp/" not in page  # no machine paths
