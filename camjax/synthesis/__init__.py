"""Law synthesis: B-spline motion laws designed for an objective, their end conditions met exactly.

- :mod:`camjax.synthesis.basis`: the B-spline basis as matrices (values, derivative control values,
  exact Gram matrices by Gauss-Legendre quadrature per knot span);
- :mod:`camjax.synthesis.problem`: the conditions (null-space form) and the objective's terms;
- :mod:`camjax.synthesis.qp`: a dense interior-point QP solver (one ``lax.while_loop``, vmaps);
- :mod:`camjax.synthesis.solve`: one synthesis as a pure JAX function, batched with ``vmap``.
- :mod:`camjax.synthesis.vibration`: the follower train's residual vibration and contact force
  as exact linear maps of the control values (the terms ``residual_vibration``, ``peak_force``).

See docs/synthesis.md (law synthesis) and docs/codesign.md (co-design).
"""

from camjax.synthesis.basis import Basis, make_basis
from camjax.synthesis.problem import (
    L2_OBJECTIVES,
    OBJECTIVES,
    PEAK_OBJECTIVES,
    Condition,
    SynthesisProblem,
    build_problem,
    inconsistent_condition,
    kept_values,
)
from camjax.synthesis.qp import QPResult, solve_qp
from camjax.synthesis.solve import (
    Measures,
    SynthesisResult,
    batch_synthesizer,
    measures,
    synthesizer,
    weights_vector,
)

__all__ = [
    "L2_OBJECTIVES", "OBJECTIVES", "PEAK_OBJECTIVES", "Basis", "Condition", "Measures", "QPResult",
    "SynthesisProblem", "SynthesisResult", "batch_synthesizer", "build_problem", "inconsistent_condition",
    "kept_values", "make_basis", "measures", "solve_qp", "synthesizer", "weights_vector",
]
