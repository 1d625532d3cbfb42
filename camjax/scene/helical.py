"""[synthesis.helical_spring]: the material and ranges of a helical compression spring sized for
the co-design's spring (:mod:`camjax.codesign.helical`). Every problem is a SceneError naming the key.
"""

from __future__ import annotations

from camjax.scene.reader import TableReader, build
from camjax.scene.spec import HelicalSpec

HELICAL_KEYS = ("shear_modulus_GPa", "density_kg_m3", "allowable_shear_MPa", "wire_mm", "coil_mm",
                "surge_ratio", "harmonics", "spectrum_tail", "index", "active_coils", "end_coils")
MAX_HARMONIC = 1000  # a given highest harmonic: far above any cam's (the spectrum's is 5 to 30)


def parse_helical(r: TableReader) -> HelicalSpec:
    """The sub-table's :class:`HelicalSpec`: ``allowable_shear_MPa``, ``wire_mm`` and ``coil_mm``
    ([low, high], 0 < low <= high) required; ``index`` [low, high] with low > 1 (the Wahl factor's
    pole at C = 1); ``surge_ratio`` >= 0 (0: no surge constraint); ``harmonics`` an integer >= 1, or
    ``spectrum_tail`` in (0, 0.5] (not both)."""
    r.check_keys(HELICAL_KEYS)
    opt = {}
    for key in ("shear_modulus_GPa", "density_kg_m3"):
        if r.has(key):
            opt[key] = r.number(key, low=0.0, low_open=True)
    tau = r.number("allowable_shear_MPa", low=0.0, low_open=True)
    wire, coil = r.interval("wire_mm"), r.interval("coil_mm")
    if r.has("surge_ratio"):
        opt["surge_ratio"] = r.number("surge_ratio", low=0.0, high=1e3)
    if r.has("harmonics") and r.has("spectrum_tail"):
        raise r.error("spectrum_tail", r.table["spectrum_tail"], "is for the harmonic found from the "
                      "spectrum: harmonics is given", "one of harmonics, spectrum_tail")
    if r.has("harmonics"):
        opt["harmonics"] = int(r.number("harmonics", low=1, high=MAX_HARMONIC, integer=True))
    if r.has("spectrum_tail"):
        opt["spectrum_tail"] = r.number("spectrum_tail", low=0.0, low_open=True, high=0.5)
    if r.has("index"):
        index = r.interval("index")
        if index[0] <= 1.0:
            raise r.error("index", r.table["index"], "the spring index C = D/d must exceed 1 (the Wahl "
                          "factor has a pole at C = 1)", "[low, high] with 1 < low <= high, e.g. [4, 12]")
        opt["index"] = index
    if r.has("active_coils"):
        opt["active_coils"] = r.interval("active_coils")
    if r.has("end_coils"):
        opt["end_coils"] = r.number("end_coils", low=0.0, high=1e3)
    return build(HelicalSpec, allowable_shear_MPa=tau, wire_mm=wire, coil_mm=coil, **opt)
