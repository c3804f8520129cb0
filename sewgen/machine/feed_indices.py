"""Feed-dog trajectory indices (seed 001 §五.3), vectorised over designs × shaft angles.

Seed 001 compares feed mechanisms by the path of the feed dog's tooth tip against the throat plate. Its text of
the definitions is lost; these are the standard ones (DOMAIN-NOTES "Feed-dog trajectory indices"), with z = y −
plate the tip's height above the plate, x its horizontal position (+ forward), φ the machine's shaft angle and
φ_r, φ_s the angles where z crosses 0 upwards (the dog rises) and downwards (it sinks):

=========================  ===========================================================================  ======
``travel``                 x(φ_s) − x(φ_r): the cloth's advance, the stitch                              mm
``effective_travel``       Σ x(sink) − Σ x(rise) over the crossings of z = tooth depth (the teeth bite)  mm
``height``                 max z                                                                         mm
``rise_lag``               φ_r − φ(needle point leaves the cloth), wrapped to (−180°, 180°]              deg
``sink_lead``              φ(needle point enters the cloth) − φ_s, wrapped                               deg
``overlap_travel``         |x| the dog moves while above the plate with the needle in the cloth          mm
``fullness``               ∫ z dx over φ_r..φ_s / (|travel| × height): 1 for a rectangle                 –
``speed_uniformity``       max |vx| / mean |vx| over φ_r..φ_s (mean = ∫|vx| dt / duration)               –
``peak_accel``             max |ax| over φ_r..φ_s                                                        m/s²
``accel_jump``             the largest jump of ax where a cam contact changes arc (whole turn)           m/s²
``tilt_min``/``tilt_max``  the dog body's inclination over φ_r..φ_s, in (−90°, 90°] (+: rising to +x)     deg
=========================  ===========================================================================  ======

Every crossing and extreme is found on the cubic Hermite interpolant of the samples and their exact shaft-angle
derivatives (dx/dφ = vx/ω; sewgen.hermite, which sewgen.machine.timing uses too: crossings by bracketed Newton steps,
extremes as roots of the pieces' quadratic slopes), so the indices are accurate far below the sweep's step; the
integrals are 3-point Gauss on each step (exact for the interpolants' product), over the whole (designs ×
steps) array at once; the peaks of |vx|, |ax| are the
sampled ones (and the interpolated ends of the arc). The acceleration jump at an arc switch between two samples
is extrapolated from each side's samples to where the two sides' velocities meet (:func:`arc_jumps`, O(h³);
sewgen.machine.cams brackets the switch exactly, which summary.json uses, and studies with
``StudyOptions.exact_jumps``).

A design whose dog does not rise above the plate exactly once a turn gets NaN indices and an ``error``.
"""
from __future__ import annotations

import math

import numpy as np

from sewgen.hermite import at, bracketed_root, crossings, hermite, maximum, power_form  # the one cubic Hermite
from sewgen.machine.cams import arc_columns
from sewgen.machine.feed import plate_height
from sewgen.roles import FEED_BAR, FEED_DOG, THROAT_PLATE

TWO_PI = 2.0 * math.pi
#: Tooth depth of a feed dog (m): the teeth bite the cloth only above it (DOMAIN-NOTES: ≈ 0.8 mm).
TOOTH_DEPTH = 0.8e-3

#: index -> (unit shown, factor from SI, column label)
INDICES = {
    "travel": ("mm", 1e3, "feed-dog travel above the plate"),
    "effective_travel": ("mm", 1e3, "travel above the tooth depth"),
    "height": ("mm", 1e3, "feed-dog height above the plate"),
    "rise_lag": ("deg", 180.0 / math.pi, "rise after the needle leaves the cloth"),
    "sink_lead": ("deg", 180.0 / math.pi, "sink before the needle enters the cloth"),
    "overlap_travel": ("mm", 1e3, "dog travel while the needle is in the cloth"),
    "fullness": ("", 1.0, "area above the plate / (travel × height)"),
    "speed_uniformity": ("", 1.0, "peak / mean horizontal speed while feeding"),
    "peak_accel": ("m/s^2", 1.0, "peak horizontal acceleration while feeding"),
    "accel_jump": ("m/s^2", 1.0, "largest horizontal-acceleration jump at a cam-arc switch"),
    "tilt_min": ("deg", 180.0 / math.pi, "least dog tilt while feeding (+: rising toward the feed direction)"),
    "tilt_max": ("deg", 180.0 / math.pi, "greatest dog tilt while feeding (+: rising toward the feed direction)"),
    "rise_at": ("deg", 180.0 / math.pi, "shaft angle where the dog rises above the plate"),
    "sink_at": ("deg", 180.0 / math.pi, "shaft angle where the dog sinks below the plate"),
}

#: The angle indices and their period (rad): an angle is known only modulo it, so a study's values are compared
#: and drawn continuous across it (rise and sink angles, lags and leads a turn; a tilt, an inclination, half one).
PERIODS = {"rise_lag": TWO_PI, "sink_lead": TWO_PI, "rise_at": TWO_PI, "sink_at": TWO_PI, "tilt_min": math.pi,
           "tilt_max": math.pi}

_GAUSS_X = np.array([-math.sqrt(0.6), 0.0, math.sqrt(0.6)])
_GAUSS_W = np.array([5.0, 8.0, 5.0]) / 9.0


def column(name: str) -> str:
    """The study-table column of index ``name``: ``feed_<name> [unit]``."""
    unit = INDICES[name][0]
    return f"feed_{name} [{unit}]" if unit else f"feed_{name}"



def _next(a):
    return np.roll(a, -1, axis=-1)


def _per_row(d, rows, values):
    out = np.full(d, np.nan)
    out[rows] = values
    return out


def _arc_integrals(z, dz, x, dx, h, u, span, good):
    """Per row: ∫ z dx and ∫ |dx/dφ| dφ over the arc [rise, rise + span] (``u`` (D, N): each step's start
    measured from the rise), by 3-point Gauss on each step's part inside the arc (exact for z·x′, a quintic).
    Every step of every row at once in the power form of its pieces; the one step per row that wraps past
    the rise (its start a little less than 2π after it) is added apart."""
    zc = power_form(z, _next(z), dz, _next(dz), h)
    xc = power_form(x, _next(x), dx, _next(dx), h)
    area, absx = np.zeros(len(z)), np.zeros(len(z))
    sp = span[:, None]

    def add(rows, zc, xc, t0, t1, out_area, out_absx):
        half = 0.5 * (t1 - t0)
        for xi, wi in zip(_GAUSS_X, _GAUSS_W):
            s = (t0 + half * (1.0 + xi)) / h
            zq = ((zc[3] * s + zc[2]) * s + zc[1]) * s + zc[0]
            xq = ((3.0 * xc[3] * s + 2.0 * xc[2]) * s + xc[1]) / h  # dx/dφ
            wh = wi * half
            if rows is None:
                out_area += (wh * zq * xq).sum(axis=1)
                out_absx += (wh * np.abs(xq)).sum(axis=1)
            else:
                np.add.at(out_area, rows, wh * zq * xq)
                np.add.at(out_absx, rows, wh * np.abs(xq))

    with np.errstate(invalid="ignore"):
        # every step: its part [a, b] ⊂ [0, span] (no part: a = b, weight 0)
        t0 = np.maximum(-u, 0.0)
        t1 = np.minimum(sp - u, h)
        use = (t1 > t0) & good[:, None]
    # a step outside the arc has weight 0 (its pieces are finite in a row that rises and sinks once: ``good``)
    t0 = np.where(use, t0, 0.0)
    t1 = np.where(use, t1, 0.0)
    add(None, zc, xc, t0, t1, area, absx)
    # the step that starts before the rise (u near 2π): its part from the rise on
    with np.errstate(invalid="ignore"):
        t0w = (TWO_PI - u)
        t1w = np.minimum(sp + TWO_PI - u, h)
        wrapped = (t1w > t0w) & good[:, None]
    rr, cc = np.nonzero(wrapped)
    if len(rr):
        add(rr, tuple(c[rr, cc] for c in zc), tuple(c[rr, cc] for c in xc), t0w[rr, cc], t1w[rr, cc], area, absx)
    return area, absx


def arc_jumps(arc, v, a, h):
    """Every switch of a cam contact's arc in ``arc`` (D, N) between two samples, and the jump of a (D, N), the
    shaft-angle derivative of v (D, N), there: (rows, sample index i before the switch, a after − a before).

    A G1 cam keeps v continuous and makes a jump at the switch (sewgen.machine.cams). Each side's a is the quadratic
    through its last three samples on its own arc (two: linear; one: constant) and v is its integral from the
    side's last sample; the switch is where the two sides' v agree (the root of their difference, a cubic, in
    the step; the nearer end without a sign change) and the jump is the difference of the two sides' a there.
    Error O(h³) against the exact jump of sewgen.machine.cams.arc_switches (JB1-3 feed: 2e-4 of it at 5° steps, 2e-6
    at 1°); the exact one needs a solve at each design's own switch angle (StudyOptions.exact_jumps)."""
    d, n = arc.shape
    rows, i = np.nonzero(arc != _next(arc))
    if not len(rows):
        return rows, i, np.zeros(0)
    j = (i + 1) % n
    im, im2, jp, jp2 = (i - 1) % n, (i - 2) % n, (j + 1) % n, (j + 2) % n
    al, alm, alm2 = a[rows, i], a[rows, im], a[rows, im2]
    ar_, arp, arp2 = a[rows, j], a[rows, jp], a[rows, jp2]
    same = lambda k: arc[rows, k] == arc[rows, i]  # noqa: E731
    other = lambda k: arc[rows, k] == arc[rows, j]  # noqa: E731
    l1, l2 = same(im), same(im) & same(im2)
    r1, r2 = other(jp), other(jp) & other(jp2)
    # derivatives at the side's last sample (one-sided differences of order 2, 1 or 0)
    jl = np.where(l2, (3 * al - 4 * alm + alm2) / (2 * h), np.where(l1, (al - alm) / h, 0.0))
    kl = np.where(l2, (al - 2 * alm + alm2) / h**2, 0.0)
    jr = np.where(r2, (-3 * ar_ + 4 * arp - arp2) / (2 * h), np.where(r1, (arp - ar_) / h, 0.0))
    kr = np.where(r2, (ar_ - 2 * arp + arp2) / h**2, 0.0)
    vl, vr = v[rows, i], v[rows, j]
    # Δv(t) = v_right − v_left at offset t from sample i, in powers of s = t/h
    c0 = vr - ar_ * h + jr * h**2 / 2 - kr * h**3 / 6 - vl
    c1 = (ar_ - jr * h + kr * h**2 / 2 - al) * h
    c2 = (jr / 2 - kr * h / 2 - jl / 2) * h**2
    c3 = (kr - kl) / 6 * h**3
    f0, f1 = c0, c0 + c1 + c2 + c3
    t = np.where(np.abs(f0) <= np.abs(f1), 0.0, h)
    b = np.flatnonzero((f0 < 0.0) != (f1 < 0.0))
    if len(b):
        t[b] = h * bracketed_root(c0[b], c1[b], c2[b], c3[b], f0[b] < 0.0)
    left = al + jl * t + kl * t * t / 2
    right = ar_ + jr * (t - h) + kr * (t - h) ** 2 / 2
    return rows, i, right - left


def wrap(a):
    """Angles into (−π, π]."""
    return np.pi - (np.pi - np.asarray(a)) % TWO_PI


def inclination(a):
    """A body's angle (its u axis from +x) as the inclination of its line to the horizontal, in (−π/2, π/2]:
    positive where the line rises toward +x (the feed direction), whichever way the body's u axis points (the
    51-A's rack points back along −x: its angle 179° is the inclination −1°)."""
    return 0.5 * np.pi - (0.5 * np.pi - np.asarray(a)) % np.pi


# -- the indices ------------------------------------------------------------------------------------------------

def feed_indices(phi, x, y, vx, vy, ax, omega, plate, *, needle_in=None, needle_out=None,
                 tooth_depth: float = TOOTH_DEPTH, tilt=None, arc=None) -> dict:
    """Every feed-dog index (see the module docstring) for D designs at once.

    ``phi`` (N,): one revolution of machine shaft angles in equal steps; x, y, vx, vy, ax (D, N): the dog tip's
    position (m), velocity and horizontal acceleration at constant speed ``omega`` (rad/s, > 0); ``plate`` (D,)
    or scalar: the plate's height. ``needle_in``/``needle_out`` (D,) or scalar: the machine angles where the
    needle point enters and leaves the cloth (NaN or None: those indices are NaN); ``tilt`` (D, N): the dog
    body's angle (rad; reported as its :func:`inclination`); ``arc`` (D, N): a cam contact's active arc. Returns
    index -> (D,) array in SI (angles in rad, ``rise_at``/``sink_at`` in [0, 2π)) and ``error`` -> a list of None
    or the design's problem."""
    phi = np.asarray(phi, float)
    x, y, vx, vy, ax = (np.atleast_2d(np.asarray(a, float)) for a in (x, y, vx, vy, ax))
    d, n = y.shape
    h = float(phi[1] - phi[0])
    if not (h > 0 and abs(n * h - TWO_PI) < 1e-9 and np.allclose(np.diff(phi), h)):
        raise ValueError("feed_indices needs one revolution of shaft angles in equal steps")
    if not omega > 0:
        raise ValueError("feed_indices needs a constant speed > 0 (the slopes are v/ω)")
    plate = np.broadcast_to(np.asarray(plate, float), (d,))
    z = y - plate[:, None]
    dx, dz = vx / omega, vy / omega
    dvx = ax / omega
    out = {k: np.full(d, np.nan) for k in INDICES}
    errors = [None] * d

    # rise and sink: exactly one each
    r, c, t, s = crossings(z, dz, h)
    n_up = np.bincount(r[s > 0], minlength=d)
    n_down = np.bincount(r[s < 0], minlength=d)
    good = (n_up == 1) & (n_down == 1)
    for k in np.flatnonzero(~good):
        errors[k] = (f"the feed dog must rise above the plate once a turn (rises {n_up[k]}, sinks {n_down[k]})")
    xs = at(x, dx, h, r, c, t)
    ang = phi[c] + t
    up, dn = (s > 0) & good[r], (s < 0) & good[r]
    rise = _per_row(d, r[up], ang[up] % TWO_PI)
    sink = _per_row(d, r[dn], ang[dn] % TWO_PI)
    x_rise, x_sink = _per_row(d, r[up], xs[up]), _per_row(d, r[dn], xs[dn])
    out["rise_at"], out["sink_at"] = rise, sink
    out["travel"] = x_sink - x_rise

    # effective travel: Σ x(sink) − Σ x(rise) over the crossings of the tooth depth (pairs round the turn)
    r2, c2, t2, s2 = crossings(z - tooth_depth, dz, h)
    eff = np.zeros(d)
    np.add.at(eff, r2, -s2 * at(x, dx, h, r2, c2, t2))
    out["effective_travel"] = np.where(good, eff, np.nan)

    zmax, _, _ = maximum(z, dz, h)
    out["height"] = np.where(good, zmax, np.nan)

    # the arc above the plate: every step's part inside [rise, sink] (round the turn), as sub-intervals of the step
    span = (sink - rise) % TWO_PI  # NaN rows stay NaN
    u = (phi[None, :] - rise[:, None]) % TWO_PI  # each step's start, measured from the rise
    area, absx = _arc_integrals(z, dz, x, dx, h, u, span, good)
    with np.errstate(invalid="ignore", divide="ignore"):
        out["fullness"] = np.where(good, np.abs(area) / (np.abs(out["travel"]) * out["height"]), np.nan)

    # samples inside the arc, and the arc's interpolated ends
    inside = (u <= span[:, None]) & good[:, None]
    ends = [(r[m], c[m], t[m]) for m in (up, dn)]

    def peak(v, dv):
        p = np.where(inside, np.abs(v), 0.0).max(axis=1)
        for rr, cc, tt in ends:
            if dv is None:  # linear between samples
                jj = (cc + 1) % n
                val = v[rr, cc] + (v[rr, jj] - v[rr, cc]) * tt / h
            else:
                val = at(v, dv, h, rr, cc, tt)
            p[rr] = np.maximum(p[rr], np.abs(val))
        return np.where(good, p, np.nan)

    vpeak = peak(vx, dvx)
    with np.errstate(invalid="ignore", divide="ignore"):
        out["speed_uniformity"] = vpeak / (omega * absx / span)
    out["peak_accel"] = peak(ax, None)

    # overlap with the needle in the cloth: the dog's |Δx| from the needle's entry to its sink, and from its rise
    # to the needle's exit, when they overlap
    if needle_in is not None and needle_out is not None:
        n_in = np.broadcast_to(np.asarray(needle_in, float), (d,))
        n_out = np.broadcast_to(np.asarray(needle_out, float), (d,))
        lead, lag = wrap(n_in - sink), wrap(rise - n_out)
        out["sink_lead"], out["rise_lag"] = lead, lag
        rows = np.arange(d)

        def x_at(angle):
            uu = (angle - phi[0]) % TWO_PI
            i = np.minimum((uu // h).astype(int), n - 1)
            return hermite(x[rows, i], x[rows, (i + 1) % n], dx[rows, i], dx[rows, (i + 1) % n], h, uu - i * h)

        with np.errstate(invalid="ignore"):
            ok = np.isfinite(lead) & np.isfinite(lag)
            safe_in, safe_out = np.where(ok, n_in, 0.0), np.where(ok, n_out, 0.0)
            ov = (np.where(lead < 0, np.abs(x_sink - x_at(safe_in)), 0.0)
                  + np.where(lag < 0, np.abs(x_at(safe_out) - x_rise), 0.0))
        out["overlap_travel"] = np.where(ok, ov, np.nan)

    # cam-arc switches: each side's acceleration extrapolated to the switch, located where the two sides'
    # velocities meet (the function below)
    if arc is not None:
        ar, ac, jumps = arc_jumps(np.atleast_2d(arc), vx, dvx, h)  # v and its slope dv/dφ = a/ω
        jump = np.zeros(d)
        np.maximum.at(jump, ar, np.abs(jumps) * omega)
        out["accel_jump"] = np.where(good, jump, np.nan)

    if tilt is not None:
        tilt = inclination(np.atleast_2d(np.asarray(tilt, float)))
        lo = np.where(inside, tilt, np.inf).min(axis=1)
        hi = np.where(inside, tilt, -np.inf).max(axis=1)
        for rr, cc, tt in ends:
            jj = (cc + 1) % n
            val = tilt[rr, cc] + inclination(tilt[rr, jj] - tilt[rr, cc]) * tt / h
            lo[rr], hi[rr] = np.minimum(lo[rr], val), np.maximum(hi[rr], val)
        out["tilt_min"], out["tilt_max"] = np.where(good, lo, np.nan), np.where(good, hi, np.nan)
    out["error"] = errors
    return out


def feed_observables(mech) -> tuple:
    """The indices, among ``mech``'s observables, of the dog's x, y, vx, vy, ax, the dog body's angle (its
    declared u axis; None without one) and the first cam contact's arc (None without a cam). Parts by role:
    the ``feed_dog`` point and its body (``feed_bar`` role if declared)."""
    desc = mech.description
    pt = desc.role(FEED_DOG)
    body = desc.role(FEED_BAR).name if desc.has_role(FEED_BAR) else pt.body
    tilt = desc.body(body).offset if body and desc.has("body", body) else None
    arcs = arc_columns(mech)
    arc = next(iter(arcs.values())) if arcs else None
    return tuple(pt.offset + k for k in range(5)) + (tilt, arc)


def group_arrays(mech, obs):
    """From a feed mechanism's observables ``obs`` (D, N, nobs) or (N, nobs), or a function observable index ->
    (D, N): the dog's x, y, vx, vy, ax, the dog body's angle and the first cam contact's arc (None where the
    mechanism has none; see :func:`feed_observables`)."""
    if callable(obs):
        get = obs
    else:
        obs = obs if obs.ndim == 3 else obs[None]

        def get(k):
            return obs[:, :, k]

    return tuple(None if k is None else get(k) for k in feed_observables(mech))


def as_dict(ix: dict, k: int = 0, exact_jump: float | None = None) -> dict:
    """summary.json's ``feed_dog.indices`` for design ``k``: every index in the unit shown (``<name>_<unit>``)."""
    out = {}
    for name, (unit, factor, _) in INDICES.items():
        v = float(ix[name][k]) * factor
        if name in ("rise_at", "sink_at"):
            v %= 360.0
        if name == "accel_jump" and exact_jump is not None:
            v = exact_jump
        key = f"{name}_{unit.replace('/', '_per_').replace('^2', '2')}" if unit else name
        out[key] = v if math.isfinite(v) else None
    out["tooth_depth_mm"] = TOOTH_DEPTH * 1e3
    return out


def machine_indices(machine, tm=None, step_deg: float = 0.25, switches: dict | None = None) -> dict:
    """Group name -> summary dict of the feed-dog indices of every group of ``machine`` with a feed dog and a
    throat plate (by role), on the timing sweep ``tm`` (sewgen.machine.timing.Timing; else a sweep of ``step_deg`` at
    the machine's speed). The needle events come from the timing (the machine's needle point and cloth);
    ``switches`` (group -> sewgen.machine.cams.ArcSwitch list) gives the exact acceleration jumps."""
    out = {}
    groups = [g for g in machine.groups
              if g.mechanism.description.has_role(FEED_DOG) and g.mechanism.description.has_role(THROAT_PLATE)]
    if not groups:
        return out
    if tm is not None:
        phi, w, motions, values = tm.phi, tm.speed, tm.motions, tm.values
    else:
        phi = np.radians(np.arange(0.0, 360.0, step_deg))
        w = machine.speed
        motions, values = machine.kinematics(phi, w), {}
    for g in groups:
        mo = motions[g.name]
        x, y, vx, vy, ax, tilt, arc = group_arrays(g.mechanism, mo.obs)
        ix = feed_indices(phi, x, y, vx, vy, ax, w, plate_height(g.mechanism, g.params or None),
                          needle_in=values.get("needle_in_cloth", np.nan),
                          needle_out=values.get("needle_out_cloth", np.nan), tilt=tilt, arc=arc)
        if ix["error"][0]:
            out[g.name] = {"error": ix["error"][0]}
            continue
        exact = None
        if switches and switches.get(g.name):
            dog = g.mechanism.description.role(FEED_DOG).name
            exact = max(abs(s.jumps[dog][0]) for s in switches[g.name])
        out[g.name] = as_dict(ix, 0, exact)
    return out
