"""Symbolic kinetostatics: the force-balance matrices A(q) f = b(q, q', q'', loads) (seed 000 §二(三)).

Seed 000 writes, for every moving body i, m_i·g̈_i = Σ F and I_i·θ̈_i = Σ M_G (its eqs. for 构件 13–17 and
the feed group), stacks them into one matrix per group and solves "by numerical methods in one go". Here the
same equations are derived from the declaration, for any mechanism:

* unknowns f: two reaction components per revolute (force on its body b from its body a, frame axes), the
  normal force and the couple per prismatic (on the slider side, normal n = guide direction turned +90°),
  and one driving torque per driven body (a held input's is its holding torque);
* rows: per moving body, force x, force y, moment about the centre of mass G;
* b: m(a_G − g) minus the external loads, and I·α minus the loads' moments about G.

Driven bodies are pinned to ground at their pivot (joint ``<body>.pivot``); a slider's guide is a prismatic
joint ``<slider>.guide``. Loads: a force (frame components) at every named point of a moving body, a torque
on every moving body — values per position at run time, so windows and magnitudes are not baked in. Gravity
is a run-time vector in the mechanism's plane.

The kinematic quantities b needs (a_G, α, ω, v of points) are the motion kernel's observables: they enter as
placeholder symbols ``o_k`` (= obs[k]) so nothing is computed twice.

The system is square for every declaration the kinematics accepts (3 per body = 2 per joint + 1 per drive,
given as many closure equations as coordinates). Its solve is planned here, in two steps:

1. elimination on constant pivots: the force rows carry ±1 entries, which can never vanish, so Gaussian
   elimination on them is fixed at derive time (Markowitz order, least fill first). What remains is the
   Schur complement on the moment rows — for a dyad the classical 2 × 2 of its two moment equations;
2. the Schur complement in block-triangular order (Dulmage–Mendelsohn: a perfect matching, then strongly
   connected blocks in dependency order, as KLU does), each block by the runtime's pivoted LU. No pivot that
   depends on the position is ever fixed symbolically.
"""
from __future__ import annotations

import sympy as sp

from .elements import ELEMENTS
from .joints import Reaction, kind_of
from .kinematics import Kinematics, rot
from .vocabulary import Attachment, Body, DeclarationError


class Kinetostatics:
    """A, b, the outputs derived from the solution, and the block order to solve A f = b in."""

    def __init__(self, kin: Kinematics):
        self.kin, self.mech = kin, kin.mech
        mech = self.mech
        self.moving = [b for b in mech.bodies if b.moving]
        self.reactions = self._reactions()
        self.obs = [sp.Symbol(f"o_{k}", real=True) for k in range(len(kin.observables))]
        self.gravity = [sp.Symbol("gv_0", real=True), sp.Symbol("gv_1", real=True)]
        self._obs_index = {o.name: k for k, o in enumerate(kin.observables)}
        self.load_slots = self._load_slots()
        self.loads = [sp.Symbol(f"ld_{k}", real=True) for k in range(len(self.load_slots))]
        self.f = [sp.Symbol(f"f_{k}", real=True) for k in range(sum(len(r.columns) for r in self.reactions))]
        self.unknown_names = [f"{r.name}.{c}" for r in self.reactions for c in r.columns]
        self.column, k = {}, 0  # reaction name -> index of its first unknown in f
        for r in self.reactions:
            self.column[r.name] = k
            k += len(r.columns)
        self.row_names = [f"{b.name}.{e}" for b in self.moving for e in ("x", "y", "moment")]
        self.frictions = self._frictions()
        self.A, self.b = self._balance()
        self.eliminated, self.schur, self.schur_rhs = self._eliminate_constant_pivots()
        self.blocks = self._block_order()
        self.outputs = self._outputs()

    # -- what acts where ------------------------------------------------------------------------------------
    def _reactions(self) -> list[Reaction]:
        """The joints the bodies imply, every declared joint (each as its kind makes it, derive.joints), then
        the drive of every driven body."""
        kin, mech = self.kin, self.mech
        out = [kind_of(j).reaction(kin, j) for j in mech.implied_joints() + mech.joints]
        for body in mech.bodies:
            if body.kind == "driven" and body.guide is not None:  # a held travel: a force along the guide
                g = body.guide
                out.append(Reaction(f"{body.name}.drive", "linear_drive", g.body, body,
                                    Attachment(body, sp.S.Zero, sp.S.Zero),
                                    guide_angle=kin.pose[g.body][2] + g.angle, input_index=body.input_index))
            elif body.kind == "driven":
                rate = body.sense * body.ratio if body.input_index == 0 else sp.S.One  # d(relative angle)/d(input)
                out.append(Reaction(f"{body.name}.drive", "drive", body.pivot.body, body, None, sense=rate,
                                    input_index=body.input_index))
        return out

    def _frictions(self) -> list[tuple]:
        """(reaction, symbol fr_k, its update from the reactions) of every joint with Coulomb friction: the
        friction moment or force is a known load in b, iterated to a fixed point with the reactions (the
        forces kernel: fr ← update(f) until it settles; A never changes)."""
        by_name = {r.name: r for r in self.reactions}
        out = []
        for k, (name, mu, radius) in enumerate(self.mech.frictions):
            r = by_name[name]
            c = self.column[r.name]
            update = r.joint_kind.friction_magnitude(self, r, self.f[c:c + len(r.columns)], mu, radius)
            out.append((r, sp.Symbol(f"fr_{k}", real=True), update))
        return out

    def _load_slots(self) -> list[tuple]:
        """(name, kind, body, attachment, component): fx, fy per named point of a moving body, torque per body."""
        slots = []
        for name, att, _doc in self.mech.points:
            if att.body.moving:
                slots += [(name, "fx", att.body, att), (name, "fy", att.body, att)]
        for body in self.moving:
            slots.append((body.name, "torque", body, None))
        return slots

    def o(self, name: str) -> sp.Symbol:
        """The placeholder of observable ``name`` (see derive.kinematics: "<body>.com.x_dd", "<point>.x_d")."""
        return self.obs[self._obs_index[name]]

    def arm(self, body: Body, world_point) -> tuple:
        """world_point − G of ``body``, world axes."""
        gx, gy, _gz = self.kin.com(body)
        return (world_point[0] - gx, world_point[1] - gy)

    def point_velocity(self, att: Attachment) -> tuple:
        """World velocity of a point fixed in its body: v_G + ω × (point − G); zero on the frame."""
        body = att.body
        if not body.moving:
            return (sp.S.Zero, sp.S.Zero)
        rx, ry = self.own_arm(att)
        w = self.o(f"{body.name}.angle_d")
        return (self.o(f"{body.name}.com.x_d") - w * ry, self.o(f"{body.name}.com.y_d") + w * rx)

    def velocity_at(self, body: Body, world_point) -> tuple:
        """World velocity of the point of ``body`` that is at ``world_point`` now: v_G + ω × (point − G)."""
        if not body.moving:
            return (sp.S.Zero, sp.S.Zero)
        rx, ry = self.arm(body, world_point)
        w = self.o(f"{body.name}.angle_d")
        return (self.o(f"{body.name}.com.x_d") - w * ry, self.o(f"{body.name}.com.y_d") + w * rx)

    def own_arm(self, att: Attachment) -> tuple:
        """A point fixed in its body, relative to the body's G: R(θ)(u − u_G, v − v_G). A spatial crank's moment
        row is about its own axis (see :meth:`_spatial_moment`): its one planar point, its origin (the pivot, on
        the axis), has no arm about it."""
        body = att.body
        if body.axis is not None:
            if att.u != 0 or att.v != 0:
                raise DeclarationError(f"{self.mech.name}: {body.name!r} turns about an axis in space: its points "
                                       f"are {body.name}.pin(radius, along)")
            return (sp.S.Zero, sp.S.Zero)
        return rot(self.kin.pose[body][2], att.u - body.com[0], att.v - body.com[1])

    def _spatial_moment(self, body: Body) -> sp.Expr:
        """The right-hand side of a spatial crank's moment row, about its fixed axis (unit a through A):

            Σ M_A·a = (I + m d²) θ̈ − m a·(r_G × g),    r_G = G − A ⊥ a,  d² = com_u² + com_v²,

        Euler's equation about a fixed axis (any rigid-dynamics text: H_A·a = I_A θ̇ for rotation about a fixed
        axis, I_A = I + m d² by the parallel-axis theorem, I about the line through G parallel to a), gravity's
        moment about the axis moved to the right. The reactions' moments about the axis are the rows' entries
        (the bearing's force, through the axis, has none)."""
        axis, (u, v) = body.axis, body.com
        centre = self.kin.com(body)
        r = [centre[k] - axis.point[k] for k in range(3)]
        g = (self.gravity[0], self.gravity[1], sp.S.Zero)
        a = axis.direction
        moment_of_weight = sum(a[k] * (r[(k + 1) % 3] * g[(k + 2) % 3] - r[(k + 2) % 3] * g[(k + 1) % 3])
                               for k in range(3))
        return ((body.inertia + body.mass * (u * u + v * v)) * self.o(f"{body.name}.angle_dd")
                - body.mass * moment_of_weight)

    # -- the matrices ---------------------------------------------------------------------------------------
    def _balance(self):
        rows = {b: 3 * i for i, b in enumerate(self.moving)}
        n = len(self.f)
        A = sp.zeros(n, n)
        col = 0
        for r in self.reactions:
            for sign, body in ((1, r.b), (-1, r.a)):
                if body.moving:
                    for row, column, entry in r.joint_kind.rows(self, r, body, sign):
                        A[rows[body] + row, col + column] += entry
            col += len(r.columns)
        b = sp.zeros(n, 1)
        gx, gy = self.gravity
        for body in self.moving:
            k, name = rows[body], body.name
            b[k] = body.mass * (self.o(f"{name}.com.x_dd") - gx)
            b[k + 1] = body.mass * (self.o(f"{name}.com.y_dd") - gy)
            b[k + 2] = (body.inertia * self.o(f"{name}.angle_dd") if body.axis is None
                        else self._spatial_moment(body))
        for (name, comp, body, att), load in zip(self.load_slots, self.loads):
            k = rows[body]
            if comp == "torque":
                b[k + 2] -= load
                continue
            dx, dy = self.own_arm(att)
            b[k if comp == "fx" else k + 1] -= load
            b[k + 2] -= (-dy if comp == "fx" else dx) * load
        for r, fr, _update in self.frictions:  # friction: loads in b that the kernel iterates with f
            for body, fx, fy, moment in r.joint_kind.friction_loads(self, r, fr):
                if body.moving:
                    k = rows[body]
                    b[k] -= fx
                    b[k + 1] -= fy
                    b[k + 2] -= moment
        for ap in self._applied():  # force elements: known forces from positions and velocities
            if ap.body.moving:
                k = rows[ap.body]
                dx, dy = self.own_arm(ap.at) if ap.at is not None else (0, 0)
                b[k] -= ap.fx
                b[k + 1] -= ap.fy
                b[k + 2] -= dx * ap.fy - dy * ap.fx + ap.torque
        return A, b

    def _applied(self) -> list:
        """What every force element puts on each of its bodies (derive.elements), in declaration order."""
        return [ap for el in self.mech.elements for ap in ELEMENTS[el.kind].applied(self, el)]

    # -- outputs derived from the solution ------------------------------------------------------------------
    def _outputs(self) -> list[tuple[str, str, sp.Expr]]:
        """(name, unit, expression in f, observables, gravity, loads) of every result after f itself."""
        kin, mech, col = self.kin, self.mech, self.column
        out = []
        for i, inp in enumerate(mech.inputs):
            tau = sum((r.sense * self.f[col[r.name]] for r in self.reactions  # the drives: the reactions
                       if r.input_index == i), sp.S.Zero)                   # with an input
            out.append((f"{inp.name}.torque", "N*m" if inp.quantity == "angle" else "N", tau))
        for i, inp in enumerate(mech.inputs):
            out.append((f"{inp.name}.power", "W", out[i][2] * kin.xd[i]))
        for r in self.reactions:  # what each kind adds (a normal force in frame components)
            c = col[r.name]
            out += r.joint_kind.outputs(self, r, self.f[c:c + len(r.columns)])
        fx = fy = mz = sp.S.Zero  # the frame's force on the moving parts (drives counted as frame)
        for r in self.reactions:
            if not r.grounded:
                continue
            sign = 1 if not r.a.moving else -1  # f acts on b from a
            c = col[r.name]
            on_x, on_y, on_z = r.joint_kind.on_body(self, r, self.f[c:c + len(r.columns)])
            fx += sign * on_x
            fy += sign * on_y
            mz += sign * on_z
        for r, fr, _update in self.frictions:  # friction in a frame joint: from the frame too
            if not r.grounded:
                continue
            for body, bx, by, moment in r.joint_kind.friction_loads(self, r, fr):
                if body.moving:
                    gx_, gy_, _gz = kin.com(body)
                    fx += bx
                    fy += by
                    mz += moment + gx_ * by - gy_ * bx
        for el in self.mech.elements:  # an element anchored to the frame acts on the parts from the frame
            if all(body.moving for body in el.bodies):
                continue
            for ap in ELEMENTS[el.kind].applied(self, el):
                if ap.body.moving:
                    px, py = kin.world(ap.at) if ap.at is not None else (0, 0)
                    fx += ap.fx
                    fy += ap.fy
                    mz += px * ap.fy - py * ap.fx + ap.torque
        out += [("frame_force_on_parts.fx", "N", fx), ("frame_force_on_parts.fy", "N", fy),
                ("frame_moment_on_parts", "N*m", mz)]
        ke = pe = sp.S.Zero
        gx, gy = self.gravity
        for body in self.moving:
            n = body.name
            vx, vy, w = self.o(f"{n}.com.x_d"), self.o(f"{n}.com.y_d"), self.o(f"{n}.angle_d")
            vz = self.o(f"{n}.com.z_d") if body.axis is not None else sp.S.Zero  # a spatial crank's G: off the plane
            ke += body.mass * (vx * vx + vy * vy + vz * vz) / 2 + body.inertia * w * w / 2
            pe -= body.mass * (gx * self.o(f"{n}.com.x") + gy * self.o(f"{n}.com.y"))
        power = sp.S.Zero
        for (name, comp, body, _att), load in zip(self.load_slots, self.loads):
            rate = self.o(f"{body.name}.angle_d") if comp == "torque" else self.o(f"{name}.{comp[1]}_d")
            power += load * rate
        for el in self.mech.elements:  # springs store energy; dampers take power
            pe += ELEMENTS[el.kind].energy(self, el)
            power += ELEMENTS[el.kind].power(self, el)
        for r, fr, _update in self.frictions:  # friction's power on the parts (≤ 0)
            power += fr * r.joint_kind.relative_rate(self, r)
        out += [("kinetic_energy", "J", ke), ("potential_energy", "J", pe), ("load_power", "W", power)]
        elastic = sum((ELEMENTS[el.kind].energy_rate(self, el) for el in self.mech.elements), sp.S.Zero)
        out.append(("elastic_power", "W", elastic))  # d/dt of the energy the springs store
        for el in self.mech.elements:
            out += ELEMENTS[el.kind].outputs(self, el)
        for r, fr, _update in self.frictions:
            out += [(f"{r.name}.friction", r.joint_kind.friction_unit, fr),
                    (f"{r.name}.friction_power", "W", -fr * r.joint_kind.relative_rate(self, r))]
        return out

    # -- solve plan -----------------------------------------------------------------------------------------
    def _eliminate_constant_pivots(self):
        """Gaussian elimination on every pivot that is a nonzero number, least fill first (Markowitz).

        Returns the steps (column j, row i, pivot, b_i, [(l, A_il)]) in elimination order — back substitution
        runs them in reverse — and the remaining system as {(i, l): entry} and {i: rhs}."""
        n = len(self.f)
        a = {(i, j): self.A[i, j] for i in range(n) for j in range(n) if self.A[i, j] != 0}
        rhs = {i: self.b[i] for i in range(n)}
        rows, cols = set(range(n)), set(range(n))
        steps = []
        while True:
            best = None
            for (i, j), v in a.items():
                if i in rows and j in cols and v.is_Number:
                    r = sum(1 for (k, l) in a if k == i and l in cols)
                    c = sum(1 for (k, l) in a if l == j and k in rows)
                    key = ((r - 1) * (c - 1), -abs(float(v)), i, j)
                    if best is None or key < best[0]:
                        best = (key, i, j)
            if best is None:
                break
            _, i, j = best
            piv = a[(i, j)]
            row = [(l, a[(i, l)]) for l in sorted(cols) if l != j and (i, l) in a]
            steps.append((j, i, piv, rhs[i], row))
            rows.discard(i)
            cols.discard(j)
            for k in sorted(rows):
                factor = a.pop((k, j), None)
                if factor is None:
                    continue
                m = factor / piv
                for l, v in row:
                    e = sp.expand(a.get((k, l), sp.S.Zero) - m * v)
                    if e == 0:
                        a.pop((k, l), None)
                    else:
                        a[(k, l)] = e
                rhs[k] = rhs[k] - m * rhs[i]
        schur = {ij: v for ij, v in a.items() if ij[0] in rows and ij[1] in cols}
        return steps, schur, {i: rhs[i] for i in sorted(rows)}

    def _block_order(self) -> list[tuple[list[int], list[int]]]:
        """(rows, columns) of each diagonal block of the Schur complement's block-triangular form, in solve order."""
        rows = sorted(self.schur_rhs)
        cols = sorted(set(range(len(self.f))) - {j for j, *_ in self.eliminated})
        nz = {i: [j for j in cols if (i, j) in self.schur] for i in rows}
        owner = _perfect_matching(nz, rows)  # column -> row
        if owner is None:
            raise DeclarationError(f"{self.mech.name}: the force balance is structurally singular "
                                   "(a body or joint is over- or under-constrained)")
        deps = {j: sorted({k for k in nz[owner[j]] if k != j}) for j in cols}
        return [([owner[j] for j in comp], comp) for comp in _tarjan(deps)]


def _perfect_matching(nz: dict, rows: list) -> dict | None:
    """Kuhn's augmenting paths, rows -> columns: {column: row}, or None if no perfect matching exists."""
    owner: dict = {}

    def augment(i, seen):
        for j in nz[i]:
            if j in seen:
                continue
            seen.add(j)
            if j not in owner or augment(owner[j], seen):
                owner[j] = i
                return True
        return False

    for i in rows:
        if not augment(i, set()):
            return None
    return owner


def _tarjan(deps: dict) -> list[list[int]]:
    """Strongly connected components of j -> deps[j], each listed after every component it depends on."""
    index, low, on, stack, comps = {}, {}, set(), [], []

    def visit(v):
        index[v] = low[v] = len(index)
        stack.append(v)
        on.add(v)
        for w in deps[v]:
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            comp = []
            while True:
                w = stack.pop()
                on.discard(w)
                comp.append(w)
                if w == v:
                    break
            comps.append(sorted(comp))

    for v in sorted(deps):
        if v not in index:
            visit(v)
    return comps
