"""Co-design of a scene's designed laws and its cam's geometry (``camjax design`` on a scene with
[design] and ``design = true`` segments); see docs/synthesis.md.

- :mod:`camjax.codesign.problem`: F(z), the inner geometry optimum and its envelope gradient;
- :mod:`camjax.codesign.builtin`: the built-in laws of each joint class, each with its own geometry;
- :mod:`camjax.codesign.search`: the BFGS search and the scene with the chosen laws fixed;
- :mod:`camjax.codesign.spring`: the spring's rate and preload as variables, contact kept at an overspeed.
- :mod:`camjax.codesign.helical`: a helical compression spring sized for that spring (stress, surge).

The pipeline's layer: it runs the solvers and imports no output.
"""

from camjax.codesign.builtin import best_builtin_combination, builtin_candidates, builtin_kinematics
from camjax.codesign.problem import SUPPORTED, Codesign, CodesignError, Inner, multipliers
from camjax.codesign.search import Outcome, codesign_scene, fixed_scene

__all__ = ["SUPPORTED", "Codesign", "CodesignError", "Inner", "Outcome", "best_builtin_combination",
           "builtin_candidates", "builtin_kinematics", "codesign_scene", "fixed_scene", "multipliers"]
