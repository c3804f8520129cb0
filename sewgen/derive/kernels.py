"""Kernel bodies as C text, computed in Python (DESIGN.md §4): the templates only lay them out.

The kernels of a mechanism, each one joint CSE over everything it returns:

* ``constants`` — every subexpression of the parameters alone (link lengths from triangle sides, cos and
  sin of fixed angles, 1/l² ...), evaluated once per sweep into ``c[]``;
* ``closed``    — the dyad chain (derive.dyads) calling the runtime's sg_dyad_* solvers; it returns the
  coordinates and the cos/sin of every angle coordinate straight from the geometry;
* ``residual``  — Φ and Φ_q for Newton and residual checks;
* ``motion``    — Φ_q, −Φ_x x', LU, q'; γ, q''; every observable. Its CSE temporaries are emitted in
  three stages by what they depend on (positions only / q' / q''), so each is computed once;
* ``rates`` and ``observe`` — the motion kernel split for sweeps that keep a few outputs: q', q'' without the
  observables, and one group of observables (a point, a body, a cam's arc) at a time, each printed from the
  motion kernel's own CSE statements (those its outputs read), so the values are the motion kernel's to the bit.

No kernel calls a trigonometric function of a coordinate or input: sin(a + c) of an angle a and a fixed
c is expanded by the addition formulas and sin a, cos a are read from ``cq[]`` (coordinates) and ``cx[]``
(inputs), which the runtime fills once per position (closed form: from the dyads' geometry, no call).
"""
from __future__ import annotations

import re
from dataclasses import dataclass, field

import sympy as sp

from .. import abi
from .blockfactor import BlockFactor
from .cprint import KernelPrinter, NoVectorForm, VectorPrinter, ops, per_sweep
from .dyads import Dyad
from .joints import KINDS
from .kinematics import Kinematics
from .kinetostatics import Kinetostatics
from .vocabulary import DeclarationError

#: The largest LU the runtime's stack arrays hold (sewgen.abi.LIMITS SG_MAX_Q).
MAX_BLOCK = abi.LIMIT["SG_MAX_Q"]


@dataclass
class Kernel:
    name: str
    signature: str
    body: list = field(default_factory=list)  # C lines, without indentation
    ops: int = 0

    @property
    def prototype(self) -> str:
        return self.signature + ";"


def _cse(exprs):
    return sp.cse(list(exprs), symbols=sp.numbered_symbols("t", real=True), order="canonical")


class _Flavour:
    """How a kernel body prints: scalar C (double) or the SIMD twin (sg_vd lanes, csrc/sg_simd.h), where a value
    that reads only per-sweep scalars (constants c[], gravity gv[], friction fr[]; cprint.per_sweep) or nothing
    is broadcast to every lane."""

    def __init__(self, vector: bool):
        self.vector = vector
        self.printer = VectorPrinter() if vector else KernelPrinter()
        self.real = "sg_vd" if vector else "double"

    def value(self, e) -> str:
        text = self.printer.doprint(e)
        if self.vector and per_sweep(e):
            return f"sgv_set1({text})"
        return text

    def temps(self, repl) -> list[str]:
        return [f"const {self.real} {self.printer.doprint(t)} = {self.value(e)};" for t, e in repl]


SCALAR, VECTOR = _Flavour(False), _Flavour(True)
_VECTOR_FORCE_ARGS = ("q", "cq", "x", "cx", "xd", "c", "obs", "gv", "ld", "out")

#: The SIMD twins' signatures (static in each generated file; passed to the loops of csrc/sg_simd.h, whose
#: sgv_<kind>_fn types are these).
VECTOR_SIGNATURES = {
    "closed": "sg_vm {f}(const sg_vd *x, const sg_vd *cx, const double *c, const int *branch, int angles, sg_vd *q, "
              "sg_vd *cq, sg_vd *err)",
    "motion": "sg_vm {f}(const sg_vd *q, const sg_vd *cq, const sg_vd *x, const sg_vd *cx, const sg_vd *xd, "
              "const sg_vd *xdd, const double *c, sg_vd *qd, sg_vd *qdd, sg_vd *obs, sg_vd *cond)",
    "forces": "sg_vm {f}(const sg_vd *q, const sg_vd *cq, const sg_vd *x, const sg_vd *cx, const sg_vd *xd, "
              "const double *c, const sg_vd *obs, const double *gv, const sg_vd *ld, sg_vd *out)",
    "rates": "sg_vm {f}(const sg_vd *q, const sg_vd *cq, const sg_vd *x, const sg_vd *cx, const sg_vd *xd, "
             "const sg_vd *xdd, const double *c, sg_vd *qd, sg_vd *qdd, sg_vd *cond)",
    "observe": "sg_vm {f}(const sg_vd *q, const sg_vd *cq, const sg_vd *x, const sg_vd *cx, const sg_vd *xd, "
               "const sg_vd *xdd, const double *c, const sg_vd *qd, const sg_vd *qdd, int group, sg_vd *obs)",
    "residual": "void {f}(const sg_vd *q, const sg_vd *cq, const sg_vd *x, const sg_vd *cx, const double *c, "
                "sg_vd *r, sg_vd *jac)",
    "lu_factor": "sg_vm {f}(sg_vd *a, sg_vm *piv)",
    "lu_solve": "void {f}(const sg_vd *lu, const sg_vm *piv, sg_vd *b)",
    "blocks": "void {f}(const sg_vd *jac, sg_vd *out)",
}


def _unused(body, *names):
    """(void) casts for the arguments a kernel body never reads (-Wextra)."""
    text = "\n".join(body)
    return [f"(void){n};" for n in names if not re.search(rf"\b{n}\b", text)]


#: The most coordinates a mechanism's SIMD Newton (csrc/sg_simd.h sgv_newton) is generated for: its
#: Φ_q vectors live on the stack, three times (nq² × 64 bytes each).
NEWTON_SIMD_MAX_Q = 16

#: Coulomb friction's fixed point: relative change of the friction loads that ends it, and the most iterations.
FRICTION_RTOL = 1e-13
FRICTION_ITER = 100

_DYAD_CALL = {
    "rrr": ("double J[2];", "sg_dyad_rrr(P, Q, l[0], l[1], branch[{k}], ein, e, J)"),
    "rrp": ("double s, J[2];", "sg_dyad_rrp(P, l[0], L0, u, branch[{k}], ein, e, &s, J)"),
    "rpr": ("double s, theta;", "sg_dyad_rpr(D, w0, u, branch[{k}], ein, e, &s, &theta)"),
    "rrs": ("double J[2];", "sg_dyad_rrr(P, Q, l[0], l[1], branch[{k}], ein, e, J)"),  # the rod's reach as l[1]
}
#: A dyad's inputs that are points placed by earlier coordinates (their error is the dyad's ein); the others are
#: lengths, the guide's direction (its angle's error the dyad's own e[0]) and a bar's frame (constants).
_DYAD_POINTS = ("P", "Q", "L0", "D")


class KernelSet:
    """The kernels of one mechanism, sharing one table of hoisted parameter-only constants."""

    def __init__(self, prefix: str, kin: Kinematics):
        self.prefix, self.kin = prefix, kin
        self.printer = KernelPrinter()
        self.params = set(kin.p)
        self.constants: dict = {}  # expression -> symbol c_k, in first-seen order
        self.trig: dict = {}  # angle symbol -> (cos symbol, sin symbol)
        self._selection_lines: dict = {}  # flavour (vector?) -> selection_block's lines
        self._memo: dict = {}  # CSE results a scalar kernel and its SIMD twin share
        self._block_factor: BlockFactor | None = None  # solve_by_blocks
        for i, (c, q) in enumerate(zip(kin.coords, kin.q)):
            if c.kind == "angle":
                self.trig[q] = (sp.Symbol(f"cq_{2 * i}", real=True), sp.Symbol(f"cq_{2 * i + 1}", real=True))
        for k, x in enumerate(kin.x):
            self.trig[x] = (sp.Symbol(f"cx_{2 * k}", real=True), sp.Symbol(f"cx_{2 * k + 1}", real=True))

    # -- expression preparation ------------------------------------------------------------------------
    def _signature(self, kind: str) -> str:
        """The C signature of this mechanism's kernel of ``kind``, from the one table in :mod:`sewgen.abi`."""
        return abi.kernel_signature(kind, f"{self.prefix}_{kind}")

    def _expand_trig(self, expr: sp.Expr) -> sp.Expr:
        """sin/cos(±a ± b ... + c), a, b coordinate or input angles and c fixed -> products of cq/cx entries and
        sin/cos c, by the addition formulas applied one angle at a time."""
        repl = {}
        for f in expr.atoms(sp.sin, sp.cos):
            cs = self._cos_sin(f.args[0])
            if cs is not None:
                repl[f] = cs[0] if isinstance(f, sp.cos) else cs[1]
        return expr.xreplace(repl) if repl else expr

    def _cos_sin(self, arg):
        """(cos arg, sin arg) with every angle symbol of coefficient ±1 taken out; None if arg has none."""
        angles = sorted((s for s in arg.free_symbols if s in self.trig), key=lambda s: s.name)
        for a in angles:
            k = arg.coeff(a)
            rest = sp.expand(arg - k * a)
            if k not in (1, -1) or a in rest.free_symbols:
                continue
            ca, sa = self.trig[a]
            sa = k * sa
            inner = self._cos_sin(rest)
            cr, sr = inner if inner is not None else (sp.cos(rest), sp.sin(rest))
            return ca * cr - sa * sr, sa * cr + ca * sr
        return None

    def _is_const(self, e: sp.Expr) -> bool:
        return isinstance(e, sp.Expr) and bool(e.free_symbols) and e.free_symbols <= self.params

    def _const(self, e: sp.Expr) -> sp.Symbol:
        if e not in self.constants:
            self.constants[e] = sp.Symbol(f"c_{len(self.constants)}", real=True)
        return self.constants[e]

    def _hoist(self, e: sp.Expr) -> sp.Expr:
        """Replace every maximal parameter-only subexpression (a bare parameter too) by a constant c_k."""
        if e.is_Atom:
            return self._const(e) if e in self.params else e
        if self._is_const(e):
            return self._const(e)
        if isinstance(e, (sp.Add, sp.Mul)):  # group the fixed part of a sum or product (numbers with it)
            fixed = [o for o in e.args if self._is_const(o) or o.is_Number]
            if len(fixed) >= 2 and any(self._is_const(o) for o in fixed):
                rest = [self._hoist(o) for o in e.args if not (self._is_const(o) or o.is_Number)]
                return e.func(self._const(e.func(*fixed)), *rest)
        return e.func(*[self._hoist(a) for a in e.args])

    def prepare(self, exprs) -> list:
        return [self._hoist(self._expand_trig(sp.sympify(e))) for e in exprs]

    def selection_block(self, vector: bool = False) -> list[str]:
        """What the joints choose at run time before any kernel reads them (a cam's active arc, ka[]: see
        derive.joints.Cam.selection_c), in kind order; ``vector``: lane by lane, for the SIMD twins. The same
        lines open every kernel that reads ka; they are built once a flavour."""
        if vector not in self._selection_lines:
            fl = VECTOR if vector else SCALAR
            self._selection_lines[vector] = [line for kind in KINDS.values()
                                             for line in kind.selection_c(self.kin, fl, self.prepare)]
        return self._selection_lines[vector]

    # -- kernels ---------------------------------------------------------------------------------------
    def residual(self, vector: bool = False) -> Kernel:
        """Φ(q, x) and Φ_q at a position: Newton's kernel. ``vector``: the SIMD twin (the SIMD Newton of a block of
        positions, csrc/sg_simd.h sgv_newton) from the same CSE, the same values lane by lane, to the
        bit; a residual whose twin would not be exact (libmvec's atan2) has none (:class:`NoVectorForm`)."""
        kin, n = self.kin, len(self.kin.q)
        fl = VECTOR if vector else SCALAR
        if "residual" not in self._memo:
            self._memo["residual"] = _cse(self.prepare(list(kin.closure) +
                                                       [kin.jac_q[i, j] for i in range(n) for j in range(n)]))
        repl, red = self._memo["residual"]
        body = self.selection_block(vector) + fl.temps(repl)
        body += [f"r[{i}] = {fl.value(e)};" for i, e in enumerate(red[:n])]
        body += [f"jac[{k}] = {fl.value(e)};" for k, e in enumerate(red[n:])]
        if vector and any("sgv_atan2" in line for line in body):
            raise NoVectorForm("the residual's atan2 has no exact vector form")
        body = _unused(body, "q", "cq", "x", "cx", "c") + body
        name = f"{self.prefix}_residual" + ("_v" if vector else "")
        return Kernel(name, VECTOR_SIGNATURES["residual"].format(f=name) if vector else self._signature("residual"),
                      body, ops(e for _, e in repl) + ops(red))

    def anchors(self, exprs: list) -> Kernel:
        """World x, y of every drawing anchor, then the cam arcs' radii and normal sectors (derive.drawing)."""
        pr = self.printer
        repl, red = _cse(self.prepare(exprs))
        body = SCALAR.temps(repl) + [f"out[{k}] = {pr.doprint(e)};" for k, e in enumerate(red)]
        body = _unused(body, "q", "cq", "x", "cx", "c") + body
        return Kernel(f"{self.prefix}_anchors", self._signature("anchors"), body, ops(e for _, e in repl) + ops(red))

    def motion(self, scales: list | None = None, vector: bool = False) -> Kernel:
        """``scales``: each closure equation's loop size (derive.branches.row_scales): the rows of Φ_q are divided
        by them before the condition number is taken (their reciprocals mostly hoist into constants).
        ``vector``: the SIMD twin (csrc/sg_simd.h) from the same expressions; it computes every lane and returns
        the mask of lanes whose factor and outputs are good (raises NoVectorForm where it cannot be printed)."""
        n = len(self.kin.q)
        fl = VECTOR if vector else SCALAR
        repl, red = self._motion_cse(scales)
        r_inv = red[len(red) - n:] if n else []
        red = red[:len(red) - n] if n else red
        levels: dict = {}
        for t, e in repl:
            levels[t] = max((_stage(s, levels) for s in e.free_symbols), default=0)
        staged = [[(t, e) for t, e in repl if levels[t] == k] for k in range(3)]
        r_jac, r_vel = red[: n * n], red[n * n: n * n + n]
        r_gam, r_obs = red[n * n + n: n * n + 2 * n], red[n * n + 2 * n:]
        body = self.selection_block(vector) + fl.temps(staged[0]) + self._velocity_lines(fl, n, r_jac, r_vel, r_inv)
        body += fl.temps(staged[1]) + self._acceleration_lines(fl, n, r_gam)
        body += fl.temps(staged[2])
        body += [f"obs[{k}] = {fl.value(e)};" for k, e in enumerate(r_obs)]
        outputs = [f"{a}[{i}]" for a in ("q", "qd", "qdd") for i in range(n)] + [f"obs[{k}]" for k in range(len(r_obs))]
        if outputs:  # one NaN/inf test per position: a balanced sum is non-finite iff an entry is
            body += [f"ok &= sgv_isfinite({_balanced_sum(outputs)});" if vector
                     else f"if (!isfinite({_balanced_sum(outputs)})) return SG_NONFINITE;"]
        names = ("q", "cq", "x", "cx", "xd", "xdd", "c", "qd", "qdd", "obs", "cond")
        body = _unused(body, *names) + body + ["return ok;" if vector else "return SG_OK;"]
        name = f"{self.prefix}_motion" + ("_v" if vector else "")
        return Kernel(name, VECTOR_SIGNATURES["motion"].format(f=name) if vector else self._signature("motion"),
                      body, ops(e for _, e in repl) + ops(red))

    def solve_by_blocks(self, blocks: list) -> None:
        """The motion and rates kernels and their SIMD twins factor Φ_q by these diagonal blocks
        (derive.branches.blocks; sewgen/derive/blockfactor.py) where its structure allows: for a mechanism Newton
        solves, whose twins finish its solved positions (csrc/sg_simd.h sgv_finish) with the same
        factor, lane by lane. Φ_q's structure is taken once, here."""
        n = len(self.kin.q)
        self._block_factor = BlockFactor.of(n, [self.kin.jac_q[i, j] for i in range(n) for j in range(n)], blocks)

    def _velocity_lines(self, fl: _Flavour, n: int, r_jac, r_vel, r_inv) -> list[str]:
        """The motion and rates kernels' LU of Φ_q — rows over their loop size (an angle row: 1 rad), columns
        equilibrated — with its condition number (the runtime's singular-position estimate), and q'."""
        vector = fl.vector
        if not n:  # no coordinates: nothing solved (csrc/sg_runtime.h sg_rates_error)
            if vector:
                return ["cond[0] = cond[1] = cond[2] = sgv_set1(1.0);", "sg_vm ok = sgv_true();"]
            return ["cond[0] = cond[1] = cond[2] = 1.0;"]
        bf = self._block_factor
        body = [f"{fl.real} J[{n * n}], rs[{n}], cs[{2 * n}];"]
        body += bf.declarations(vector) if bf else [f"{'sg_vm' if vector else 'int'} piv[{n}];"]
        body += [f"J[{k}] = {fl.value(e)};" for k, e in enumerate(r_jac)]
        body += [f"qd[{i}] = {fl.value(e)};" for i, e in enumerate(r_vel)]
        body += [f"rs[{i}] = {fl.value(e)};" for i, e in enumerate(r_inv)]
        if bf:
            return body + bf.factor_lines(vector) + bf.solve_lines("qd", vector)
        if vector:
            return body + [f"sg_vm ok = sgv_factor_eq({n}, J, piv, rs, cs, cond);",
                           f"sgv_solve_eq({n}, J, piv, rs, cs, qd);"]
        return body + [f"if (sg_factor_eq_inl({n}, J, piv, rs, cs, cond) != SG_OK) return SG_SINGULAR;",
                       f"sg_solve_eq_inl({n}, J, piv, rs, cs, qd);"]

    def _acceleration_lines(self, fl: _Flavour, n: int, r_gam) -> list[str]:
        """q'' from γ with the same factor (after :meth:`_velocity_lines`), then the rest of the error estimate's
        numbers (csrc/sg_runtime.h sg_rates_scale_inl: cond[1], cond[2])."""
        if not n:
            return []
        lines = [f"qdd[{i}] = {fl.value(e)};" for i, e in enumerate(r_gam)]
        bf = self._block_factor
        if bf:
            lines += bf.solve_lines("qdd", fl.vector)
        else:
            lines += [f"{'sgv_solve_eq' if fl.vector else 'sg_solve_eq_inl'}({n}, J, piv, rs, cs, qdd);"]
        return lines + [self._rates_scale_line(fl, n)]

    def _rates_scale_line(self, fl: _Flavour, n: int) -> str:
        """The call of sg_rates_scale_inl (or its SIMD twin): which coordinates are angles (a bit mask) and the
        fastest turning input (the shaft's speed times the largest ratio of a body it drives; 0 where it drives
        none: held inputs do not move). The mask has 64 bits: SG_MAX_Q (sewgen.abi) is 48."""
        angles = sum(1 << i for i, c in enumerate(self.kin.coords) if c.kind == "angle")
        ratios = [abs(float(b.ratio)) for b in self.kin.mech.bodies if b.kind == "driven" and b.guide is None]
        if ratios and self.kin.x:
            scale = max(ratios)
            turn = ("sgv_fabs(xd[0])" if fl.vector else "fabs(xd[0])") + ("" if scale == 1.0 else f" * {scale!r}")
        else:
            turn = "sgv_set1(0.0)" if fl.vector else "0.0"
        call = "sgv_rates_scale" if fl.vector else "sg_rates_scale_inl"
        return f"{call}({n}, {angles:#x}ULL, {turn}, cs, qd, qdd, cond);"

    def _motion_parts(self, scales):
        """The motion kernel's CSE split as the kernels read it: (temporaries, Φ_q entries, −Φ_x x', γ, every
        observable, the rows' 1/loop size)."""
        n = len(self.kin.q)
        repl, red = self._motion_cse(scales)
        r_inv = red[len(red) - n:] if n else []
        red = red[:len(red) - n] if n else red
        return repl, red[: n * n], red[n * n: n * n + n], red[n * n + n: n * n + 2 * n], red[n * n + 2 * n:], r_inv

    @staticmethod
    def _needed(repl, exprs) -> list:
        """The temporaries of ``repl`` that ``exprs`` read, directly or through other temporaries, in ``repl``'s
        order: the same statements as the joint kernel's, so every value they give is the joint kernel's to the
        bit (the same C expressions of the same inputs, no reassociation: no -ffast-math)."""
        defs = dict(repl)
        need: set = set()
        stack = [s for e in exprs for s in sp.sympify(e).free_symbols if s in defs]
        while stack:
            t = stack.pop()
            if t in need:
                continue
            need.add(t)
            stack.extend(s for s in defs[t].free_symbols if s in defs and s not in need)
        return [(t, e) for t, e in repl if t in need]

    def rates(self, scales: list | None = None, vector: bool = False) -> Kernel:
        """q', q'' and the condition estimate of the motion kernel without its observables (so that a
        sweep that keeps a few outputs computes only their groups, kernel ``observe``). The same temporaries
        and LU as :meth:`motion`, those the observables alone read left out: q', q'', cond equal the motion
        kernel's to the bit, and the status too but for a non-finite observable (``observe`` tests those).
        ``vector``: the SIMD twin, equal to the bit to the motion kernel's SIMD twin; it returns the mask of
        lanes whose factor and rates are good."""
        n = len(self.kin.q)
        fl = VECTOR if vector else SCALAR
        repl, r_jac, r_vel, r_gam, _r_obs, r_inv = self._motion_parts(scales)
        used = self._needed(repl, r_jac + r_vel + r_gam + r_inv)
        levels: dict = {}
        for t, e in repl:
            levels[t] = max((_stage(s, levels) for s in e.free_symbols), default=0)
        early = [(t, e) for t, e in used if levels[t] == 0]
        late = [(t, e) for t, e in used if levels[t] >= 1]
        body = list(self.selection_block(vector)) if _reads_ka(early + late, r_jac + r_vel + r_gam + r_inv) else []
        body += fl.temps(early) + self._velocity_lines(fl, n, r_jac, r_vel, r_inv)
        body += fl.temps(late) + self._acceleration_lines(fl, n, r_gam)
        if n:
            outputs = [f"{a}[{i}]" for a in ("q", "qd", "qdd") for i in range(n)]
            body += [f"ok &= sgv_isfinite({_balanced_sum(outputs)});" if vector
                     else f"if (!isfinite({_balanced_sum(outputs)})) return SG_NONFINITE;"]
        names = ("q", "cq", "x", "cx", "xd", "xdd", "c", "qd", "qdd", "cond")
        body = _unused(body, *names) + body + ["return ok;" if vector else "return SG_OK;"]
        name = f"{self.prefix}_rates" + ("_v" if vector else "")
        return Kernel(name, VECTOR_SIGNATURES["rates"].format(f=name) if vector else self._signature("rates"),
                      body, ops(e for _, e in used) + ops(r_jac + r_vel + r_gam + r_inv))

    def observe(self, groups: list, scales: list | None = None, vector: bool = False) -> Kernel:
        """One group of observables (a point's or a body's columns, a cam's arc) from a position and its rates
        (kernel ``rates``): ``groups`` lists each group's first observable and the next group's. Each case emits
        the temporaries its observables read, as the joint motion kernel does (the same values to the bit), and
        tests its own outputs for a non-finite value. ``vector``: the SIMD twin (the motion twin's values to the
        bit), returning the mask of lanes whose group is finite."""
        fl = VECTOR if vector else SCALAR
        repl, *_rest, r_obs, _r_inv = self._motion_parts(scales)
        body = ["switch (group) {"]
        total = 0
        for g, (a, b) in enumerate(zip(groups[:-1], groups[1:])):
            exprs = r_obs[a:b]
            used = self._needed(repl, exprs)
            total += ops(e for _, e in used) + ops(exprs)
            case = (list(self.selection_block(vector)) if _reads_ka(used, exprs) else []) + fl.temps(used)
            case += [f"obs[{k}] = {fl.value(e)};" for k, e in zip(range(a, b), exprs)]
            outs = [f"obs[{k}]" for k in range(a, b)]
            if vector:
                case += [f"return sgv_isfinite({_balanced_sum(outs)});" if outs else "return sgv_true();"]
            else:
                case += [f"return isfinite({_balanced_sum(outs)}) ? SG_OK : SG_NONFINITE;" if outs
                         else "return SG_OK;"]
            body += [f"case {g}: {{"] + ["    " + line for line in case] + ["}"]
        body += ["default:", "    return sgv_false();" if vector else "    return SG_BAD_ARGUMENT;", "}"]
        names = ("q", "cq", "x", "cx", "xd", "xdd", "c", "qd", "qdd", "obs")
        body = _unused(body, *names) + body
        name = f"{self.prefix}_observe" + ("_v" if vector else "")
        return Kernel(name, VECTOR_SIGNATURES["observe"].format(f=name) if vector else self._signature("observe"),
                      body, total)

    def observe_always(self, groups: list, scales: list | None = None) -> list[int]:
        """Per group, 1 where its observables may come out non-finite from finite coordinates, rates, inputs and
        constants (a division by a coordinate's function, a square root, any function): the runtime computes
        such a group in every sweep, selected or not, so a selective sweep fails where the full one does. A
        polynomial group (the catalog's) is 0: only an overflow past 1e308 could make it non-finite."""
        repl, *_rest, r_obs, _r_inv = self._motion_parts(scales)
        flags = []
        for a, b in zip(groups[:-1], groups[1:]):
            exprs = r_obs[a:b]
            used = self._needed(repl, exprs)
            flags.append(0 if all(_polynomial(e) for e in [e for _, e in used] + list(exprs)) else 1)
        return flags

    def _angle_symbols(self) -> set:
        return {q for q, c in zip(self.kin.q, self.kin.coords) if c.kind == "angle"}

    def angle_readers(self, groups: list, scales: list | None = None) -> list[int]:
        """Per group, 1 where its observables read an angle coordinate's value itself (a body's angle), not only
        its cos and sin; then 1 where the rates do (none in the catalog): a selective SIMD sweep whose wanted
        groups and caller read no angle skips the dyads' atan2 (kernel ``closed``'s ``angles``)."""
        repl, r_jac, r_vel, r_gam, r_obs, r_inv = self._motion_parts(scales)
        angles = self._angle_symbols()

        def reads(exprs) -> int:
            exprs = list(exprs)
            used = [e for _, e in self._needed(repl, exprs)]
            return int(any(sym in angles for e in used + exprs for sym in sp.sympify(e).free_symbols))

        flags = [reads(r_obs[a:b]) for a, b in zip(groups[:-1], groups[1:])]
        return flags + [reads(r_jac + r_vel + r_gam + r_inv)]

    def _motion_cse(self, scales):
        """The motion kernel's expressions after one joint CSE (shared by the scalar kernel and its SIMD twin)."""
        key = ("motion", tuple(scales or ()))
        if key not in self._memo:
            kin, n = self.kin, len(self.kin.q)
            jac = [kin.jac_q[i, j] for i in range(n) for j in range(n)]
            inv = [1 / e for e in (scales or [sp.S.One] * n)]
            exprs = self.prepare(jac + list(kin.vel_rhs) + list(kin.gamma) + [o.expr for o in kin.observables]
                                 + inv)
            self._memo[key] = _cse(exprs)
        return self._memo[key]

    def forces(self, kst: Kinetostatics, vector: bool = False) -> Kernel:
        """The solve of A f = b as derive.kinetostatics plans it, then every derived output.

        Schur-complement blocks by the runtime's pivoted LU (a division for 1 × 1), then back substitution
        through the constant-pivot eliminations, then the outputs. Temporaries are staged like the motion
        kernel's: those of the matrices first, those that read the solved reactions after. ``vector``: the SIMD
        twin (csrc/sg_simd.h), the frictionless solve only (the SIMD loop runs it only where every friction
        coefficient is 0: :meth:`forces_in_simd`), returning the mask of lanes whose blocks and outputs are
        good."""
        fl = VECTOR if vector else SCALAR
        pr, f = fl.printer, kst.f
        schur = sorted(kst.schur)
        steps = kst.eliminated
        repl, red = self._forces_cse(kst)
        late: set = set()
        for t, e in repl:
            if e.free_symbols & (set(f) | late):
                late.add(t)
        it = iter(red)
        a = {ij: next(it) for ij in schur}
        rhs = {i: next(it) for i in sorted(kst.schur_rhs)}
        back = []
        for j, _i, piv, _b, row in steps:
            b_i = next(it)
            back.append((j, (b_i - sum((next(it) * f[l] for l, _ in row), sp.S.Zero)) / piv))
        rest = list(it)
        nfr = len(kst.frictions)
        r_out, r_fr = rest[:len(rest) - nfr], rest[len(rest) - nfr:]
        solve = fl.temps([(t, e) for t, e in repl if t not in late])
        for rows, cols in kst.blocks:
            solve += self._block_solve(rows, cols, a, rhs, f, fl)
        solve += [f"out[{j}] = {fl.value(e)};" for j, e in reversed(back)]
        solve += fl.temps([(t, e) for t, e in repl if t in late])
        n = len(f)
        finish = [f"out[{n + k}] = {fl.value(e)};" for k, e in enumerate(r_out)]
        outputs = [f"out[{k}]" for k in range(n + len(r_out))]
        if vector:
            head = ["sg_vm ok = sgv_true();"] + ([f"const double fr[{nfr}] = {{0.0}};"] if nfr else [])
            body = head + solve + finish + [f"ok &= sgv_isfinite({_balanced_sum(outputs)});", "return ok;"]
        else:
            finish += [f"if (!isfinite({_balanced_sum(outputs)})) return SG_NONFINITE;", "return SG_OK;"]
            if nfr:  # Coulomb friction: fr <- its value from the reactions, until it settles (A never changes)
                # every coefficient 0 (the seeds' assumption, the catalog's default): fr stays 0, the first solve
                # is the answer, bit for bit the kernel without friction
                step = [f"double frn[{nfr}];"] + [f"frn[{k}] = {pr.doprint(e)};" for k, e in enumerate(r_fr)]
                step += ["double d = 0.0, s = 0.0;",
                         f"for (int k = 0; k < {nfr}; ++k) {{ d = fmax(d, fabs(frn[k] - fr[k])); s = fmax(s, fabs(frn[k])); }}",
                         f"if (!(d <= {FRICTION_RTOL!r} * s)) {{",  # not settled (NaN included): once more
                         f"    if (it >= {FRICTION_ITER}) return SG_FRICTION_LOCK;",
                         f"    for (int k = 0; k < {nfr}; ++k) fr[k] = frn[k];",
                         "    continue;", "}"]
                loop = (solve + [f"if (!({self._frictionless(kst)})) {{"] + ["    " + line for line in step] + ["}"]
                        + finish)
                body = [f"double fr[{nfr}] = {{0.0}};", "for (int it = 0; ; ++it) {"] + ["    " + x for x in loop] + ["}"]
            else:
                body = solve + finish
        body = self.selection_block(vector) + body
        body = _unused(body, *_VECTOR_FORCE_ARGS) + body
        name = f"{self.prefix}_forces" + ("_v" if vector else "")
        return Kernel(name, VECTOR_SIGNATURES["forces"].format(f=name) if vector else self._signature("forces"),
                      body, ops(e for _, e in repl) + ops(red))

    def _forces_cse(self, kst: Kinetostatics):
        """The forces kernel's expressions after one joint CSE (shared by the scalar kernel and its SIMD twin)."""
        key = ("forces", id(kst))
        if key not in self._memo:
            exprs = ([kst.schur[ij] for ij in sorted(kst.schur)] + [kst.schur_rhs[i] for i in sorted(kst.schur_rhs)]
                     + [e for *_, b_i, row in kst.eliminated for e in [b_i] + [v for _, v in row]]
                     + [e for _, _, e in kst.outputs] + [update for *_, update in kst.frictions])
            self._memo[key] = (kst, _cse(self.prepare(exprs)))  # kst kept alive: its id stays its own
        return self._memo[key][1]

    def _frictionless(self, kst: Kinetostatics) -> str:
        """C test that every Coulomb coefficient of the mechanism is 0 ("1" without friction)."""
        mus = self.prepare([mu for _, mu, _ in kst.mech.frictions])
        return " && ".join(f"{SCALAR.printer.doprint(e)} == 0.0" for e in mus) or "1"

    def forces_in_simd(self, kst: Kinetostatics, has_vector: bool) -> Kernel:
        """Whether the SIMD loop may run this mechanism's forces: it has the vector twin and every friction
        coefficient is 0 (the twin is the frictionless solve); else that sweep runs the scalar loop."""
        body = [f"return {self._frictionless(kst)};" if has_vector else "return 0;"]
        body = _unused(body, "c") + body
        name = f"{self.prefix}_forces_in_simd"
        return Kernel(name, f"int {name}(const double *c)", body, 0)

    def _block_solve(self, rows, cols, a, rhs, f, fl) -> list[str]:
        """C for one diagonal block: its right-hand side less the columns solved before, then LU or a division
        (the SIMD twin: lane masks instead of early returns)."""
        n = len(f)
        inside = set(cols)

        def known_part(i):
            """b_i less the products with reactions solved in earlier blocks (f_j prints as out[j])."""
            return rhs[i] - sum((a[(i, j)] * f[j] for j in range(n) if (i, j) in a and j not in inside), sp.S.Zero)

        label = ", ".join(str(j) for j in cols)
        if len(cols) == 1:
            (i,), (j,) = rows, cols
            piv = a[(i, j)]
            if piv.is_Number:
                return [f"out[{j}] = {fl.value(known_part(i) / piv)};"]
            column = [fl.value(a[(k, j)]) for k in range(n) if (k, j) in a]  # the LU's column-scaled test
            test = (f"    ok &= sgv_fabs(d) > SG_PIVOT_RTOL * {_fmax(column, fab='sgv_fabs', fmx='sgv_fmax')};"
                    if fl.vector else f"    if (!(fabs(d) > SG_PIVOT_RTOL * {_fmax(column)})) return SG_SINGULAR;")
            return ["{", f"    const {fl.real} d = {fl.value(piv)};", test,
                    f"    out[{j}] = ({fl.value(known_part(i))})/d;", "}"]
        k = len(cols)
        if k > MAX_BLOCK:
            raise DeclarationError(f"{self.kin.mech.name}: a force block of {k} unknowns ({label}) is larger "
                                   f"than the runtime's {MAX_BLOCK} (SG_MAX_Q)")
        lines = [f"/* block of unknowns {label} */", f"{fl.real} M[{k * k}], r[{k}];",
                 f"{'sg_vm' if fl.vector else 'int'} piv[{k}];"]
        zero = "sgv_set1(0.0)" if fl.vector else "0.0"
        for bi, i in enumerate(rows):
            for bj, j in enumerate(cols):
                lines.append(f"M[{bi * k + bj}] = {fl.value(a[(i, j)]) if (i, j) in a else zero};")
            lines.append(f"r[{bi}] = {fl.value(known_part(i))};")
        if fl.vector:
            lines += [f"ok &= sgv_lu_factor({k}, M, piv);", f"sgv_lu_solve({k}, M, piv, r);"]
        else:
            lines += [f"if (sg_lu_factor_inl({k}, M, piv, 0) != SG_OK) return SG_SINGULAR;",
                      f"sg_lu_solve_inl({k}, M, piv, r);"]
        lines += [f"out[{j}] = r[{bj}];" for bj, j in enumerate(cols)]
        return ["{"] + ["    " + line for line in lines] + ["}"]

    def force_matrix(self, kst: Kinetostatics) -> Kernel:
        """A (row-major) and b as they are, for inspection, tests and baselines (b without the friction loads,
        which depend on the reactions)."""
        pr, A, n = self.printer, kst.A, len(kst.f)
        nz = [(i, j) for i in range(n) for j in range(n) if A[i, j] != 0]
        no_friction = {fr: 0 for _r, fr, _u in kst.frictions}  # b as without friction (it needs the reactions)
        repl, red = _cse(self.prepare([A[i, j] for i, j in nz] + [e.xreplace(no_friction) for e in kst.b]))
        body = self.selection_block() + SCALAR.temps(repl) + [f"for (int k = 0; k < {n * n}; ++k) A[k] = 0.0;"]
        body += [f"A[{i * n + j}] = {pr.doprint(e)};" for (i, j), e in zip(nz, red)]
        body += [f"b[{i}] = {pr.doprint(e)};" for i, e in enumerate(red[len(nz):])]
        body = _unused(body, "q", "cq", "x", "cx", "c", "obs", "gv", "ld") + body
        return Kernel(f"{self.prefix}_force_matrix",
                      self._signature("force_matrix"),
                      body, ops(e for _, e in repl) + ops(red))

    def _magnitude(self, e: sp.Expr) -> sp.Expr:
        """A bound of |e| term by term (SymPy, before :meth:`prepare`): a sum's terms' bounds added, a product's
        multiplied, every cos and sin taken as 1, a parameter-only factor by its absolute value; anything else (a
        travel) by its own absolute value."""
        if e.is_Number:
            return abs(e)
        if isinstance(e, sp.Add):
            return sp.Add(*[self._magnitude(a) for a in e.args])
        if isinstance(e, sp.Mul):
            return sp.Mul(*[self._magnitude(a) for a in e.args])
        if isinstance(e, (sp.cos, sp.sin)):
            return sp.S.One
        return sp.Abs(e)

    def _dyad_input_error(self, dyad: Dyad, fl: _Flavour) -> str:
        """The error of a dyad's input points (m) as the runtime's dyads take it (csrc/sg_runtime.h: ein), from e[0]
        (the earlier angles' largest error, rad) and e[1] (the earlier travels', m): each point's coordinates are
        sums of lengths times cos and sin of earlier angles (and travels), so an angle error moves them by at most
        the lengths of the terms that turn with a coordinate (their magnitude), a travel error by itself per
        coordinate, and each is rounded to SG_DYAD_ROUND roundings of all its terms' magnitude."""
        points = [sp.expand(e) for key in _DYAD_POINTS for e in dyad.inputs.get(key, [])]
        angles = self._angle_symbols()
        travels = {q for q, c in zip(self.kin.q, self.kin.coords) if c.kind != "angle"}
        turning = sum((self._magnitude(t) for e in points for t in sp.Add.make_args(e)
                       if t.free_symbols & angles), sp.S.Zero)
        size = sum((self._magnitude(e) for e in points), sp.S.Zero)
        turning, size = self.prepare([turning, size])
        ein = f"(SG_DYAD_ROUND * SG_EPS) * {fl.value(size)}"
        if turning != 0:
            ein += f" + {fl.value(turning)} * e[0]"
        if any(s in travels for p in points for s in p.free_symbols):
            ein += " + 2.0 * e[1]"
        return ein

    def closed(self, dyads: list[Dyad], vector: bool = False) -> Kernel:
        """The dyad chain: each dyad's inputs, the runtime's solver (csrc/sg_runtime.h sg_dyad_*), its coordinates
        and their cos, sin, and ``err``: the largest error of an angle coordinate (rad) and the product of the
        dyads' amplifications, as the dyads bound them (the rates' error estimate, csrc/sg_runtime.h
        sg_rates_error). ``vector``: the SIMD twin (csrc/sg_simd.h sgv_dyad_*), which returns the mask of lanes
        where every dyad closes by a margin."""
        fl = VECTOR if vector else SCALAR
        body = (["sg_vm ok = sgv_true();"] if vector else ["int st;"]) if dyads else []  # no loop: nothing to solve
        if dyads:  # the dyads' error bounds: angles (rad), travels (m), amplification (csrc/sg_runtime.h sg_dyad_*)
            body.append(f"{fl.real} e[3] = {{{fl.value(sp.S.Zero)}, {fl.value(sp.S.Zero)}, {fl.value(sp.S.One)}}};")
        total = 0
        # the SIMD twin's angles: computed only where asked (angles != 0) when no dyad reads an angle's value
        angle_syms = self._angle_symbols()
        skippable = vector and not any(
            sym in angle_syms for dyad in dyads for key in dyad.inputs
            for e in self.prepare(dyad.inputs[key]) + self.prepare(e for _, cs, sn in dyad.trig for e in (cs, sn))
            for sym in e.free_symbols)
        for k, dyad in enumerate(dyads):
            keys = list(dyad.inputs)
            repl, red = _cse(self.prepare(e for key in keys for e in dyad.inputs[key]))
            outs = self.prepare(e for _, e in dyad.outputs)
            trig = self.prepare(e for _, cs, sn in dyad.trig for e in (cs, sn))
            total += ops(e for _, e in repl) + ops(red) + ops(outs) + ops(trig)
            names = ", ".join(b.name for b in dyad.bodies)
            block = [f"/* dyad {k}: {dyad.kind.upper()} closed at joint {dyad.joint.name} ({names}) */"]
            block += fl.temps(repl)
            pos = 0
            for key in keys:
                size = len(dyad.inputs[key])
                vals = ", ".join(fl.value(e) for e in red[pos: pos + size])
                block.append(f"const {fl.real} {key}[{size}] = {{{vals}}};")
                pos += size
            block.append(f"const {fl.real} ein = {self._dyad_input_error(dyad, fl)};")
            decl, call = _DYAD_CALL[dyad.kind]
            if vector:
                block += [decl.replace("double", "sg_vd"), f"ok &= {call.format(k=k).replace('sg_dyad_', 'sgv_dyad_')};"]
            else:
                block += [decl, f"st = {call.format(k=k)};", "if (st != SG_OK) return st;"]
            for (i, _), e in zip(dyad.outputs, outs):
                if skippable and self.kin.q[i] in angle_syms:
                    block.append(f"q[{i}] = angles ? {fl.value(e)} : sgv_set1(0.0);")
                else:
                    block.append(f"q[{i}] = {fl.value(e)};")
            for j, (i, _, _) in enumerate(dyad.trig):
                block += [f"cq[{2 * i}] = {fl.value(trig[2 * j])};",
                          f"cq[{2 * i + 1}] = {fl.value(trig[2 * j + 1])};"]
            body += ["{"] + ["    " + line for line in block] + ["}"]
        body += (["err[0] = e[0];", "err[1] = e[2];"] if dyads else
                 [f"err[0] = {fl.value(sp.S.Zero)};", f"err[1] = {fl.value(sp.S.One)};"])
        done = ("return ok;" if dyads else "return sgv_true();") if vector else "return SG_OK;"
        body = _unused(body, "x", "cx", "c", "branch", "q", "cq", *(("angles",) if vector else ())) + body + [done]
        name = f"{self.prefix}_closed" + ("_v" if vector else "")
        return Kernel(name, VECTOR_SIGNATURES["closed"].format(f=name) if vector else self._signature("closed"),
                      body, total)

    def vector_kernels(self, dyads: list[Dyad] | None, scales, kst: Kinetostatics, groups: list,
                       blocks: list) -> list[Kernel]:
        """The SIMD twins of the closed (where ``dyads`` is not None), motion, rates, observe and forces kernels and
        the forces' run-time test, or none where the kinematics have no vector form (where only the forces have
        none, the test says no: the SIMD loop then runs a force sweep scalar, and the template passes
        csrc/sg_simd.h's sgv_no_forces for the twin). A mechanism Newton solves gets the twins without the closed
        form: its SIMD loop finishes SG_LANES solved positions at a time (csrc/sg_simd.h sgv_finish)."""
        try:
            kernels = ([self.closed(dyads, vector=True)] if dyads is not None else []) + [
                self.motion(scales, vector=True), self.rates(scales, vector=True),
                self.observe(groups, scales, vector=True)]
        except NoVectorForm:
            return []
        if dyads is None and len(self.kin.q) <= NEWTON_SIMD_MAX_Q:  # Newton's residual and LU: the SIMD Newton
            try:
                kernels += [self.residual(vector=True), *self.lu(vector=True), self.blocks(blocks, vector=True)]
            except NoVectorForm:
                pass
        try:
            kernels.append(self.forces(kst, vector=True))
        except NoVectorForm:
            return kernels + [self.forces_in_simd(kst, has_vector=False)]
        return kernels + [self.forces_in_simd(kst, has_vector=True)]

    def scales(self, exprs: list) -> Kernel:
        """Each closure equation's own size (derive.branches.row_scales): Newton's per-equation tolerance."""
        pr = self.printer
        repl, red = _cse(self.prepare(exprs))
        body = self.selection_block() + SCALAR.temps(repl) + [f"out[{k}] = {pr.doprint(e)};" for k, e in enumerate(red)]
        body = _unused(body, "q", "cq", "x", "cx", "c") + body
        return Kernel(f"{self.prefix}_scales", self._signature("scales"), body,
                      ops(e for _, e in repl) + ops(red) + len(red))  # a copy of a hoisted size counts

    def lu(self, vector: bool = False) -> list[Kernel]:
        """Newton's factor and solve of Φ_q with nq a literal: the runtime's sg_lu_factor_inl / sg_lu_solve_inl
        (SG_UNROLL) unrolled whole for this mechanism, where the runtime's exported copies, for any n, ran ~2.3×
        the instructions (the feed's 7 × 7: 2.6k against 1.1k); by Φ_q's diagonal blocks where the rates are
        (:meth:`solve_by_blocks`). ``vector``: their SIMD twins (csrc/sg_simd.h sgv_newton), the same
        operations lane by lane; the factor returns the mask of the lanes it accepts."""
        n = len(self.kin.q)
        bf = self._block_factor
        names = [f"{self.prefix}_{kind}" + ("_v" if vector else "") for kind in ("lu_factor", "lu_solve")]
        sigs = ([VECTOR_SIGNATURES[kind].format(f=name) for kind, name in zip(("lu_factor", "lu_solve"), names)]
                if vector else [self._signature("lu_factor"), self._signature("lu_solve")])
        if bf:  # Φ_q by its diagonal blocks (sewgen/derive/blockfactor.py)
            return [Kernel(names[0], sigs[0], bf.newton_factor_lines(vector), bf.ops() // 2),
                    Kernel(names[1], sigs[1], bf.newton_solve_lines(vector), bf.ops() // 2)]
        factor, solve = ("sgv_lu_factor", "sgv_lu_solve") if vector else ("sg_lu_factor_inl", "sg_lu_solve_inl")
        return [Kernel(names[0], sigs[0], [f"return {factor}({n}, a, piv{'' if vector else ', NULL'});"],
                       2 * n ** 3 // 3),
                Kernel(names[1], sigs[1], [f"{solve}({n}, lu, piv, b);"], 2 * n * n)]

    def _row_norm2(self, i: int) -> str:
        """Φ_q's row i squared norm from the numeric jac, its structural zeros left out: the same value as the
        sum over all n entries in order, to the bit (0 + a² is a², and a zero entry adds +0), unrolled."""
        n = len(self.kin.q)
        terms = [f"jac[{i * n + j}] * jac[{i * n + j}]" for j in range(n) if self.kin.jac_q[i, j] != 0]
        return "(" + " + ".join(terms) + ")" if terms else "0.0"

    def blocks(self, blocks: list, vector: bool = False) -> Kernel:
        """The normalised determinant of every diagonal block of Φ_q (derive.branches) from the numeric Φ_q:
        det over the product of the block rows' norms in Φ_q; its sign is the block's assembly branch.
        ``vector``: the SIMD twin (sgv_newton's), the same operations lane by lane where every block has
        at most three rows (its determinant in closed form), else the scalar kernel lane after lane."""
        n = len(self.kin.q)
        name = f"{self.prefix}_blocks" + ("_v" if vector else "")
        sig = VECTOR_SIGNATURES["blocks"].format(f=name) if vector else self._signature("blocks")
        if vector and any(len(blk.rows) > 3 for blk in blocks):
            body = [f"double rj[SG_W][{n * n}], ro[SG_W][{len(blocks)}], *pj[SG_W];",
                    "for (int l = 0; l < SG_W; ++l) pj[l] = rj[l];",
                    f"sgv_store_rows(jac, {n * n}, pj);",
                    f"for (int l = 0; l < SG_W; ++l) {self.prefix}_blocks(rj[l], ro[l]);",
                    f"for (int k = 0; k < {len(blocks)}; ++k)",
                    "    for (int l = 0; l < SG_W; ++l) out[k][l] = ro[l][k];"]
            return Kernel(name, sig, body, 0)
        real, sqrt = ("sg_vd", "sgv_sqrt") if vector else ("double", "sqrt")
        body = []
        count = 0
        for k, blk in enumerate(blocks):
            m = len(blk.rows)
            count += {1: 0, 2: 3, 3: 14}.get(m, 2 * m ** 3 // 3) + m * (2 * n + 1) + 2  # det, row norms, quotient
            el = [[f"jac[{i * n + j}]" for j in blk.cols] for i in blk.rows]
            norms = f"{sqrt}(" + " * ".join(self._row_norm2(i) for i in blk.rows) + ")"
            body.append(f"/* block {k}: joints {', '.join(blk.joints)} */")
            body.append("{")
            if m == 1:
                det = el[0][0]
            elif m == 2:
                det = f"{el[0][0]} * {el[1][1]} - {el[0][1]} * {el[1][0]}"
            elif m == 3:
                det = (f"{el[0][0]} * ({el[1][1]} * {el[2][2]} - {el[1][2]} * {el[2][1]})"
                       f" - {el[0][1]} * ({el[1][0]} * {el[2][2]} - {el[1][2]} * {el[2][0]})"
                       f" + {el[0][2]} * ({el[1][0]} * {el[2][1]} - {el[1][1]} * {el[2][0]})")
            else:
                body += [f"    double M[{m * m}];", f"    int piv[{m}];"]
                body += [f"    M[{a * m + b}] = {el[a][b]};" for a in range(m) for b in range(m)]
                body += [f"    const double d = sg_det_inl({m}, M, piv);"]
                det = "d"
            body.append(f"    const {real} nr = {norms};")
            body.append(f"    out[{k}] = sgv_select(nr > sgv_set1(0.0), ({det}) / nr, sgv_set1(0.0));" if vector else
                        f"    out[{k}] = nr > 0.0 ? ({det}) / nr : 0.0;")
            body.append("}")
        body = _unused(body, "jac", "out") + body
        return Kernel(name, sig, body, count)

    def constants_kernel(self) -> Kernel:
        """Call last: it evaluates every constant the other kernels hoisted. A square root of a parameter sum
        (a triangle's height from its sides) takes a negative within rounding of its terms as 0, so a collinear
        triangle is accepted; a really negative one stays NaN, which sewgen.mechanism reports as a
        ParameterError naming the parameters of that constant (manifest "constants")."""
        pr = self.printer
        exprs = [_guard_sqrt(e) for e in self.constants]
        repl, red = _cse(exprs)
        body = SCALAR.temps(repl) + [f"c[{k}] = {pr.doprint(e)};" for k, e in enumerate(red)]
        body = _unused(body, "p", "c") + body
        return Kernel(f"{self.prefix}_constants",
                      self._signature("constants"),
                      body, ops(e for _, e in repl) + ops(red))


class RoundingClamp(sp.Function):
    """``value`` with a negative within 1e-12 of ``scale`` (rounding of a zero) taken as 0 (csrc/sg_runtime.h)."""

    nargs = 2

    def _ccode(self, printer):
        return f"sg_rounding_clamp({printer._print(self.args[0])}, {printer._print(self.args[1])})"


def _guard_sqrt(e: sp.Expr) -> sp.Expr:
    """Every sqrt (or half-integer power) of a sum in ``e`` with its argument clamped by :class:`RoundingClamp`
    against the sum of the magnitudes of its expanded terms."""
    repl = {}
    for pw in e.atoms(sp.Pow):
        base, ex = pw.args
        if isinstance(base, sp.Add) and ex.is_Rational and ex.q == 2:
            scale = sum((sp.Abs(t) for t in sp.Add.make_args(sp.expand(base))), sp.S.Zero)
            repl[pw] = sp.Pow(RoundingClamp(_guard_sqrt(base), scale), ex)
    return e.xreplace(repl) if repl else e


def _balanced_sum(terms: list[str]) -> str:
    """a + b + ... as a balanced tree, so the additions do not wait on each other."""
    if len(terms) == 1:
        return terms[0]
    mid = len(terms) // 2
    return f"({_balanced_sum(terms[:mid])} + {_balanced_sum(terms[mid:])})"


def _fmax(terms: list[str], absolute: bool = True, fab: str = "fabs", fmx: str = "fmax") -> str:
    """fmax of the absolute values (or of the values), as a balanced tree (``fab``, ``fmx``: the functions' names,
    sgv_fabs and sgv_fmax in the SIMD kernels)."""
    if len(terms) == 1:
        return f"{fab}({terms[0]})" if absolute else terms[0]
    mid = len(terms) // 2
    return f"{fmx}({_fmax(terms[:mid], absolute, fab, fmx)}, {_fmax(terms[mid:], absolute, fab, fmx)})"


def _reads_ka(temps, exprs) -> bool:
    """Whether any of these temporaries or expressions reads a cam's run-time selection ka[]."""
    return any(s.name.startswith("ka_") for e in [e for _, e in temps] + list(exprs)
               for s in sp.sympify(e).free_symbols)


def _polynomial(e) -> bool:
    """Sums and products of symbols and numbers with non-negative integer powers only: finite wherever its
    symbols are (but for an overflow)."""
    e = sp.sympify(e)
    if e.is_Symbol or e.is_number:
        return e.is_Symbol or bool(e.is_finite)
    if isinstance(e, (sp.Add, sp.Mul)):
        return all(_polynomial(a) for a in e.args)
    if isinstance(e, sp.Pow):
        ex = e.args[1]
        return bool(ex.is_Integer and ex >= 0) and _polynomial(e.args[0])
    return False


def _stage(sym, levels):
    name = sym.name
    if name.startswith("qdd_"):
        return 2
    if name.startswith("qd_"):
        return 1
    return levels.get(sym, 0)
