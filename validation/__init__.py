"""Validation of camjax beyond the unit tests, run from a source checkout (not installed).

``validation.extremes`` is the numerical-stability matrix that ``camjax check-extremes`` runs and
``tests/test_extremes.py`` asserts.
"""
