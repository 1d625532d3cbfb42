"""Inch scenes: the one layer between a scene's units and camjax's internal mm/MPa/N/kg.

A scene that starts with ``units = "in"`` spells every dimensional key with an inch suffix
(``lift_in``, ``sigma_max_psi``, ``mass_lb``, ``spring_lbf_per_in``, ...; :data:`SUFFIXES`).
:func:`scene_to_internal` translates such a scene's parsed TOML once, on reading, to the internal
spelling (``lift_mm``, ``sigma_max_MPa``, ...) with the values scaled exactly, so that everything
computes in mm as for any other scene; the :class:`camjax.scene.Scene` keeps ``units`` ("mm" or
"in"). On writing, :func:`report_to`, :func:`curves_to`, :func:`column_names` and :func:`relabel`
convert result.json, the curves the figures, profile.csv and profile.dxf are drawn from, and the
figures' words back to the scene's units.

The factors are exact by definition: 1 in = 25.4 mm, 1 lbf = 4.4482216152605 N,
1 lb = 0.45359237 kg, 1 psi = 1 lbf/in².

Pure Python (NumPy only for arrays): no JAX, so the drawing processes can import it.
"""

from __future__ import annotations

import math
import re
from typing import Any

from camjax.errors import MISSING, SceneError

UNITS = ("mm", "in")  # the scene's ``units``: "mm" (the default) or "in"
MM_PER_IN = 25.4  # exact
M_PER_IN = 0.0254  # exact
N_PER_LBF = 4.4482216152605  # exact (0.45359237 kg x 9.80665 m/s^2)
KG_PER_LB = 0.45359237  # exact
MPA_PER_PSI = N_PER_LBF / MM_PER_IN**2  # 1 lbf/in^2 in N/mm^2

# (internal suffix, inch suffix, internal value per inch value). Keys are matched on their longest
# suffix. The first block is every dimensional suffix a scene may spell; the second appears only in
# outputs (result.json, profile.csv, curves). Angles (_deg, _rad), rpm, Hz, rad/s and
# dimensionless values have no unit to convert.
SCENE_SUFFIXES: tuple[tuple[str, str, float], ...] = (
    ("_mm", "_in", MM_PER_IN),
    ("_MPa", "_psi", MPA_PER_PSI),
    ("_GPa", "_Mpsi", MPA_PER_PSI * 1e3),  # 1 Mpsi = 1e6 psi = 6.894757... GPa
    ("_N", "_lbf", N_PER_LBF),
    ("_kg", "_lb", KG_PER_LB),
    ("_N_per_m", "_lbf_per_in", N_PER_LBF / M_PER_IN),
    ("_Ns_per_m", "_lbf_s_per_in", N_PER_LBF / M_PER_IN),
    ("_N_m", "_lbf_in", N_PER_LBF * M_PER_IN),
    ("_N_m_per_rad", "_lbf_in_per_rad", N_PER_LBF * M_PER_IN),
    ("_N_m_s_per_rad", "_lbf_in_s_per_rad", N_PER_LBF * M_PER_IN),
    ("_kg_m2", "_lb_in2", KG_PER_LB * M_PER_IN**2),
    ("_kg_m3", "_lb_in3", KG_PER_LB / M_PER_IN**3),
    ("_m_s2", "_in_s2", M_PER_IN),
    ("_mm_per_min", "_in_per_min", MM_PER_IN),  # a feed rate ([manufacture] feed_mm_per_min)
)
OUTPUT_SUFFIXES: tuple[tuple[str, str, float], ...] = (
    ("_Nm", "_lbf_in", N_PER_LBF * M_PER_IN),
    ("_m_s", "_in_s", M_PER_IN),
    ("_m_s3", "_in_s3", M_PER_IN),
    ("_mm_per_rad", "_in_per_rad", MM_PER_IN),
    ("_mm_per_rad2", "_in_per_rad2", MM_PER_IN),
    ("_mm3", "_in3", MM_PER_IN**3),  # a volume (the solid's)
)
SUFFIXES = SCENE_SUFFIXES + OUTPUT_SUFFIXES
# suffixes that say "no unit to convert" under a converted key (``max_deg`` beside ``max``)
UNITLESS_SUFFIXES = ("_deg", "_rad", "_hz", "_rad_s", "_rad_s2", "_rad_s3", "_rpm", "_per_rad")

# report keys whose text is a name, never converted (a scene called "5 mm cam" stays so)
VERBATIM = ("scene", "file", "law", "kind", "type", "source", "solver", "mode", "camjax_version")

_BY_SI = sorted(SUFFIXES, key=lambda s: -len(s[0]))
_SCENE_BY_SI = sorted(SCENE_SUFFIXES, key=lambda s: -len(s[0]))
_SCENE_BY_IN = sorted(SCENE_SUFFIXES, key=lambda s: -len(s[1]))


def check_units(units: Any, source: str | None = None) -> str:
    """The scene's ``units`` value checked: "mm" or "in"; else :class:`SceneError` naming ``units``."""
    if units not in UNITS:
        raise SceneError("units", units, "unknown units",
                         'mm (the default: mm, MPa, N, kg) or in (in, psi, lbf, lb)', source)
    return units


def length_scale(units: str) -> float:
    """mm per length unit of ``units``: 1.0 for "mm", 25.4 for "in" (a length in the scene's units
    times this is mm; mm divided by it is the scene's units)."""
    return MM_PER_IN if check_units(units) == "in" else 1.0


def length_word(units: str) -> str:
    """The length unit's symbol in text: "mm" or "in"."""
    return check_units(units)


def _si_match(key: str, table=_BY_SI):
    """(internal suffix, inch suffix, factor) of ``key``'s longest internal unit suffix, or None."""
    for si, inch, factor in table:
        if key.endswith(si) and len(key) > len(si):
            return si, inch, factor
    return None


def _inch_match(key: str):
    """(internal suffix, inch suffix, factor) of a scene key's longest inch suffix, or None."""
    for si, inch, factor in _SCENE_BY_IN:
        if key.endswith(inch) and len(key) > len(inch):
            return si, inch, factor
    return None


def inch_key(key: str) -> str:
    """``key`` spelled in inch units (``lift_mm`` -> ``lift_in``); unchanged without a unit."""
    m = _si_match(key)
    return key if m is None else key[: -len(m[0])] + m[1]


def si_factor(key: str) -> float | None:
    """Internal value per inch value of ``key`` (an internal spelling), or None without a unit."""
    m = _si_match(key)
    return None if m is None else m[2]


def _scale(value: Any, factor: float) -> Any:
    """Every number in ``value`` (a number, list, dict or array) times ``factor``; the rest as is."""
    if isinstance(value, bool) or value is None or isinstance(value, str):
        return value
    if isinstance(value, int | float):
        return value * factor
    if isinstance(value, dict):
        return {k: (v if _unitless(k) else _scale(v, factor)) for k, v in value.items()}
    if isinstance(value, list | tuple):
        return type(value)(_scale(v, factor) for v in value)
    if hasattr(value, "dtype"):  # a NumPy array
        return value * factor
    return value


def _round15(value: Any) -> Any:
    """Every float of ``value`` to 15 significant digits (a number as the scene wrote it)."""
    if isinstance(value, float):
        return float(f"{value:.15g}")
    if isinstance(value, list | tuple):
        return type(value)(_round15(v) for v in value)
    if isinstance(value, dict):
        return {k: _round15(v) for k, v in value.items()}
    return value


def _unitless(key: Any) -> bool:
    return isinstance(key, str) and key.endswith(UNITLESS_SUFFIXES)


# ------------------------------------------------------------------------------------ reading


def scene_to_internal(data: dict, follower_rocking: bool, source: str | None = None) -> tuple[dict, str]:
    """A parsed scene (TOML dict) in the internal spelling, and its units ("mm" or "in").

    The top-level ``units`` key is removed. A mm scene (no ``units``, or ``units = "mm"``) comes
    back as it was, but a key with an inch suffix in it is a :class:`SceneError` naming it (mixed
    spellings). An inch scene has every inch-suffixed key renamed and scaled exactly; a key with
    an internal suffix in it (``lift_mm`` beside ``units = "in"``) is an error naming it, as are
    the parts not available in inches (``[dynamics]``, whose keys carry no unit, and table laws,
    whose CSV files are in mm). ``follower_rocking``: the follower swings, so the joint
    conditions of [motion] (v, a, j per degree) are in degrees and not converted.
    """
    if not isinstance(data, dict):
        return data, "mm"
    units = check_units(data.get("units", "mm"), source)
    body = {k: v for k, v in data.items() if k != "units"}
    if units == "mm":
        _refuse_spelling(body, "", _inch_match, source, units)
        return body, units
    _refuse_spelling(body, "", _si_match_scene, source, units)
    if "dynamics" in body:
        raise SceneError("dynamics", MISSING, "[dynamics] takes SI values without a unit suffix and "
                         "is not available in an inch scene (units = \"in\")",
                         "a mm scene for camjax dynamics", source)
    if "tolerances" in body:
        raise SceneError("tolerances", MISSING, "[tolerances] spreads (sd, half_width) are read in the "
                         "scene's mm: not available in an inch scene (units = \"in\") yet",
                         "a mm scene for camjax robust", source)
    motion = body.get("motion")
    if isinstance(motion, dict) and "table" in motion:
        raise SceneError("motion.table", motion["table"], "table files are read in mm: a table law "
                         "is not available in an inch scene (units = \"in\")", "segments", source)
    out = _to_internal(body)
    segments = out.get("motion", {}).get("segments") if isinstance(out.get("motion"), dict) else None
    if isinstance(segments, list):
        for i, seg in enumerate(segments):
            if isinstance(seg, dict) and seg.get("law") == "table":
                raise SceneError(f"motion.segments[{i}].law", "table", "table files are read in mm: a "
                                 "table law is not available in an inch scene (units = \"in\")",
                                 "every other law", source)
        out["motion"]["segments"] = [convert_segment(s, MM_PER_IN, follower_rocking) for s in segments]
    return out, units


def _si_match_scene(key: str):
    return _si_match(key, _SCENE_BY_SI)


def _refuse_spelling(value: Any, path: str, match, source, units: str) -> None:
    """:class:`SceneError` at the first key whose suffix ``match`` finds (the other system's)."""
    if isinstance(value, list):
        for i, v in enumerate(value):
            _refuse_spelling(v, f"{path}[{i}]", match, source, units)
        return
    if not isinstance(value, dict):
        return
    for key, v in value.items():
        where = f"{path}.{key}" if path else str(key)
        m = match(key) if isinstance(key, str) else None
        if m is not None:
            si, inch, _ = m
            if units == "in":
                raise SceneError(where, v, f"a {si[1:]} spelling in an inch scene (units = \"in\"): "
                                 f"every key is spelled in inches", key[: -len(si)] + inch, source)
            raise SceneError(where, v, f"an inch spelling ({inch[1:]}) in a mm scene: give units = \"in\" "
                             f"at the top and spell every key in inches, or write mm units",
                             key[: -len(inch)] + si, source)
        _refuse_spelling(v, where, match, source, units)


def _to_internal(value: Any) -> Any:
    """Every inch-suffixed key of ``value`` renamed to its internal suffix, its numbers scaled."""
    if isinstance(value, list):
        return [_to_internal(v) for v in value]
    if not isinstance(value, dict):
        return value
    out = {}
    for key, v in value.items():
        m = _inch_match(key) if isinstance(key, str) else None
        if m is None:
            out[key] = _to_internal(v)
        else:
            si, inch, factor = m
            out[key[: -len(inch)] + si] = _scale(v, factor)
    return out


def convert_segment(seg: Any, factor: float, rocking: bool) -> Any:
    """A [motion] segment's numbers without a unit suffix scaled by ``factor`` (a length in mm per
    length unit): the joint conditions ``start``/``end`` (v, a, j per degree) and ``through``
    (v, a) of a translating follower, and ``smoothing`` (length²). Suffixed keys are left alone."""
    if not isinstance(seg, dict):
        return seg
    out = dict(seg)
    if not rocking:
        for side in ("start", "end"):
            if isinstance(out.get(side), dict):
                out[side] = {k: (_num(v, factor) if k in ("v", "a", "j") else v)
                             for k, v in out[side].items()}
        if isinstance(out.get("through"), list):
            out["through"] = [{k: (_num(v, factor) if k in ("v", "a") else v) for k, v in p.items()}
                              if isinstance(p, dict) else p for p in out["through"]]
    if "smoothing" in out:
        out["smoothing"] = _num(out["smoothing"], factor**2)
    return out


def _num(v: Any, factor: float) -> Any:
    """``v * factor`` for a finite number (not a bool); anything else (``"match"``) as is."""
    if isinstance(v, int | float) and not isinstance(v, bool) and math.isfinite(v):
        return v * factor
    return v


def scene_error_to(exc: SceneError, units: str) -> SceneError:
    """A :class:`SceneError` raised on an inch scene's internal form, worded in the scene's units:
    the field's key spelled in inches, its value and the numbers of the message converted."""
    if units != "in":
        return exc
    head, _, key = exc.field.rpartition(".")
    factor = si_factor(key)
    field = exc.field if factor is None else (f"{head}." if head else "") + inch_key(key)
    value = exc.value
    if factor is not None and value is not MISSING:  # as written (15 digits: x * f / f rounds)
        value = _scale(value, 1.0 / factor)
        value = _round15(value)
    out = SceneError(field, value, convert_text(exc.problem, units),
                     None if exc.allowed is None else convert_text(exc.allowed, units), exc.source)
    return out


# ------------------------------------------------------------------------------------ writing


def report_to(data: Any, units: str) -> Any:
    """result.json's dict in ``units``: for "in" every key with a unit suffix renamed
    (``min_base_radius_mm`` -> ``min_base_radius_in``) and every number under it converted (keys
    such as ``max_deg`` beside it keep theirs); the echoed segments' joint conditions, the flcd
    jumps (per ``flcd_units``) and numbers written with a unit in text (``... 0.001 mm``)
    converted too. "mm": ``data`` itself."""
    if check_units(units) == "mm":
        return data
    out = _report(data, None)
    if isinstance(data, dict) and isinstance(data.get("segments"), list):
        rocking = "oscillating_follower" in data or "lift_deg" in str(data["segments"])
        out["segments"] = [convert_segment(_report(s, None), 1.0 / MM_PER_IN, rocking)
                           for s in data["segments"]]
    if isinstance(data, dict) and isinstance(data.get("flcd_units"), dict):
        scaled = {k: u for k, u in data["flcd_units"].items() if isinstance(u, str) and u.startswith("mm")}
        out["flcd_units"] = {k: (convert_unit_word(u) if k in scaled else u)
                             for k, u in data["flcd_units"].items()}
        if isinstance(data.get("flcd"), list):
            out["flcd"] = [{k: (_num(v, 1.0 / MM_PER_IN) if k in scaled else v) for k, v in j.items()}
                           if isinstance(j, dict) else j for j in out["flcd"]]
    return out


def _report(value: Any, factor: float | None) -> Any:
    """``value`` converted to inches: ``factor`` is the internal value per inch value of the key
    it sits under (None: no unit yet)."""
    if isinstance(value, dict):
        out = {}
        for key, v in value.items():
            m = _si_match(key) if isinstance(key, str) else None
            if key in VERBATIM:
                out[key] = v
            elif m is not None:
                out[key[: -len(m[0])] + m[1]] = _report(v, m[2])
            elif _unitless(key):
                out[key] = _report(v, None)
            else:
                out[key] = _report(v, factor)
        return out
    if isinstance(value, list | tuple):
        return [_report(v, factor) for v in value]
    if isinstance(value, str):
        return convert_text(value, "in")
    if factor is not None and isinstance(value, int | float) and not isinstance(value, bool):
        return value / factor
    return value


def curves_to(curves, units: str):
    """A design's curves (a NamedTuple of arrays and scalars, fields named with their units) with
    every field of a unit suffix converted to ``units`` (the field names kept: the drawing code
    reads them). "mm": ``curves`` itself."""
    if check_units(units) == "mm":
        return curves
    changed = {}
    for name, value in curves._asdict().items():
        factor = si_factor(name)
        if factor is not None:
            changed[name] = _scale_curve(value, 1.0 / factor)
        elif isinstance(value, dict):  # own_curves: each named with its unit
            changed[name] = {k: (v if si_factor(k) is None else _scale_curve(v, 1.0 / si_factor(k)))
                             for k, v in value.items()}
    return curves._replace(**changed)


def _scale_curve(value: Any, factor: float) -> Any:
    if value is None or isinstance(value, str | bool):
        return value
    if isinstance(value, dict):
        return {k: _scale_curve(v, factor) for k, v in value.items()}
    if isinstance(value, list | tuple):
        return type(value)(_scale_curve(v, factor) for v in value)
    import numpy as np

    return np.asarray(value) * factor if not isinstance(value, int | float) else value * factor


def column_names(names: list[str], units: str) -> list[str]:
    """profile.csv's column names in ``units`` (the columns' values come from :func:`curves_to`)."""
    return list(names) if check_units(units) == "mm" else [inch_key(n) for n in names]


# (pattern of an internal unit word, its inch word, internal value per inch value), longest first
_WORDS: tuple[tuple[str, str, float], ...] = (
    (r"N[ ·]m[ ·]s/rad", "lbf·in·s/rad", N_PER_LBF * M_PER_IN),
    (r"N[ ·]m/rad", "lbf·in/rad", N_PER_LBF * M_PER_IN),
    (r"N[ ·]s/m", "lbf·s/in", N_PER_LBF / M_PER_IN),
    (r"N/m", "lbf/in", N_PER_LBF / M_PER_IN),
    (r"N[ ·]m", "lbf·in", N_PER_LBF * M_PER_IN),
    (r"kg[ ·]m\^?2|kg[ ·]m²", "lb·in²", KG_PER_LB * M_PER_IN**2),
    (r"m/s\^?3|m/s³", "in/s³", M_PER_IN),
    (r"m/s\^?2|m/s²", "in/s²", M_PER_IN),
    (r"m/s", "in/s", M_PER_IN),
    (r"mm", "in", MM_PER_IN),
    (r"MPa", "psi", MPA_PER_PSI),
    (r"GPa", "Mpsi", MPA_PER_PSI * 1e3),
    (r"kg", "lb", KG_PER_LB),
    (r"N", "lbf", N_PER_LBF),
)
_NUMBER = r"[-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?"
_UNIT = "|".join(f"(?:{p})" for p, _, _ in _WORDS)
# a number with a unit after it, or "a to b unit" (both numbers in the unit)
_QUANTITY = re.compile(rf"(?<![\w.])({_NUMBER})(?:( to )({_NUMBER}))?( ?)({_UNIT})(?![\w²³^])")
_WORD = re.compile(rf"(?<![\w/·])({_UNIT})(?![\w²³^])")


def _word(unit: str) -> tuple[str, float]:
    for pattern, inch, factor in _WORDS:
        if re.fullmatch(pattern, unit):
            return inch, factor
    raise KeyError(unit)


def convert_text(text: str, units: str) -> str:
    """``text`` with every number written with an internal unit (``28.406 mm``, ``1230 MPa``,
    ``1e-09 to 1e+06 kg``) converted to ``units`` (6 significant digits). "mm": unchanged."""
    if units == "mm" or not isinstance(text, str):
        return text

    def sub(m: re.Match) -> str:
        inch, factor = _word(m.group(5))
        first = f"{float(m.group(1)) / factor:.6g}"
        second = f"{m.group(2)}{float(m.group(3)) / factor:.6g}" if m.group(2) else ""
        return f"{first}{second}{m.group(4)}{inch}"

    return _QUANTITY.sub(sub, text)


def convert_unit_word(text: str) -> str:
    """Unit words of ``text`` (``mm``, ``mm/rad``, ``MPa``, ``N·m``, ``(N)``, ``m/s²``) in inch
    units, numbers untouched: for text whose numbers are already converted (figure labels)."""
    return _WORD.sub(lambda m: _word(m.group(1))[0], text)


def relabel(fig, units: str) -> None:
    """Every text of a matplotlib figure (axis labels, titles, legends, annotations) with its unit
    words in ``units`` (:func:`convert_unit_word`): for figures drawn from :func:`curves_to`'s
    curves, whose numbers are already converted. "mm": nothing."""
    if check_units(units) == "mm":
        return
    from matplotlib.text import Text

    for t in fig.findobj(Text):
        s = t.get_text()
        if s:
            t.set_text(convert_unit_word(s))
