"""Scenes: the reference file parses exactly as written, bad input gives one clear message."""

import pytest

import camjax
from camjax.scene import SceneError, builtin_scene_text, parse_scene

BASE = """
[motion]
rpm = 240.0
samples = 360
segments = [
  { kind = "dwell",  angle_deg = 100 },
  { kind = "rise",   angle_deg = 80, law = "cycloidal", lift_mm = 5.0 },
  { kind = "dwell",  angle_deg = 120 },
  { kind = "return", angle_deg = 60, law = "cycloidal", lift_mm = 5.0 },
]

[follower]
type = "flat"
mass_kg = 1.0
spring_N_per_m = 3004.0
preload_mm = 13.0
damping_Ns_per_m = 0.345
gravity_m_s2 = 9.81
"""

CONTACT = """
[contact]
cam_width_mm = 10.0
cam = { E_MPa = 2.1e5, poisson = 0.3 }
follower = { E_MPa = 1.15e5, poisson = 0.26 }
"""


def test_default_scene_is_the_reference_case():
    sc = camjax.load_scene()
    assert sc.motion.rpm == 240.0 and sc.motion.samples == 360
    assert sc.motion.program.kinds == ("dwell", "rise", "dwell", "return")
    assert sc.motion.program.angles_deg == (100.0, 80.0, 120.0, 60.0)
    assert sc.follower.train.spring_N_per_m == 3004.0
    assert sc.contact.cam.E_MPa == 2.1e5 and sc.contact.follower.poisson == 0.26
    assert sc.design.bounds("base_radius_mm") == (5.0, 40.0) and sc.design.sigma_max_MPa == 1230.0
    assert sc.needs() == {"kinematics", "geometry", "loads", "contact", "design"}
    assert "[design]" in builtin_scene_text("default")


@pytest.mark.parametrize(
    "edit, field, words",
    [
        (("angle_deg = 120", "angle_deg = 110"), "motion.segments.angle_deg", "sum to 350"),
        (('law = "cycloidal", lift_mm = 5.0 },\n  { kind = "dwell"', 'law = "cycloid", lift_mm = 5.0 },\n  { kind = "dwell"'),
         "motion.segments[1].law", "unknown law"),
        (("angle_deg = 80, law = \"cycloidal\", lift_mm = 5.0", "angle_deg = 80, law = \"cycloidal\", lift_mm = -5.0"),
         "motion.segments[1].lift_mm", "out of range"),
        (("angle_deg = 60, law = \"cycloidal\", lift_mm = 5.0", "angle_deg = 60, law = \"cycloidal\", lift_mm = 4.0"),
         "motion.segments", "bring the follower back"),
        (("rpm = 240.0", 'rpm = "fast"'), "motion.rpm", "must be a number"),
        (("rpm = 240.0", "rpm = nan"), "motion.rpm", "finite"),
        (("mass_kg = 1.0", "mass_kg = inf"), "follower.mass_kg", "finite"),
        (("samples = 360", "samples = 360\ncolour = 3"), "motion.colour", "unknown key"),
        (('type = "flat"', 'type = "knife"'), "follower.type", "not allowed"),
        (("samples = 360", "samples = 0"), "motion.samples", "out of range"),
        (("samples = 360", "samples = 36.5"), "motion.samples", "integer"),
        (("samples = 360", 'samples = 360\nextrema = "fast"'), "motion.extrema", "not allowed"),
    ],
)
def test_bad_scenes_name_the_field(edit, field, words):
    text = BASE.replace(*edit)
    assert text != BASE, "the edit must apply"
    with pytest.raises(SceneError) as info:
        parse_scene(text)
    err = info.value
    assert err.field == field
    assert words in str(err)
    assert str(err).count("\n") == 0  # one message, one line


def test_width_and_section_rules():
    bad_width = CONTACT.replace("cam_width_mm = 10.0", "cam_width_mm = -1.0")
    with pytest.raises(SceneError, match="contact.cam_width_mm"):
        parse_scene(BASE + bad_width)
    with pytest.raises(SceneError, match="poisson"):
        parse_scene(BASE + CONTACT.replace("poisson = 0.3", "poisson = 0.7"))
    no_loads = BASE.split("mass_kg")[0]
    with pytest.raises(SceneError, match="needs the follower force"):
        parse_scene(no_loads + CONTACT)
    with pytest.raises(SceneError, match="unknown key"):
        parse_scene(BASE + "[weather]\nsunny = true\n")
    with pytest.raises(SceneError, match="not valid TOML"):
        parse_scene(BASE + "[contact\n")
    with pytest.raises(SceneError, match="design.face_width_mm"):
        parse_scene(BASE + CONTACT + '[design]\nbase_radius_mm = [5, 40]\nface_width_mm = [25, 5]\nsigma_max_MPa = 1230')
    with pytest.raises(SceneError, match="both zero"):
        parse_scene(BASE + CONTACT + "[design]\nbase_radius_mm = [5, 40]\nface_width_mm = [5, 25]\n"
                    "sigma_max_MPa = 1230\nalpha = 0\ngamma = 0")


def test_polynomial_and_fourier_segments():
    text = BASE.replace('law = "cycloidal", lift_mm = 5.0 },\n  { kind = "dwell"',
                        'law = "polynomial", exponents = [3, 4, 5], lift_mm = 5.0 },\n  { kind = "dwell"')
    sc = parse_scene(text)
    assert sc.motion.program.laws[1] is camjax.get_law("poly_3_4_5")
    with pytest.raises(SceneError, match="exponents"):
        parse_scene(text.replace("[3, 4, 5]", "[5, 4]"))
    fourier = BASE.replace('law = "cycloidal", lift_mm = 5.0 },\n  { kind = "dwell"',
                           'law = "fourier", coefficients = { h0 = 1.0, h1 = -0.5 }, lift_mm = 5.0 },\n'
                           '  { kind = "dwell"')
    assert parse_scene(fourier).motion.program.laws[1].name == "fourier"
    with pytest.raises(SceneError, match="unknown preset"):
        parse_scene(fourier.replace("{ h0 = 1.0, h1 = -0.5 }", '"nominal"'))


def test_absent_sections_compute_nothing():
    sc = parse_scene(BASE.split("mass_kg")[0])  # no loads, no contact
    assert sc.needs() == {"kinematics", "geometry"}
    arrays = camjax.scene_arrays(sc)
    assert arrays.force_N is None and arrays.torque_Nm is None and arrays.stress_coefficient is None
    sc2 = parse_scene(BASE)  # loads but no contact
    a2 = camjax.scene_arrays(sc2)
    assert a2.force_N is not None and a2.stress_coefficient is None


def test_unknown_builtin_and_missing_file(tmp_path):
    with pytest.raises(SceneError, match="no such file"):
        camjax.load_scene(tmp_path / "nope.toml")


def test_design_overrides_are_checked_by_the_scene_rules():
    from camjax.scene import with_design

    scene = camjax.load_scene("default")
    assert with_design(scene) == scene  # the spec round-trips through the parser unchanged
    changed = with_design(scene, alpha=2.0, seed=4, mode="pointwise")
    assert (changed.design.alpha, changed.design.seed, changed.design.mode) == (2.0, 4, "pointwise")
    assert changed.design.gamma == scene.design.gamma
    for bad, field in (({"alpha": -1.0}, "design.alpha"), ({"seed": 1.5}, "design.seed"),
                       ({"alpha": 0.0, "gamma": 0.0}, "design.alpha"), ({"solver": "bfgs"}, "design.solver")):
        with pytest.raises(SceneError) as info:
            with_design(scene, **bad)
        assert info.value.field == field


ROLLER_FOLLOWER = ('type = "flat"', 'type = "roller"\nroller_radius_mm = 6.0')


def test_limits_and_rotation_are_scene_data():
    from camjax.followers.flat.geometry import FLAT_MIN_CURVATURE_RADIUS_MM

    flat = parse_scene(BASE)
    assert flat.motion.rotation == "ccw"  # the convention of camjax.followers._pitch
    assert flat.follower.min_curvature_radius_mm == FLAT_MIN_CURVATURE_RADIUS_MM
    roller = parse_scene(BASE.replace(*ROLLER_FOLLOWER))
    assert roller.follower.max_pressure_angle_deg == 30.0
    assert roller.follower.min_curvature_radius_mm == 0.0
    text = BASE.replace(*ROLLER_FOLLOWER).replace("samples = 360", 'samples = 360\nrotation = "cw"')
    text = text.replace("roller_radius_mm = 6.0", "roller_radius_mm = 6.0\nmax_pressure_angle_deg = 35\n"
                        "min_curvature_radius_mm = 2.5")
    sc = parse_scene(text)
    assert (sc.motion.rotation, sc.follower.max_pressure_angle_deg, sc.follower.min_curvature_radius_mm) == \
        ("cw", 35.0, 2.5)


@pytest.mark.parametrize(
    "extra, field, words",
    [
        ("max_pressure_angle_deg = 90", "follower.max_pressure_angle_deg", "> 0 and < 90"),
        ("max_pressure_angle_deg = 0", "follower.max_pressure_angle_deg", "out of range"),
        ("max_pressure_angle_deg = -10", "follower.max_pressure_angle_deg", "out of range"),
        ("min_curvature_radius_mm = -1", "follower.min_curvature_radius_mm", "out of range"),
        ("roller_radius_mm = 0", "follower.roller_radius_mm", "out of range"),
    ],
)
def test_bad_roller_limits_name_the_field(extra, field, words):
    text = BASE.replace('type = "flat"', f'type = "roller"\n{extra}')
    if "roller_radius_mm" not in extra:
        text = text.replace('type = "roller"', 'type = "roller"\nroller_radius_mm = 6.0')
    with pytest.raises(SceneError) as info:
        parse_scene(text)
    assert info.value.field == field and words in str(info.value)
    assert "\n" not in str(info.value)


def test_bad_flat_limits_and_rotation_name_the_field():
    with pytest.raises(SceneError, match=r"follower.max_pressure_angle_deg = 30.*only for type = .*'roller', not type = 'flat'"):
        parse_scene(BASE.replace('type = "flat"', 'type = "flat"\nmax_pressure_angle_deg = 30'))
    with pytest.raises(SceneError, match=r"follower.min_curvature_radius_mm = 0.0: out of range \(allowed: > 0\)"):
        parse_scene(BASE.replace('type = "flat"', 'type = "flat"\nmin_curvature_radius_mm = 0.0'))
    with pytest.raises(SceneError, match=r"motion.rotation = 'left': is not allowed \(allowed: ccw, cw\)"):
        parse_scene(BASE.replace("samples = 360", 'samples = 360\nrotation = "left"'))
