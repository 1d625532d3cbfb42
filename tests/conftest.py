"""Tests run in float64 (camjax turns x64 on at import; asserted here).

Shared fixtures: the default scene, its arrays, and the reference case in NumPy (tests/reference.py).
"""

import gc
import os

# XLA compiles are most of the suite's time: compile as the command line does
# (camjax.runtime.CPU_XLA_FLAGS: XLA's loop emitters, not its CPU fusion emitters; the default
# scene's design compiles in 13 s instead of 19 s on 2 cores). Set before JAX starts its backend,
# so the tests' subprocesses (the CLI, process pools) inherit it; CAMJAX_XLA_FLAGS=0 runs with
# XLA's defaults. (LLVM's -O0, --xla_backend_optimization_level=0, would halve the compiles again
# but turns finite gradients of the oscillating flat face into NaN in this jaxlib: not used.)
from camjax.runtime import use_cpu_xla_flags  # noqa: E402  (loads no JAX)

use_cpu_xla_flags()

import jax  # noqa: E402
import pytest  # noqa: E402
from reference import reference_case  # noqa: E402

import camjax  # noqa: F401, E402  (enables x64)
from camjax.runtime import use_compilation_cache  # noqa: E402


def pytest_configure(config):
    assert jax.config.jax_enable_x64, "camjax tests run in float64"
    _persistent_compilation_cache(config)


def _persistent_compilation_cache(config) -> None:
    """Keep compiled kernels between test runs, in .pytest_cache/d/jax-compilation.

    XLA compiles are most of the suite's time; with them cached, a repeated quick loop
    (``-m "not slow"``) runs far faster. Turned on here, before any test, so a session does not
    depend on which CLI test first turns on the command's own cache. CAMJAX_COMPILATION_CACHE=0 (or
    ``-p no:cacheprovider``) runs without it, and then no CLI test turns one on either.
    """
    # The CLI tests trace as the library does: a saved program (camjax.runtime.program_cache)
    # compiles a module of its own, which would add a compile per scene shape to a fresh run;
    # tests/test_runtime.py and the CLI tests marked for it turn the program cache on themselves.
    os.environ.setdefault("CAMJAX_PROGRAM_CACHE", "0")
    cache = getattr(config, "cache", None)
    if os.environ.get("CAMJAX_COMPILATION_CACHE") == "0" or cache is None:
        os.environ["CAMJAX_COMPILATION_CACHE"] = "0"
        return
    if not jax.config.jax_compilation_cache_dir:  # one set through JAX itself wins
        use_compilation_cache(cache.mkdir("jax-compilation"))


@pytest.fixture(scope="session")
def default_scene():
    return camjax.load_scene()


@pytest.fixture(scope="session")
def default_arrays(default_scene):
    return camjax.scene_arrays(default_scene)


@pytest.fixture(scope="session")
def reference_1deg():
    """The reference case (SPEC 5) in independent NumPy closed forms on the scene's 1 deg grid."""
    return reference_case(360)


# Each compiled XLA program holds a few memory mappings of its own; a whole suite in one process
# compiles tens of thousands and would pass the kernel's vm.max_map_count (65,530 by default),
# after which mmap fails inside XLA and the process dies (SIGSEGV). Past this many mappings the
# in-memory caches are dropped (compiled kernels stay in the persistent cache on disk).
MAX_MAPPINGS = 25_000


def _mapping_count() -> int:
    try:
        with open("/proc/self/maps", "rb") as maps:
            return sum(1 for _ in maps)
    except OSError:  # not Linux: no such limit to keep under
        return 0


@pytest.fixture(autouse=True)
def _release_compiled_programs():
    """Drop JAX's in-memory program caches once the process holds more than MAX_MAPPINGS."""
    yield
    if _mapping_count() > MAX_MAPPINGS:
        jax.clear_caches()
        gc.collect()
