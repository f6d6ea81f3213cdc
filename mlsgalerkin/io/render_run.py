"""Moved to :mod:`mlsgalerkin.plots.run`; this alias warns and is removed in the next release."""

from mlsgalerkin.deprecation import moved_module

__getattr__, __dir__ = moved_module(__name__, "mlsgalerkin.plots.run")
