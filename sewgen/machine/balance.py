"""Partial balancing of the needle-bar crank-slider by a counterweight on the crank (seed 002).

Seed 002: 徐建勇, 严辉, 周永光, 缝纫机针杆刺布机构的惯性力优化平衡研究, 科技创新与应用 2021 (30). The copy we have
lost its displayed equations and tables 1–2; equations are cited by the numbers its text names — (5) slider
acceleration, (15) the split of m″'s force, (20) residual inertia force, (22) its numeric form at
6000 r/min — and the rest by section (§2 mass substitution and counterweights, §3 objective and optimum).

Model (§2). Static substitution: the crank's mass m1 (centre at distance c1 from A along AB) becomes m1A at
A and m1B = m1·c1/l_AB at B; the link's mass m2 (centre at c2 from B) becomes m2B = m2·(l_BC − c2)/l_BC
at B and m2C = m2·c2/l_BC at C. Rotating mass m_B = m1B + m2B (+ lumped mass at B); reciprocating mass
m_C = m2C + m3 (+ lumped mass at C), m3 the needle bar. A counterweight on the crank's extension beyond A
balances m_B fully (m′·r = m_B·l_AB) and a K-th part of m_C's first-order force (m″·r = K·m_C·l_AB,
0 ≤ K ≤ 1); in total m·r = (m_B + K·m_C)·l_AB.

Angles. Everything here takes sewgen's shaft angle θ: the crank angle counter-clockwise from +x, the needle
bar on the vertical line x = offset below the shaft (joint C branch −1), travel measured upward. The paper's
φ (crank counter-clockwise, measured from the line of stroke A→C, φ = 0 at the stroke's lower dead centre
C2, eq. (5) positive toward A) is φ = θ + 90°: the paper's slider acceleration along S is sewgen's
``needle_bar.travel`` acceleration. :func:`paper_phi` and :func:`shaft_angle` convert.

Forces are inertia forces F = −Σ m·a (N) in sewgen's frame (x right, y up): the shaking force on the frame,
inertia only (the convention of sewgen.machine.shaking), which the balancing minimises. The speed is constant.
"""
from __future__ import annotations

import math
from dataclasses import asdict, dataclass

import numpy as np
from scipy.optimize import minimize_scalar

from sewgen import roles
from sewgen.engine.loader import catalog, mechanism
from sewgen.errors import RoleError, SewgenError

SERIES = ("two-term", "exact")
DEFAULT_WEIGHTS = (0.1, 0.9)  # §3: w1 ≤ 0.2, w2 ≥ 0.8; the paper computes with 0.1, 0.9


class BalanceError(SewgenError, ValueError):
    """A balancing input that cannot be used; ``name`` is the model field (CLI option --name-with-dashes)."""

    def __init__(self, name: str, message: str):
        self.name = name
        super().__init__(f"{name}: {message}", problem=message, parameter=name)


@dataclass(frozen=True)
class NeedleBarModel:
    """A needle-bar crank-slider for balancing, SI (m, kg, rad/s).

    ``mass_b`` and ``mass_c`` are masses lumped at the crank pin B and the link pin C (the paper's m_B, m_C
    or parts of them); ``crank_mass``/``crank_com`` (from A along AB, signed), ``rod_mass``/``rod_com`` (from
    B along BC; default mid-link) and ``bar_mass`` (needle bar 14 with clamp and needle) are substituted
    onto A, B, C and added.
    """

    crank: float
    rod: float
    speed: float
    offset: float = 0.0
    mass_b: float = 0.0
    mass_c: float = 0.0
    crank_mass: float = 0.0
    crank_com: float | None = None
    rod_mass: float = 0.0
    rod_com: float | None = None
    bar_mass: float = 0.0

    def __post_init__(self):
        for name, value in asdict(self).items():
            if value is not None and not math.isfinite(value):
                raise BalanceError(name, f"must be finite, got {value!r}")
        for name in ("crank", "speed"):
            if not getattr(self, name) > 0:
                raise BalanceError(name, f"must be positive, got {getattr(self, name)!r} (SI)")
        if not self.rod > self.crank + abs(self.offset):
            raise BalanceError("rod", f"{self.rod:g} m must be longer than crank + |offset| = "
                                      f"{self.crank + abs(self.offset):g} m, or the crank cannot turn fully")
        for name in ("mass_b", "mass_c", "crank_mass", "rod_mass", "bar_mass"):
            if getattr(self, name) < 0:
                raise BalanceError(name, f"must not be negative, got {getattr(self, name)!r} kg")
        if self.crank_mass > 0 and self.crank_com is None:
            raise BalanceError("crank_com", "the crank's centre of mass (from A along AB) is needed with its mass")
        if self.rod_com is not None and not 0 <= self.rod_com <= self.rod:
            raise BalanceError("rod_com", f"must lie on the link, 0 ... {self.rod:g} m from B, got {self.rod_com!r}")
        if not self.masses()[1] > 0:
            raise BalanceError("mass_c", "the reciprocating mass at C must be positive (nothing to balance)")

    @property
    def lam(self) -> float:
        """λ = l_AB / l_BC."""
        return self.crank / self.rod

    def rod_split(self) -> tuple[float, float]:
        """The link's static substitution (m2B, m2C) (§2)."""
        c2 = self.rod / 2 if self.rod_com is None else self.rod_com
        return self.rod_mass * (1 - c2 / self.rod), self.rod_mass * c2 / self.rod

    def masses(self) -> tuple[float, float]:
        """(m_B, m_C): rotating mass at B and reciprocating mass at C after static substitution (§2)."""
        m1b = self.crank_mass * (self.crank_com or 0.0) / self.crank
        m2b, m2c = self.rod_split()
        return m1b + m2b + self.mass_b, m2c + self.bar_mass + self.mass_c


def paper_phi(theta):
    """The paper's crank angle φ (from the line of stroke A→C, 0 at lower dead centre) = θ + 90°."""
    return np.asarray(theta) + math.pi / 2


def shaft_angle(phi):
    """sewgen's shaft angle θ = φ − 90° for the paper's φ."""
    return np.asarray(phi) - math.pi / 2


def revolution(n: int = 3600) -> np.ndarray:
    """``n`` shaft angles evenly over one turn (rad)."""
    return 2 * math.pi * np.arange(n) / n


def slider_accel(model: NeedleBarModel, theta, series: str = "two-term") -> np.ndarray:
    """Needle-bar acceleration along its travel (upward, m/s²) at shaft angles θ.

    ``"two-term"``: eq. (5)'s series r·ω²(cos φ + λ·cos 2φ), plus the first-order offset term
    r·ω²·(e/l)·sin φ (zero without offset; from x = r cos φ + √(l² − (r sin φ − e)²) to first order in 1/l).
    ``"exact"``: the compiled catalog needle drive (:func:`needle_drive`).
    """
    theta = np.atleast_1d(np.asarray(theta, dtype=float))
    if series == "two-term":
        phi = paper_phi(theta)
        r, w2 = model.crank, model.speed ** 2
        return r * w2 * (np.cos(phi) + model.lam * np.cos(2 * phi) + model.offset / model.rod * np.sin(phi))
    if series == "exact":
        drive = needle_drive()
        motion = drive.mechanism.solve(theta, speed=model.speed,
                                       params={drive.crank: model.crank, drive.rod: model.rod,
                                               drive.offset: model.offset})
        return motion.coord(drive.travel).accel
    raise BalanceError("series", f"must be one of {', '.join(SERIES)}, got {series!r}")


def _force(model: NeedleBarModel, K: float, theta: np.ndarray, accel: np.ndarray) -> np.ndarray:
    m_c = model.masses()[1]
    cw = K * m_c * model.crank * model.speed ** 2  # m″·r·ω², pointing from A away from the counterweight
    return np.column_stack([-cw * np.cos(theta), -m_c * accel - cw * np.sin(theta)])


def residual_force(model: NeedleBarModel, K: float, theta, series: str = "two-term") -> np.ndarray:
    """Residual inertia force (n, 2), N, sewgen frame, after full rotating and K-partial balancing (eq. (20)).

    F = −m_C·a_C·ŷ − K·m_C·l_AB·ω²·(cos θ, sin θ): the reciprocating mass's inertia force along the guide and
    the extra counterweight m″'s centrifugal force (eq. (15): its component along the stroke cancels K of the
    first-order force, the one across it is new). m_B and m′ cancel exactly.
    """
    theta = np.atleast_1d(np.asarray(theta, dtype=float))
    return _force(model, K, theta, slider_accel(model, theta, series))


def residual_magnitude(model: NeedleBarModel, K: float, theta, series: str = "two-term") -> np.ndarray:
    """|F(θ, K)| of :func:`residual_force`, N."""
    return np.hypot(*residual_force(model, K, theta, series).T)


def indices(model: NeedleBarModel, K: float, series: str = "two-term", n: int = 3600) -> tuple[float, float]:
    """(F1, F2) = (max |F|, mean |F|) over one revolution sampled at ``n`` angles (§3)."""
    return _indices_fn(model, series, n)(K)


def _indices_fn(model, series, n):
    theta = revolution(n)
    accel = slider_accel(model, theta, series)  # independent of K: compute once

    def fn(K):
        f = np.hypot(*_force(model, K, theta, accel).T)
        return float(f.max()), float(f.mean())
    return fn


def check_weights(weights) -> tuple[float, float]:
    """(w1, w2) with w1, w2 ≥ 0 and w1 + w2 = 1 (§3), else BalanceError naming ``weights``."""
    try:
        w1, w2 = (float(w) for w in weights)
    except (TypeError, ValueError):
        raise BalanceError("weights", f"need two numbers w1, w2, got {weights!r}") from None
    if not (math.isfinite(w1) and math.isfinite(w2) and w1 >= 0 and w2 >= 0 and abs(w1 + w2 - 1) <= 1e-9):
        raise BalanceError("weights", f"need w1, w2 ≥ 0 with w1 + w2 = 1, got {w1:g}, {w2:g}")
    return w1, w2


def weighted_objective(F1: float, F2: float, weights=DEFAULT_WEIGHTS) -> float:
    """The paper's objective F(K) = w1·F1 + w2·F2 (§3)."""
    w1, w2 = check_weights(weights)
    return w1 * F1 + w2 * F2


def objective_curve(model: NeedleBarModel, Ks, weights=DEFAULT_WEIGHTS, series: str = "two-term",
                    n: int = 3600) -> np.ndarray:
    """Rows (K, F1, F2, objective) for each K — the paper's fig. 3 sweeps K = 0, 0.1, ..., 1."""
    fn = _indices_fn(model, series, n)
    rows = [(K, *fn(K)) for K in np.asarray(Ks, dtype=float)]
    return np.array([(K, f1, f2, weighted_objective(f1, f2, weights)) for K, f1, f2 in rows])


def counterweight_mr(model: NeedleBarModel, K: float) -> float:
    """Total counterweight product m·r = (m_B + K·m_C)·l_AB, kg·m (§2; §3 evaluates it at K = 0.593)."""
    m_b, m_c = model.masses()
    return (m_b + K * m_c) * model.crank


@dataclass(frozen=True)
class BalanceResult:
    """Before (K = 0: rotating mass balanced, reciprocating not) and after (optimum K), SI."""

    K: float
    F1_before: float
    F2_before: float
    objective_before: float
    F1_after: float
    F2_after: float
    objective_after: float
    counterweight_mr: float
    mass_B: float
    mass_C: float
    weights: tuple
    series: str

    def as_dict(self) -> dict:
        return asdict(self)


def optimise(model: NeedleBarModel, weights=DEFAULT_WEIGHTS, series: str = "two-term", n: int = 3600,
             xatol: float = 1e-6) -> BalanceResult:
    """The K in [0, 1] minimising w1·F1 + w2·F2 (§3: the paper finds K = 0.593), by bounded Brent search."""
    w = check_weights(weights)
    fn = _indices_fn(model, series, n)
    res = minimize_scalar(lambda K: weighted_objective(*fn(K), w), bounds=(0.0, 1.0), method="bounded",
                          options={"xatol": xatol})
    K = float(res.x)
    for edge in (0.0, 1.0):  # Brent never evaluates the bounds themselves
        if weighted_objective(*fn(edge), w) < weighted_objective(*fn(K), w):
            K = edge
    (b1, b2), (a1, a2) = fn(0.0), fn(K)
    return BalanceResult(K, b1, b2, weighted_objective(b1, b2, w), a1, a2, weighted_objective(a1, a2, w),
                         counterweight_mr(model, K), *model.masses(), w, series)


# -- sector counterweight ------------------------------------------------------------------------------------

def sector(outer: float, inner: float, thickness: float, angle: float, density: float) -> tuple[float, float]:
    """(mass, centroid radius) of an annular sector plate: radii inner < outer, full angle, thickness, ρ.

    m = ρ·t·(α/2)·(R² − r_i²); centroid r_c = (2/3)·sin(α/2)/(α/2)·(R³ − r_i³)/(R² − r_i²).
    """
    half = angle / 2
    mass = density * thickness * half * (outer ** 2 - inner ** 2)
    return mass, 2 * math.sin(half) * (outer ** 3 - inner ** 3) / (3 * half * (outer ** 2 - inner ** 2))


def sector_outer_radius(mr: float, inner: float, thickness: float, angle: float, density: float) -> float:
    """Outer radius R of the annular sector whose first moment m·r_c equals ``mr`` (kg·m).

    m·r_c = (2/3)·ρ·t·sin(α/2)·(R³ − r_i³), so R = (r_i³ + 3·mr / (2·ρ·t·sin(α/2)))^(1/3) — the sizing behind
    the paper's R = 25.982 mm, r = 12.6886 mm, m = 133.9145 g (§3; its r_i, t, α, ρ are not printed).
    """
    for name, v in (("thickness", thickness), ("density", density), ("mr", mr)):
        if not v > 0:
            raise BalanceError(name, f"must be positive, got {v!r}")
    if not 0 < angle < 2 * math.pi:
        raise BalanceError("angle", f"must be in (0°, 360°) (a ring balances nothing), got {math.degrees(angle):g}°")
    if not inner >= 0:
        raise BalanceError("inner", f"must not be negative, got {inner!r}")
    return (inner ** 3 + 3 * mr / (2 * density * thickness * math.sin(angle / 2))) ** (1 / 3)


# -- the lumped model as the parameters of a compiled needle drive --------------------------------------------

@dataclass(frozen=True)
class NeedleDrive:
    """A compiled crank-slider needle drive, its parts found by role (sewgen.roles): the parameter names of
    the crank radius, the rod length and the guide's offset, the three bodies, and the bar's travel
    coordinate. The assembly branch is the declaration's (the bar below the crank)."""

    mechanism: object
    crank: str
    rod: str
    offset: str
    crank_body: object
    rod_body: object
    bar_body: object
    travel: str


def needle_drive(mech=None) -> NeedleDrive:
    """``mech`` (default: the catalog mechanism that plays the needle-drive roles) as a :class:`NeedleDrive`."""
    if mech is None:
        found = [mechanism(n) for n in catalog()
                 if all(mechanism(n).description.has_role(r) for r in roles.NEEDLE_DRIVE)]
        if not found:
            raise RoleError("catalog", roles.NEEDLE_CRANK_RADIUS, [])
        mech = found[0]
    d = mech.description
    crank, rod, bar = (d.role(r) for r in (roles.NEEDLE_CRANK, roles.NEEDLE_ROD, roles.NEEDLE_BAR))
    return NeedleDrive(mech, d.role(roles.NEEDLE_CRANK_RADIUS).name, d.role(roles.NEEDLE_ROD_LENGTH).name,
                       d.role(roles.NEEDLE_BAR_OFFSET).name, crank, rod, bar,
                       next(c.name for c in d.coords if c.name.startswith(bar.name + ".")))


def _body(points) -> tuple[float, float, float]:
    """(mass, centre u, inertia about the centre) of point masses [(m, u), ...] on a line."""
    m = sum(p for p, _ in points)
    if m == 0:
        return 0.0, 0.0, 0.0
    u = sum(p * x for p, x in points) / m
    return m, u, sum(p * (x - u) ** 2 for p, x in points)


def mechanism_overrides(model: NeedleBarModel, K: float, cw_radius: float | None = None,
                        drive: NeedleDrive | None = None) -> dict[str, float]:
    """Parameters of the needle drive (SI; default :func:`needle_drive`) that realise ``model`` with the
    counterweight of ``K``.

    Crank: its mass at its centre c1, the lumped ``mass_b`` at B and the counterweight m = m·r / cw_radius
    (default l_AB) at u = −cw_radius. Link: m2 at c2 with inertia m2B·m2C·l²/m2 (two point masses at B, C).
    Needle bar: m3 + ``mass_c`` with its centre at C. The mechanism's generic Σ m·a_G is then exactly −F of
    :func:`residual_force` (``"exact"``, constant speed): a rigid body's Σ m·a is that of its substitute masses.
    If the mechanism has no ``rod.com_u`` (its link centre is fixed mid-link) and c2 is not mid-link, the
    link's m2B moves onto the crank at B and m2C onto the needle bar: the same Σ m·a, link massless.
    """
    drive = drive or needle_drive()
    param_names = drive.mechanism.param_names
    cb, rb, bb = drive.crank_body, drive.rod_body, drive.bar_body
    rho = model.crank if cw_radius is None else cw_radius
    if not rho > 0:
        raise BalanceError("cw_radius", f"must be positive, got {rho!r}")
    mr = counterweight_mr(model, K)
    if mr < 0:
        raise BalanceError("K", f"the crank already over-balances m_B (m·r = {mr:g} kg·m): remove mass instead")
    l = model.rod
    c2 = l / 2 if model.rod_com is None else model.rod_com
    m2b, m2c = model.rod_split()
    fold = rb.com_u is None and abs(c2 - l / 2) > 1e-12 * l and model.rod_mass > 0
    crank = _body([(model.crank_mass, model.crank_com or 0.0), (model.mass_b + (m2b if fold else 0), model.crank),
                   (mr / rho, -rho)])
    bar_mass = model.bar_mass + model.mass_c + (m2c if fold else 0)
    out = {drive.crank: model.crank, drive.rod: l, drive.offset: model.offset,
           cb.mass: crank[0], cb.com_u: crank[1], cb.com_v: 0.0, cb.inertia: crank[2],
           rb.mass: 0.0 if fold else model.rod_mass, rb.com_u: c2, rb.com_v: 0.0,
           rb.inertia: 0.0 if fold else model.rod_mass * c2 * (l - c2),
           bb.mass: bar_mass, bb.com_u: 0.0, bb.com_v: 0.0, bb.inertia: 0.0}
    return {k: v for k, v in out.items() if k is not None and k in param_names}
