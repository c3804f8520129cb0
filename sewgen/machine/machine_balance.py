"""Whole-machine balancing: seed 000 part 2's three methods on the upper shaft's counterweight planes.

Seed 000 part 1 §四 optimises the two upper-shaft bearing reactions; its part 2 compares three balancing methods
(only its table of contents survives: 一 the first method, 二 the whole machine's balancing theory, 三 a numerical
optimisation with the two bearing reactions as the objective, 四 an evaluation of the effect). Here:

* **separate** (method 1, seed 002 generalised): each group balanced by itself by a counterweight on its own
  plane, minimising w₁·max|F| + w₂·mean|F| of that group's shaking force on the frame (seed 002's objective; its
  weights 0.1, 0.9 by default) — the rotating masses are balanced fully and the reciprocating ones by the
  factor the optimum chooses;
* **harmonic** (method 2): the machine's shaking force and moments on the frame about x and y as harmonic orders of
  φ; the counterweights cancel the forward-rotating first order of both (a counterweight turning with the shaft
  makes nothing else; the backward-rotating first order of a reciprocating mass needs a counter-rotating shaft
  and is reported as residual);
* **bearings** (method 3): minimise the peak (or the RMS) over a revolution of the front and rear bearing loads,
  optionally plus a weight times the shaking force on the frame, over the counterweights' m·r vectors within
  their bounds.

The shaking force and moments are the ones on the frame, inertia only (−Σ m a_G; sewgen.machine.shaking states
the convention): the moving parts' weight is constant and no counterweight turning with the shaft changes it.

Every quantity the methods look at is affine in the counterweights' m·r vectors u_k (a point mass m at radius r
and angle α from the crank direction φ puts m r ω² e(φ + α) on the shaft at its z): the influence of each u_k is
taken from the machine analysis itself (a test mass at α = 0 and at α = 180° differenced: its weight cancels),
so the linear model and :meth:`MachineAnalysis.bearing` agree exactly. The peak problem is a second-order-cone
program and the RMS one a constrained least-squares problem: both are solved exactly with CVXPY (Clarabel),
whose primal and dual objectives give the optimality gap. The optimum leaves out the counterweights' own weight
(constant, a fraction of a newton); the "after" figures come from analysing the balanced machine, weight
included — the very numbers ``sewgen analyze`` gives for the written model file.

The methods work on the machine analysed every :data:`STEP_DEG` at most (the model's step where it is finer): a
peak objective on coarse samples is minimised where the samples are, not between them (JB1-3 at 5°: the rear
bearing's "peak" fell from 182 to 178 N while the true peak rose from 190 to 194 N). The "before" and "after"
figures (:func:`metrics`) take every peak refined between the samples (sewgen.machine.peaks: the machine solved
again around each sampled peak), so the improvement they report is the machine's own.
"""
from __future__ import annotations

import math
import tomllib
from dataclasses import dataclass, replace

import numpy as np

from sewgen.errors import SewgenError
from sewgen.machine import shaking
from sewgen.machine.assembly import Machine, MachineAnalysis, ShaftMass
from sewgen.machine.modelfile import Plane, read_counterweights
from sewgen.machine.peaks import extremes

METHODS = ("separate", "harmonic", "bearings")
OBJECTIVES = ("peak", "rms")
DEFAULT_WEIGHTS = (0.1, 0.9)  # seed 002: w1·max|F| + w2·mean|F|
#: The largest step (deg) of the analyses the methods balance and evaluate: on JB1-3 a 1° sweep gives the RMS and
#: the orders of the loads within 0.2 % of a 0.1° sweep (5°: 0.6 %), and a peak between its samples only
#: ~ f″h²/8 above the sampled one (the rear bearing: 0.02 %) where the objective constrains the samples.
STEP_DEG = 1.0


class BalancingError(SewgenError, ValueError):
    """A balancing problem that cannot be set up or solved (names the machine and what is wrong)."""


@dataclass(frozen=True)
class Counterweight:
    """A counterweight chosen on a plane: m·r (kg·m) at ``angle`` (rad, from the crank direction φ)."""

    plane: Plane
    mr: float
    angle: float

    @property
    def mass(self) -> float:
        return self.mr / self.plane.radius

    def shaft_mass(self) -> ShaftMass:
        return ShaftMass(self.plane.name, self.mass, self.plane.radius, self.angle % (2 * math.pi), self.plane.z)

    def as_dict(self) -> dict:
        return {"name": self.plane.name, "z": self.plane.z, "mr": self.mr, "angle": self.angle % (2 * math.pi),
                "mass": self.mass, "radius": self.plane.radius}


def planes_of(machine: Machine) -> list[Plane]:
    """The counterweight planes of a machine's model file (``[[shaft.counterweights]]``)."""
    return read_counterweights(machine.source, [g.name for g in machine.groups])


# -- the machine with counterweights, and what they change --------------------------------------------------------

def with_counterweights(machine: Machine, counterweights) -> Machine:
    """A copy of ``machine`` with the counterweights added to the shaft's point masses."""
    shaft = replace(machine.shaft, masses=list(machine.shaft.masses) + [c.shaft_mass() for c in counterweights])
    return replace(machine, shaft=shaft)


def reanalyse(base: MachineAnalysis, counterweights) -> MachineAnalysis:
    """The machine analysis with the counterweights added, reusing the group sweeps (they do not change)."""
    return MachineAnalysis(with_counterweights(base.machine, counterweights), base.phi, base.groups)


def _quantities(a: MachineAnalysis) -> dict:
    """The (n, 2) quantities the methods shape: bearing loads on the frame, the shaking force on the frame, the
    shaking moments on the frame (about x, y) about the front bearing's point on the axis."""
    z0 = a.machine.shaft.front
    moments = a.shaking_moments_on_frame((0.0, 0.0, z0))
    return {"front": a.bearing("front"), "rear": a.bearing("rear"), "force": a.shaking_force_on_frame,
            "moment": moments[:, :2]}


@dataclass
class LinearModel:
    """Every quantity q(u) = q0 + Σ_k G_k u_k, u_k = m·r of plane k as a vector (kg·m) in the crank frame."""

    planes: list
    base: dict  # name -> (n, 2)
    gain: dict  # name -> (n, 2, 2K): columns (u_0x, u_0y, u_1x, ...)

    def at(self, u: np.ndarray) -> dict:
        return {k: self.base[k] + self.gain[k] @ u for k in self.base}


def linear_model(base: MachineAnalysis, planes: list[Plane]) -> LinearModel:
    """The exact affine model of :func:`_quantities` in the counterweights (from the analysis: see the module)."""
    if not planes:
        raise BalancingError(f"{base.machine.name}: the model file has no [[shaft.counterweights]] planes")
    q0 = _quantities(base)
    gain = {k: np.zeros(v.shape + (2 * len(planes),)) for k, v in q0.items()}
    test = 1e-3  # kg·m of the test mass: any size gives the same columns (affine)
    for k, plane in enumerate(planes):
        for j, angle in enumerate((0.0, math.pi / 2)):
            plus = _quantities(reanalyse(base, [Counterweight(plane, test, angle)]))
            minus = _quantities(reanalyse(base, [Counterweight(plane, test, angle + math.pi)]))
            for name in q0:
                gain[name][:, :, 2 * k + j] = (plus[name] - minus[name]) / (2 * test)
    return LinearModel(planes, q0, gain)


def counterweights_of(planes, u, clip: bool = False) -> list[Counterweight]:
    """The counterweights of the m·r vectors ``u`` (2 per plane); ``clip``: brought inside the planes' bounds
    (an interior-point solve ends within its tolerance, ~1e-5, of an active bound, on either side)."""
    u = np.asarray(u, dtype=float).reshape(-1, 2)
    out = []
    for p, v in zip(planes, u):
        mr = float(math.hypot(*v))
        out.append(Counterweight(p, min(mr, p.max_mr) if clip else mr, float(math.atan2(v[1], v[0]))))
    return out


# -- the three methods ---------------------------------------------------------------------------------------------

@dataclass
class Solution:
    counterweights: list
    objective: float | None
    gap: float | None  # primal − dual objective of the convex solve (None where no solver ran)
    status: str


def _solve(problem, machine: str):
    import cvxpy as cp

    try:  # tolerances below the default 1e-8: the peak the counterweights give within 1e-7 of the optimum's
        problem.solve(solver=cp.CLARABEL, tol_gap_abs=1e-10, tol_gap_rel=1e-10, tol_feas=1e-10)
    except cp.error.SolverError as exc:
        raise BalancingError(f"{machine}: the convex solver failed ({exc})") from None
    if problem.status not in ("optimal", "optimal_inaccurate"):
        raise BalancingError(f"{machine}: the balancing problem is {problem.status}")
    return float(problem.value), _gap(problem), problem.status


def _gap(problem) -> float | None:
    """Primal minus dual objective of the conic problem Clarabel solves (the optimality certificate): CVXPY keeps
    Clarabel's dual objective to itself, so the same conic data are solved once more directly."""
    import cvxpy as cp

    try:
        data, chain, _inverse = problem.get_problem_data(cp.CLARABEL)
        raw = chain.solve_via_data(problem, data, False, False, {})
        return float(raw.obj_val - raw.obj_val_dual)
    except Exception:  # CVXPY's internals moved: no certificate rather than no answer
        return None


def _bounds(cp, u, planes):
    return [cp.norm(u[2 * k:2 * k + 2]) <= p.max_mr for k, p in enumerate(planes)]


def bearings(model: LinearModel, objective: str = "peak", shaking_weight: float = 0.0, machine: str = "") -> Solution:
    """Method 3: min over u of max_i max(|R_A,i|, |R_B,i|) (peak) or √(mean_i (|R_A,i|² + |R_B,i|²)) (rms), plus
    ``shaking_weight`` × the same measure of the shaking force on the frame, with |u_k| ≤ max_mr_k."""
    import cvxpy as cp

    if objective not in OBJECTIVES:
        raise BalancingError(f"{machine}: objective must be one of {', '.join(OBJECTIVES)}, got {objective!r}")
    u = cp.Variable(2 * len(model.planes))
    terms = ["front", "rear"] + (["force"] if shaking_weight else [])
    rows = {}
    for k in terms:
        g, b = model.gain[k], model.base[k]
        rows[k] = (np.concatenate([g[:, 0, :], g[:, 1, :]]), np.concatenate([b[:, 0], b[:, 1]]))
    n = len(next(iter(model.base.values())))

    def vec(k):
        a, c = rows[k]
        return a @ u + c  # x components then y components

    if objective == "peak":
        t = cp.Variable()
        cons = _bounds(cp, u, model.planes)
        for k in ("front", "rear"):
            v = vec(k)
            cons.append(cp.norm(cp.vstack([v[:n], v[n:]]), axis=0) <= t)
        cost = t
        if shaking_weight:
            s = cp.Variable()
            v = vec("force")
            cons.append(cp.norm(cp.vstack([v[:n], v[n:]]), axis=0) <= s)
            cost = t + shaking_weight * s
    else:
        cost = cp.norm(cp.hstack([vec("front"), vec("rear")])) / math.sqrt(n)
        if shaking_weight:
            cost = cost + shaking_weight * cp.norm(vec("force")) / math.sqrt(n)
        cons = _bounds(cp, u, model.planes)
    value, gap, status = _solve(cp.Problem(cp.Minimize(cost), cons), machine)
    return Solution(counterweights_of(model.planes, u.value, clip=True), value, gap, status)


FIRST_ORDER = ("forward", "x", "y")


def harmonic(model: LinearModel, moment_length: float | None = None, machine: str = "",
             first_order: str = "forward") -> Solution:
    """Method 2: the first harmonic order of the shaking force and moments on the frame about x and y (about the front
    bearing's point), with the moments weighed against the force over ``moment_length`` (default 1 m).

    ``first_order="forward"``: cancel the forward-rotating first order (in complex form F_x + i F_y = Σ c_n e^{inφ}
    a counterweight turning with the shaft changes only c₁): what rotating masses can cancel, the backward part
    (half a reciprocating mass's first order) stays. ``"x"`` or ``"y"``: cancel the first order along that frame
    axis completely — the textbook primary balance along a vertical (y) or horizontal (x) line of stroke — which
    moves as much into the other axis. With two planes at different z the solution is unique; with more, the
    least m·r (least squares)."""
    if first_order not in FIRST_ORDER:
        raise BalancingError(f"{machine}: first order must be one of {', '.join(FIRST_ORDER)}, got {first_order!r}")
    n = len(model.base["force"])
    span = moment_length or 1.0
    kernel = np.exp(-1j * 2 * np.pi * np.arange(n) / n) / n

    def coefficient(values):  # first-order Fourier coefficient along the sweep (axis 0)
        return np.tensordot(kernel, values, axes=(0, 0))

    rows, rhs = [], []
    for name, scale in (("force", 1.0), ("moment", 1.0 / span)):
        g, b = model.gain[name] * scale, model.base[name] * scale  # (n, 2, 2K), (n, 2)
        if first_order == "forward":
            cg, cb = coefficient(g[:, 0] + 1j * g[:, 1]), coefficient(b[:, 0] + 1j * b[:, 1])
        else:  # the axis of the force; the moment about the perpendicular axis goes with it
            axis = {"force": "xy".index(first_order), "moment": "yx".index(first_order)}[name]
            cg, cb = coefficient(g[:, axis]), coefficient(b[:, axis])
        rows += [cg.real, cg.imag]
        rhs += [-cb.real, -cb.imag]
    a, b = np.array(rows), np.array(rhs)
    u, *_ = np.linalg.lstsq(a, b, rcond=None)
    cws = counterweights_of(model.planes, u)
    over = [c.plane.name for c in cws if c.mr > c.plane.max_mr * (1 + 1e-12)]
    if over:
        need = ", ".join(f"{c.plane.name}: {c.mr * 1e6:.0f} > {c.plane.max_mr * 1e6:.0f} g·mm" for c in cws
                         if c.plane.name in over)
        raise BalancingError(f"{machine}: harmonic balance needs more m·r than its planes allow ({need})")
    return Solution(cws, float(np.linalg.norm(a @ u - b)), None, f"solved (least squares, first order {first_order})")


def separate(base: MachineAnalysis, planes: list[Plane], weights=DEFAULT_WEIGHTS, machine: str = "") -> Solution:
    """Method 1 (seed 002 for each group): the plane tied to a group (``group = ...``) gets the counterweight that
    minimises w₁·max|F_g + ω²-term| + w₂·mean|…| of that group's shaking force on the frame by itself (its own
    moving parts' inertia, in the machine frame)."""
    import cvxpy as cp

    w1, w2 = weights
    out, total, gaps = [], 0.0, []
    tied = [p for p in planes if p.group]
    if not tied:
        raise BalancingError(f"{machine}: method separate needs planes tied to groups (group = \"...\")")
    for plane in tied:
        group = next(g for g in base.machine.groups if g.name == plane.group)
        force = shaking.shaking_force_on_frame(base, group)
        model = linear_model(_lone(base, plane.group), [plane])
        g = model.gain["force"]
        u = cp.Variable(2)
        v = [g[:, 0, :] @ u + force[:, 0], g[:, 1, :] @ u + force[:, 1]]
        mag = cp.norm(cp.vstack(v), axis=0)
        cost = w1 * cp.max(mag) + w2 * cp.sum(mag) / len(force)
        value, gap, _ = _solve(cp.Problem(cp.Minimize(cost), [cp.norm(u) <= plane.max_mr]), machine)
        out += counterweights_of([plane], u.value, clip=True)
        total += value
        gaps.append(gap)
    return Solution(out, total, None if None in gaps else float(sum(gaps)), "optimal")


def _lone(base: MachineAnalysis, group: str) -> MachineAnalysis:
    """The machine reduced to one group (its shaft core kept) for that group's own balance."""
    m = base.machine
    lone = replace(m, groups=[g for g in m.groups if g.name == group])
    return MachineAnalysis(lone, base.phi, {group: base.groups[group]})


# -- the evaluation (seed 000 part 2 §四) -----------------------------------------------------------------------

def orders(values: np.ndarray, k: int = 3) -> list[float]:
    """Amplitudes of harmonic orders 1..k of an (n, 2) vector quantity over a revolution: the peak of each order's
    ellipse, |c_n| + |c_−n| of x + i y."""
    n = len(values)
    z = values[:, 0] + 1j * values[:, 1]
    c = np.fft.fft(z) / n
    return [float(abs(c[j]) + abs(c[-j])) for j in range(1, k + 1)]


def _moments(a: MachineAnalysis) -> np.ndarray:
    """(n, 3) the shaking moments on the frame about the front bearing's point on the axis."""
    return a.shaking_moments_on_frame((0.0, 0.0, a.machine.shaft.front))


#: metrics' peaks: key -> the quantity (a function of an analysis) whose largest value it is
PEAKS = {
    "bearing_front_peak": lambda a: np.hypot(*a.bearing("front").T),
    "bearing_rear_peak": lambda a: np.hypot(*a.bearing("rear").T),
    "shaking_force_on_frame_peak": lambda a: np.hypot(*a.shaking_force_on_frame.T),
    "shaking_moment_on_frame_x_peak": lambda a: np.abs(_moments(a)[:, 0]),
    "shaking_moment_on_frame_y_peak": lambda a: np.abs(_moments(a)[:, 1]),
    "shaking_moment_on_frame_z_peak": lambda a: np.abs(_moments(a)[:, 2]),
    "torque_peak": lambda a: np.abs(a.torque),
}


def metrics(a: MachineAnalysis) -> dict:
    """Peak and RMS of both bearing loads, of the shaking force on the frame and its orders, the peaks of the three
    shaking moments on the frame (about the front bearing's point on the axis), the moving parts' weight on the
    frame, the driving torque (SI). Every peak is refined between the samples (sewgen.machine.peaks), with its
    shaft angle (``peak_at_deg``) and how it was found (``peak_how``); RMS and orders are over the samples."""
    q = _quantities(a)
    mag = {k: np.hypot(*q[k].T) for k in ("front", "rear")}
    force = q["force"]
    fmag = np.hypot(*force.T)
    moments = _moments(a)
    peaks = {k: e["max"] for k, e in extremes(a, PEAKS, ("max",)).items()}
    out = {k: peaks[k].value for k in PEAKS}
    out.update({
        "bearing_front_rms": float(np.sqrt(np.mean(mag["front"] ** 2))),
        "bearing_rear_rms": float(np.sqrt(np.mean(mag["rear"] ** 2))),
        "shaking_force_on_frame_rms": float(np.sqrt(np.mean(fmag**2))),
        "weight_on_frame": [float(v) for v in a.weight_on_frame],
        "torque_rms": float(np.sqrt(np.mean(a.torque**2))),
        "shaking_force_on_frame_orders": orders(force), "shaking_moments_on_frame_xy_orders": orders(moments[:, :2]),
        "peak_at_deg": {k: p.deg for k, p in peaks.items()}, "peak_how": {k: p.how for k, p in peaks.items()},
        "step_deg": float(math.degrees(a.phi[1] - a.phi[0])) if len(a.phi) > 1 else None,
    })
    return out


def balance_angles(machine: Machine) -> np.ndarray:
    """The shaft angles the methods balance and evaluate ``machine`` at: its own step, or :data:`STEP_DEG` where
    that is finer."""
    return machine.shaft_angles(min(machine.step, math.radians(STEP_DEG)))


@dataclass
class BalanceReport:
    method: str
    objective: str | None
    solution: Solution
    before: MachineAnalysis
    after: MachineAnalysis
    speeds: list  # (rpm, before metrics, after metrics)

    def as_dict(self) -> dict:
        """In SI: method, objective, before, after, counterweights, the solve's objective and gap, speeds."""
        return {"method": self.method, "objective": self.objective,
                "before": metrics(self.before), "after": metrics(self.after),
                "counterweights": [c.as_dict() for c in self.solution.counterweights],
                "solver": {"status": self.solution.status, "objective": self.solution.objective,
                           "gap": self.solution.gap},
                "speeds": [{"rpm": rpm, "before": b, "after": a} for rpm, b, a in self.speeds],
                "units": {"force": "N", "moment": "N*m", "torque": "N*m", "mr": "kg*m", "mass": "kg",
                          "length": "m", "angle": "rad (from the crank direction φ)"}}


def balance(machine: Machine, method: str, objective: str = "peak", shaking_weight: float = 0.0,
            weights=DEFAULT_WEIGHTS, speeds_rpm=(), planes: list[Plane] | None = None,
            first_order: str = "forward") -> BalanceReport:
    """Balance ``machine`` by ``method`` (:data:`METHODS`) on its counterweight planes; evaluate before and after
    at its speed and at each of ``speeds_rpm``."""
    if method not in METHODS:
        raise BalancingError(f"{machine.name}: method must be one of {', '.join(METHODS)}, got {method!r}")
    planes = planes_of(machine) if planes is None else planes
    phi = balance_angles(machine)
    before = machine.analyze(phi)
    if method == "separate":
        sol = separate(before, planes, weights, machine.name)
    else:
        model = linear_model(before, planes)
        sol = (harmonic(model, machine.shaft.rear - machine.shaft.front, machine.name, first_order)
               if method == "harmonic"
               else bearings(model, objective, shaking_weight, machine.name))
    after = reanalyse(before, sol.counterweights)
    balanced = with_counterweights(machine, sol.counterweights)
    rows = []
    for rpm in speeds_rpm:
        w = rpm * 2 * math.pi / 60
        rows.append((rpm, metrics(machine.analyze(phi, speed=w)), metrics(balanced.analyze(phi, speed=w))))
    return BalanceReport(method, objective if method == "bearings" else None, sol, before, after, rows)


def model_text(source_text: str, counterweights, source: str = "") -> str:
    """The model file's text with the counterweights appended as shaft point masses (analysable as it is).

    A model that already has a shaft mass named as a counterweight's plane (written by an earlier balancing) is
    refused with a :class:`BalancingError`: appending would put two counterweights on the plane, more than its
    ``max_mass`` — balance the model without them (``source``: the model file, named in the error)."""
    masses = tomllib.loads(source_text).get("shaft", {}).get("masses", [])
    names = {m.get("name") for m in masses if isinstance(m, dict)}
    twice = [c.plane.name for c in counterweights if c.plane.name in names]
    if twice:
        raise BalancingError(f"{source or 'the model'}: shaft.masses already has {', '.join(twice)} (counterweights "
                             "of an earlier balancing): a second one on the same plane would exceed its max_mass; "
                             "remove them from the model file to balance it again")
    lines = [source_text.rstrip("\n"), "", "# counterweights chosen by sewgen balance machine"]
    for c in counterweights:
        lines += ["[[shaft.masses]]", f'name = "{c.plane.name}"', f'mass = "{c.mass * 1e3:.15g} g"',
                  f'radius = "{c.plane.radius * 1e3:.15g} mm"',
                  f'angle = "{math.degrees(c.angle % (2 * math.pi)):.15g} deg"', f'z = "{c.plane.z * 1e3:.15g} mm"', ""]
    return "\n".join(lines)
