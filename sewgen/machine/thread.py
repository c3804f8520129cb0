"""Thread control (seed 004's purpose): the needle thread's path, the take-up's supply and the stitch's demand.

The needle thread runs from the tension discs through guides to the needle eye (``[[thread.guides]]`` of the
model file): points on the frame (``at = ["x", "y"]``) or on moving parts (``point`` = a role such as
``"thread_eye"`` or ``"group.point"``, with an ``offset`` along that point's body's own axes — for the needle bar
the first axis points up the bar, so the needle-bar thread guide is ``point = "needle_eye"``, ``offset =
["45 mm", "0 mm"]``). Its length, segment by segment in the machine's plane,

    L(φ) = Σ |P_{k+1}(φ) − P_k(φ)|,

is longest when the take-up is high; at any other angle the path holds S(φ) = L_max − L(φ) less thread: that
is the **supply**, the thread the take-up (and the needle bar's thread guide) let below the needle eye.

The stitch's **demand** D(φ) is a parametric model of the thread needed below the needle eye, counted from the
moment the stitch is set — the take-up's top φ_T, where it pulls the stitch tight and draws the next stitch's
thread through the tension discs: D(φ_T) = S(φ_T), so the slack is zero there — plus:

* needle: the strand from the eye to the cloth's top surface, |y_eye − y_cloth|; from the moment the eye
  enters the cloth until the loop is cast off the thread carried below the cloth stays there (the rising
  needle leaves it as the loop, the hook holds it), so the depth below the cloth counts at its running maximum;
* loop: while the hook carries the loop (from the hook point's forward pass at the needle to the cast-off,
  ``stitch.loop_release`` past it), its two legs are stretched from the needle to the hook point:
  2 |H(φ) − H(φ_pickup)|;
* stitch: the cloth moves with the feed dog while the dog is above the plate; the thread laid along the cloth
  grows with the cloth's travel since φ_T (one stitch length per turn, drawn from the spool at the next φ_T).

Where the demand exceeds the supply the thread is drawn through the tension discs (the needle pulling it down
through the cloth, the take-up setting the stitch): that thread stays below the eye, so the **slack** is

    S − D + T(φ),   T = the thread drawn through the tension since the stitch was set,

T growing by the deficit D − S wherever it occurs — except while the hook carries the loop: the loop must not
pull thread through the tension (it would be robbed from the hook, the stitch skipped), so there T stays put
and the slack must stay ≥ 0 (rule ``thread_slack``, sewgen.machine.timing). T at the end of the turn is the thread one
stitch consumes. The take-up amount per stitch is L_max − L_min; the take-up eye's speed and acceleration are
seed 004's figure-3 quantities.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from sewgen.hermite import Series
from sewgen.machine.modelfile import Guide, ThreadPath
from sewgen.machine.parts import role_group
from sewgen.roles import FEED_DOG, HOOK_POINT, NEEDLE_EYE, THREAD_EYE

TWO_PI = 2.0 * math.pi


def find_point(machine, ref: str):
    """(group, point name) of ``ref``: "group.point" or a point role."""
    if "." in ref:
        gname, pname = ref.split(".", 1)
        for g in machine.groups:
            if g.name == gname and g.mechanism.description.has("point", pname):
                return g, pname
        raise KeyError(f"{machine.name}: no point {ref!r} (group.point)")
    for g in machine.groups:
        d = g.mechanism.description
        if d.has_role(ref) and d.roles[ref][0] == "point":
            return g, d.roles[ref][1]
    raise KeyError(f"{machine.name}: no group has a point with the role {ref!r}")


def guide_positions(machine, motions: dict, path: ThreadPath, n: int) -> list:
    """[(name, (n, 2) positions in m)] of every guide on the sweep of ``motions``."""
    out = []
    for gd in path.guides:
        if gd.at is not None:
            out.append((gd.name, np.tile(np.asarray(gd.at, float), (n, 1))))
            continue
        g, pname = find_point(machine, gd.point)
        mo = motions[g.name]
        p = mo.point(pname)
        pos = np.column_stack([p.x, p.y])
        du, dv = gd.offset
        if du or dv:
            body = g.mechanism.description.point(pname).body
            th = mo.body(body).angle
            pos = pos + np.column_stack([du * np.cos(th) - dv * np.sin(th), du * np.sin(th) + dv * np.cos(th)])
        out.append((gd.name, pos))
    return out


def path_length(points: list) -> np.ndarray:
    """L = Σ |P_{k+1} − P_k| over the guides' positions (each (n, 2)), m."""
    return sum(np.hypot(*(b - a).T) for (_, a), (_, b) in zip(points, points[1:]))


@dataclass
class ThreadControl:
    """Supply, demand and slack over the timing sweep (m), and the take-up's numbers."""

    phi: np.ndarray
    length: np.ndarray  # L(φ)
    supply: np.ndarray  # S = L_max − L
    demand: np.ndarray  # D = needle + loop + stitch
    drawn: np.ndarray  # T: thread drawn through the tension discs since the stitch was set
    parts: dict  # "needle", "loop", "stitch": the demand's terms
    set_at: float  # φ_T: the path is longest, the stitch set (rad)
    window: tuple  # (pick-up, cast-off), rad: where the hook carries the loop
    min_slack: float  # m, over the window
    min_slack_at: float  # rad
    take_up_amount: float  # L_max − L_min, m
    eye_speed: np.ndarray  # |v| of the take-up eye, m/s
    eye_accel: np.ndarray  # |a|, m/s²
    speed: float  # rad/s of the sweep
    per_stitch: float  # thread one stitch draws through the tension (T at the end of the turn), m
    guides: list  # (name, (n, 2)) positions

    @property
    def slack(self) -> np.ndarray:
        return self.supply - self.demand + self.drawn

    def in_window(self) -> np.ndarray:
        a, b = self.window
        return (self.phi - a) % TWO_PI <= (b - a) % TWO_PI

    def lines(self) -> list:
        d = math.degrees
        i, j = int(np.argmax(self.eye_speed)), int(np.argmax(self.eye_accel))
        return [f"thread: path through {len(self.guides)} guides, {self.length.min() * 1e3:.1f} – "
                f"{self.length.max() * 1e3:.1f} mm; take-up amount per stitch {self.take_up_amount * 1e3:.2f} mm "
                f"(stitch set at φ = {d(self.set_at) % 360:.1f}°); thread drawn through the tension per stitch "
                f"{self.per_stitch * 1e3:.2f} mm",
                f"thread: least slack S − D + T while the hook carries the loop {self.min_slack * 1e3:.2f} mm at "
                f"φ = {d(self.min_slack_at) % 360:.1f}° (largest demand {self.demand.max() * 1e3:.1f} mm)",
                f"take-up eye at {self.speed * 30 / math.pi:.0f} rpm: peak speed {self.eye_speed[i]:.3f} m/s at "
                f"φ = {d(self.phi[i]):.1f}°, peak acceleration {self.eye_accel[j]:.0f} m/s² at "
                f"φ = {d(self.phi[j]):.1f}°"]

    def as_dict(self) -> dict:
        i, j = int(np.argmax(self.eye_speed)), int(np.argmax(self.eye_accel))
        return {"path_mm": [round(float(self.length.min()) * 1e3, 3), round(float(self.length.max()) * 1e3, 3)],
                "take_up_amount_mm": round(self.take_up_amount * 1e3, 3),
                "stitch_set_deg": round(math.degrees(self.set_at) % 360, 3),
                "per_stitch_mm": round(self.per_stitch * 1e3, 3),
                "min_slack_mm": round(self.min_slack * 1e3, 3),
                "min_slack_deg": round(math.degrees(self.min_slack_at) % 360, 3),
                "max_demand_mm": round(float(self.demand.max()) * 1e3, 3),
                "eye_peak_speed_m_s": round(float(self.eye_speed[i]), 4),
                "eye_peak_speed_deg": round(math.degrees(self.phi[i]) % 360, 2),
                "eye_peak_accel_m_s2": round(float(self.eye_accel[j]), 2),
                "eye_peak_accel_deg": round(math.degrees(self.phi[j]) % 360, 2)}


def eye_motion(motion, point: str | None = None):
    """(|v| m/s, |a| m/s²) of the take-up's thread eye (role ``thread_eye``, or ``point``) over ``motion``'s
    sweep: seed 004's figure-3 quantities (the JACK A4 take-up at 5000 r/min is the catalog's default)."""
    name = point or motion.mechanism.description.role(THREAD_EYE).name
    p = motion.point(name)
    return np.hypot(p.vx, p.vy), np.hypot(p.ax, p.ay)


def thread_control(machine, motions: dict, tm, path: ThreadPath, stitch) -> ThreadControl:
    """Supply, demand and slack of ``machine`` over the timing sweep ``tm`` (sewgen.machine.timing.Timing)."""

    phi, n = tm.phi, len(tm.phi)
    pts = guide_positions(machine, motions, path, n)
    L = path_length(pts)
    v = tm.values
    S = L.max() - L
    set_at = v.get("take_up_top", float(phi[int(np.argmax(L))]))  # the stitch is set at the take-up's top
    k_set = int(np.argmin(np.abs(np.angle(np.exp(1j * (phi - set_at))))))
    order = (np.arange(n) + k_set) % n  # the turn from the stitch set on

    # needle: eye to the cloth's top surface; the depth below it held from the eye's entry to the cast-off
    ge, eye = role_group(machine, NEEDLE_EYE)
    ye = motions[ge.name].point(eye).y
    top = v.get("cloth_top", float(np.min(ye)))
    u = (phi - set_at) % TWO_PI
    below = np.maximum(top - ye, 0.0)
    above = np.maximum(ye - top, 0.0)
    release = v.get("release")
    pick = v.get("hook_fwd")
    entry_idx = [i for i in order if below[i] > 0.0]
    held = np.zeros(n, dtype=bool)
    if entry_idx and release is not None:
        u_in, u_rel = u[entry_idx[0]], (release - set_at) % TWO_PI
        held = (u >= u_in) & (u <= u_rel) if u_rel >= u_in else (u >= u_in)
    needle = above.copy()
    run = 0.0
    for i in order:
        if held[i]:
            run = max(run, below[i])
            needle[i] = above[i] + run
        else:
            run = 0.0
            needle[i] = above[i] + below[i]
    needle = needle - needle[k_set]

    # loop: two legs from the needle to the hook point while the hook carries the loop
    loop = np.zeros(n)
    window = (pick if pick is not None else set_at, release if release is not None else set_at)
    gh, hpt = role_group(machine, HOOK_POINT)
    if gh is not None and pick is not None and release is not None:
        hp = motions[gh.name].point(hpt)

        w = tm.speed
        hx = Series(phi, hp.x, hp.vx / w).at(pick)
        hy = Series(phi, hp.y, hp.vy / w).at(pick)
        on = (phi - pick) % TWO_PI <= (release - pick) % TWO_PI
        loop[on] = 2.0 * np.hypot(hp.x[on] - hx, hp.y[on] - hy)

    # stitch: the cloth's travel with the dog above the plate, since the stitch was set
    stitch_part = np.zeros(n)
    gf, dog = role_group(machine, FEED_DOG)
    plate = v.get("plate")
    if gf is not None and plate is not None:
        dp = motions[gf.name].point(dog)
        x, up = dp.x[order], dp.y[order] > plate
        dx = np.diff(np.append(x, x[0]))
        moved = np.where(up & np.roll(up, -1), dx, 0.0)
        cum = np.concatenate([[0.0], np.cumsum(np.abs(moved))[:-1]])
        stitch_part[order] = cum

    D = needle + loop + stitch_part + S[k_set]  # the slack is zero where the stitch is set
    a, b = window
    on = (phi - a) % TWO_PI <= (b - a) % TWO_PI
    drawn = np.zeros(n)
    deficit = D - S
    run = 0.0
    for i in order:  # thread drawn through the tension: never while the hook carries the loop
        if not on[i]:
            run = max(run, deficit[i])
        drawn[i] = run
    slack = S - D + drawn
    if on.any():
        k = int(np.flatnonzero(on)[np.argmin(slack[on])])
        min_slack, min_at = float(slack[k]), float(phi[k])
    else:
        min_slack, min_at = math.nan, math.nan
    gt, te = role_group(machine, THREAD_EYE)
    if gt is not None:
        spd, acc = eye_motion(motions[gt.name], te)
    else:
        spd = acc = np.zeros(n)
    return ThreadControl(phi, L, S, D, drawn, {"needle": needle, "loop": loop, "stitch": stitch_part}, set_at,
                         window, min_slack, min_at, float(L.max() - L.min()), spd, acc, tm.speed,
                         float(drawn[order[-1]]), pts)


__all__ = ["Guide", "ThreadControl", "ThreadPath", "eye_motion", "find_point", "guide_positions", "path_length",
           "thread_control"]
