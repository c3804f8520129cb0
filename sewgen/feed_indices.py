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
``tilt_min``/``tilt_max``  the dog body's angle over φ_r..φ_s (+: its front raised)                      deg
=========================  ===========================================================================  ======

Every crossing and extreme is found on the cubic Hermite interpolant of the samples and their exact shaft-angle
derivatives (dx/dφ = vx/ω, as sewgen.timing does), so the indices are accurate far below the sweep's step; the
integrals are 3-point Gauss on each step (exact for the interpolants' product); the peaks of |vx|, |ax| are the
sampled ones (and the interpolated ends of the arc). The acceleration jump at an arc switch between two samples
is estimated by extrapolating ax linearly from each side to the step's middle (to O(h); sewgen.cams brackets
the switch exactly, which summary.json uses).

A design whose dog does not rise above the plate exactly once a turn gets NaN indices and an ``error``.
"""
from __future__ import annotations

import math

import numpy as np

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
    "tilt_min": ("deg", 180.0 / math.pi, "least dog tilt while feeding"),
    "tilt_max": ("deg", 180.0 / math.pi, "greatest dog tilt while feeding"),
    "rise_at": ("deg", 180.0 / math.pi, "shaft angle where the dog rises above the plate"),
    "sink_at": ("deg", 180.0 / math.pi, "shaft angle where the dog sinks below the plate"),
}

_GAUSS_X = np.array([-math.sqrt(0.6), 0.0, math.sqrt(0.6)])
_GAUSS_W = np.array([5.0, 8.0, 5.0]) / 9.0


def column(name: str) -> str:
    """The study-table column of index ``name``: ``feed_<name> [unit]``."""
    unit = INDICES[name][0]
    return f"feed_{name} [{unit}]" if unit else f"feed_{name}"


# -- cubic Hermite pieces, vectorised -------------------------------------------------------------------------

def hermite(p0, p1, d0, d1, h, t):
    """Cubic Hermite on [0, h] at t: values p0, p1, slopes d0, d1 (all broadcast)."""
    s = t / h
    return ((2 * s**3 - 3 * s**2 + 1) * p0 + (s**3 - 2 * s**2 + s) * h * d0
            + (-2 * s**3 + 3 * s**2) * p1 + (s**3 - s**2) * h * d1)


def hermite_slope(p0, p1, d0, d1, h, t):
    """d/dt of :func:`hermite`."""
    s = t / h
    return ((6 * s**2 - 6 * s) * p0 / h + (3 * s**2 - 4 * s + 1) * d0
            + (-6 * s**2 + 6 * s) * p1 / h + (3 * s**2 - 2 * s) * d1)


def _next(a):
    return np.roll(a, -1, axis=-1)


def crossings(z, dz, h, iters: int = 60):
    """Every sign change of z (D, N) over one periodic turn: rows, sample index i (the step i..i+1), the offset
    t in [0, h] of the crossing on the Hermite piece, and the sign (+1 rising through 0, −1 falling)."""
    neg = z < 0.0
    rows, cols = np.nonzero(neg != _next(neg))
    n = z.shape[1]
    j = (cols + 1) % n
    p0, p1, d0, d1 = z[rows, cols], z[rows, j], dz[rows, cols], dz[rows, j]
    lo, hi = np.zeros(len(rows)), np.full(len(rows), h)
    f_lo_neg = p0 < 0.0
    for _ in range(iters):
        mid = 0.5 * (lo + hi)
        same = (hermite(p0, p1, d0, d1, h, mid) < 0.0) == f_lo_neg
        lo = np.where(same, mid, lo)
        hi = np.where(same, hi, mid)
    return rows, cols, 0.5 * (lo + hi), np.where(f_lo_neg, 1, -1)


def at(y, dy, h, rows, cols, t):
    """The Hermite interpolant of y (D, N) on the pieces (rows, cols) at offsets t."""
    j = (cols + 1) % y.shape[1]
    return hermite(y[rows, cols], y[rows, j], dy[rows, cols], dy[rows, j], h, t)


def maximum(y, dy, h, iters: int = 60):
    """Per row: the largest value of the Hermite interpolant (found near the largest sample) and its (index,
    offset). The slope dy changes sign at the extreme; it is bisected on the derivative of the piece."""
    d, n = y.shape
    rows = np.arange(d)
    k = np.argmax(y, axis=1)
    left = dy[rows, k] < 0.0  # the maximum lies before sample k
    i = np.where(left, (k - 1) % n, k)
    j = (i + 1) % n
    p0, p1, d0, d1 = y[rows, i], y[rows, j], dy[rows, i], dy[rows, j]
    lo, hi = np.zeros(d), np.full(d, h)
    ok = (d0 >= 0.0) & (d1 <= 0.0)
    for _ in range(iters):
        mid = 0.5 * (lo + hi)
        up = hermite_slope(p0, p1, d0, d1, h, mid) > 0.0
        lo = np.where(up, mid, lo)
        hi = np.where(up, hi, mid)
    t = np.where(ok, 0.5 * (lo + hi), np.where(left, h, 0.0))
    return np.maximum(hermite(p0, p1, d0, d1, h, t), y[rows, k]), i, t


def _per_row(d, rows, values):
    out = np.full(d, np.nan)
    out[rows] = values
    return out


def wrap(a):
    """Angles into (−π, π]."""
    return np.pi - (np.pi - np.asarray(a)) % TWO_PI


# -- the indices ------------------------------------------------------------------------------------------------

def feed_indices(phi, x, y, vx, vy, ax, omega, plate, *, needle_in=None, needle_out=None,
                 tooth_depth: float = TOOTH_DEPTH, tilt=None, arc=None) -> dict:
    """Every feed-dog index (see the module docstring) for D designs at once.

    ``phi`` (N,): one revolution of machine shaft angles in equal steps; x, y, vx, vy, ax (D, N): the dog tip's
    position (m), velocity and horizontal acceleration at constant speed ``omega`` (rad/s, > 0); ``plate`` (D,)
    or scalar: the plate's height. ``needle_in``/``needle_out`` (D,) or scalar: the machine angles where the
    needle point enters and leaves the cloth (NaN or None: those indices are NaN); ``tilt`` (D, N): the dog
    body's angle (rad); ``arc`` (D, N): a cam contact's active arc. Returns index -> (D,) array in SI (angles in
    rad, ``rise_at``/``sink_at`` in [0, 2π)) and ``error`` -> a list of None or the design's problem."""
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
    area, absx = np.zeros(d), np.zeros(d)
    jn = (np.arange(n) + 1) % n
    for shift in (0.0, TWO_PI):
        a = np.clip(np.maximum(u - shift, 0.0), None, span[:, None])
        b = np.clip(np.minimum(u - shift + h, span[:, None]), 0.0, None)
        inside = b > a
        if not inside.any():
            continue
        rr, cc = np.nonzero(inside & good[:, None])
        t0, t1 = a[rr, cc] - (u[rr, cc] - shift), b[rr, cc] - (u[rr, cc] - shift)
        half = 0.5 * (t1 - t0)
        for xi, wi in zip(_GAUSS_X, _GAUSS_W):
            tq = t0 + half * (1.0 + xi)
            jj = jn[cc]
            zq = hermite(z[rr, cc], z[rr, jj], dz[rr, cc], dz[rr, jj], h, tq)
            xq = hermite_slope(x[rr, cc], x[rr, jj], dx[rr, cc], dx[rr, jj], h, tq)
            np.add.at(area, rr, wi * half * zq * xq)
            np.add.at(absx, rr, wi * half * np.abs(xq))
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

    # cam-arc switches: ax extrapolated from each side to the middle of the step
    if arc is not None:
        arc = np.atleast_2d(arc)
        sw = arc != _next(arc)
        ar, ac = np.nonzero(sw)
        prev, nxt, nxt2 = (ac - 1) % n, (ac + 1) % n, (ac + 2) % n
        left = ax[ar, ac] + 0.5 * (ax[ar, ac] - ax[ar, prev])
        right = ax[ar, nxt] + 0.5 * (ax[ar, nxt] - ax[ar, nxt2])
        jump = np.zeros(d)
        np.maximum.at(jump, ar, np.abs(right - left))
        out["accel_jump"] = np.where(good, jump, np.nan)

    if tilt is not None:
        tilt = wrap(np.atleast_2d(np.asarray(tilt, float)))
        lo = np.where(inside, tilt, np.inf).min(axis=1)
        hi = np.where(inside, tilt, -np.inf).max(axis=1)
        for rr, cc, tt in ends:
            jj = (cc + 1) % n
            val = tilt[rr, cc] + wrap(tilt[rr, jj] - tilt[rr, cc]) * tt / h
            lo[rr], hi[rr] = np.minimum(lo[rr], val), np.maximum(hi[rr], val)
        out["tilt_min"], out["tilt_max"] = np.where(good, lo, np.nan), np.where(good, hi, np.nan)
    out["error"] = errors
    return out


def group_arrays(mech, obs):
    """From a feed mechanism's observables ``obs`` (D, N, nobs) or (N, nobs): the dog's x, y, vx, vy, ax, the
    dog body's angle (its declared u axis) and the first cam contact's arc (or None). Parts by role: the
    ``feed_dog`` point and its body (``feed_bar`` role if declared)."""
    from .cams import _arc_columns
    from .roles import FEED_BAR, FEED_DOG

    desc = mech.description
    obs = obs if obs.ndim == 3 else obs[None]
    pt = desc.role(FEED_DOG)
    off = pt.offset
    x, y, vx, vy, ax = (obs[:, :, off + k] for k in (0, 1, 2, 3, 4))
    body = desc.role(FEED_BAR).name if desc.has_role(FEED_BAR) else pt.body
    tilt = obs[:, :, desc.body(body).offset] if body and desc.has("body", body) else None
    arcs = _arc_columns(mech)
    arc = obs[:, :, next(iter(arcs.values()))] if arcs else None
    return x, y, vx, vy, ax, tilt, arc


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
    throat plate (by role), on the timing sweep ``tm`` (sewgen.timing.Timing; else a sweep of ``step_deg`` at
    the machine's speed). The needle events come from the timing (the machine's needle point and cloth);
    ``switches`` (group -> sewgen.cams.ArcSwitch list) gives the exact acceleration jumps."""
    from .feed import plate_height
    from .roles import FEED_DOG, THROAT_PLATE

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
