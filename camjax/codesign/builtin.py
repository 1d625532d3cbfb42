"""The built-in laws of a co-design's joint classes, each combination with its own optimal geometry.

For every designed segment the built-in laws (:data:`camjax.laws.LAWS`) that meet its conditions
(:func:`camjax.synthesis.segments.meets_conditions`: the same joint class) are candidates; every
combination (one law per segment) is played on the grid and its geometry optimized by the same
inner solve as the search's, so "the best built-in law with its own optimal geometry" is measured
on the same footing as the co-designed laws.
"""

from __future__ import annotations

import functools
import itertools
import math

import jax.numpy as jnp
import numpy as np

from camjax.codesign.problem import Codesign, Inner
from camjax.laws import LAWS
from camjax.synthesis.linear import segment_samples
from camjax.synthesis.segments import builtin_measures, builtin_q, meets_conditions, term_value
from camjax.synthesis.vibration import builtin_train_measures

MAX_COMBINATIONS = 256  # built-in law combinations solved (more: one law for every segment)
RATE_REFINED = 3  # with a free spring rate: the best combinations at the start's rate given their own

def builtin_candidates(designed) -> list[list[str]]:
    """Per designed segment, the built-in laws that meet its conditions (its joint class)."""
    return [[name for name, law in LAWS.items() if meets_conditions(law, ds)] for ds in designed]


def builtin_kinematics(cd: Codesign, names) -> jnp.ndarray:
    """(4, samples) kinematics with designed segment k moving by the built-in law ``names[k]``."""
    program = cd.scene.motion.program
    lifts = np.asarray(program.lifts, dtype=np.float64)
    signs = [1.0 if k == "rise" else -1.0 if k == "return" else 0.0 for k in program.kinds]
    levels = np.concatenate([[0.0], np.cumsum(lifts * np.asarray(signs))])
    kin = np.array(cd.kin0)
    for ds, name in zip(cd.designed, names, strict=True):
        i = ds.index
        rows, x = segment_samples(program, i, cd.samples)
        q = cd.builtin_cache.get((name, i))
        if q is None:  # each law compiles per shape: once per segment
            q = cd.builtin_cache[(name, i)] = builtin_q(LAWS[name], program.kinds[i], x)
        signed, beta = signs[i] * lifts[i], math.radians(program.angles_deg[i])
        kin[0, rows] = levels[i] + signed * q[0]
        for r in (1, 2, 3):
            kin[r, rows] = signed * q[r] / beta**r
    return jnp.asarray(kin)


@functools.cache
def _builtin_measures(name: str, kind: str) -> dict:
    return builtin_measures(LAWS[name], kind)


def builtin_law_value(cd: Codesign, names) -> float:
    """The [synthesis] terms of built-in laws (their exact figures, :func:`builtin_measures`; the
    residual vibration squared, as the designed laws' term, from :func:`builtin_residual`)."""
    total = 0.0
    for ds, name in zip(cd.designed, names, strict=True):
        m = dict(_builtin_measures(name, ds.kind))
        if "residual_vibration" in cd.law_weights:
            m["residual_vibration"] = builtin_residual(cd, name, ds)["residual_vibration"]
        if "peak_force" in cd.law_weights:
            m["peak_force"] = builtin_residual(cd, name, ds, force=True)["peak_force"]
        total += sum(w * term_value(term, m[term]) for term, w in cd.law_weights.items())
    return total


def builtin_residual(cd: Codesign, name: str, ds, force: bool = False) -> dict:
    """The residual vibration of the built-in law ``name`` played as designed segment ``ds`` on the
    co-design's follower train (:func:`camjax.synthesis.vibration.builtin_train_measures`: RMS over
    the speeds, per lift, and its values per speed), cached per law and segment; ``force``: its
    peak contact force (N) too, with the train's spring."""
    key = ("residual", name, ds.index, force)
    if key not in cd.builtin_cache:
        q_of = functools.partial(builtin_q, LAWS[name], ds.kind)
        train = cd.train if force else cd.train._replace(spring_rate=None)  # the residual alone: no force
        cd.builtin_cache[key] = builtin_train_measures(q_of, train, ds)
    return cd.builtin_cache[key]


def best_builtin_combination(cd: Codesign) -> tuple[tuple[str, ...], float, Inner] | None:
    """The combination of built-in laws (one per designed segment, each meeting its conditions)
    with the least co-design objective, each with its own optimal geometry: (names, F, inner).
    With a free spring rate every combination is solved at the start's rate, then the
    :data:`RATE_REFINED` best get their own optimal rate (:meth:`Codesign.best_rate`); the preload is
    each one's optimal at its rate (:mod:`camjax.codesign.spring`)."""
    cands = builtin_candidates(cd.designed)
    if any(not c for c in cands):
        return None
    combos = list(itertools.product(*cands))
    if len(combos) > MAX_COMBINATIONS:
        common = set.intersection(*(set(c) for c in cands))
        combos = [tuple([n] * len(cands)) for n in LAWS if n in common]
    solved = []
    for names in combos:
        inner = cd.inner(builtin_kinematics(cd, names))
        solved.append((inner.objective + builtin_law_value(cd, names), tuple(names), inner))
    solved.sort(key=lambda t: t[0])
    if cd.u0 is not None:
        for j, (_, names, _) in enumerate(solved[:RATE_REFINED]):
            inner = cd.best_rate(builtin_kinematics(cd, names))[1]
            solved[j] = (inner.objective + builtin_law_value(cd, names), names, inner)
    f, names, inner = min(solved, key=lambda t: t[0])
    return names, f, inner


def fitted_coordinates(cd: Codesign, names) -> np.ndarray:
    """z of the B-spline laws nearest (least squares on 401 points, within the conditions) to the
    built-in laws ``names``."""
    from camjax.synthesis.basis import evaluation_matrix

    x = np.linspace(0.0, 1.0, 401)
    z = np.zeros(cd.lin.free)
    for seg, ds, name in zip(cd.lin.segments, cd.designed, names, strict=True):
        E = evaluation_matrix(ds.basis(), x, 0)
        target = builtin_q(LAWS[name], ds.kind, x)[0]
        m = seg.null.shape[1]
        z[seg.offset: seg.offset + m] = np.linalg.lstsq(E @ seg.null, target - E @ seg.cp, rcond=None)[0]
    return z
