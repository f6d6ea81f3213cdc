"""The pictures moved from mlsgalerkin.io to mlsgalerkin.plots: the old import paths keep working
for a release with a DeprecationWarning naming the new one; the removed renderer says what to use."""

import importlib
import sys

import pytest

import mlsgalerkin.io as mio
import mlsgalerkin.plots as plots

OLD_MODULES = {"render_fields": "fields", "render_frames": "frames", "render_timeseries": "timeseries",
               "render_run": "run"}


@pytest.mark.parametrize("old, new", OLD_MODULES.items())
def test_old_module_paths_warn_and_forward(old, new):
    sys.modules.pop(f"mlsgalerkin.io.{old}", None)
    with pytest.warns(DeprecationWarning, match=f"mlsgalerkin.plots.{new}"):
        module = importlib.import_module(f"mlsgalerkin.io.{old}")
    target = importlib.import_module(f"mlsgalerkin.plots.{new}")
    for name in target.__all__:
        assert getattr(module, name) is getattr(target, name)


@pytest.mark.parametrize("name", ["FieldStyle", "register_field", "RenderError", "render_frame", "render_run",
                                  "render_timeseries"])
def test_old_package_names_warn_and_forward(name):
    # a test above imported the old module of the same name, which binds it on the package, or read
    # the old name, which keeps it there (each old name warns once per process)
    vars(mio).pop(name, None)
    with pytest.warns(DeprecationWarning, match=f"write 'from mlsgalerkin.plots import {name}'"):
        value = getattr(mio, name)
    assert value is getattr(plots, name)


def test_removed_renderer_names_say_what_to_use():
    with pytest.raises(AttributeError, match="render_run"):
        mio.render_snapshot  # noqa: B018
    with pytest.raises(AttributeError, match="no attribute 'nothing'"):
        mio.nothing  # noqa: B018
