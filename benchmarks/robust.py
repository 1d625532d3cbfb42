"""Benchmark: ``camjax robust`` on the default scene with tolerances, batch vs NumPy.

The default scene (flat face) with a [tolerances] section (:data:`TOLERANCES`: speed, spring,
preload, mass, base radius, face width, cam width and a form error) has its nominal design
evaluated for N samples (:func:`camjax.robust.evaluate.batch`: one program, blocks of 256 vmapped samples).
The same evaluation of the flat face's outputs (peak stress, least contact force, least
curvature radius, dwell error, peak acceleration) is written in NumPy twice: a Python loop over
the samples (one (n,)-grid evaluation each; timed on ``LOOP_SAMPLES`` samples and scaled to N)
and one vectorized over (block, n) arrays (the faster of blocks of 512 and 8192 samples counts);
both are checked against the batch's outputs
(``max_rel_diff``) before their times count. Ratios: ``numpy_loop_ratio`` and
``numpy_vectorized_ratio`` (NumPy time / batch time, same run, medians). ``cli_wall_s``: the wall
time of ``camjax robust SCENE --samples N --out DIR`` in a fresh process, first and warm (the
median of the next runs: the compilation cache filled), figures included: it solves the
[design] first. ``cli_given_design_wall_s``: the same with ``--design`` (the nominal design
given, no solve).

The machine is a shared 2-core CPU: other processes run beside it (``environment``'s load
average), so the figures are medians, and ratios come from the same run.

With ``--dynamics``: ``camjax robust`` of the built-in thesis-bench (a rocker with [dynamics]: the
follower train's residual vibration is an output of every sample) with a [design] and a
[tolerances] section added (:data:`DYNAMICS_TOLERANCES`: speed, the train's stiffness, damping and
inertia, roller radius, spring), ``--samples 1000`` by default: wall and CPU seconds (the child
process's user + system) of a cold run (compilation caches in an empty folder) and of warm runs
(the same folders, filled), written under the key ``robust_dynamics`` of ``--out``, whose other keys
are kept.

``python -m benchmarks.robust [--samples N] [--dynamics] --out FILE.json``.
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

import camjax  # noqa: E402, F401  (float64)
from benchmarks.harness import environment  # noqa: E402

TOLERANCES = """
[tolerances]
rpm = { half_width = 10, dist = "uniform" }
spring_N_per_m = { sd_percent = 5 }
preload_mm = { sd = 0.2 }
mass_kg = { sd_percent = 2 }
base_radius_mm = { sd = 0.02 }
face_width_mm = { sd = 0.05 }
cam_width_mm = { sd = 0.05 }
profile_error_mm = { amplitude = 0.005, harmonics = [2, 3, 5] }
"""
DYNAMICS_DESIGN = """
[design]
base_radius_mm = [20.0, 200.0]
"""
DYNAMICS_TOLERANCES = """
[tolerances]
rpm = { sd_percent = 2 }
k23 = { sd_percent = 5 }
c3 = { sd_percent = 10 }
I3 = { half_width_percent = 3, dist = "uniform" }
roller_radius_mm = { sd = 0.02 }
spring_N_m_per_rad = { sd_percent = 5 }
"""
LOOP_SAMPLES = 2000
CHUNK = 8192


def scene_text() -> str:
    from camjax.scene import builtin_scene_text

    return builtin_scene_text("default") + TOLERANCES


def numpy_setup(scene, nom):
    """What the NumPy evaluations share: the nominal kinematics on the grid and the constants."""
    from camjax.evaluate import scene_arrays
    from camjax.robust.evaluate import dwell_mask

    a = scene_arrays(scene, extrema="grid")
    f, c = scene.follower.train, scene.contact
    comp = (1 - c.cam.poisson**2) / c.cam.E_MPa + (1 - c.follower.poisson**2) / c.follower.E_MPa
    n = scene.motion.samples
    return {"s": np.asarray(a.kin.s), "ds": np.asarray(a.kin.ds), "d2s": np.asarray(a.kin.d2s),
            "theta": np.arange(n) * (2 * np.pi / n), "comp": comp, "damping": f.damping_Ns_per_m,
            "g": f.gravity_m_s2, "dwell": dwell_mask(scene, n),
            "harmonics": np.asarray(nom.tolerances.profile.harmonics, float),
            "amplitude": nom.tolerances.profile.amplitude_mm,
            "names": [t.name for t in nom.tolerances.values]}


def numpy_outputs(ctx, values, phases):
    """The flat face's outputs for samples ``values`` (B, k) and ``phases`` (B, H), vectorized
    over (B, n): SPEC 4's force, Hertz C = 0.564 sqrt(F / (w K)), rho = R_b + s + s''."""
    v = dict(zip(ctx["names"], np.atleast_2d(values).T, strict=True))
    col = lambda x: np.asarray(x)[:, None]  # noqa: E731
    arg = ctx["harmonics"][None, :, None] * ctx["theta"][None, None, :] + np.atleast_2d(phases)[:, :, None]
    h = ctx["harmonics"][None, :, None]
    amp = ctx["amplitude"]
    eps = amp * np.cos(arg).sum(1)
    s = ctx["s"] + eps
    ds = ctx["ds"] - amp * (h * np.sin(arg)).sum(1)
    d2s = ctx["d2s"] - amp * (h**2 * np.cos(arg)).sum(1)
    w = col(v["rpm"]) * 2 * np.pi / 60
    accel = d2s * w**2 * 1e-3
    force = (col(v["mass_kg"]) * accel + ctx["damping"] * ds * w * 1e-3
             + col(v["spring_N_per_m"]) * (s * 1e-3 + col(v["preload_mm"]) * 1e-3)
             + col(v["mass_kg"]) * ctx["g"])
    coeff = 0.564 * np.sqrt(np.maximum(force, 0.0) / (col(v["cam_width_mm"]) * ctx["comp"]))
    rho = col(v["base_radius_mm"]) + s + d2s
    stress = coeff / np.sqrt(np.maximum(rho, 1e-15))
    return np.stack([stress.max(1), force.min(1), rho.min(1),
                     np.where(ctx["dwell"], np.abs(eps), 0.0).max(1), np.abs(accel).max(1)], axis=1)


def cli_wall(path: str, samples: int, runs: int, extra: tuple[str, ...] = (), env_extra=None,
             cpu: list | None = None, keep: Path | None = None) -> list[float]:
    """Wall seconds of ``runs`` fresh ``camjax robust`` processes; each one's CPU seconds (user +
    system of the child) appended to ``cpu`` when given; the last run's folder written to ``keep``
    when given."""
    import resource

    out = []
    env = dict(os.environ, PYTHONPATH=str(Path(__file__).resolve().parent.parent), **(env_extra or {}))
    for i in range(runs):
        with tempfile.TemporaryDirectory() as tmp:
            folder = keep if keep is not None and i == runs - 1 else Path(tmp) / "o"
            r0 = resource.getrusage(resource.RUSAGE_CHILDREN)
            t0 = time.perf_counter()
            subprocess.run([sys.executable, "-m", "camjax.cli", "robust", path, "--samples", str(samples),
                            "--out", str(folder), *extra], check=True, env=env, capture_output=True)
            out.append(time.perf_counter() - t0)
            r1 = resource.getrusage(resource.RUSAGE_CHILDREN)
            if cpu is not None:
                cpu.append(r1.ru_utime - r0.ru_utime + r1.ru_stime - r0.ru_stime)
    return out


def dynamics_run(samples: int = 1000, cli_runs: int = 3) -> dict:
    """``camjax robust`` of thesis-bench with [design] and [tolerances] added: a cold run (empty
    compilation caches) then ``cli_runs - 1`` warm runs, wall and CPU seconds each."""
    from camjax.scene import builtin_scene_text

    with tempfile.TemporaryDirectory() as tmp:
        path = str(Path(tmp) / "thesis-bench-tolerances.toml")
        Path(path).write_text(builtin_scene_text("thesis-bench") + DYNAMICS_DESIGN + DYNAMICS_TOLERANCES)
        caches = {"CAMJAX_COMPILATION_CACHE": str(Path(tmp) / "xla"),
                  "CAMJAX_PROGRAM_CACHE": str(Path(tmp) / "programs")}
        cpu: list[float] = []
        out = Path(tmp) / "last"
        walls = cli_wall(path, samples, cli_runs, env_extra=caches, cpu=cpu, keep=out)
        result = json.loads((out / "robust.json").read_text())
    return {
        "samples": samples,
        "cli_command": f"camjax robust <thesis-bench + [design] + [tolerances]> --samples {samples} "
                       "--out DIR",
        "tolerances": DYNAMICS_TOLERANCES.strip().splitlines()[1:],
        "cli_wall_s": {"cold_first": walls[0], "warm": walls[1:],
                       "warm_median": statistics.median(walls[1:]) if len(walls) > 1 else None},
        "cli_cpu_s": {"cold_first": cpu[0], "warm": cpu[1:],
                      "warm_median": statistics.median(cpu[1:]) if len(cpu) > 1 else None},
        "timings_s_of_the_last_run": result["timings_s"],
        "residual_vibration": result["outputs"]["residual_vibration"],
        "residual_vibration_sensitivities": result["sensitivities"]["residual_vibration"],
        "limits": result["limits"],
        "load_average_at_end": list(os.getloadavg()),
        "target_s": 30.0,
    }


def run(samples: int = 100_000, repeats: int = 3, cli_runs: int = 3) -> dict:
    from camjax.robust import evaluate as ev
    from camjax.robust.report import nominal_design
    from camjax.robust.tolerances import draw
    from camjax.scene import parse_scene

    scene = parse_scene(scene_text(), "default")
    design, _ = nominal_design(scene)
    nom = ev.nominal(scene, scene.tolerances, design)
    d = draw(scene.tolerances, samples, 0)
    unit, phases = np.asarray(d.unit), np.asarray(d.phases)
    t0 = time.perf_counter()
    res = ev.batch(nom, unit, phases, curves=0)
    first_s = time.perf_counter() - t0
    batch_s = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        res = ev.batch(nom, unit, phases, curves=0)
        batch_s.append(time.perf_counter() - t0)
    values = np.asarray(nom.values) + np.asarray(nom.scales) * unit
    ctx = numpy_setup(scene, nom)
    cols = [ev.output_names(scene, scene.tolerances).index(n) for n in
            ("peak_stress_MPa", "least_contact_force_N", "least_curvature_radius_mm",
             "dwell_position_error_mm", "peak_acceleration_m_s2")]
    vec_by_block = {}
    for block in (512, CHUNK):
        vec_by_block[block] = []
        for _ in range(repeats):
            t0 = time.perf_counter()
            vec = np.concatenate([numpy_outputs(ctx, values[i:i + block], phases[i:i + block])
                                  for i in range(0, samples, block)])
            vec_by_block[block].append(time.perf_counter() - t0)
    best = min(vec_by_block, key=lambda b: statistics.median(vec_by_block[b]))
    vec_s = vec_by_block[best]
    m = min(LOOP_SAMPLES, samples)
    t0 = time.perf_counter()
    loop = np.concatenate([numpy_outputs(ctx, values[i:i + 1], phases[i:i + 1]) for i in range(m)])
    loop_s = (time.perf_counter() - t0) * samples / m
    ref = res.outputs[:, cols]
    diff = float(np.max(np.abs(vec - ref) / np.maximum(np.abs(ref), 1e-9)))
    diff_loop = float(np.max(np.abs(loop - ref[:m]) / np.maximum(np.abs(ref[:m]), 1e-9)))
    batch = statistics.median(batch_s)
    with tempfile.TemporaryDirectory() as tmp:
        path = str(Path(tmp) / "default-tolerances.toml")
        Path(path).write_text(scene_text())
        # empty compilation and program caches of its own: the first run is a user's first (cold)
        caches = {"CAMJAX_COMPILATION_CACHE": str(Path(tmp) / "xla"),
                  "CAMJAX_PROGRAM_CACHE": str(Path(tmp) / "programs")}
        walls = cli_wall(path, samples, cli_runs, env_extra=caches)
        given = str(Path(tmp) / "design.json")
        Path(given).write_text(json.dumps({"follower_type": "flat", "design": design}))
        walls_given = cli_wall(path, samples, cli_runs, ("--design", given), env_extra=caches)
    return {
        "samples": samples,
        "grid": scene.motion.samples,
        "batch_first_call_s": first_s,
        "batch_s": batch_s,
        "batch_median_s": batch,
        "samples_per_s": samples / batch,
        "numpy_vectorized_s": vec_s,
        "numpy_vectorized_block": best,
        "numpy_vectorized_s_by_block": {str(b): t for b, t in vec_by_block.items()},
        "numpy_vectorized_median_s": statistics.median(vec_s),
        "numpy_loop_s_scaled": loop_s,
        "numpy_loop_measured_samples": m,
        "numpy_vectorized_ratio": statistics.median(vec_s) / batch,
        "numpy_loop_ratio": loop_s / batch,
        "max_rel_diff_numpy_vectorized": diff,
        "max_rel_diff_numpy_loop": diff_loop,
        "cli_wall_s": {"cold_first": walls[0], "warm": walls[1:], "warm_median": statistics.median(walls[1:])
                       if len(walls) > 1 else None},
        "cli_given_design_wall_s": {"first": walls_given[0], "next": walls_given[1:],
                                    "next_median": statistics.median(walls_given[1:]) if len(walls_given) > 1
                                    else None},
        "cli_command": f"camjax robust <default + [tolerances]> --samples {samples} --out DIR",
        "cli_given_design_command": f"camjax robust <default + [tolerances]> --samples {samples} --out DIR "
                                    "--design <the nominal design's JSON>",
        "target_warm_s": 10.0,
    }


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--samples", type=int, default=100_000)
    p.add_argument("--cli-runs", type=int, default=3)
    p.add_argument("--dynamics", action="store_true",
                   help="measure thesis-bench with [dynamics] (default 1000 samples) under the key "
                        "robust_dynamics of --out, keeping its other keys")
    p.add_argument("--out", required=True)
    args = p.parse_args(argv)
    if args.dynamics:
        path = Path(args.out)
        data = json.loads(path.read_text()) if path.exists() else {}
        samples = 1000 if args.samples == p.get_default("samples") else args.samples
        data["robust_dynamics"] = {"environment": environment("float64"),
                                   **dynamics_run(samples, cli_runs=args.cli_runs)}
        path.write_text(json.dumps(data, indent=1) + "\n")
        r = data["robust_dynamics"]
        wall, cpu = r["cli_wall_s"], r["cli_cpu_s"]
        print(f"thesis-bench with [dynamics], {samples} samples: CLI cold {wall['cold_first']:.1f} s wall "
              f"({cpu['cold_first']:.1f} s CPU), warm {wall['warm_median']} s wall ({cpu['warm_median']} s "
              f"CPU); load {r['environment']['load_average_at_start']}")
        return 0
    path = Path(args.out)
    data = json.loads(path.read_text()) if path.exists() else {}  # keeps robust_dynamics
    data.update({"environment": environment("float64"), "robust": run(args.samples, cli_runs=args.cli_runs)})
    path.write_text(json.dumps(data, indent=1) + "\n")
    r = data["robust"]
    print(f"batch {r['batch_median_s']:.3f} s for {r['samples']} samples ({r['samples_per_s']:.3g}/s); "
          f"NumPy vectorized x{r['numpy_vectorized_ratio']:.2f}, loop x{r['numpy_loop_ratio']:.1f}; "
          f"CLI warm {r['cli_wall_s']['warm_median']} s, cold {r['cli_wall_s']['cold_first']:.1f} s; "
          f"with --design: {r['cli_given_design_wall_s']['next_median']} s")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
