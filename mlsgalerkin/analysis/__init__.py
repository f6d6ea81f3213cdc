"""Verification tools: error norms against closed-form solutions and convergence rates; signal
analysis of time series (:mod:`~mlsgalerkin.analysis.signals`); results a run did not measure
(:mod:`~mlsgalerkin.analysis.measured`); a channel flow's row-averaged velocity profile against an
exact one, split into a smooth part and a row-to-row alternation
(:mod:`~mlsgalerkin.analysis.channel`); regular waves from gauge records, split into incident and
reflected waves (:mod:`~mlsgalerkin.analysis.waves`)."""

from mlsgalerkin.analysis.channel import ChannelProfileErrors, channel_profile_errors, row_means, three_row_filter
from mlsgalerkin.analysis.convergence import (
    ROUNDOFF,
    ObservedOrder,
    PowerLawFit,
    fit_power_law,
    observed_order,
    observed_orders,
)
from mlsgalerkin.analysis.measured import not_measured, unexplained_values
from mlsgalerkin.analysis.norms import (
    ErrorNorms,
    Quadrature,
    energy_error,
    h1_seminorm_error,
    l2_error,
    rectangle_quadrature,
)
from mlsgalerkin.analysis.signals import (
    crossing_period,
    grid_average,
    half_height_window,
    running_mean,
    spectral_period,
    threshold_windows,
    upward_crossings,
)
from mlsgalerkin.analysis.waves import (
    IncidentReflected,
    complex_amplitude,
    gauge_positions,
    harmonic_fit,
    incident_reflected,
)

__all__ = [
    "ChannelProfileErrors",
    "channel_profile_errors",
    "row_means",
    "three_row_filter",
    "ROUNDOFF",
    "ObservedOrder",
    "PowerLawFit",
    "fit_power_law",
    "observed_order",
    "observed_orders",
    "ErrorNorms",
    "Quadrature",
    "energy_error",
    "h1_seminorm_error",
    "l2_error",
    "rectangle_quadrature",
    "not_measured",
    "unexplained_values",
    "crossing_period",
    "grid_average",
    "half_height_window",
    "running_mean",
    "spectral_period",
    "threshold_windows",
    "upward_crossings",
    "IncidentReflected",
    "complex_amplitude",
    "gauge_positions",
    "harmonic_fit",
    "incident_reflected",
]
