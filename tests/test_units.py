"""Inch scenes (``units = "in"``, camjax.units): a built-in scene converted to inches by this file's
own converter designs the same cam (result.json, profile.csv and profile.dxf equal after unit
conversion), mixed spellings and unknown units exit 2 naming the key, scenes without ``units`` are
read as before.

The converter here is independent of camjax.units: its own suffix table and factors, written from
the definitions (1 in = 25.4 mm, 1 lbf = 0.45359237 kg x 9.80665 m/s², 1 lb = 0.45359237 kg).
"""

import json
import math
import re
import tomllib

import numpy as np
import pytest

from camjax import cli
from camjax.scene import builtin_scene_text, parse_scene

IN = 25.4  # mm
LBF = 0.45359237 * 9.80665  # N
LB = 0.45359237  # kg
PSI = LBF / IN**2  # MPa (N/mm²)
# internal suffix -> (inch suffix, internal value of one inch unit)
TABLE = {
    "_mm": ("_in", IN), "_MPa": ("_psi", PSI), "_N": ("_lbf", LBF), "_kg": ("_lb", LB),
    "_N_per_m": ("_lbf_per_in", LBF / (IN / 1000)), "_Ns_per_m": ("_lbf_s_per_in", LBF / (IN / 1000)),
    "_N_m": ("_lbf_in", LBF * IN / 1000), "_N_m_per_rad": ("_lbf_in_per_rad", LBF * IN / 1000),
    "_N_m_s_per_rad": ("_lbf_in_s_per_rad", LBF * IN / 1000),
    "_kg_m2": ("_lb_in2", LB * (IN / 1000) ** 2), "_m_s2": ("_in_s2", IN / 1000),
    # outputs only
    "_Nm": ("_lbf_in", LBF * IN / 1000), "_m_s": ("_in_s", IN / 1000), "_m_s3": ("_in_s3", IN / 1000),
    "_mm_per_rad": ("_in_per_rad", IN), "_mm_per_rad2": ("_in_per_rad2", IN),
}
UNITLESS = ("_deg", "_rad", "_hz", "_per_rad")  # keys beside a converted one that keep their unit


def _suffix(key):
    """(internal suffix, inch suffix, factor) of a key's longest suffix in TABLE, or None."""
    hits = [s for s in TABLE if key.endswith(s) and len(key) > len(s)]
    if not hits:
        return None
    s = max(hits, key=len)
    return s, *TABLE[s]


def to_inches(value, factor=None):
    """A scene's parsed TOML (or any part) in inches: suffixed keys renamed, numbers divided."""
    if isinstance(value, dict):
        out = {}
        for k, v in value.items():
            m = _suffix(k)
            if m:
                out[k[: -len(m[0])] + m[1]] = to_inches(v, m[2])
            else:
                out[k] = to_inches(v, None if k.endswith(UNITLESS) else factor)
        return out
    if isinstance(value, list):
        return [to_inches(v, factor) for v in value]
    if factor is not None and isinstance(value, int | float) and not isinstance(value, bool):
        return value / factor
    return value


def toml_text(doc):
    """A small TOML writer: top-level keys, then one [section] per table (inline tables below)."""
    def val(v):
        if isinstance(v, bool):
            return "true" if v else "false"
        if isinstance(v, int | float):
            return repr(v)
        if isinstance(v, str):
            return json.dumps(v)
        if isinstance(v, list):
            return "[" + ", ".join(val(x) for x in v) + "]"
        return "{ " + ", ".join(f"{k} = {val(x)}" for k, x in v.items()) + " }"

    lines = [f"{k} = {val(v)}" for k, v in doc.items() if not isinstance(v, dict)]
    for name, table in doc.items():
        if isinstance(table, dict):
            lines += [f"[{name}]"] + [f"{k} = {val(v)}" for k, v in table.items()]
    return "\n".join(lines) + "\n"


def _scene(name, samples):
    doc = tomllib.loads(builtin_scene_text(name))
    doc["motion"]["samples"] = samples
    return doc


def _design(tmp, name, doc):
    path = tmp / f"{name}.toml"
    path.write_text(toml_text(doc))
    out = tmp / name
    assert cli.main(["design", str(path), "--out", str(out), "--dpi", "30"]) == 0
    return out


@pytest.fixture(scope="module")
def pair(tmp_path_factory):
    """The built-in default scene (flat face: mass, spring, damping, gravity, contact, [design])
    designed as written (mm) and converted to inches, at its own 360 samples (the compiled design is
    the one tests/test_cli.py runs; the inch run reuses it). A rocker's units are checked on
    reading, below: its design runs the same code in mm."""
    tmp = tmp_path_factory.mktemp("units")
    doc = _scene("default", 360)
    inch = {"units": "in", **to_inches(doc)}
    return _design(tmp, "mm", doc), _design(tmp, "in", inch)


def _pairs(mm, inch):
    """(path, mm number, inch number, factor) of every number of result.json, matched by key; the
    flcd jumps in the units ``flcd_units`` names (mm, mm/rad, ...: lengths)."""
    flcd = mm.pop("flcd", [])
    inch_flcd = inch.pop("flcd", [])
    yield from _pairs_in(mm, inch, "", None)
    units = mm["flcd_units"]
    assert inch["flcd_units"] == {k: u.replace("mm", "in") for k, u in units.items()}
    for i, (a, b) in enumerate(zip(flcd, inch_flcd, strict=True)):
        for k, v in a.items():
            f = IN if units.get(k, "").startswith("mm") else None
            yield from _pairs_in(v, b[k], f".flcd[{i}].{k}", f)


def _pairs_in(mm, inch, path, factor):
    if isinstance(mm, dict):
        for k, v in mm.items():
            m = _suffix(k)
            key = k if m is None else k[: -len(m[0])] + m[1]
            assert key in inch, f"{path}.{key} missing from the inch result.json"
            f = m[2] if m else (None if k.endswith(UNITLESS) else factor)
            yield from _pairs_in(v, inch[key], f"{path}.{key}", f)
    elif isinstance(mm, list):
        assert len(mm) == len(inch), path
        for i, (a, b) in enumerate(zip(mm, inch, strict=True)):
            yield from _pairs_in(a, b, f"{path}[{i}]", factor)
    elif isinstance(mm, int | float) and not isinstance(mm, bool):
        yield path, mm, inch, factor or 1.0


# The designs agree to ~1e-12 relative: the inch scene's values come back in mm to rounding
# (x / 25.4 * 25.4), so the computation is the same one with inputs perturbed by ~1e-16; the
# optimizer's result moves by that times its conditioning. A value that is zero up to rounding
# (a dwell's velocity, 1e-33) is compared absolutely, at 1e-12 of the largest value of its kind.
# Where an extremum lies (``max_deg``, ``min_deg``) is the exception: a smooth maximum is flat, so
# a change d in the values moves it by ~sqrt(2 d / |f''|), ~1e-8 of the angle for d ~ 1e-16
# (measured on the built-in roller scene: 4.7e-7 deg of its smallest pressure angle at 255 deg, the
# only number past 1e-13 relative; the default scene's worst is 2e-16); compared to 1e-6 deg.
RTOL = 1e-12
WHERE_TOL_DEG = 1e-6


@pytest.mark.slow
def test_result_json_is_the_same_design(pair):
    mm_dir, in_dir = pair
    mm = json.loads((mm_dir / "result.json").read_text())
    inch = json.loads((in_dir / "result.json").read_text())
    pairs = list(_pairs(mm, inch))
    assert len(pairs) > 100
    scale = {}
    for path, a, _, _ in pairs:
        kind = re.sub(r"\[\d+\]", "", path)
        scale[kind] = max(scale.get(kind, 0.0), abs(a))
    worst = 0.0
    for path, a, b, f in pairs:
        if path.endswith(".iterations"):  # the solver's steps, not the design: rounding may change
            continue  # them (the oscillating roller: 1068 and 1054 steps to the same design)
        if re.search(r"\.certificate\.(stationarity|primal_feasibility|complementarity)$", path):
            # newton's scaled KKT residuals at its answer (dimensionless): rounding-level numbers
            # (~1e-11), which two roundings of the same problem give differently in their own
            # digits (the default scene: 4.78439e-11 and 4.78443e-11, 3.3e-16 apart); compared
            # absolutely, at 1e-13 (room for another CPU's rounding), both within newton's 1e-9
            assert abs(b - a) <= 1e-13 and max(a, b) <= 1e-9, f"{path}: {a} (mm) vs {b} (in)"
            continue
        if ".certificate." in path and abs(a) <= 1e-9:
            # the price of a limit that does not bind (the default scene's curvature: 2.8e-10 per
            # mm): the barrier's remainder ~ mu / slack, as rounding-level as the residuals (the
            # two scenes' 7e-21 apart); compared absolutely, at 1e-16
            assert abs(b * f - a) <= 1e-16, f"{path}: {a} (mm scene) vs {b} x {f} (inch scene)"
            continue
        if isinstance(a, int) and isinstance(b, int) and f == 1.0:
            assert a == b, path  # counts, samples, segment numbers
            continue
        tol = RTOL * max(abs(a), 1e-3 * scale[re.sub(r"\[\d+\]", "", path)]) + 1e-300
        if re.search(r"\.(max|min)\w*_deg$", path):
            tol = WHERE_TOL_DEG
        err = abs(b * f - a)
        worst = max(worst, err / max(abs(a), 1e-300))
        assert err <= tol, f"{path}: {a} (mm scene) vs {b} x {f} = {b * f} (inch scene)"
    print(f"worst relative difference {worst:.3g} over {len(pairs)} numbers")
    # every key is spelled in inches: none of the internal suffixes remains
    keys = re.findall(r'"(\w+)":', (in_dir / "result.json").read_text())
    assert keys and not [k for k in keys if _suffix(k) is not None]


@pytest.mark.slow
def test_profile_csv_is_the_same_design(pair):
    mm_dir, in_dir = pair
    mm_names = (mm_dir / "profile.csv").read_text().splitlines()[0].split(",")
    in_names = (in_dir / "profile.csv").read_text().splitlines()[0].split(",")
    mm_rows = np.loadtxt(mm_dir / "profile.csv", delimiter=",", skiprows=1)
    in_rows = np.loadtxt(in_dir / "profile.csv", delimiter=",", skiprows=1)
    assert len(mm_names) == len(in_names) and mm_rows.shape == in_rows.shape
    for j, name in enumerate(mm_names):
        m = _suffix(name)
        assert in_names[j] == (name if m is None else name[: -len(m[0])] + m[1])
        f = 1.0 if m is None else m[2]
        # the CSV is written to 12 decimals in each file's unit: rounding of 0.5e-12 in both
        tol = 0.5e-12 * (1 + f) + RTOL * np.abs(mm_rows[:, j])
        np.testing.assert_array_less(np.abs(in_rows[:, j] * f - mm_rows[:, j]), tol + 1e-15,
                                     err_msg=name)


def _dxf(path):
    """($INSUNITS, $MEASUREMENT, (n, 2) polyline vertices) read from a DXF's group codes."""
    lines = path.read_text().splitlines()
    pairs = list(zip(lines[0::2], lines[1::2], strict=False))
    header = {}
    for i, (code, value) in enumerate(pairs):
        if code.strip() == "9" and value in ("$INSUNITS", "$MEASUREMENT"):
            header[value] = int(pairs[i + 1][1])
    start = next(i for i, (_, v) in enumerate(pairs) if v == "AcDbPolyline")
    xs, ys = [], []
    for code, value in pairs[start:]:
        if code.strip() == "0":
            break
        if code.strip() == "10":
            xs.append(float(value))
        elif code.strip() == "20":
            ys.append(float(value))
    return header["$INSUNITS"], header["$MEASUREMENT"], np.column_stack([xs, ys])


@pytest.mark.slow
def test_dxf_is_in_inches(pair):
    mm_dir, in_dir = pair
    u_mm, meas_mm, xy_mm = _dxf(mm_dir / "profile.dxf")
    u_in, meas_in, xy_in = _dxf(in_dir / "profile.dxf")
    assert (u_mm, meas_mm) == (4, 1)  # millimetres, metric
    assert (u_in, meas_in) == (1, 0)  # inches, imperial
    assert xy_in.shape == xy_mm.shape and len(xy_mm) == 360
    # 12 decimals in each file's unit, and the design's agreement
    np.testing.assert_allclose(xy_in * IN, xy_mm, rtol=RTOL, atol=0.5e-12 * (1 + IN))


# ----------------------------------------------------------------------------- reading


def _inch_default():
    return {"units": "in", **to_inches(tomllib.loads(builtin_scene_text("default")))}


def test_inch_scene_reads_to_the_mm_scene():
    """The inch default scene is the mm one to rounding, and keeps its units."""
    mm = parse_scene(builtin_scene_text("default"))
    inch = parse_scene(toml_text(_inch_default()))
    assert mm.units == "mm" and inch.units == "in"
    assert inch.follower.train.mass_kg == pytest.approx(mm.follower.train.mass_kg, rel=1e-15)
    assert inch.contact.cam_width_mm == pytest.approx(mm.contact.cam_width_mm, rel=1e-15)
    assert inch.design.sigma_max_MPa == pytest.approx(mm.design.sigma_max_MPa, rel=1e-15)
    assert inch.design.bounds("base_radius_mm") == pytest.approx(mm.design.bounds("base_radius_mm"),
                                                                 rel=1e-15)


def test_rocker_inch_scene_reads_to_the_mm_scene():
    """The oscillating roller's inertia (lb in²), torsion spring (lbf in/rad) and lengths."""
    doc = tomllib.loads(builtin_scene_text("oscillating-roller"))
    inch = {"units": "in", **to_inches(doc)}
    assert "inertia_lb_in2" in inch["follower"] and "spring_lbf_in_per_rad" in inch["follower"]
    mm, sc = parse_scene(builtin_scene_text("oscillating-roller")), parse_scene(toml_text(inch))
    assert sc.units == "in"
    for name in ("inertia_kg_m2", "spring_N_m_per_rad", "preload_rad"):
        assert getattr(sc.follower.train, name) == pytest.approx(getattr(mm.follower.train, name),
                                                                 rel=1e-15), name
    assert sc.follower.pivot_distance_mm == pytest.approx(mm.follower.pivot_distance_mm, rel=1e-15)
    assert sc.motion.segments == mm.motion.segments  # lift_deg: no unit to convert


def test_scene_without_units_is_read_as_before():
    """No ``units`` and ``units = "mm"`` read the same scene as today (equal dataclasses)."""
    text = builtin_scene_text("roller")
    assert parse_scene('units = "mm"\n' + text) == parse_scene(text)
    from camjax.units import report_to

    data = {"min_base_radius_mm": 1.0, "rule": "rho >= 0.001 mm"}
    assert report_to(data, "mm") is data


def _bad(tmp_path, capsys, text):
    path = tmp_path / "bad.toml"
    path.write_text(text)
    out = tmp_path / "out"
    assert cli.main(["design", str(path), "--out", str(out)]) == 2
    assert not out.exists()
    return capsys.readouterr().err


def test_mixed_spelling_in_an_inch_scene_exits_2(tmp_path, capsys):
    doc = _inch_default()
    doc["motion"]["segments"][1] = {**doc["motion"]["segments"][1], "lift_mm": 5.0}
    del doc["motion"]["segments"][1]["lift_in"]
    err = _bad(tmp_path, capsys, toml_text(doc))
    assert "motion.segments[1].lift_mm" in err and "lift_in" in err and "inch scene" in err


def test_inch_spelling_in_a_mm_scene_exits_2(tmp_path, capsys):
    text = builtin_scene_text("default").replace("mass_kg = 1.0", "mass_lb = 2.2")
    err = _bad(tmp_path, capsys, text)
    assert "follower.mass_lb" in err and "mass_kg" in err and 'units = "in"' in err


@pytest.mark.parametrize("units", ['"cm"', '"inch"', "25.4"])
def test_unknown_units_exit_2(tmp_path, capsys, units):
    err = _bad(tmp_path, capsys, f"units = {units}\n" + builtin_scene_text("default"))
    assert "units = " in err and "unknown units" in err and "mm" in err and "in" in err


def test_out_of_range_inch_value_is_named_in_inches(tmp_path, capsys):
    doc = _inch_default()
    doc["follower"]["mass_lb"] = 1e7  # 4.5e6 kg: past the 1e6 kg limit
    err = _bad(tmp_path, capsys, toml_text(doc))
    assert "follower.mass_lb" in err and "mass_kg" not in err
    # the allowed range in pounds: 1e-09 kg .. 1e+06 kg
    assert f"{1e6 / LB:.6g} lb" in err


def test_dynamics_is_refused_in_an_inch_scene(tmp_path, capsys):
    doc = _inch_default()
    doc["dynamics"] = {"follower": "translating", "I3": 1.0, "c3": 0.0, "k23": 1e5}
    err = _bad(tmp_path, capsys, toml_text(doc))
    assert "dynamics" in err and "inch scene" in err


def test_tolerances_are_refused_in_an_inch_scene(tmp_path, capsys):
    doc = _inch_default()
    doc["tolerances"] = {"rpm": {"sd": 1.0}}
    err = _bad(tmp_path, capsys, toml_text(doc))
    assert "tolerances" in err and "inch scene" in err


def test_joint_conditions_and_text_are_converted():
    """Unsuffixed numbers of a translating follower's joint conditions (mm per deg^k) are scaled;
    numbers with a unit in text are converted, unit words relabelled."""
    from camjax.units import convert_segment, convert_text, convert_unit_word

    seg = {"kind": "rise", "law": "polynomial", "lift_mm": 5.0, "start": {"v": 0.1, "a": "match"},
           "through": [{"at_deg": 10.0, "s_mm": 1.0, "v": 0.2}], "smoothing": 2.0}
    out = convert_segment(seg, IN, rocking=False)
    assert out["start"] == {"v": 0.1 * IN, "a": "match"}
    assert out["through"][0]["v"] == 0.2 * IN and out["through"][0]["s_mm"] == 1.0
    assert out["smoothing"] == 2.0 * IN**2 and out["lift_mm"] == 5.0
    assert convert_segment(seg, IN, rocking=True)["start"]["v"] == 0.1  # deg per deg
    assert convert_text("R_b = 25.4 mm, sigma 1230 MPa, 1e-09 to 1e+06 kg", "in") == (
        f"R_b = 1 in, sigma {1230 / PSI:.6g} psi, {1e-9 / LB:.6g} to {1e6 / LB:.6g} lb")
    assert convert_unit_word("force (N)") == "force (lbf)"
    assert convert_unit_word("cam torque T (N·m)") == "cam torque T (lbf·in)"
    assert convert_unit_word("a (m/s²)") == "a (in/s²)"
    assert convert_unit_word("σ (MPa), x_mm") == "σ (psi), x_mm"
    assert math.isclose(LBF, 4.4482216152605, rel_tol=1e-15)


@pytest.mark.slow
def test_figures_speak_inches(pair):
    """The default scene's figures drawn from its curves in inches: every text names inch units
    (no mm, MPa, N, N·m, m/s left) and the outline's axes span the mm outline / 25.4."""
    from matplotlib.text import Text

    from camjax import followers
    from camjax.pipeline import analyse
    from camjax.scene import load_scene
    from camjax.units import curves_to, relabel

    curves = analyse(load_scene("default")).curves  # compiled by the pair's runs
    inch = curves_to(curves, "in")
    np.testing.assert_allclose(inch.profile_x_mm * IN, curves.profile_x_mm, rtol=1e-15, atol=1e-15)
    np.testing.assert_allclose(inch.stress_MPa * PSI, curves.stress_MPa, rtol=1e-15)
    texts = []
    for name, build in followers.drawing("flat").figure_builders(inch).items():
        fig = build(inch, "R_b = 1.118 in")
        relabel(fig, "in")
        texts += [t.get_text() for t in fig.findobj(Text) if t.get_text()]
        if name == "profile.png":
            ax = next(a for a in fig.axes if a.get_xlabel() == "X (in)")
            r = float(np.max(np.hypot(curves.profile_x_mm, curves.profile_y_mm))) / IN
            assert r <= max(abs(v) for v in ax.get_xlim()) < 2 * r
    joined = "\n".join(texts)
    for word in ("(in)", "in/s", "(lbf)", "lbf·in", "(psi)"):
        assert word in joined, word
    for word in (r"\bmm\b", r"MPa", r"\(N\)", r"N·m", r"\bm/s"):
        assert not re.search(word, joined), (word, [t for t in texts if re.search(word, t)])


@pytest.mark.slow
def test_base_radius_option_and_summary_in_inches(pair, tmp_path, capsys):
    """--base-radius is read in the scene's units; the summary on stdout speaks them."""
    path = tmp_path / "inch.toml"
    doc = _inch_default()
    path.write_text(toml_text(doc))
    out = tmp_path / "out"
    capsys.readouterr()
    assert cli.main(["design", str(path), "--out", str(out), "--dpi", "30", "--base-radius", "1.2"]) == 0
    at = json.loads((out / "result.json").read_text())["evaluated_at"]
    assert at["base_radius_in"] == pytest.approx(1.2, rel=1e-15) and "--base-radius" in at["source"]
    text = capsys.readouterr().out
    assert "files drawn at R_b = 1.2 in" in text, text
    assert " mm" not in text


def test_base_radius_option_limit_holds_in_mm(tmp_path, capsys):
    """--base-radius beyond the command's 1e6 mm in an inch scene (1e6 in = 25.4 km) exits 2 naming
    the option and the limit in inches; nothing is written."""
    from camjax.cli.common import MAX_BASE_RADIUS_MM

    path = tmp_path / "inch.toml"
    path.write_text(toml_text(_inch_default()))
    out = tmp_path / "out"
    capsys.readouterr()
    assert cli.main(["design", str(path), "--out", str(out), "--base-radius", "1e6"]) == 2
    err = capsys.readouterr().err
    assert "--base-radius" in err and f"{MAX_BASE_RADIUS_MM / 25.4:g}, in" in err, err
    assert not out.exists()
