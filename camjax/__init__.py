"""camjax: disc cam design with JAX.

Importing camjax turns on JAX's 64-bit mode (``jax_enable_x64``): cam geometry near the
curvature limit needs it. Ask for float32 per call (``dtype=jnp.float32``) where speed matters
more than the last digits; the documentation's "Accuracy and limits" page says what that costs.

The package itself is light: importing it loads no JAX and no model, so a process that needs one
module (a figure worker, the command line before its first computation) imports that module
alone. The names below load on first use (``camjax.load_scene``, ``camjax.design_report``, ...).
"""

import importlib as _importlib
import os as _os
import sys as _sys

# 64-bit mode, whether JAX is imported before camjax or after it (JAX reads the variable once, at
# its import; a JAX already imported is switched directly).
_os.environ["JAX_ENABLE_X64"] = "1"
if "jax" in _sys.modules:
    _sys.modules["jax"].config.update("jax_enable_x64", True)

__version__ = "0.1.0"

# public name -> the module that defines it (loaded on first use)
_NAMES = {
    "Material": "camjax.contact", "hertz_line_stress": "camjax.contact",
    "SceneArrays": "camjax.evaluate", "scene_arrays": "camjax.evaluate",
    "Weights": "camjax.family",
    "LAWS": "camjax.laws", "FourierSeries": "camjax.laws", "Law": "camjax.laws",
    "LawValues": "camjax.laws", "fourier_law": "camjax.laws", "get_law": "camjax.laws",
    "polynomial_law": "camjax.laws", "stepped_law": "camjax.laws",
    "FollowerTrain": "camjax.loads", "Guide": "camjax.loads", "RockerTrain": "camjax.loads",
    "Report": "camjax.pipeline", "analyse": "camjax.pipeline", "design_report": "camjax.pipeline",
    "run_design": "camjax.pipeline",
    "Kinematics": "camjax.program", "MotionProgram": "camjax.program", "Segment": "camjax.program",
    "joints": "camjax.program",
    "Scene": "camjax.scene", "SceneError": "camjax.scene", "load_scene": "camjax.scene",
    "parse_scene": "camjax.scene",
    "problem_from_scene": "camjax.solvers.base",
}
# subpackages and modules reachable as attributes (camjax.laws, camjax.solvers, ...)
_MODULES = ("contact", "dynamics", "evaluate", "family", "followers", "laws", "loads", "numerics",
            "output", "pipeline", "program", "runtime", "solvers")

__all__ = sorted([*_NAMES, *_MODULES, "report"])


def __getattr__(name):
    if name in _NAMES:
        value = getattr(_importlib.import_module(_NAMES[name]), name)
    elif name in _MODULES:
        value = _importlib.import_module(f"camjax.{name}")
    elif name == "report":  # the result.json blocks every follower shares
        value = _importlib.import_module("camjax.output.report")
    else:
        raise AttributeError(f"module 'camjax' has no attribute {name!r}")
    globals()[name] = value
    return value


def __dir__():
    return sorted({*globals(), *__all__})
