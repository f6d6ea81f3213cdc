"""Moved to :mod:`mlsgalerkin.plots.timeseries`; this alias warns and is removed in the next release."""

import importlib
import warnings

warnings.warn("mlsgalerkin.io.render_timeseries moved to mlsgalerkin.plots.timeseries; import it from there",
              DeprecationWarning, stacklevel=2)
# imported by name at run time: io is the layer below the pictures and has no import edge to them
_new = importlib.import_module("mlsgalerkin.plots.timeseries")


def __getattr__(name: str):
    return getattr(_new, name)


def __dir__() -> list[str]:
    return dir(_new)
