"""A mechanism drawn from its description: where every part is at every position, in mm, ready to plot.

The compiled ``sg_<name>_anchors`` kernel gives, for one solved position, the world x, y of every drawing anchor
the manifest lists — each joint's attachment on each of its bodies (ground included), the named points, every
guide's origin and unit direction, the cam arcs' centres, the centres of mass — then each cam arc's radius and
world normal sector. From those alone:

* a moving body is the outline through its anchors: a bar for two places, a polygon (the convex hull, in an
  order fixed at the first position) for three or more; a moving guide adds the ends of its slot;
* a slider is a block on its guide, oriented along it; the guide is a dashed line over the travel;
* a cam is its arc profile; a flat follower whose cam has the same breadth at every position is a yoke, so
  its second face is drawn too;
* ground pivots (ground-side joint anchors) are hatched pivot symbols; a crank the shaft turns gets a dotted
  circle through its farthest joint;
* every named point is marked, with its path.

Nothing here knows a catalog mechanism: a user's mechanism is drawn the same way.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from sewgen.report.plots.common import MM, run_of

GROUND = "ground"


@dataclass
class Slider:
    """A slider block: its body, the joint it slides in, centre and unit guide direction (n, 2), size (mm)."""

    body: str
    joint: str
    center: np.ndarray
    direction: np.ndarray
    length: float
    width: float

    def corners(self) -> np.ndarray:
        """(n, 4, 2) mm: the block's rectangle at every position."""
        d = self.direction
        nrm = np.column_stack([-d[:, 1], d[:, 0]])
        hl, hw = self.length / 2, self.width / 2
        c = self.center
        return np.stack([c - hl * d - hw * nrm, c + hl * d - hw * nrm, c + hl * d + hw * nrm,
                         c - hl * d + hw * nrm], axis=1)


@dataclass
class Guide:
    """A guide line (a slider's, a slot's or a cam follower's face) over the travel it is used: ends (n, 2, 2)
    mm; ``fixed`` when it belongs to the ground (then every position is the same)."""

    joint: str
    body: str
    ends: np.ndarray
    fixed: bool
    kind: str  # "slide", "slot" or "face"


@dataclass
class Linkage:
    """One group drawn as a plane linkage, in mm, at every position of its sweep (n positions).

    ``bodies``: moving body -> outline (n, k, 2): k = 2 a bar, k >= 3 a polygon. ``joints``: joint -> {body:
    (n, 2)}, each joint's attachment on each of its bodies (ground included). ``pins``: (n, m, 2) the moving
    pins. ``pivots``: (k, 2) ground pivots. ``circles``: (centre (2,), radius) of the cranks the shaft turns.
    ``guides``, ``sliders``: see :class:`Guide`, :class:`Slider`. ``cams``: cam body -> profile (n, m, 2).
    ``rods``: (crank, body, (n, 2, 2)) each ball-jointed rod from its crank pin's projection to its planar pin.
    ``points``: every named point (n, 2); ``marks``: the points whose paths are drawn (role-tagged first).
    ``roles``: point role -> point name. ``body_roles``: body -> role."""

    group: str
    mechanism: str
    bodies: dict = field(default_factory=dict)
    joints: dict = field(default_factory=dict)
    pins: np.ndarray | None = None
    pivots: np.ndarray | None = None
    circles: list = field(default_factory=list)
    guides: list = field(default_factory=list)
    sliders: list = field(default_factory=list)
    cams: dict = field(default_factory=dict)
    rods: list = field(default_factory=list)  # (body, body, (n, 2, 2) mm): ball-jointed rods, end to end
    points: dict = field(default_factory=dict)
    marks: list = field(default_factory=list)
    roles: dict = field(default_factory=dict)
    body_roles: dict = field(default_factory=dict)

    @property
    def n(self) -> int:
        return len(next(iter(self.points.values()))) if self.points else 0

    def extent(self, margin: float = 5.0):
        """(x0, x1, y0, y1) mm round everything drawn, at every position, with ``margin`` (mm) to spare."""
        parts = [v.reshape(-1, 2) for v in (*self.bodies.values(), *self.cams.values())]
        parts += [gd.ends.reshape(-1, 2) for gd in self.guides]
        parts += [s.corners().reshape(-1, 2) for s in self.sliders]
        parts += [self.points[m] for m in self.marks]
        if self.pivots is not None:
            parts.append(self.pivots)
        parts += [np.array([c - r, c + r]) for c, r in self.circles]
        xy = np.concatenate(parts) if parts else np.zeros((1, 2))
        lo, hi = xy.min(axis=0) - margin, xy.max(axis=0) + margin
        return lo[0], hi[0], lo[1], hi[1]


# -- the anchors kernel ----------------------------------------------------------------------------------------

def has_anchors(mech) -> bool:
    """Whether ``mech`` was compiled with drawing anchors (a manifest with "anchors" and its kernel)."""
    return bool(mech.description.anchors) and "nanchor_out" in mech.description.sizes


def anchor_values(mech, motion, p=None, held=None) -> np.ndarray:
    """The anchors kernel over a solved ``motion``: (n, nanchor_out), SI. ``p``: the run's parameter vector
    (default: the defaults), ``held``: its held inputs (default: the defaults)."""
    p = mech.param_vector(None) if p is None else np.asarray(p, dtype=float)
    held = np.asarray(mech.held_vector(None) if held is None else held, dtype=float).reshape(-1)
    n = len(motion.phi)
    x = np.column_stack([np.asarray(motion.phi, float)] + [np.full(n, h) for h in held])
    q = np.asarray(motion.q, float).reshape(n, -1)
    return np.array([mech.anchors(q[i], x[i], params=p) for i in range(n)]).reshape(n, -1)


# -- building the drawing --------------------------------------------------------------------------------------

def _hull_order(pts: np.ndarray) -> list:
    """Indices of the convex hull of 2-D points (k, 2), counter-clockwise (monotone chain)."""
    idx = sorted(range(len(pts)), key=lambda i: (pts[i, 0], pts[i, 1]))

    def cross(o, a, b):
        return (pts[a, 0] - pts[o, 0]) * (pts[b, 1] - pts[o, 1]) - (pts[a, 1] - pts[o, 1]) * (pts[b, 0] - pts[o, 0])

    lower, upper = [], []
    for i in idx:
        while len(lower) >= 2 and cross(lower[-2], lower[-1], i) <= 0:
            lower.pop()
        lower.append(i)
    for i in reversed(idx):
        while len(upper) >= 2 and cross(upper[-2], upper[-1], i) <= 0:
            upper.pop()
        upper.append(i)
    return lower[:-1] + upper[:-1]


def _dist(a, b) -> float:
    return float(np.hypot(a[0] - b[0], a[1] - b[1]))


def _outline(places: list) -> np.ndarray | None:
    """A body's outline (n, k, 2) through its places (each (n, 2), rigid with the body): duplicates merged, a
    bar between the two farthest places when they lie on a line, else the convex hull (its order taken at the
    first position: a rigid body keeps it)."""
    if not places:
        return None
    pts = np.stack(places, axis=1)  # (n, k, 2)
    first = pts[0]
    scale = max(float(np.ptp(pts.reshape(-1, 2), axis=0).max()), 1e-9)
    apart = lambda i, j: float(np.hypot(*(pts[:, i] - pts[:, j]).T).max())  # noqa: E731 (a projected body is not rigid)
    keep = []
    for i in range(len(first)):
        if all(apart(i, j) > 1e-6 * scale for j in keep):
            keep.append(i)
    if len(keep) < 2:
        return None
    sub = first[keep]
    i, j = max(((i, j) for i in range(len(sub)) for j in range(i)), key=lambda ij: _dist(sub[ij[0]], sub[ij[1]]))
    length = _dist(sub[i], sub[j])
    u = (sub[i] - sub[j]) / length
    off = np.abs((sub[:, 0] - sub[j, 0]) * u[1] - (sub[:, 1] - sub[j, 1]) * u[0])
    if len(keep) == 2 or off.max() < 1e-3 * length:  # on one line: a bar from end to end
        order = [keep[j], keep[i]]
    else:
        order = [keep[k] for k in _hull_order(sub)]
    return pts[:, order, :]


def linkage_of(mech, motion, *, p=None, held=None, group: str = "") -> Linkage:
    """How to draw ``mech`` over a solved ``motion`` (p, held: the run's parameter vector and held inputs)."""
    desc = mech.description
    lk = Linkage(group or mech.name, mech.name)
    for pt in desc.points:
        pm = motion.point(pt.name)
        lk.points[pt.name] = np.column_stack([pm.x, pm.y]) * MM
        if pt.role:
            lk.roles[pt.role] = pt.name
    lk.body_roles = {b.name: b.role for b in desc.bodies if b.role}
    lk.marks = [pt.name for pt in desc.points if pt.role] + [pt.name for pt in desc.points if not pt.role]
    if not has_anchors(mech):  # a build without drawing anchors: its named points only
        return lk
    out = anchor_values(mech, motion, p, held)
    xy = {an.index: out[:, 2 * an.index:2 * an.index + 2] * (1.0 if an.kind == "guide_direction" else MM)
          for an in desc.anchors}  # mm; the guides' directions stay unit vectors
    kinds = {j.name: j.kind for j in desc.joints}
    kinds.update({r.name: r.kind for r in desc.reactions if r.name not in kinds})
    places = _places(desc, xy, kinds, lk)
    block = max(0.05 * _span(xy, desc), 2.0)  # mm: a slider block's length
    lk.cams = _cam_profiles(desc, xy, out)
    pins = _guides(desc, xy, kinds, lk, places, block)
    for b in desc.bodies:
        ol = _outline(places[b.name])
        if ol is not None:
            lk.bodies[b.name] = ol
    for jname, sides in lk.joints.items():  # a rod to a spatial crank: a line between its ball ends
        if kinds.get(jname) == "rod" and len(sides) == 2:
            (ba, ea), (bb, eb) = sides.items()
            lk.rods.append((ba, bb, np.stack([ea, eb], axis=1)))
            pins += [ea, eb]
    _pivots(desc, kinds, lk, pins, len(motion.phi))
    return lk


def _places(desc, xy, kinds, lk) -> dict:
    """moving body -> [(n, 2) mm] of the anchors its outline goes through; fills ``lk.joints``."""
    places: dict = {b.name: [] for b in desc.bodies}
    guide_body = {an.joint: an.body for an in desc.anchors if an.kind == "guide"}
    for an in desc.anchors:
        if an.kind == "joint":
            joint = an.joint or an.name
            lk.joints.setdefault(joint, {})[an.body] = xy[an.index]
            # a body's outline goes through its pins; a guide's body gets the slot instead of the point running in
            # it (see _guides), and a cam's contact belongs to neither body
            if an.body in places and kinds.get(joint) != "cam" and guide_body.get(joint) != an.body:
                places[an.body].append(xy[an.index])
        elif an.kind in ("point", "guide") and an.body in places:
            places[an.body].append(xy[an.index])
    return places


def _cam_profiles(desc, xy, out, k: int = 12) -> dict:
    """cam body -> its profile (n, m, 2) mm: every arc sampled at ``k`` points, all sorted by the direction of
    their outward normal (the arcs' normal sectors tile the circle)."""
    arcs: dict = {}
    first = 2 * len(desc.anchors)  # the arcs' radius, normal_from, normal_to follow the anchors' x, y
    for arc in desc.arcs:
        r, t0, t1 = (out[:, first + 3 * arc.out + j] for j in range(3))
        arcs.setdefault(arc.body, []).append((xy[arc.center], r * MM, t0, np.where(t1 < t0, t1 + 2 * np.pi, t1)))
    profiles = {}
    s = np.linspace(0.0, 1.0, k)
    for body, items in arcs.items():
        xs, ts = [], []
        for c, r, t0, t1 in items:
            t = t0[:, None] + (t1 - t0)[:, None] * s[None, :]
            xs.append(c[:, None, :] + r[:, None, None] * np.stack([np.cos(t), np.sin(t)], axis=-1))
            ts.append(np.mod(t, 2 * np.pi))
        allx, allt = np.concatenate(xs, axis=1), np.concatenate(ts, axis=1)
        order = np.argsort(allt, axis=1, kind="stable")
        profiles[body] = np.take_along_axis(allx, order[:, :, None], axis=1)
    return profiles


def _guides(desc, xy, kinds, lk, places, block) -> list:
    """The guides (slides, slots, cam faces) over the travel they see, and the slider blocks on them, into
    ``lk``; a moving guide's ends join its body's places. Returns the pins that run in slots ((n, 2) mm)."""
    by_joint: dict = {}
    for an in desc.anchors:
        if an.joint is not None:
            by_joint.setdefault(an.joint, []).append(an)
    pins = []
    for jname, ans in by_joint.items():
        kind = kinds.get(jname, "")
        origin = next((a for a in ans if a.kind == "guide"), None)
        direc = next((a for a in ans if a.kind == "guide_direction"), None)
        if origin is None or direc is None:
            continue
        o, d = xy[origin.index], xy[direc.index]
        d = d / np.maximum(np.hypot(d[:, 0], d[:, 1]), 1e-300)[:, None]
        gbody = origin.body
        if kind == "cam":
            prof = lk.cams.get(next((a.body for a in ans if a.kind == "arc_center"), None))
            ends = [] if prof is None else _faces(o, d, prof, margin=0.15 * block)
            kind_drawn = "face"
        else:
            follower = next((a for a in ans if a.kind == "joint" and a.body != gbody), None)
            if follower is None:
                continue
            pt = xy[follower.index]
            s = np.einsum("nc,nc->n", pt - o, d)
            slide = kind == "prismatic" or (kind != "slot" and desc.has("body", follower.body)
                                            and desc.body(follower.body).kind == "slider")
            margin = 0.6 * block if slide else 0.25 * block
            ends = [np.stack([o + (s.min() - margin) * d, o + (s.max() + margin) * d], axis=1)]
            kind_drawn = "slide" if slide else "slot"
            if slide:
                lk.sliders.append(Slider(follower.body, jname, pt, d, block, 0.55 * block))
            else:
                pins.append(pt)
        for e in ends:
            lk.guides.append(Guide(jname, gbody, e, gbody == GROUND, kind_drawn))
            if gbody in places:
                places[gbody] += [e[:, 0], e[:, 1]]
    return pins


def _pivots(desc, kinds, lk, pins, n) -> None:
    """Ground pivots (the ground side of the revolutes, once per place), the moving pins (one per revolute, and
    the pins in slots), and a dotted circle round each crank the shaft turns, through its farthest joint."""
    pivots = []
    for jname, sides in lk.joints.items():
        if kinds.get(jname, "revolute") != "revolute":
            continue
        if GROUND in sides:
            if all(_dist(sides[GROUND][0], v) > 1e-6 for v in pivots):
                pivots.append(sides[GROUND][0])
        else:
            pins.append(next(iter(sides.values())))
    for body in desc.driven_bodies:
        centre = next((sides[GROUND][0] for sides in lk.joints.values() if GROUND in sides and body.name in sides),
                      None)
        reach = [_dist(sides[body.name][0], centre) for sides in lk.joints.values()
                 if centre is not None and body.name in sides and GROUND not in sides]
        if reach and max(reach) > 1e-9:
            lk.circles.append((centre, max(reach)))
    lk.pivots = np.array(pivots) if pivots else None
    lk.pins = np.stack(pins, axis=1) if pins else np.zeros((n, 0, 2))


def _span(xy: dict, desc) -> float:
    """The size (mm) of a mechanism's drawing: the larger side of the box round its anchors (not the
    directions, not the centres of mass)."""
    pts = np.concatenate([xy[a.index] for a in desc.anchors if a.kind not in ("guide_direction", "com")])
    return float(max(np.ptp(pts[:, 0]), np.ptp(pts[:, 1]), 1e-3))


def _faces(o, d, prof, margin):
    """The follower face(s) of a cam joint (each (n, 2, 2) mm): the declared face over the profile's extent
    along it; and, when the cam's breadth across the face is the same at every position (a constant-breadth
    cam in a yoke), the opposite face too."""
    rel = prof - o[:, None, :]
    along = np.einsum("nkc,nc->nk", rel, d)
    nrm = np.column_stack([-d[:, 1], d[:, 0]])  # the face normal: points away from the cam
    across = np.einsum("nkc,nc->nk", rel, nrm)
    lo, hi = along.min() - margin, along.max() + margin
    faces = [np.stack([o + lo * d, o + hi * d], axis=1)]
    breadth = across.max(axis=1) - across.min(axis=1)
    if np.ptp(breadth) < 0.01 * breadth.mean():  # the sampled arcs fall short of the breadth by their sag
        shift = o - breadth.max() * nrm
        faces.append(np.stack([shift + lo * d, shift + hi * d], axis=1))
    return faces


def linkage(g, fa) -> Linkage:
    """How to draw group ``g`` (a machine Group) from its results ``fa`` (ForceAnalysis, or a Motion), with the
    parameters and held inputs of that run."""
    p, held, _loads = run_of(fa)
    if p is None:
        p = g.mechanism.param_vector(getattr(g, "params", None) or None)
    if held is None:
        held = g.mechanism.held_vector(getattr(g, "held", None) or None)
    return linkage_of(g.mechanism, getattr(fa, "motion", fa), p=p, held=held, group=g.name)
