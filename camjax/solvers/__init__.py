"""Solvers of the optimal-design problem (:mod:`camjax.problem`)."""
