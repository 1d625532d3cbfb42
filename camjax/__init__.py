"""camjax: disc cam design with JAX.

Importing camjax turns on JAX's 64-bit mode (``jax_enable_x64``): cam geometry near the
curvature limit needs it. Ask for float32 per call (``dtype=jnp.float32``) where speed matters
more than the last digits; the documentation's "Accuracy and limits" page says what that costs.
"""

import os as _os
import sys as _sys

if _os.path.basename(_sys.argv[0]) == "camjax" or "camjax.cli" in _sys.orig_argv[1:3]:
    # the command line is starting: an interrupt during the imports below is one line, not a traceback
    from camjax.runtime import quiet_startup_interrupts

    quiet_startup_interrupts()

import jax  # noqa: E402

jax.config.update("jax_enable_x64", True)

from camjax import (  # noqa: E402
    contact,
    evaluate,
    family,
    followers,
    laws,
    loads,
    numerics,
    output,
    pipeline,
    program,
    runtime,
)
from camjax.contact import Material, hertz_line_stress  # noqa: E402
from camjax.evaluate import SceneArrays, scene_arrays  # noqa: E402
from camjax.family import Weights  # noqa: E402
from camjax.laws import (  # noqa: E402
    LAWS,
    FourierSeries,
    Law,
    LawValues,
    fourier_law,
    get_law,
    polynomial_law,
    stepped_law,
)
from camjax.loads import FollowerTrain, Guide, RockerTrain  # noqa: E402
from camjax.output import report  # noqa: E402
from camjax.output.report import Report, analyse, design_report  # noqa: E402
from camjax.pipeline import run_design  # noqa: E402
from camjax.program import Kinematics, MotionProgram, Segment, joints  # noqa: E402
from camjax.scene import Scene, SceneError, load_scene, parse_scene  # noqa: E402

__version__ = "0.1.0"

__all__ = [
    "LAWS", "FollowerTrain", "FourierSeries", "Guide", "Kinematics", "Law", "LawValues",
    "Material", "MotionProgram", "Scene", "SceneArrays", "SceneError", "Segment", "contact",
    "fourier_law", "get_law", "hertz_line_stress", "joints", "laws", "load_scene",
    "loads", "numerics", "parse_scene", "polynomial_law", "program", "scene_arrays",
    "stepped_law", "design_report", "report", "Report", "analyse", "run_design", "evaluate", "output",
    "pipeline", "runtime", "Weights", "family", "followers", "problem_from_scene", "solvers", "RockerTrain",
]


def __getattr__(name):
    # camjax.dynamics loads lazily: a scene without [dynamics] never imports its models (or optax)
    if name in ("dynamics", "solvers"):  # solvers: optax loads only when a solver is used
        import importlib

        return importlib.import_module(f"camjax.{name}")
    if name == "problem_from_scene":  # the design problem of any follower type (camjax.solvers.base)
        from camjax.solvers.base import problem_from_scene

        return problem_from_scene
    raise AttributeError(f"module 'camjax' has no attribute {name!r}")
