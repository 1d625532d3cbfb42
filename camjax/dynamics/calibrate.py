"""Measure the per-unit costs behind ``camjax dynamics``' work estimate on this machine
(:data:`camjax.dynamics.budget.COSTS`): ``python -m camjax.dynamics.calibrate`` prints them.

A measurement, run by hand: each kernel is timed warm at two sizes, the per-unit cost the
difference over the difference of the counts.
"""

from __future__ import annotations

import time

from camjax.dynamics import report
from camjax.dynamics.budget import TWO_PI, Costs, shaping_constraint_count


def calibrate(repeats: int = 3) -> Costs:  # pragma: no cover - a measurement, run by hand
    """Measure :class:`Costs` on this machine: each kernel timed warm (best of ``repeats``) at
    two sizes, the per-unit cost the difference over the difference of the counts."""
    import dataclasses

    import jax
    import jax.numpy as jnp
    import numpy as np

    import camjax
    from camjax import dynamics as d
    from camjax.dynamics.context import drive_of

    bench = camjax.load_scene("thesis-bench")
    plant = d.plant_of(bench.dynamics)
    w = TWO_PI * bench.dynamics.cam_speed_hz

    def best(f):
        jax.block_until_ready(f())
        times = []
        for _ in range(repeats):
            t = time.perf_counter()
            jax.block_until_ready(f())
            times.append(time.perf_counter() - t)
        return min(times)

    def slope(f, sizes, units):
        t0, t1 = (best(lambda s=s: f(s)) for s in sizes)
        return (t1 - t0) / (units(sizes[1]) - units(sizes[0]))

    # a full evaluation (f, f', f'') on a grid, per entry of the table
    def table(nh):
        n, h = nh
        cam = d.program_cam(bench, n, h)
        return d.evaluate_cam(cam, d.cam_grid(n))
    table_ns = slope(table, ((2048, 100), (8192, 400)), lambda nh: nh[0] * (nh[1] + 1)) * 1e9

    # one more batched plant over the same table (the robustness grid's inner loop)
    cam = d.program_cam(bench, 4096, 200)
    phi = d.cam_grid(4096)
    one = np.ones(1)

    def grid(k):
        return d.robustness_grid(cam, cam, plant, w, one, one, jnp.linspace(0.8, 1.2, k), phi)
    batch_ns = slope(grid, (8, 512), lambda k: k * 4096 * 201) * 1e9

    u = d.evaluate_cam(d.program_cam(bench), d.cam_grid(2 * 720)).f
    train_ns = slope(lambda c: d.integrate_train(plant, u, w, c), (20, 400), lambda c: c * 720) * 1e9

    drive = drive_of(bench.dynamics)

    def regimes(step, hs):
        out = []
        for lo, hi in hs:
            per = []
            for h in (lo, hi):
                cam_h = d.program_cam(bench, 1024, h)
                per.append(slope(lambda c, cam_h=cam_h, h=h: step(cam_h, h, c), (10, 60),
                                 lambda c: c * 360) * 1e6)
            b = (per[1] - per[0]) / (hi - lo)
            out += [per[0] - b * (lo + 1), b]
        return tuple(out)

    drive_us = regimes(lambda cam_h, h, c: d.simulate_drive(cam_h, drive, plant, w, c, 360),
                       ((5, 20), (60, 200)))
    nl_us = regimes(lambda cam_h, h, c: d.compensate_nonlinear(cam_h, drive, plant, w, h, c, 360),
                    ((5, 20), (60, 200)))

    phi_m = jnp.linspace(0.0, TWO_PI, 720, endpoint=False) + 1e-3
    lstsq_ns = slope(lambda h: d.fit_harmonics(phi_m, jnp.sin(phi_m), h), (50, 300),
                     lambda h: 720 * (2 * h + 1) ** 2) * 1e9

    def shaping(sh, steps):
        scene = dataclasses.replace(bench, dynamics=dataclasses.replace(
            bench.dynamics, shaping_harmonics=sh, shaping_steps=steps))
        return report.shaping(report.context(scene)).max_tracking_error
    q = shaping_constraint_count(bench.motion.program)
    per_small = slope(lambda s: shaping(15, s), (100, 600), lambda s: s) * 1e6
    per_large = slope(lambda s: shaping(60, s), (100, 600), lambda s: s) * 1e6
    b = (per_large - per_small) / ((9 + q) * (60 - 15))
    shaping_us = (per_small - b * (9 + q) * 16, b)
    return Costs(table_ns, batch_ns, train_ns, drive_us, nl_us, lstsq_ns, shaping_us)


if __name__ == "__main__":  # pragma: no cover
    print(calibrate())
