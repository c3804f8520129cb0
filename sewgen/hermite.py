"""Cubic Hermite pieces of a periodic sampled quantity: values, slopes, crossings and extremes, vectorised.

Every module that finds events between the samples of a sweep (the stitch timing, the feed-dog travel, the
feed-dog indices) reads a quantity y at equal shaft-angle steps h together with its exact shaft-angle
derivative dy = dy/dφ (v/ω, a/ω² from the kinematics at constant speed; DESIGN.md "events below the step").
Between samples i and i+1 the quantity is the cubic Hermite interpolant of (y_i, y_{i+1}, dy_i, dy_{i+1}),
accurate to O(h⁴) — the one implementation here; crossings and extremes are found on it.

On a piece with s = t/h ∈ [0, 1] (t the offset from sample i) the interpolant in the Hermite basis is

    H(t) = (2s³ − 3s² + 1) p₀ + (s³ − 2s² + s) h d₀ + (−2s³ + 3s²) p₁ + (s³ − s²) h d₁

and in powers of s: H = c₀ + c₁ s + c₂ s² + c₃ s³ with c₀ = p₀, c₁ = h d₀, c₂ = 3(p₁ − p₀) − h(2d₀ + d₁),
c₃ = 2(p₀ − p₁) + h(d₀ + d₁). A root of H in a bracketing piece (a sign change between its ends) is found by
Newton's method on the power form, safeguarded by the bracket (a step leaving it bisects instead), to the last
bit; an extreme is the root of the quadratic H′ the same way.
"""
from __future__ import annotations

import math

import numpy as np

TWO_PI = 2.0 * math.pi


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


def power_form(p0, p1, d0, d1, h):
    """(c₀, c₁, c₂, c₃): the piece as c₀ + c₁ s + c₂ s² + c₃ s³, s = t/h (module docstring)."""
    hd0, hd1 = h * d0, h * d1
    dp = p1 - p0
    return p0, hd0, 3.0 * dp - 2.0 * hd0 - hd1, hd0 + hd1 - 2.0 * dp


def bracketed_root(c0, c1, c2, c3, lo_negative, max_iter: int = 60):
    """The root s ∈ [0, 1] of c₀ + c₁s + c₂s² + c₃s³ (arrays) between s = 0, where the polynomial is negative
    if ``lo_negative`` (else ≥ 0), and s = 1, where it has the other sign: Newton from the secant's guess,
    each step kept inside the shrinking bracket (bisection otherwise), until a step moves by less than 1e-15
    or ``max_iter`` steps. Deterministic: the same inputs give the same bits."""
    c0, c1, c2, c3 = (np.asarray(c, float) for c in (c0, c1, c2, c3))
    lo_negative = np.broadcast_to(np.asarray(lo_negative, bool), c0.shape)
    f1 = c0 + c1 + c2 + c3
    with np.errstate(invalid="ignore", divide="ignore"):
        s = np.clip(c0 / (c0 - f1), 0.0, 1.0)
    s = np.where(np.isfinite(s), s, 0.5)
    lo, hi = np.zeros_like(s), np.ones_like(s)
    idx = np.arange(s.size)
    a0, a1, a2, a3, neg, x, l, u = c0, c1, c2, c3, lo_negative, s, lo, hi
    for _ in range(max_iter):
        f = ((a3 * x + a2) * x + a1) * x + a0
        df = (3.0 * a3 * x + 2.0 * a2) * x + a1
        same = (f < 0.0) == neg
        l = np.where(same, x, l)
        u = np.where(same, u, x)
        with np.errstate(invalid="ignore", divide="ignore"):
            nx = x - f / df
        inside = (nx > l) & (nx < u)
        nx = np.where(inside, nx, 0.5 * (l + u))
        done = (np.abs(nx - x) <= 1e-15) | (f == 0.0) | (u - l <= 1e-15)
        nx = np.where(f == 0.0, x, nx)
        s[idx] = nx
        if done.all():
            break
        keep = ~done
        idx, a0, a1, a2, a3, neg = idx[keep], a0[keep], a1[keep], a2[keep], a3[keep], neg[keep]
        x, l, u = nx[keep], l[keep], u[keep]
    return s


def piece_root(p0, p1, d0, d1, h):
    """The offset t ∈ [0, h] where the Hermite piece (p0 at t = 0, p1 at t = h; p0 < 0 ≤ p1 or p1 < 0 ≤ p0)
    crosses zero (arrays)."""
    c0, c1, c2, c3 = power_form(np.asarray(p0, float), p1, d0, d1, h)
    return h * bracketed_root(c0, c1, c2, c3, np.asarray(p0) < 0.0)


def _next(a):
    return np.roll(a, -1, axis=-1)


def crossings(z, dz, h, iters: int = 60):
    """Every sign change of z (D, N) over one periodic turn: rows, sample index i (the step i..i+1), the offset
    t in [0, h] of the crossing on the Hermite piece, and the sign (+1 rising through 0, −1 falling). ``iters``
    bounds the safeguarded Newton steps (a few suffice)."""
    z = np.atleast_2d(z)
    dz = np.atleast_2d(dz)
    neg = z < 0.0
    rows, cols = np.nonzero(neg != _next(neg))
    n = z.shape[1]
    j = (cols + 1) % n
    p0, p1, d0, d1 = z[rows, cols], z[rows, j], dz[rows, cols], dz[rows, j]
    c0, c1, c2, c3 = power_form(p0, p1, d0, d1, h)
    lo_neg = p0 < 0.0
    t = h * bracketed_root(c0, c1, c2, c3, lo_neg, iters)
    return rows, cols, t, np.where(lo_neg, 1, -1)


def at(y, dy, h, rows, cols, t):
    """The Hermite interpolant of y (D, N) on the pieces (rows, cols) at offsets t."""
    j = (cols + 1) % y.shape[1]
    return hermite(y[rows, cols], y[rows, j], dy[rows, cols], dy[rows, j], h, t)


def maximum(y, dy, h, iters: int = 60):
    """Per row of y (D, N): the largest value of the Hermite interpolant (found next to the largest sample)
    and its (index, offset). Where the slope changes sign from + to − on that piece, the extreme is the root
    of the piece's quadratic derivative; otherwise the largest sample is the answer."""
    y, dy = np.atleast_2d(y), np.atleast_2d(dy)
    d, n = y.shape
    rows = np.arange(d)
    k = np.argmax(y, axis=1)
    left = dy[rows, k] < 0.0  # the maximum lies before sample k
    i = np.where(left, (k - 1) % n, k)
    j = (i + 1) % n
    p0, p1, d0, d1 = y[rows, i], y[rows, j], dy[rows, i], dy[rows, j]
    ok = (d0 >= 0.0) & (d1 <= 0.0)
    t = np.where(left, h, 0.0)
    m = np.flatnonzero(ok)
    _, c1, c2, c3 = power_form(p0[m], p1[m], d0[m], d1[m], h)
    t[m] = h * bracketed_root(-c1, -2.0 * c2, -3.0 * c3, np.zeros_like(c3), np.ones(len(m), bool), iters)
    return np.maximum(hermite(p0, p1, d0, d1, h, t), y[rows, k]), i, t


class Series:
    """A quantity over one revolution of equal steps: values ``y`` and shaft-angle derivatives ``dy`` (dy/dφ),
    interpolated by the cubic Hermite pieces of this module; crossings found on them."""

    def __init__(self, phi, y, dy):
        self.phi, self.y, self.dy = np.asarray(phi), np.asarray(y, float), np.asarray(dy, float)
        self.h = float(self.phi[1] - self.phi[0])

    def at(self, angle: float) -> float:
        """The value at shaft angle ``angle`` (rad)."""
        u = (angle - self.phi[0]) % TWO_PI
        i = min(int(u // self.h), len(self.y) - 1)
        j = (i + 1) % len(self.y)
        return float(hermite(self.y[i], self.y[j], self.dy[i], self.dy[j], self.h, u - i * self.h))

    def crossings(self, level: float = 0.0) -> list:
        """[(angle, +1 rising / −1 falling)] where the quantity crosses ``level``, over the turn, in the order
        of the samples."""
        _, cols, t, sign = crossings(self.y - level, self.dy, self.h)
        return [(float((self.phi[c] + tt) % TWO_PI), int(s)) for c, tt, s in zip(cols, t, sign)]
