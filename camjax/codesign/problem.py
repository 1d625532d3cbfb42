"""Co-design of a scene's designed laws and the cam's geometry: the bilevel search of ``camjax design``.

A scene with both [design] and ``design = true`` segments asks for the motion and the cam around
it together. The free coordinates z of the designed laws (:mod:`camjax.synthesis.linear`: the
joint conditions met by construction) are the outer variables; for each z the cam's geometry is
the [design] optimum of the follower family's problem built on the kinematics of z:

    F(z) = min_d  f(P(z), d)  subject to  g(P(z), d) <= 0  +  law(z),

f the family's objective (alpha size + gamma stress), g its constraints, P(z) its problem on the
sample grid (the kinematics affine in z, loads and contact coefficient computed from them by
:func:`camjax.evaluate.arrays_from_kinematics`), law(z) the [synthesis] terms that are quadratics
in z: the squared-derivative terms and the mean square residual vibration of the follower train
(:func:`train_quadratics`: the map of :mod:`camjax.synthesis.vibration`, with the scene's
[dynamics] and [synthesis]'s speed band, the same term ``camjax synthesize`` weighs), and the peak
terms (``peak_velocity``, ``peak_accel``, ``peak_jerk``, ``peak_force``: maxima of affine
functions of z, not smooth), which the search takes as smooth maxima sharpened by a continuation
(:mod:`camjax.codesign.peaks`: :attr:`Codesign.taus` set, their gradient added; the exact maxima
when it is None).

- **Inner**: the registered interior-point solver (:data:`INNER_SOLVER`, its KKT residual to
  1e-12) on the grid (``extrema = "grid"``: the problem is a pytree of arrays whose kinematic
  fields are functions of z); the outer search's solves start from the inner optimum of the point
  it moves from (a continuation: the outer steps are small). The scenes the joint program takes
  keep the gradient solver (:data:`JOINT_INNER_SOLVER`).
- **Compiled once per shape**: the pieces are module-level programs whose static argument is the
  :class:`ProblemShape` (what the family's problem reads of the scene, compared by value) and whose
  weights, kinematics and spring are arrays: every z, every weighting of a sweep and every spring
  box of one scene and grid share one program each.
- **Gradient of the inner optimum** by the envelope theorem: at the optimum d* with multipliers
  lambda >= 0 of its active constraints, every angle's its own (from stationarity by nonnegative
  least squares, :func:`camjax.codesign.kkt.multipliers`), dF/dz is the partial derivative in z of
  the Lagrangian f + lambda . g with d* and lambda held fixed (g: the family's ``constraints`` at
  every angle), by ``jax.grad`` through the problem's construction, plus the law terms'.
  tests/test_codesign.py checks it against central differences of F.
- **Spring** (:mod:`camjax.codesign.spring`, where [synthesis] gives spring keys): the preload is
  eliminated in closed form (the least keeping contact at the overspeed: exact, the objective
  grows with it; a rocker's is a moment, its condition on the moment about the pivot), the rate is
  one more outer coordinate u (box transform) after z; the problem is built with that spring (the
  follower train replaced, translating or rocker), and the envelope gradient differentiates
  through both.
- **Outer**: BFGS on z with a backtracking (Armijo) line search, in NumPy (z has tens of
  coordinates); an infeasible inner optimum counts as +inf.
- **Never worse than choosing**: every combination of the built-in laws that meet each designed
  segment's conditions is solved with its own optimal geometry (:func:`builtin_candidates`); the
  search starts from the best of them projected onto the B-spline space and from the law-only
  synthesis, and if it cannot beat the best built-in combination that combination is returned.

Python (a driver of jitted pieces); the pieces are pure JAX.
"""

from __future__ import annotations

import dataclasses
import math
from functools import partial
from typing import Any, NamedTuple

import jax
import jax.numpy as jnp
import numpy as np

import camjax.codesign.helical as helical
import camjax.codesign.peaks as peaks_mod
import camjax.codesign.spring as spring_mod
from camjax.codesign.kkt import multipliers
from camjax.evaluate import arrays_from_kinematics, scene_arrays
from camjax.family import weights_of
from camjax.program import Kinematics
from camjax.solvers.base import Settings, family_of, problem_from_scene, solver_module
from camjax.solvers.box import midpoint
from camjax.solvers.newton import NewtonSettings
from camjax.synthesis.linear import law_quadratics, linear_kinematics
from camjax.synthesis.problem import ALL_OBJECTIVES, L2_OBJECTIVES
from camjax.synthesis.vibration import residual_maps

# the [synthesis] terms the co-design takes: quadratics in z, and the peaks as smooth maxima
SUPPORTED = ALL_OBJECTIVES
RATE_TIE_RTOL = 1e-9  # best_rate: objectives this close (relative) tie (inner solves repeat to ~1e-12)


class CodesignError(ValueError):
    """A scene the co-design cannot take: ``field`` names the scene key."""

    def __init__(self, field: str, message: str):
        super().__init__(f"{field}: {message}")
        self.field = field


class Inner(NamedTuple):
    """The geometry optimum of one set of kinematics (NumPy floats)."""

    objective: float  # the family's objective at its optimum (+inf if infeasible)
    design: Any
    feasible: bool
    spring: tuple[float, float] | None = None  # (rate, preload) solved with: N/m, N (a rocker's N m/rad, N m)


def check_scene(scene) -> dict[str, float]:
    """What the co-design cannot take, as :class:`CodesignError` naming the scene field (a missing
    [design], a pointwise mode, a train term without [dynamics], peak_force with a designed spring,
    a spring it cannot design); returns the [synthesis] terms' weights. Python, cheap: no solve."""
    if scene.design is None:
        raise CodesignError("design", "co-design needs a [design] section")
    if scene.design.mode != "global":
        raise CodesignError("design.mode", f"'{scene.design.mode}': co-design designs one cam for "
                            "the whole turn (allowed: 'global')")
    terms = dict(scene.synthesis.objective) if scene.synthesis is not None else {}
    for name in terms:
        if name not in SUPPORTED:
            raise CodesignError(f"synthesis.objective.{name}", "not a term of the co-design "
                                f"(allowed: {', '.join(SUPPORTED)})")
    for name in ("residual_vibration", "peak_force"):
        if name in terms and scene.dynamics is None:
            raise CodesignError("dynamics", f"synthesis.objective.{name} needs the follower "
                                "train: a [dynamics] section (I3, c3, k23)")
    box = spring_mod.spring_box(scene, CodesignError)
    helical.check_scene(scene, CodesignError)
    if "peak_force" in terms:
        if scene.dynamics.spring_rate is None:
            raise CodesignError("dynamics", "synthesis.objective.peak_force needs the follower "
                                "train's spring (the contact force: give [dynamics]' spring)")
        if box is not None:
            raise CodesignError("synthesis.objective.peak_force", "not taken with a designed spring "
                                "(the train's force is [dynamics]' spring's; allowed: a fixed spring, "
                                "or drop peak_force)")
    return terms


class Codesign:
    """The static data of one co-design and its compiled pieces (see the module docstring)."""

    def __init__(self, scene, samples: int | None = None, controls=None, builtin_cache: dict | None = None):
        """``samples``: the search grid (default the scene's); ``controls``: the normalized control
        values the scene's designed segments move by (default their starting laws);
        ``builtin_cache``: the built-in laws' kinematics and residuals of another co-design of the
        same motion and grid (they do not depend on [design]'s weights; shared by a sweep)."""
        from camjax.scene.designed import starting_control

        terms = check_scene(scene)
        self.scene = scene
        self.law_weights = terms
        self.samples = int(scene.motion.samples if samples is None else samples)
        self.designed = scene.motion.designed
        program = scene.motion.program
        starts = [starting_control(ds) for ds in self.designed] if controls is None else controls
        self.lin = linear_kinematics(program, self.designed, self.samples, starts)
        self.jacobian = jnp.asarray(self.lin.jacobian)
        self.spring = spring_mod.spring_box(scene, CodesignError)
        self.nz = self.lin.free  # the laws' coordinates; the outer x = z, then u (a free rate)
        free_rate = self.spring is not None and self.spring.free_rate
        self.u0 = self._start_rate() if free_rate else None
        self.x0 = np.concatenate([self.lin.z0, [self.u0]]) if free_rate else np.asarray(self.lin.z0)
        grid = dataclasses.replace(scene, motion=dataclasses.replace(scene.motion, extrema="grid"))
        self.grid_scene = grid
        self.theta, self.kin0 = grid_kinematics(grid, self.samples)
        self.train = None
        if scene.dynamics is not None:  # the follower train: its residual term and figures
            from camjax.dynamics.context import synthesis_train

            self.train = synthesis_train(scene)
        per_span = scene.synthesis.samples_per_span if scene.synthesis is not None else 8
        self.peaks = peaks_mod.peak_terms(self.lin, self.designed, terms, per_span, self.train)
        self.taus = None  # the smoothing of the peak terms (None: their exact maxima)
        # per designed segment: (rows, Q) of its residual vibration (None without the train)
        self.residual = ([residual_maps(ds.basis(), self.train, ds) for ds in self.designed]
                         if self.train is not None else None)
        l2 = {n: w for n, w in terms.items() if n in L2_OBJECTIVES}
        self.law_P, self.law_q, self.law_c = law_quadratics(self.lin, self.designed, l2)
        self.l2_quadratic = (self.law_P, self.law_q, self.law_c)
        # law_P, law_q: the gradient of every law term; the residual's value is summed from its
        # rows (law_value: the expanded quadratic cancels to ~1e-8 relative near a zero residual)
        self.residual_weight = float(terms.get("residual_vibration", 0.0))
        if self.residual_weight > 0.0:
            P, q, c = train_quadratics(self.lin, [Q for _, Q in self.residual], self.residual_weight)
            self.law_P, self.law_q, self.law_c = self.law_P + P, self.law_q + q, self.law_c + c
        self.weights = weights_of(scene.design.alpha, scene.design.gamma)
        self.shape = ProblemShape.of(grid, self.spring)
        # the joint program's scenes (no designed spring, no peak terms) keep its inner solver
        self.inner_solver = JOINT_INNER_SOLVER if self.spring is None and self.peaks is None else INNER_SOLVER
        self.evaluations = 0
        self._placeholder = None  # a design of the family's structure: a cold inner solve's start argument
        self.builtin_cache: dict = {} if builtin_cache is None else builtin_cache

    # ------------------------------------------------------------------ pure pieces

    def _start_rate(self) -> float:
        """u of the scene's rate, or of the box's geometric middle where the scene's is outside."""
        lo, hi = self.spring.rate
        k0 = self.spring.scene_rate
        return spring_mod.u_of(self.spring, k0 if lo < k0 < hi else math.sqrt(lo * hi))

    @property
    def free(self) -> int:
        """The number of outer coordinates (the laws' z, and u for a free rate)."""
        return self.x0.size

    def split(self, x):
        """(z, u) of the outer coordinates x (u None without a free rate; traceable)."""
        return x[: self.nz], (x[self.nz] if self.x0.size > self.nz else None)

    def problem(self, kin4, spring=None):
        """The family's problem on kinematics ``kin4`` (4, samples): s, s', s'', s''' (traceable);
        ``spring``: (rate, preload) replacing the scene's (a designed spring: N/m and N, or a rocker's
        N m/rad and N m)."""
        return self.shape.problem(self.theta, kin4, spring)

    @property
    def builder(self) -> ProblemBuilder:
        """:meth:`problem` as a callable equal to that of every co-design of the same shape and grid
        (the static ``build`` of :class:`camjax.codesign.joint.JointProblem`: one compiled joint
        solve for every co-design of one scene and grid, e.g. a sweep's weightings)."""
        return ProblemBuilder(self.shape, self.theta)

    def kinematics(self, z):
        """(4, samples) kinematics of the coordinates z (traceable)."""
        return _kinematics(self.kin0, self.jacobian, self.lin.z0, z)

    def _inner(self, kin4, spring, start=None):
        """(F, design, feasible) of the inner optimum on ``kin4`` with ``spring`` (None: the scene's),
        solved from the design ``start`` (mm; None: the solver's own start)."""
        spring = _rate_preload(spring)
        cold = start is None and self.inner_solver == INNER_SOLVER
        if cold:  # the warm solves' program, from the solver's own start (own_start)
            if self._placeholder is None:
                shapes = jax.eval_shape(lambda k, s: own_start(self.problem(k, s)), jnp.asarray(kin4), spring)
                self._placeholder = jax.tree.map(lambda a: np.zeros(a.shape, a.dtype), shapes)
            start = self._placeholder
        return _inner_program(self.inner_solver, self.shape, self.theta, jnp.asarray(kin4), spring,
                              self.weights, start, np.bool_(cold))

    def _local(self, kin4, spring, design):
        """The objective and every angle's constraints at ``design``, their Jacobian in the design,
        the bounds and the size norm (:func:`_local_program`)."""
        return _local_program(self.shape, self.theta, jnp.asarray(kin4), _rate_preload(spring), design,
                              self.weights)

    def _spring_at(self, kin4, u):
        """(k, P, P_min): the rate of u, the optimal preload and the least keeping contact."""
        return _spring_program(self.spring, jnp.asarray(kin4), u)

    # ------------------------------------------------------------------ evaluations

    def law_value(self, x) -> float:
        """The [synthesis] terms at the outer x: the squared-derivative terms' quadratic in z, plus
        the weighted mean square residual of each designed law (from its rows on c(z))."""
        z = np.asarray(x, dtype=np.float64)[: self.nz]
        P, q, c = self.l2_quadratic
        value = float(0.5 * z @ P @ z + q @ z + c)
        if self.residual_weight > 0.0:
            for control, (rows, _) in zip(self.lin.control(z), self.residual, strict=True):
                value += self.residual_weight * float(np.mean(np.sum((rows @ control) ** 2, axis=1)))
        if self.peaks is not None:
            value += (peaks_mod.exact_value(self.peaks, z) if self.taus is None else
                      peaks_mod.smooth_value(self.peaks, z, self.taus)[0])
        return value

    def inner(self, kin4, u=None, start=None) -> Inner:
        """The geometry optimum on ``kin4``; with a designed spring at the rate of ``u`` (default
        the start's) and the optimal preload, +inf where no preload in the box keeps contact.
        ``start``: the design (mm) the solve starts from (a warm start: a nearby inner optimum;
        None: the solver's own start), taken by the interior-point solver only (the gradient
        solver's Rprop restarts with its full step from any start: no step saved)."""
        self.evaluations += 1
        spring = None
        if self.spring is not None:
            u = self.u0 if u is None else u
            k, p, need = (float(v) for v in jax.device_get(
                self._spring_at(kin4, None if u is None else np.float64(u))))
            spring = (k, p)
            high = self.spring.preload[1]
            if not need <= high + spring_mod.PRELOAD_TOL * max(1.0, abs(high)):
                return Inner(math.inf, None, False, spring)
        start = start if self.inner_solver == INNER_SOLVER else None
        f, d, ok = jax.device_get(self._inner(kin4, spring, start))
        return Inner(float(f) if bool(ok) and np.isfinite(f) else math.inf, d, bool(ok), spring)

    def value(self, x, start=None) -> tuple[float, Inner]:
        """F(x) and the inner optimum (x: the laws' z, then u for a free rate); ``start``: the
        inner solve's start (:meth:`inner`)."""
        z, u = self.split(np.asarray(x, dtype=np.float64))
        inner = self.inner(self.kinematics(z), u, start)
        return inner.objective + self.law_value(x), inner

    def gradient(self, x, inner: Inner) -> np.ndarray:
        """dF/dx by the envelope theorem at the inner optimum ``inner`` of x."""
        x = np.asarray(x, dtype=np.float64)
        kin4 = self.kinematics(x[: self.nz])
        values, jac, lower, upper, norm = jax.device_get(self._local(kin4, inner.spring, inner.design))
        lam = multipliers(values, jac, inner.design, lower, upper, norm)
        if self.spring is None:  # through the kinematics, chained with J
            gk = _kin_lagrangian_grad(self.shape, self.theta, kin4, inner.design, jnp.asarray(lam), None,
                                      self.weights)
            g = np.asarray(jnp.tensordot(gk, self.jacobian, axes=((0, 1), (0, 1))))
        else:  # x's rate and the preload it implies too
            g = np.asarray(_lagrangian_grad(self.shape, self.spring, self.theta, self.kin0, self.jacobian,
                                            jnp.asarray(self.lin.z0), jnp.asarray(x), inner.design,
                                            jnp.asarray(lam), self.weights))
        # (g + P z) + q: the order of the sums as ever (the search's path is sensitive to rounding)
        gz = g[: self.nz] + self.law_P @ x[: self.nz] + self.law_q
        if self.peaks is not None:  # the smooth peaks' (the last stage's smoothing where none is set)
            taus = self.taus if self.taus is not None else peaks_mod.schedule(self.peaks, x[: self.nz])[-1]
            gz = gz + peaks_mod.smooth_value(self.peaks, x[: self.nz], taus)[1]
        return np.concatenate([gz, g[self.nz:]])

    def best_rate(self, kin4, count: int = 9, refine: int = 12) -> tuple[float, Inner]:
        """The rate (as u) with the least objective on fixed kinematics ``kin4``: ``count`` rates
        geometric over the box, then golden-section search in log k between the best one's
        neighbours (``refine`` intervals, each inside the last by the golden ratio; one solve
        each, the other interior point kept), each solve from the best geometry so far. Objectives
        within :data:`RATE_TIE_RTOL` are a tie, won by the softer spring (F is often flat in the
        rate near the box's low end; which rate wins there would be the inner solve's rounding).
        Python; a fixed rate: the inner optimum at it."""
        if self.u0 is None:
            return 0.0, self.inner(kin4)
        lo, hi = (math.log(v) for v in self.spring.rate)

        def u_at(t):
            return spring_mod.u_of(self.spring, math.exp(lo + t * (hi - lo)))

        ts = np.linspace(0.0, 1.0, count)
        inners = [self.inner(kin4, u_at(t)) for t in ts]
        fs = np.asarray([inn.objective for inn in inners])
        i = int(np.argmax(fs <= fs.min() + RATE_TIE_RTOL * abs(fs.min()))) if np.isfinite(fs.min()) else 0
        best = (u_at(ts[i]), inners[i])
        if not np.isfinite(best[1].objective):
            return best
        a, b = ts[max(i - 1, 0)], ts[min(i + 1, count - 1)]
        ratio = (math.sqrt(5.0) - 1.0) / 2.0

        def solved(t):  # from the best geometry so far: a neighbouring rate's (a warm start)
            nonlocal best
            inn = self.inner(kin4, u_at(t), best[1].design)
            if inn.objective < best[1].objective - RATE_TIE_RTOL * abs(best[1].objective):
                best = (u_at(t), inn)
            return inn.objective

        c, d = b - ratio * (b - a), a + ratio * (b - a)
        fc, fd = solved(c), solved(d)
        for _ in range(refine - 1):  # one interior point kept: one new solve per shrink
            if fc <= fd:
                b, d, fd = d, c, fc
                c = b - ratio * (b - a)
                fc = solved(c)
            else:
                a, c, fc = c, d, fd
                d = a + ratio * (b - a)
                fd = solved(d)
        return best

    def gradient_fd(self, z, h: float = 1e-5) -> np.ndarray:
        """dF/dx by central differences of F (2 inner solves per coordinate)."""
        z = np.asarray(z, dtype=np.float64)
        out = np.zeros_like(z)
        for i in range(z.size):
            e = np.zeros_like(z)
            e[i] = h
            out[i] = (self.value(z + e)[0] - self.value(z - e)[0]) / (2.0 * h)
        return out


# ------------------------------------------------------------------ compiled pieces
# One compiled program per problem shape, shared by every Codesign of it: the scene's values enter
# as the static ProblemShape (compared by value) or as arrays (the weights, the kinematics, the
# spring), so a sweep's weightings and the co-designs of one scene with other spring boxes reuse the
# programs of the first.

# the inner geometry solve: the registered interior-point solver, its scaled KKT residual driven to
# 1e-12 (its default 1e-9 leaves F ~5e-10 relative above the optimum; the envelope gradient is
# checked against central differences of F with h = 1e-5, which amplify that scatter by 1e5), 12
# trial step lengths (of 30 by default: the same steps on the co-designs' inner problems in 2/3 of
# the time). The search's solves start warm, from the inner optimum of the point it moves from
# (:meth:`Codesign.value`'s ``start``): ~10 Newton steps where the solver's own start takes ~25.
# The gradient solver (Rprop to its 1000-step cap, then its BFGS refinement: ~1,050 steps a solve)
# gave the same optima but F only to ~3e-9 relative between two solves of one problem, the noise
# the outer line search then spent most of its trials on; 3.5 x the CPU per solve
# Its grids are solved whole (``exchange_angles`` = 0, not the exchange rounds of a design's solve):
# the search stalls on the piecewise-smooth F where the inner optima's last bits put it, and with
# the rounds' optima (the same to the 1e-12 KKT residual) the spring scene's free search of
# tests/test_codesign_spring.py stalled 1.15e-4 above the fixed rate's (its STALL_SCATTER: 5e-5).
INNER_SOLVER = "newton"
INNER_SETTINGS = Settings.of_solvers(newton=NewtonSettings(tol=1e-12, line_search_trials=12,
                                                          exchange_angles=0))
# the inner solve of a co-design the joint program takes (camjax.codesign.joint: no designed spring,
# no peak terms): the gradient solver, as before the bilevel search took the interior-point one. Its
# solves there are few (the built-in floor, the start, the end: 68 of the `codesign` scene's 43 CPU
# s), and the joint solve runs from the start's geometry to its evaluation cap (24,000 on that
# scene), so the start's last digits move its end: with the interior-point solver the scene's
# objective moved 0.41884 -> 0.41908 (R_b 15.67 -> 15.97 mm) for no time saved
JOINT_INNER_SOLVER = "gradient"


class ProblemShape:
    """What the compiled pieces of a co-design read from its scene: the grid scene without what
    the family's problem does not read (its name, [synthesis], [design]'s weights, which are an
    argument), and the spring box's follower train (the rate and preload are arguments). Equal
    when their text is: the static argument of the compiled pieces."""

    def __init__(self, scene, train_box):
        self.scene = scene
        self.train_box = train_box  # a SpringBox whose train and kind alone are read (train_of), or None
        self.key = repr((scene, train_box))

    @classmethod
    def of(cls, grid_scene, box) -> ProblemShape:
        """The shape of a co-design's grid scene and its spring box (None: the scene's spring)."""
        design = dataclasses.replace(grid_scene.design, alpha=1.0, gamma=1.0)
        scene = dataclasses.replace(grid_scene, name="", synthesis=None, design=design)
        train_box = None if box is None else box._replace(rate=(1.0, 1.0), preload=(0.0, 0.0), min_force=0.0,
                                                          overspeed=1.0, omega_os=0.0)
        return cls(scene, train_box)

    def __eq__(self, other) -> bool:
        return isinstance(other, ProblemShape) and self.key == other.key

    def __hash__(self) -> int:
        return hash(self.key)

    def problem(self, theta, kin4, spring=None):
        """The family's problem on kinematics ``kin4`` (4, samples) at the grid's angles ``theta``;
        ``spring``: (rate, preload) replacing the scene's (traceable)."""
        kin = Kinematics(theta, kin4[0], kin4[1], kin4[2], kin4[3])
        scene = self.scene
        if spring is not None:
            train = spring_mod.train_of(self.train_box, spring[0], spring[1])
            scene = dataclasses.replace(scene, follower=dataclasses.replace(scene.follower, train=train))
        return problem_from_scene(scene, arrays_from_kinematics(scene, kin))


class ProblemBuilder:
    """``build(kin4, spring=None)``: the family's problem of a :class:`ProblemShape` on the grid's
    angles ``theta`` (:meth:`ProblemShape.problem`), equal (and hashing alike) where the shape and
    the angles are: a static argument of compiled programs that another co-design of the same scene
    and grid reuses (a bound method of each co-design is a new one, compiled again)."""

    def __init__(self, shape: ProblemShape, theta):
        self.shape = shape
        self.theta = theta
        self._angles = np.asarray(theta)

    def __call__(self, kin4, spring=None):
        return self.shape.problem(self.theta, kin4, spring)

    def __eq__(self, other) -> bool:
        return (isinstance(other, ProblemBuilder) and self.shape == other.shape
                and np.array_equal(self._angles, other._angles))

    def __hash__(self) -> int:
        return hash((self.shape, self._angles.shape))


KINEMATICS_KEPT = 32  # grid kinematics kept by grid_kinematics (the oldest dropped first)
_KINEMATICS: dict[str, tuple] = {}


def grid_kinematics(grid_scene, samples: int):
    """(theta, kin0): the grid's angles (rad) and the (4, samples) kinematics (s and its first three
    derivatives) of the scene's motion by :func:`camjax.evaluate.scene_arrays`, which compiles a
    program per scene; kept per motion and grid, so the co-designs of one motion (a sweep's
    weightings, the fixed springs of one box) take the same arrays without compiling it again (the
    kinematics read the motion's program alone)."""
    motion = grid_scene.motion
    leaves, tree = jax.tree.flatten(motion.program)  # the segment tables, the laws, the lifts (scaled)
    key = repr((motion, str(tree), [np.asarray(v).tobytes() for v in leaves], int(samples)))
    if key not in _KINEMATICS:
        kin = scene_arrays(grid_scene, samples=samples, extrema="grid").kin
        if len(_KINEMATICS) >= KINEMATICS_KEPT:
            del _KINEMATICS[next(iter(_KINEMATICS))]
        _KINEMATICS[key] = (kin.theta, jnp.stack([kin.s, kin.ds, kin.d2s, kin.d3s]))
    return _KINEMATICS[key]


def _rate_preload(spring):
    """A (rate, preload) argument of the compiled pieces as float64 scalars (None stays None): a
    Python float and a NumPy one are other argument types to ``jax.jit`` (weak and strong), each
    compiled once more for the same program."""
    return None if spring is None else tuple(np.float64(v) for v in spring)


def _kinematics(kin0, jacobian, z0, z):
    """(4, samples) kinematics kin0 + J (z - z0) of the laws' coordinates z (traceable)."""
    return kin0 + jnp.tensordot(jacobian, jnp.asarray(z) - z0, axes=1)


def _spring_fn(box, kin4, u):
    k = spring_mod.rate_of(box, u)
    p, need = spring_mod.preload_of(box, kin4, k)
    return k, p, need


_spring_program = jax.jit(_spring_fn, static_argnums=0)


def inner_solve(problem, weights, start=None, solver: str = INNER_SOLVER):
    """(F, design, feasible): the geometry optimum of a grid problem by ``solver`` from
    ``start`` (a design, mm; None: the solver's own start), judged by the family's evaluation (on
    the grid: a solution's polish moves nothing without exact extrema). Traceable."""
    raw = solver_module(solver).run_one(problem, weights, jax.random.key(0), INNER_SETTINGS, start)
    ev = family_of(problem).evaluate(problem, weights, raw.design)
    return ev.objective, raw.design, ev.feasible


def own_start(problem):
    """The design the inner solver starts from without a start given: the family's ``start``, or
    the middle of its box (:func:`camjax.solvers.newton.minimize`'s default). Traceable."""
    return getattr(family_of(problem), "start", midpoint)(problem)


@partial(jax.jit, static_argnums=(0, 1))
def _inner_program(solver: str, shape: ProblemShape, theta, kin4, spring, weights, start, cold):
    """:func:`inner_solve` on the shape's problem; ``start`` a design and ``cold`` True: from
    :func:`own_start` instead (one program for the cold and the warm solves: ``start`` is then a
    placeholder of the design's structure), ``start`` None: the solver's own start."""
    problem = shape.problem(theta, kin4, spring)
    if start is not None:
        start = jax.tree.map(lambda own, given: jnp.where(cold, own, given), own_start(problem), start)
    return inner_solve(problem, weights, start, solver)


@partial(jax.jit, static_argnums=0)
def _local_program(shape: ProblemShape, theta, kin4, spring, design, weights):
    problem = shape.problem(theta, kin4, spring)
    family = family_of(problem)

    def parts(d):
        g = _stacked(family, problem, d)
        return jnp.concatenate([family.objective(problem, weights, d)[None], g])

    jac = jax.jacobian(parts)(design)
    return parts(design), jac, problem.lower, problem.upper, family.size_norm(problem)


def _kin_lagrangian(shape: ProblemShape, theta, kin4, design, lam, spring, weights):
    """f + lam . g on kinematics ``kin4`` at ``design`` (every angle's constraint its own lam)."""
    problem = shape.problem(theta, kin4, spring)
    family = family_of(problem)
    return family.objective(problem, weights, design) + jnp.dot(lam, _stacked(family, problem, design))


_kin_lagrangian_grad = jax.jit(jax.grad(_kin_lagrangian, argnums=2), static_argnums=0)


@partial(jax.jit, static_argnums=(0, 1))
def _lagrangian_grad(shape: ProblemShape, box, theta, kin0, jacobian, z0, x, design, lam, weights):
    """d/dx of f + lam . g at ``design`` as a function of the outer x = (z, u): the kinematics of z,
    the rate of u and the preload they imply (a designed spring)."""
    nz = jacobian.shape[-1]

    def lagrangian(v):
        z, u = v[:nz], (v[nz] if v.shape[0] > nz else None)
        kin4 = _kinematics(kin0, jacobian, z0, z)
        return _kin_lagrangian(shape, theta, kin4, design, lam, _spring_fn(box, kin4, u)[:2], weights)

    return jax.grad(lagrangian)(x)


def train_quadratics(lin, grams, weight: float) -> tuple[np.ndarray, np.ndarray, float]:
    """``weight`` x the residual vibration squared (mean square over the speeds, per lift) summed over
    the designed segments, each c^T Q c with Q in ``grams``
    (:func:`camjax.synthesis.vibration.residual_maps`), as 0.5 z^T P z + q^T z + const in the
    coordinates z of ``lin`` (c = cp + N z), as :func:`camjax.synthesis.linear.law_quadratics`
    writes the squared-derivative terms."""
    m = lin.free
    P, q, const = np.zeros((m, m)), np.zeros(m), 0.0
    for seg, Q in zip(lin.segments, grams, strict=True):
        sl = slice(seg.offset, seg.offset + seg.null.shape[1])
        NQ = seg.null.T @ Q
        P[sl, sl] += 2.0 * weight * NQ @ seg.null
        q[sl] += 2.0 * weight * NQ @ seg.cp
        const += weight * float(seg.cp @ Q @ seg.cp)
    return P, q, const


def _stacked(family, problem, design):
    """Every constraint of the family at every angle, g <= 0 (mm), as one vector."""
    return jnp.concatenate([jnp.atleast_1d(g) for g in family.constraints(problem, design)])
