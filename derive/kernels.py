"""Kernel bodies as C text, computed in Python (DESIGN.md §4): the templates only lay them out.

Three kernels per mechanism, each one joint CSE over everything it returns:

* ``closed``   — the dyad chain (derive.dyads) calling the runtime's sg_dyad_* solvers;
* ``residual`` — Φ(q, x) and Φ_q for Newton and for residual checks;
* ``motion``   — Φ_q, −Φ_x x', LU, q'; γ, q''; every observable. The CSE temporaries are emitted in three
  stages by what they depend on (positions only / q' / q''), so a subexpression such as sin(q[1]) is
  computed once for the Jacobian, γ and the observables alike.
"""
from __future__ import annotations

import re
from dataclasses import dataclass, field

import sympy as sp

from .cprint import KernelPrinter, ops
from .dyads import Dyad
from .kinematics import Kinematics


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


def _temps(printer, repl):
    return [f"const double {printer.doprint(t)} = {printer.doprint(e)};" for t, e in repl]


def _unused(body, *names):
    """(void) casts for the arguments a kernel body never reads (-Wextra)."""
    text = "\n".join(body)
    return [f"(void){n};" for n in names if not re.search(rf"\b{n}\b", text)]


def residual_kernel(prefix: str, kin: Kinematics) -> Kernel:
    n = len(kin.q)
    pr = KernelPrinter()
    exprs = list(kin.closure) + [kin.jac_q[i, j] for i in range(n) for j in range(n)]
    repl, red = _cse(exprs)
    body = _temps(pr, repl)
    body += [f"r[{i}] = {pr.doprint(e)};" for i, e in enumerate(red[:n])]
    body += [f"jac[{k}] = {pr.doprint(e)};" for k, e in enumerate(red[n:])]
    body = _unused(body, "q", "x", "p") + body
    return Kernel(f"{prefix}_residual",
                  f"void {prefix}_residual(const double *q, const double *x, const double *p, double *r, double *jac)",
                  body, ops(e for _, e in repl) + ops(red))


def _stage(sym, levels):
    name = sym.name
    if name.startswith("qdd_"):
        return 2
    if name.startswith("qd_"):
        return 1
    return levels.get(sym, 0)


def motion_kernel(prefix: str, kin: Kinematics) -> Kernel:
    n = len(kin.q)
    pr = KernelPrinter()
    jac = [kin.jac_q[i, j] for i in range(n) for j in range(n)]
    obs = [o.expr for o in kin.observables]
    exprs = jac + list(kin.vel_rhs) + list(kin.gamma) + obs
    repl, red = _cse(exprs)
    levels: dict = {}
    for t, e in repl:
        levels[t] = max((_stage(s, levels) for s in e.free_symbols), default=0)
    staged = [[(t, e) for t, e in repl if levels[t] == k] for k in range(3)]
    r_jac, r_vel = red[: n * n], red[n * n: n * n + n]
    r_gam, r_obs = red[n * n + n: n * n + 2 * n], red[n * n + 2 * n:]
    body = _temps(pr, staged[0])
    if n:
        body += [f"double J[{n * n}];", f"int piv[{n}];"]
        body += [f"J[{k}] = {pr.doprint(e)};" for k, e in enumerate(r_jac)]
        body += [f"qd[{i}] = {pr.doprint(e)};" for i, e in enumerate(r_vel)]
        body += [f"if (sg_lu_factor({n}, J, piv, 0) != SG_OK) return SG_SINGULAR;",
                 f"sg_lu_solve({n}, J, piv, qd);"]
    body += _temps(pr, staged[1])
    if n:
        body += [f"qdd[{i}] = {pr.doprint(e)};" for i, e in enumerate(r_gam)]
        body += [f"sg_lu_solve({n}, J, piv, qdd);"]
    body += _temps(pr, staged[2])
    body += [f"obs[{k}] = {pr.doprint(e)};" for k, e in enumerate(r_obs)]
    body = _unused(body, "q", "x", "xd", "xdd", "p", "qd", "qdd", "obs") + body + ["return SG_OK;"]
    return Kernel(f"{prefix}_motion",
                  f"int {prefix}_motion(const double *q, const double *x, const double *xd, const double *xdd, "
                  f"const double *p, double *qd, double *qdd, double *obs)",
                  body, ops(e for _, e in repl) + ops(red))


_DYAD_CALL = {
    "rrr": ("double J[2];", "sg_dyad_rrr(P, Q, l[0], l[1], branch[{k}], J)"),
    "rrp": ("double s, J[2];", "sg_dyad_rrp(P, l[0], L0, u, branch[{k}], &s, J)"),
    "rpr": ("double s, theta;", "sg_dyad_rpr(D, w0, u, branch[{k}], &s, &theta)"),
}


def closed_kernel(prefix: str, kin: Kinematics, dyads: list[Dyad]) -> Kernel:
    pr = KernelPrinter()
    body = ["int st;"]
    total = 0
    for k, dyad in enumerate(dyads):
        keys = list(dyad.inputs)
        flat = [e for key in keys for e in dyad.inputs[key]]
        repl, red = _cse(flat)
        total += ops(e for _, e in repl) + ops(red) + ops(e for _, e in dyad.outputs)
        names = ", ".join(b.name for b in dyad.bodies)
        block = [f"/* dyad {k}: {dyad.kind.upper()} closed at joint {dyad.joint.name} ({names}) */"]
        block += _temps(pr, repl)
        pos = 0
        for key in keys:
            size = len(dyad.inputs[key])
            vals = ", ".join(pr.doprint(e) for e in red[pos: pos + size])
            block.append(f"const double {key}[{size}] = {{{vals}}};")
            pos += size
        decl, call = _DYAD_CALL[dyad.kind]
        block += [decl, f"st = {call.format(k=k)};", "if (st != SG_OK) return st;"]
        block += [f"q[{i}] = {pr.doprint(e)};" for i, e in dyad.outputs]
        body += ["{"] + ["    " + line for line in block] + ["}"]
    body = _unused(body, "x", "p", "branch", "q") + body + ["return SG_OK;"]
    return Kernel(f"{prefix}_closed",
                  f"int {prefix}_closed(const double *x, const double *p, const int *branch, double *q)",
                  body, total)
