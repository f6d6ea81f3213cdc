"""Verification: the shipped studies' reports and the physical validations.

Each study is driven by a script here (``kernel_study.py``, ``galerkin_convergence.py``,
``fluid_validation.py``); the report code of the two shipped studies (claims, observations,
``summary.md`` prose, the study's figures) lives in the packages ``kernel_report`` and
``galerkin_report``, their measurements in :mod:`mlsgalerkin.studies`. This directory is a
package so that ``tests/`` can import the report code (``pythonpath = ["."]`` in
``pyproject.toml``); the scripts put the repository root on ``sys.path`` themselves.
"""
