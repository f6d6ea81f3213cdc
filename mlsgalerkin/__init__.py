"""mlsgalerkin."""
__version__ = "0.1.0"
