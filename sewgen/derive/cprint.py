"""SymPy -> C99 expression text: flat-array symbol names, integer powers as products (DESIGN.md §4).

User names never reach C: every symbol prints as an element of a flat array (q[i], p[j], ...) or as a
numbered temporary. Output depends only on the expressions, never on hash order.
"""
from __future__ import annotations

import re

import sympy as sp
from sympy.printing.c import C99CodePrinter

_ARRAY = re.compile(r"^(q|qd|qdd|x|xd|xdd|p|c|cq|cx|o|gv|ld|f|ka)_(\d+)$")
#: Symbol prefixes printed under another array name: observables o_k -> obs[k], force results f_k -> out[k].
_ALIAS = {"o": "obs", "f": "out"}
_LOCAL = re.compile(r"^([A-Za-z]+\w*?)_(\d+)$")


class KernelPrinter(C99CodePrinter):
    """C99 printer with sewgen's symbol mapping. ``names`` overrides the text of given symbols."""

    def __init__(self, names: dict | None = None):
        super().__init__({"math_macros": {}})
        self.names = names or {}

    def _print_Symbol(self, expr):
        if expr in self.names:
            return self.names[expr]
        m = _ARRAY.match(expr.name)
        if m:
            return f"{_ALIAS.get(m.group(1), m.group(1))}[{m.group(2)}]"
        m = _LOCAL.match(expr.name)
        if m:
            return f"{m.group(1)}[{m.group(2)}]"
        return expr.name

    def _print_Pow(self, expr):
        base, exp = expr.args
        if exp.is_Integer and 2 <= abs(int(exp)) <= 4:
            b = self.parenthesize(base, 1000)  # strictly atomic or parenthesised
            prod = "*".join([b] * abs(int(exp)))
            return f"({prod})" if exp > 0 else f"(1.0/({prod}))"
        if exp == -1:
            return f"(1.0/{self.parenthesize(base, 1000)})"
        return super()._print_Pow(expr)

    def _print_sign(self, expr):  # sign(x): +1, -1, or 0 at exactly 0 (Coulomb friction at rest: none)
        a = self._print(expr.args[0])
        return f"(({a}) > 0.0 ? 1.0 : (({a}) < 0.0 ? -1.0 : 0.0))"

    def _print_NumberSymbol(self, expr):  # pi, E, ...: a literal, never a macro or a declaration
        return repr(float(expr))

    _print_Pi = _print_Exp1 = _print_NumberSymbol

    def _print_Float(self, expr):
        return repr(float(expr))

    def _print_Rational(self, expr):
        return repr(float(expr))

    def _print_Integer(self, expr):
        return f"{int(expr)}.0" if abs(int(expr)) < 2**53 else repr(float(expr))


def ops(exprs) -> int:
    """Operation count of a list of expressions (the 'Total ops' of a kernel)."""
    return int(sum(sp.count_ops(e) for e in exprs))


class NoVectorForm(ValueError):
    """An expression the SIMD kernels cannot print (a function csrc/sg_simd.h has no vector form of)."""


#: Symbols that are one number for a whole sweep (constants c[], gravity gv[], friction loads fr[] of the
#: frictionless solve): scalars in the SIMD kernels.
PER_SWEEP = ("c_", "gv_", "fr_")


def per_sweep(expr) -> bool:
    """Whether ``expr`` reads only per-sweep scalars (or nothing): one number for every lane of a SIMD block."""
    return all(s.name.startswith(PER_SWEEP) for s in sp.sympify(expr).free_symbols)


class VectorPrinter(KernelPrinter):
    """KernelPrinter for the SIMD twins of the closed, motion and forces kernels (csrc/sg_simd.h): the same text
    with the arithmetic on GCC vectors (sg_vd) and the functions sg_simd.h vectorises (sqrt, |x|, atan2); a
    subexpression of per-sweep scalars only prints as scalar C. Anything else (trigonometric functions of a
    coordinate, sign, min/max, piecewise) raises :class:`NoVectorForm`: that mechanism then has no SIMD loop, only
    the scalar one."""

    def __init__(self):
        super().__init__()
        self.known_functions = {"Abs": "sgv_fabs", "atan2": "sgv_atan2", "sqrt": "sgv_sqrt"}
        self._scalar = KernelPrinter()

    def _print_math_func(self, expr, nest=False, known=None):
        if per_sweep(expr):  # sqrt(5), |c|: a scalar, which the vector arithmetic around it broadcasts
            return self._scalar.doprint(expr)
        name = type(expr).__name__
        if name not in self.known_functions:
            raise NoVectorForm(f"no vector form of {name}")
        return f"{self.known_functions[name]}({', '.join(self._print(a) for a in expr.args)})"

    _print_Abs = _print_atan2 = _print_sqrt = _print_math_func

    def _print_Pow(self, expr):
        base, exp = expr.args
        if per_sweep(expr):
            return self._scalar.doprint(expr)
        if exp == sp.S.Half:
            return f"sgv_sqrt({self._print(base)})"
        if exp == -sp.S.Half:
            return f"(1.0/sgv_sqrt({self._print(base)}))"
        if exp.is_Integer and 1 <= abs(int(exp)) <= 4 or exp == -1:
            return super()._print_Pow(expr)
        raise NoVectorForm(f"no vector form of the power {exp}")

    def _print_not_supported(self, expr):
        raise NoVectorForm(f"no vector form of {type(expr).__name__}")

    # everything else the C99 printer would print as C of doubles: a scalar where it reads per-sweep values
    # only, refused otherwise (_print_math_func)
    _print_sign = _print_Max = _print_Min = _print_Piecewise = _print_ITE = _print_Relational = _print_math_func
    _print_sin = _print_cos = _print_tan = _print_exp = _print_log = _print_floor = _print_math_func
    _print_ceiling = _print_acos = _print_asin = _print_atan = _print_Mod = _print_Heaviside = _print_math_func
