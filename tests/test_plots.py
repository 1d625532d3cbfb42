"""Design figures: closed cycles, the title block, the stress scale and margin, load parts."""

import numpy as np
import pytest
from reference import reference_motion

import camjax
from camjax import followers
from camjax.followers import _translating_drawing
from camjax.output import titles


def design_figures(curves, title=""):
    """Every figure of a run's curves, drawn (the follower's figure builders)."""
    builders = followers.drawing(curves.follower_type).figure_builders(curves)
    return {name: build(curves, title) for name, build in builders.items()}


@pytest.fixture(scope="module")
def default_run(default_scene, default_arrays):
    return camjax.analyse(default_scene, default_arrays)


@pytest.fixture(scope="module")
def figures(default_run):
    return design_figures(default_run.curves, titles.title_block(default_run.data))


def _curves(ax):
    return [ln for ln in ax.get_lines() if len(ln.get_xdata()) > 10]


def test_every_cycle_is_closed_at_360(figures):
    for name in ("svaj.png", "loads.png", "stress.png"):
        for ax in figures[name].axes:
            for line in _curves(ax):
                x, y = np.asarray(line.get_xdata()), np.asarray(line.get_ydata())
                assert x[0] == 0.0 and x[-1] == 360.0, name
                assert y[-1] == y[0] or (np.isnan(y[-1]) and np.isnan(y[0])), name


def test_svaj_displacement_is_the_reference_motion(figures):
    line = _curves(figures["svaj.png"].axes[0])[0]
    x, y = np.asarray(line.get_xdata()), np.asarray(line.get_ydata())
    s, _, _ = reference_motion(x)  # closed-form cycloids; 360 deg wraps to 0
    np.testing.assert_allclose(y, s, atol=1e-12)


def test_title_block_names_the_run(figures, default_run):
    text = titles.title_block(default_run.data)
    lines = text.splitlines()
    assert len(lines) == 3
    assert "scene default" in lines[0] and "240 rpm" in lines[0] and "counter-clockwise" in lines[0]
    assert lines[1] == "dwell 100° · rise 80° cycloidal 5 mm · dwell 120° · return 60° cycloidal 5 mm"
    rb = default_run.data["design"]["base_radius_mm"]
    assert f"R_b = {rb:.3f} mm" in lines[2] and "feasible" in lines[2]
    for fig in figures.values():
        assert text in fig._suptitle.get_text()


def test_stress_axis_follows_the_data_and_states_the_margin(figures, default_run):
    ax = figures["stress.png"].axes[0]
    curves = default_run.curves
    peak, smax = float(np.max(curves.stress_MPa)), curves.sigma_max_MPa
    low, high = ax.get_ylim()
    # the reference design peaks at ~162 MPa against sigma_max = 1230: the axis stays near the data
    assert low <= float(np.min(curves.stress_MPa)) and peak < high < 0.5 * smax
    texts = " ".join(t.get_text() for t in ax.texts)
    assert f"margin {smax - peak:.4g} MPa" in texts and f"{peak / smax:.0%} of σ_max" in texts


def test_loads_parts_add_up_to_the_drawn_total(figures):
    ax = figures["loads.png"].axes[0]
    by_label = {ln.get_label(): np.asarray(ln.get_ydata()) for ln in _curves(ax)}
    parts = [by_label[k] for k in ("inertia", "spring", "damping", "gravity")]
    # 1e-9 N: float64 rounding of a ~60 N sum
    np.testing.assert_allclose(sum(parts), by_label["total contact force F"], atol=1e-9)
    assert any("contact margin: min F" in t.get_text() for t in ax.texts)


def test_profile_marks_angles_dimensions_and_smallest_rho(figures, default_run):
    fig = figures["profile.png"]
    ax = fig.axes[0]
    texts = [t.get_text() for t in ax.texts]
    assert [f"{d}°" for d in range(0, 360, 30)] == [t for t in texts if t.endswith("°") and t[:-1].isdigit()]
    assert any(t.startswith("lift h = 5 mm") for t in texts)
    r_max = float(np.max(np.hypot(default_run.curves.profile_x_mm, default_run.curves.profile_y_mm)))
    assert any(t.startswith(f"R_max = {r_max:.3f} mm") for t in texts)
    legend = [t.get_text() for t in fig.legends[0].get_texts()]
    rho = default_run.curves.rho_mm
    assert any(t.startswith("flat-face follower") for t in legend)
    assert f"smallest ρ = {rho.min():.3g} mm at θ = {default_run.curves.theta_deg[np.argmin(rho)]:g}°" in legend


def test_infeasible_design_draws_without_valid_stress_where_rho_is_negative(default_scene, default_arrays):
    run = camjax.analyse(default_scene, default_arrays, base_radius_mm=10.0)
    figs = design_figures(run.curves, titles.title_block(run.data))
    ax = figs["stress.png"].axes[0]
    y = np.asarray(_curves(ax)[0].get_ydata())[:-1]
    np.testing.assert_array_equal(np.isnan(y), run.curves.rho_mm <= 0)
    assert any("EXCEEDED" in t.get_text() for t in ax.texts)
    legend = [t.get_text() for t in figs["profile.png"].legends[0].get_texts()]
    assert "ρ < 0: the face cannot follow the outline" in legend


def _drawn_boxes(fig):
    """Render ``fig`` (Agg) and return its renderer."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg

    canvas = FigureCanvasAgg(fig)
    canvas.draw()
    return canvas.get_renderer()


@pytest.mark.slow
@pytest.mark.parametrize("rpm", ["240.0", "10.0"])
def test_loads_labels_stay_inside_their_axes_wherever_the_minimum_falls(default_scene, rpm):
    # at 10 rpm the inertia is negligible and the force is least on the first dwell, at theta = 0:
    # the contact-margin label must open into the axes there (it ran off the left edge, and the
    # layout squeezed the axes to make room for it)
    import dataclasses

    from camjax.scene import builtin_scene_text, parse_scene

    scene = dataclasses.replace(parse_scene(builtin_scene_text("default").replace("rpm = 240.0", f"rpm = {rpm}")),
                                design=None)
    run = camjax.analyse(scene)
    if rpm == "10.0":
        assert run.data["loads"]["contact"]["min_force_deg"] == 0.0
    fig = _translating_drawing.loads_figure(run.curves, titles.title_block(run.data))
    renderer = _drawn_boxes(fig)
    ax = fig.axes[0]
    box = ax.get_window_extent(renderer)
    # the axes keep most of the figure's width (a label outside them would have taken it)
    assert box.width >= 0.75 * fig.bbox.width
    legends = [lg.get_window_extent(renderer) for lg in fig.legends + ax.get_children()
               if type(lg).__name__ == "Legend"]
    for text in ax.texts:
        t = text.get_window_extent(renderer)
        assert box.x0 - 1 <= t.x0 and t.x1 <= box.x1 + 1 and box.y0 - 1 <= t.y0 and t.y1 <= box.y1 + 1, \
            text.get_text()
        for lg in legends:  # no label hidden under the legend
            assert not t.overlaps(lg), text.get_text()
