"""Co-design of a scene's designed laws and its cam's geometry (``camjax design`` and ``camjax sweep``
on a scene with [design] and ``design = true`` segments); see docs/codesign.md.

- :mod:`camjax.codesign.problem`: F(z), the inner geometry optimum and its envelope gradient;
- :mod:`camjax.codesign.joint`: the laws and the geometry as one program (where no spring is designed);
- :mod:`camjax.codesign.builtin`: the built-in laws of each joint class, each with its own geometry;
- :mod:`camjax.codesign.search`: the BFGS search and the scene with the chosen laws fixed;
- :mod:`camjax.codesign.spring`: the spring's rate and preload as variables, contact kept at an overspeed;
- :mod:`camjax.codesign.sweep`: ``camjax sweep`` of such a scene, the laws co-designed at every weighting;
- :mod:`camjax.codesign.helical`: a helical compression spring sized for that spring (stress, surge).

The pipeline's layer: it runs the solvers and imports no output.
"""

from camjax.codesign.builtin import best_builtin_combination, builtin_candidates, builtin_kinematics
from camjax.codesign.kkt import multipliers
from camjax.codesign.problem import SUPPORTED, Codesign, CodesignError, Inner
from camjax.codesign.search import Outcome, codesign_outcome, codesign_scene, fixed_scene
from camjax.codesign.sweep import codesign_sweep

__all__ = ["SUPPORTED", "Codesign", "CodesignError", "Inner", "Outcome", "best_builtin_combination",
           "builtin_candidates", "builtin_kinematics", "codesign_outcome", "codesign_scene", "codesign_sweep",
           "fixed_scene", "multipliers"]
