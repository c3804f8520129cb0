/* sewgen C runtime: pivoted LU, closed-form dyads, damped Newton with a predictor, sweep driver.
 *
 * Hand-written; the generated kernels (generated/sg_<mechanism>.c) include this header and fill one
 * sg_mechanism descriptor each (its fields: sg_abi.h). Everything exported is prefixed sg_. C99, no
 * allocation, no globals.
 */
#ifndef SG_RUNTIME_H
#define SG_RUNTIME_H

#include <math.h>
#include <stddef.h>

/* Status codes, the options struct, the kernel function types, the mechanism descriptor and the exported
 * functions are generated from sewgen/abi.py (one source for C and Python). */
#include "sg_abi.h"

/* SG_MAX_Q, SG_MAX_C, SG_MAX_GROUP, SG_MAX_LOAD, SG_MAX_DIRECT, SG_BLOCK, SG_HISTORY, SG_NCOND: sg_abi.h
 * (sewgen.abi.LIMITS). */

/* Flat column j of one position (q, qd, qdd: nq each, then obs): a pointer into the arrays q, qd, qdd, obs of that
 * position (doubles, or a SIMD block's lane vectors): the layout of sg_columns' col[] (sg_runtime.c's col_ptr
 * reads the same layout out of the design sweeps' scratch, where qd and qdd may be absent). */
#define SG_FLAT_COLUMN(j, nq, q, qd, qdd, obs)                                                     \
    ((j) < (nq) ? (q) + (j)                                                                         \
                : (j) < 2 * (nq) ? (qd) + ((j) - (nq))                                              \
                                 : (j) < 3 * (nq) ? (qdd) + ((j) - 2 * (nq)) : (obs) + ((j) - 3 * (nq)))

/* Columns a SIMD sweep writes straight to their own arrays (sg_sweep_designs' selected outputs,
 * no row then copy): column k is the flat column col[k] (q, qd, qdd, then obs, as sg_runtime.c's sg_scratch), its
 * position i at dst[k][i]. The SIMD loop sets written to 1 when it takes them; the scalar loops leave it 0 and
 * write rows only. */
typedef struct sg_columns {
    int n;
    const int *col;
    double *const *dst;
    int written;
} sg_columns;

/* Solved positions of a Newton sweep waiting for their rates, observables and forces, which the mechanism's SIMD
 * finish (descriptor finish_simd, csrc/sg_simd.h sgv_finish) computes SG_LANES at a time: per lane
 * its position's index, coordinates and their cos, sin, inputs with theirs and their rates, Newton's last relative
 * residual; est receives the rates' estimated relative error of each lane the finish vouches for. A block of
 * fewer than SG_LANES positions repeats its last one in the lanes after count. SG_LANES: the SIMD vector's lanes,
 * 8 in a module built for AVX-512 (SG_SIMD_LEVEL 512, sewgen/build.py), else 4 (AVX2). */
#if defined(SG_SIMD_LEVEL) && SG_SIMD_LEVEL == 512
#define SG_LANES 8
#else
#define SG_LANES 4
#endif
typedef struct sg_lanes {
    int count;
    size_t index[SG_LANES];
    double q[SG_LANES][SG_MAX_Q], cq[SG_LANES][2 * SG_MAX_Q];
    double x[SG_LANES][SG_MAX_Q], cx[SG_LANES][2 * SG_MAX_Q], xd[SG_LANES][SG_MAX_Q], xdd[SG_LANES][SG_MAX_Q];
    double resid[SG_LANES], est[SG_LANES];
} sg_lanes;

/* Positions the Newton continuation predicts from one history and solves independently (csrc/sg_runtime.c,
 * solve_block): SG_BLOCK of them in every loop and at every SIMD level, so that the scalar and the SIMD loops
 * (descriptor newton_simd, csrc/sg_simd.h sgv_newton, SG_LANES lanes a call) solve the same positions
 * from the same starts. Per lane its inputs with their cos, sin, and after the solve its coordinates with
 * theirs, Newton's last relative residual and the loops' orientation determinants (kernel 'blocks'). SG_BLOCK is a
 * multiple of SG_LANES; SG_HISTORY earlier states feed the predictor (both in sg_abi.h). */
typedef struct sg_block {
    int count;
    double q[SG_BLOCK][SG_MAX_Q], cq[SG_BLOCK][2 * SG_MAX_Q], x[SG_BLOCK][SG_MAX_Q], cx[SG_BLOCK][2 * SG_MAX_Q];
    double resid[SG_BLOCK], bv[SG_BLOCK][SG_MAX_Q];
    /* what the SIMD Newton predicts the starts from: the history's angles and states (newest first), the newest
     * state's cos, sin, and each coordinate's largest change a prediction or a correction may make (SG_DQ_MAX; a
     * travel's times the loops' size) */
    double hphi[SG_HISTORY], lim[SG_MAX_Q];
    const double *hq[SG_HISTORY], *hcq;
} sg_block;

/* cos and sin of a step d of an angle coordinate for shift_trig (csrc/sg_runtime.c) and its SIMD twin
 * (sgv_shift_trig): below SG_TINY_STEP cos d = 1 and sin d = d exactly (their corrections, d^2/2 and d^2/6
 * relative, are under 2^-54, half an ulp of 1, up to |d| = 1.05e-8); below SG_SHORT_STEP three terms of each
 * Taylor series (the first omitted, d^7/7! and d^6/6!, below 2e-22 and 1.4e-21 relative); below SG_SMALL_STEP
 * four (d^10/10! and d^9/9! below 1e-26); larger steps take sincos. The series' divisions are products with
 * their reciprocals (constants): within an ulp of the quotients, in a correction already below 1e-4 of the
 * result. The expressions are written once here for double and sg_vd operands alike (h: the step, h2 = h h), so
 * the two loops compute the same values. */
#define SG_TINY_STEP 1e-9
#define SG_SHORT_STEP 1e-3
#define SG_SMALL_STEP 1e-2
#define SG_SIN_SHORT(h, h2) ((h) * (1.0 - (h2) * (1.0 / 6.0) * (1.0 - (h2) * (1.0 / 20.0))))
#define SG_COS_SHORT(h2) (1.0 - (h2) * 0.5 * (1.0 - (h2) * (1.0 / 12.0)))
#define SG_SIN_SMALL(h, h2) \
    ((h) * (1.0 - (h2) * (1.0 / 6.0) * (1.0 - (h2) * (1.0 / 20.0) * (1.0 - (h2) * (1.0 / 42.0)))))
#define SG_COS_SMALL(h2) \
    (1.0 - (h2) * 0.5 * (1.0 - (h2) * (1.0 / 12.0) * (1.0 - (h2) * (1.0 / 30.0) * (1.0 - (h2) * (1.0 / 56.0)))))

/* LU with partial pivoting, in place, row-major n x n. Returns SG_SINGULAR when a pivot is below
 * 1e-11 of its column's largest original entry (column-scale invariant: columns may be rad or m).
 * Always inline, so that a kernel's call with a literal n unrolls; sg_lu_factor/sg_lu_solve are the exported
 * copies. */
#define SG_PIVOT_RTOL 1e-11
#define SG_TWO_PI 6.283185307179586476925286766559
/* Unit roundoff. */
#define SG_EPS 1.1102230246251565e-16
/* A relative loop residual below this is rounding of the residual's own terms (sizes taken with every cos and
 * sin as 1): the position is then as exact as a closed form's. */
#define SG_RESID_FLOOR (64.0 * SG_EPS)
#if defined(__GNUC__)
#define SG_INLINE static inline __attribute__((always_inline))
/* A loop of the small dense solves unrolled: whole where n is a literal (the generated rates kernels). -O2 alone
 * kept the loops; without their counters and hard-to-predict branches the feed's sweep takes less time for the
 * same instruction count. */
#define SG_UNROLL _Pragma("GCC unroll 8")
#define SG_FLATTEN __attribute__((flatten)) /* every call in the function's body inlined */
#define SG_NOINLINE __attribute__((noinline))
#else
#define SG_INLINE static inline
#define SG_UNROLL
#define SG_FLATTEN
#define SG_NOINLINE
#endif

/* The five-state Lagrange extrapolation, the continuation's predictor (csrc/sg_runtime.c predict5, and its SIMD
 * twin sgv_newton): the weights w_a = prod_{b != a} (t - x_b) / (x_a - x_b) from the ten differences of the angles
 * x (den: the five denominators; 0 where two angles are equal) and the numerators as prefix and suffix products;
 * the scalar and the vector weights (csrc/sg_simd.h sgv_lagrange5_weights) the same operations in the same order. */
SG_INLINE int sg_lagrange5_den(const double *x, double *den)
{
    const double d01 = x[0] - x[1], d02 = x[0] - x[2], d03 = x[0] - x[3], d04 = x[0] - x[4];
    const double d12 = x[1] - x[2], d13 = x[1] - x[3], d14 = x[1] - x[4];
    const double d23 = x[2] - x[3], d24 = x[2] - x[4], d34 = x[3] - x[4];
    den[0] = d01 * d02 * d03 * d04, den[1] = -d01 * d12 * d13 * d14, den[2] = d02 * d12 * d23 * d24;
    den[3] = -d03 * d13 * d23 * d34, den[4] = d04 * d14 * d24 * d34;
    return den[0] != 0.0 && den[1] != 0.0 && den[2] != 0.0 && den[3] != 0.0 && den[4] != 0.0;
}
SG_INLINE void sg_lagrange5_weights(double t, const double *x, const double *den, double *w)
{
    const double e0 = t - x[0], e1 = t - x[1], e2 = t - x[2], e3 = t - x[3], e4 = t - x[4];
    const double p01 = e0 * e1, p012 = p01 * e2, s34 = e3 * e4, s234 = e2 * s34;
    w[0] = e1 * s234 / den[0], w[1] = e0 * s234 / den[1], w[2] = p01 * s34 / den[2];
    w[3] = p012 * e4 / den[3], w[4] = p012 * e3 / den[4];
}
/* The extrapolated value of coordinate i from the weights w and the states q (newest first): double or sg_vd. */
#define SG_LAGRANGE5_VALUE(w, q, i) \
    ((w[0] * q[0][i] + w[1] * q[1][i]) + (w[2] * q[2][i] + w[3] * q[3][i]) + w[4] * q[4][i])

/* LU with partial pivoting in place, a pivot singular below SG_PIVOT_RTOL times its column's colmax[k] (the
 * largest |entry| of column k of the whole matrix: a mechanism's block factor, sewgen/derive/blockfactor.py,
 * factors a diagonal block against its columns in all of Φ_q). */
SG_INLINE int sg_lu_factor_cm_inl(int n, double *a, int *piv, const double *colmax, double *det_sign)
{
    double sign = 1.0;
    SG_UNROLL
    for (int k = 0; k < n; ++k) {
        int pr = k;
        double best = fabs(a[k * n + k]);
        SG_UNROLL
        for (int i = k + 1; i < n; ++i) {
            const double v = fabs(a[i * n + k]);
            if (v > best) {
                best = v;
                pr = i;
            }
        }
        piv[k] = pr;
        if (!(best > SG_PIVOT_RTOL * colmax[k])) return SG_SINGULAR;
        if (pr != k) {
            sign = -sign;
            SG_UNROLL
            for (int j = 0; j < n; ++j) {
                const double t = a[k * n + j];
                a[k * n + j] = a[pr * n + j];
                a[pr * n + j] = t;
            }
        }
        const double inv = 1.0 / a[k * n + k];
        if (a[k * n + k] < 0.0) sign = -sign;
        SG_UNROLL
        for (int i = k + 1; i < n; ++i) {
            const double f = a[i * n + k] * inv;
            a[i * n + k] = f;
            if (f != 0.0)
                SG_UNROLL
                for (int j = k + 1; j < n; ++j) a[i * n + j] -= f * a[k * n + j];
        }
    }
    if (det_sign) *det_sign = sign;
    return SG_OK;
}

SG_INLINE int sg_lu_factor_inl(int n, double *a, int *piv, double *det_sign)
{
    double colmax[SG_MAX_Q];
    SG_UNROLL
    for (int j = 0; j < n; ++j) {
        double cm = 0.0;
        SG_UNROLL
        for (int i = 0; i < n; ++i) {
            const double v = fabs(a[i * n + j]);
            if (v > cm) cm = v;
        }
        colmax[j] = cm;
    }
    return sg_lu_factor_cm_inl(n, a, piv, colmax, det_sign);
}

/* The factor swaps whole rows (L's multipliers too, as LAPACK's dgetrf), so every interchange is applied
 * to b before the forward substitution. */
SG_INLINE void sg_lu_solve_inl(int n, const double *lu, const int *piv, double *b)
{
    SG_UNROLL
    for (int k = 0; k < n; ++k) {
        if (piv[k] != k) {
            const double t = b[k];
            b[k] = b[piv[k]];
            b[piv[k]] = t;
        }
    }
    SG_UNROLL
    for (int k = 0; k < n; ++k)
        SG_UNROLL
        for (int i = k + 1; i < n; ++i) b[i] -= lu[i * n + k] * b[k];
    SG_UNROLL
    for (int k = n - 1; k >= 0; --k) {
        double s = b[k];
        SG_UNROLL
        for (int j = k + 1; j < n; ++j) s -= lu[k * n + j] * b[j];
        b[k] = s / lu[k * n + k];
    }
}

/* The 2 x 2 case of sg_factor_eq_inl in closed form (one dyad's loop, the commonest case): a
 * (row-major) is overwritten by the inverse of B = R A, B^-1 = adj(B) / det B, so that the solve is a product.
 * With E = B C the equilibrated matrix (C = diag(1/m0, 1/m1), m_j the largest |entry| of B's column j):
 *   - the singular test is sg_factor_eq_inl's second pivot, |det E| = |det B| / (m0 m1) > SG_PIVOT_RTOL (its
 *     first pivot is 1), made without a division;
 *   - cond is E's condition number in the inf norm exactly, ||E|| ||E^-1|| with
 *     ||E|| = max_i (|b_i0| m1 + |b_i1| m0) / (m0 m1) and ||E^-1|| = max(m0 (|b11| + |b01|), m1 (|b10| + |b00|))
 *     / |det B| (E^-1 = diag(m) adj(B) / det B), where the general factor gives an upper bound of it (at most a
 *     few times larger).
 * One division for all of it (the general factor takes four, three of them in a chain), and no pivoting: the
 * adjugate needs none. cs as sg_factor_eq_inl's (1/m0, 1/m1 from the one division: m1 / (m0 m1), m0 / (m0 m1);
 * then m0, m1), for the rates' scales (sg_rates_scale_inl); the solve does not read it. csrc/sg_simd.h's
 * sgv_factor_eq2 is this lane by lane, operation for operation, so the two loops agree to the bit. A NaN, a zero
 * column (a coordinate no loop reads) or a singular B gives SG_SINGULAR. */
SG_INLINE int sg_factor_eq2_inl(double *a, const double *rs, double *cs, double *cond)
{
    const double b00 = a[0] * rs[0], b01 = a[1] * rs[0], b10 = a[2] * rs[1], b11 = a[3] * rs[1];
    const double f00 = fabs(b00), f01 = fabs(b01), f10 = fabs(b10), f11 = fabs(b11);
    const double m0 = f00 > f10 ? f00 : f10, m1 = f01 > f11 ? f01 : f11;
    const double det = b00 * b11 - b01 * b10, mm = m0 * m1;
    const double r = 1.0 / (mm * det), inv = r * mm, imm = r * det;
    const double n1a = f00 * m1 + f01 * m0, n1b = f10 * m1 + f11 * m0;
    const double n2a = m0 * (f11 + f01), n2b = m1 * (f10 + f00);
    *cond = (n1a > n1b ? n1a : n1b) * (n2a > n2b ? n2a : n2b) * fabs(r);
    cs[0] = m1 * imm;
    cs[1] = m0 * imm;
    cs[2] = m0;
    cs[3] = m1;
    a[0] = b11 * inv;
    a[1] = -b01 * inv;
    a[2] = -b10 * inv;
    a[3] = b00 * inv;
    return fabs(det) > SG_PIVOT_RTOL * mm && isfinite(*cond) ? SG_OK : SG_SINGULAR;
}

/* The LU with partial pivoting of an equilibrated matrix (every column's largest entry about 1: pivots below
 * SG_PIVOT_RTOL are singular; U's diagonal kept as its reciprocal) and *inorm, an upper bound of ||A^-1||_inf
 * (below). sg_factor_eq_inl's factor after its scaling, and each diagonal block's of a mechanism whose rates
 * solve Φ_q block by block (sewgen/derive/blockfactor.py). */
SG_INLINE int sg_lu_bound_inl(int n, double *a, int *piv, double *inorm_out)
{
    SG_UNROLL
    for (int k = 0; k < n; ++k) { /* LU with partial pivoting: every column's largest entry is 1 already */
        int pr = k;
        double best = fabs(a[k * n + k]);
        SG_UNROLL
        for (int i = k + 1; i < n; ++i) {
            const double v = fabs(a[i * n + k]);
            if (v > best) best = v, pr = i;
        }
        piv[k] = pr;
        if (!(best > SG_PIVOT_RTOL)) return SG_SINGULAR;
        if (pr != k)
            SG_UNROLL
            for (int j = 0; j < n; ++j) {
                const double t = a[k * n + j];
                a[k * n + j] = a[pr * n + j];
                a[pr * n + j] = t;
            }
        const double inv = 1.0 / a[k * n + k];
        a[k * n + k] = inv; /* U's diagonal kept as its reciprocal: the solves multiply */
        SG_UNROLL
        for (int i = k + 1; i < n; ++i) {
            const double f = a[i * n + k] * inv;
            a[i * n + k] = f;
            if (f != 0.0)
                SG_UNROLL
                for (int j = k + 1; j < n; ++j) a[i * n + j] -= f * a[k * n + j];
        }
    }
    /* ||A^-1||_inf = || |A^-1| 1 || <= || |U^-1| |L^-1| 1 || <= || M(U)^-1 M(L)^-1 1 ||, M the comparison matrix
     * (|diagonal|, -|off-diagonal|: the inverse of a triangular one is non-negative and bounds the inverse's
     * magnitudes entry by entry): a triangular solve with a vector of ones, then one with its result. An upper
     * bound, tight for the small well-scaled factors here (at most ||M(U)^-1|| ||M(L)^-1||, the bound of the two
     * solves each with ones); two passes of n^2/2 instead of n solves. */
    double y[SG_MAX_Q];
    double inorm = 0.0;
    SG_UNROLL
    for (int i = 0; i < n; ++i) {
        double s = 1.0;
        SG_UNROLL
        for (int j = 0; j < i; ++j) s += fabs(a[i * n + j]) * y[j];
        y[i] = s;
    }
    SG_UNROLL
    for (int i = n - 1; i >= 0; --i) {
        double s = y[i];
        SG_UNROLL
        for (int j = i + 1; j < n; ++j) s += fabs(a[i * n + j]) * y[j];
        y[i] = s * fabs(a[i * n + i]);
        if (!(y[i] <= inorm)) inorm = y[i];
    }
    *inorm_out = inorm;
    return SG_OK;
}

/* LU of A scaled, R A C: R = diag(rs) given in natural units (sewgen's motion kernels: each row over its loop's
 * size, so that a loop near its toggle, whose rows all but vanish, stays near-singular), C = diag(cs) found here
 * (each column of R A to its largest entry 1: rad and m columns alike, the solution's components each to its
 * own scale); and a bound of the condition number of R A C in the inf norm (from the factor, below), in cond[0].
 * cs holds 2 n values: the column factors 1/m_j, then the columns' largest entries m_j (the rates' scales,
 * sg_rates_scale_inl). The runtime turns cond into the estimated relative error of the rates (sg_rates_error).
 * Solve with sg_solve_eq_inl. n = 2 is sg_factor_eq2_inl (piv unused). */
SG_INLINE int sg_factor_eq_inl(int n, double *a, int *piv, const double *rs, double *cs, double *cond)
{
    if (n == 2) return sg_factor_eq2_inl(a, rs, cs, cond);
    *cond = INFINITY;
    SG_UNROLL
    for (int j = 0; j < n; ++j) {
        double m = 0.0;
        SG_UNROLL
        for (int i = 0; i < n; ++i) {
            a[i * n + j] *= rs[i];
            const double v = fabs(a[i * n + j]);
            if (!(v <= m)) m = v; /* NaN propagates */
        }
        if (!(m > 0.0) || !(m < INFINITY)) return SG_SINGULAR; /* a coordinate no loop reads */
        cs[j] = 1.0 / m;
        cs[n + j] = m;
        SG_UNROLL
        for (int i = 0; i < n; ++i) a[i * n + j] *= cs[j];
    }
    double anorm = 0.0;
    SG_UNROLL
    for (int i = 0; i < n; ++i) {
        double s = 0.0;
        SG_UNROLL
        for (int j = 0; j < n; ++j) s += fabs(a[i * n + j]);
        if (!(s <= anorm)) anorm = s; /* NaN propagates */
    }
    double inorm;
    if (sg_lu_bound_inl(n, a, piv, &inorm) != SG_OK) return SG_SINGULAR;
    *cond = anorm * inorm;
    return isfinite(*cond) ? SG_OK : SG_SINGULAR;
}

/* b overwritten by A^-1 b with a factor of sg_lu_bound_inl (interchanges, L, then U by its reciprocal
 * diagonal). */
SG_INLINE void sg_lu_apply_inl(int n, const double *lu, const int *piv, double *b)
{
    SG_UNROLL
    for (int k = 0; k < n; ++k)
        if (piv[k] != k) {
            const double t = b[k];
            b[k] = b[piv[k]];
            b[piv[k]] = t;
        }
    SG_UNROLL
    for (int k = 0; k < n; ++k)
        SG_UNROLL
        for (int i = k + 1; i < n; ++i) b[i] -= lu[i * n + k] * b[k];
    SG_UNROLL
    for (int k = n - 1; k >= 0; --k) {
        double s = b[k];
        SG_UNROLL
        for (int j = k + 1; j < n; ++j) s -= lu[k * n + j] * b[j];
        b[k] = s * lu[k * n + k];
    }
}

/* Solve A x = b with a factor of sg_factor_eq_inl (b overwritten by x; U's diagonal holds reciprocals; for
 * n = 2, x = B^-1 (R b)). */
SG_INLINE void sg_solve_eq_inl(int n, const double *lu, const int *piv, const double *rs, const double *cs,
                               double *b)
{
    if (n == 2) {
        const double b0 = b[0] * rs[0], b1 = b[1] * rs[1];
        b[0] = lu[0] * b0 + lu[1] * b1;
        b[1] = lu[2] * b0 + lu[3] * b1;
        return;
    }
    SG_UNROLL
    for (int i = 0; i < n; ++i) b[i] *= rs[i];
    sg_lu_apply_inl(n, lu, piv, b);
    SG_UNROLL
    for (int j = 0; j < n; ++j) b[j] *= cs[j];
}

/* The rates' error estimate (sg_closed_finish; csrc/sg_runtime.c finish_position; the SIMD loops' twins in
 * csrc/sg_simd.h), relative: q' to ||y'||, q'' to max(||y''||, S), y = q' m and y'' = q'' m the rates scaled by
 * their columns, S their centripetal and Coriolis terms (sg_rates_scale_inl).
 *
 * The rates solve Φ_q q' = -Φ_x x' and Φ_q q'' = γ(q, q'). A relative perturbation e of either moves the
 * solution by up to amp e, amp the solve's amplification. Three sources of e:
 *   - rounding: eps;
 *   - the position's own error, ej (rad: the largest error of an angle coordinate), which turns Φ_q's columns with
 *     their bodies (and γ's terms): e = ej;
 *   - for q'', the error of q' in γ's terms: 2 E_v of their sensitivity, 2 E_v μ of the accelerations' scale
 *     (μ = cond[1], sg_rates_scale_inl).
 * Hence E_v = amp (eps + ej) for q' and E_a = amp ((2 E_v + eps) μ + ej) for q''; the estimate is the larger. At a
 * dead centre (q' growing as amp, q'' as amp³: μ about 1 / amp) both are about amp ej; at a change point (two
 * branches meeting, q' and q'' finite: μ about 1) E_a is about amp² ej, and ej there is itself about amp eps: the
 * accelerations lose amp³ eps (the closed form's square root of a cancelled difference, then two solves near
 * singular). A closed form's dyads give ej and amp themselves (sg_dyad_*: amp the product of their triangles'
 * amplifications, 1 / sin of the angle at the joint). For Newton's position (sg_newton_error) amp is κ = cond[0],
 * the equilibrated Φ_q's condition number, and ej = (κ + λ) resid: a position whose loops close to resid of their
 * sizes solves loops changed by that much, so its scaled coordinates are off by up to κ resid, and a coordinate on
 * a lever ℓ short against its loop's size L turns by its loop's residual over ℓ / L however well the loops are
 * conditioned: λ = cond[2], the largest L / ℓ of an angle coordinate (its column's 1 / m_j; an oscillating guide's
 * pin near its pivot: L / s). A residual below SG_ROUND_RESID is rounding and counts as that much: a position
 * exact to rounding (Newton's at its fixed point, a closed form's) is off by about 15 eps / sin γ near a toggle
 * (the dyads' bound, measured against mpmath); a larger one is polished first where the estimate is above the
 * tolerance (csrc/sg_runtime.c finish_position). First-order estimates: of the order of the error, not below it
 * (tools/fuzz.py checks them against an mpmath reference). */
#define SG_ROUND_RESID (16.0 * SG_EPS)
SG_INLINE double sg_rates_error(double amp, double mu, double ej)
{
    const double ev = amp * (SG_EPS + ej);
    const double ea = amp * ((2.0 * ev + SG_EPS) * mu + ej);
    return ev > ea ? ev : ea;
}

/* sg_rates_error of a position Newton solved: resid its last relative residual, cond the rates kernel's. */
SG_INLINE double sg_newton_error(const double *cond, double resid)
{
    const double rho = resid > SG_ROUND_RESID ? resid : SG_ROUND_RESID;
    return sg_rates_error(cond[0], cond[1], (cond[0] + cond[2]) * rho);
}

/* cond[1] and cond[2] of a motion or rates kernel (sg_rates_error's μ, sg_newton_error's λ) from its solved rates:
 * cs the factor's 2 n column values (sg_factor_eq_inl: 1/m_j, then m_j), angles bit j set where coordinate j is
 * an angle, turn the largest |rate| of an angle input. y' = q' m and y'' = q'' m are the scaled rates, λ the
 * largest 1/m_j of an angle coordinate (at least 1). γ's terms, each a column of Φ_q times a rate squared or two
 * rates (centripetal, Coriolis), are at most S = 2 n Ω ||y'|| (Ω the fastest angle's rate, inputs' too); their
 * sensitivity to an error of q' relative to ||y'|| is at most 2 n (Ω + λ Y_t) ||y'||, Y_t the largest scaled rate
 * of a travel (a Coriolis term 2 s' θ' moves by 2 s' δθ', and δθ' may be ||y'|| / m_θ: an oscillating guide's pin
 * running radially past its pivot). μ is that sensitivity over the accelerations' scale max(||y''||, S): 1 where
 * the accelerations are no larger than their terms and no travel runs on a short lever (a change point, where
 * they cancel), about 1 / κ at a dead centre (where they grow as κ³ and their terms as κ²), λ Y_t / Ω past a
 * guide's pivot. A NaN propagates. */
SG_INLINE void sg_rates_scale_inl(int n, unsigned long long angles, double turn, const double *cs, const double *qd,
                                  const double *qdd, double *cond)
{
    double y1 = 0.0, y2 = 0.0, yt = 0.0, om = turn, lam = 1.0;
    SG_UNROLL
    for (int j = 0; j < n; ++j) {
        const double w = fabs(qd[j]), v = w * cs[n + j], a = fabs(qdd[j]) * cs[n + j];
        if (!(v <= y1)) y1 = v;
        if (!(a <= y2)) y2 = a;
        if (angles >> j & 1) {
            if (w > om) om = w;
            if (cs[j] > lam) lam = cs[j];
        } else if (v > yt) {
            yt = v;
        }
    }
    const double terms = (2.0 * n) * om * y1, scale = terms > y2 ? terms : y2;
    cond[1] = scale > 0.0 ? (2.0 * n) * (om + lam * yt) * y1 / scale : 1.0;
    cond[2] = lam;
}

/* A parameter sum under a square root (a triangle's height from its sides): a negative within 1e-12 of the sum
 * of its terms' magnitudes is rounding of a zero (a collinear triangle) and becomes 0; a real negative stays. */
static inline double sg_rounding_clamp(double value, double scale)
{
    return value < 0.0 && value >= -1e-12 * scale ? 0.0 : value;
}

/* Determinant of an n x n matrix (destroyed), 0 where the LU finds it singular. */
SG_INLINE double sg_det_inl(int n, double *a, int *piv)
{
    double sign = 1.0;
    if (sg_lu_factor_inl(n, a, piv, &sign) != SG_OK) return 0.0;
    double d = 1.0;
    for (int k = 0; k < n; ++k) d *= fabs(a[k * n + k]);
    return sign * d;
}

/* Closed-form dyads (seed 001 §三, Makino's vector triangles; BV4 is the RRR dyad). ------------------
 * A triangle that closes only within the rounding of its sides (a toggle or change point hit exactly) is taken
 * as closed, flat: SG_TOUCH is that rounding, relative to the squares summed. The position is then singular
 * and its error bound (below) infinite.
 *
 * Each dyad also bounds the error of what it solves (first order) for the rates' error estimate (sg_rates_error):
 * ein is its input points' error (m: the earlier dyads' errors carried by the lengths that place them, and their
 * rounding; the generated closed kernel computes it), e[0] the largest error of an angle coordinate so far (rad),
 * e[1] of a travel (m), both raised to this dyad's, and e[2] the product of the dyads' amplifications (how much a
 * relative error of the rates' right side grows in this dyad's solve, an upstream one's too). A triangle moves its
 * inputs' errors by 1 / sin of its angle at the joint (the amplification), and its square root of a cancelled
 * difference (the height squared, the discriminant) turns that difference's rounding, SG_DYAD_ROUND roundings of
 * its terms, into an error over twice the root: the loss near a toggle or change point, which no Jacobian's
 * condition number sees (the closed form's position is taken as it is). An oscillating guide's angle is its
 * pin's error over the pin's distance from the pivot. One division and one square root a dyad. */
#define SG_TOUCH 1e-14
#define SG_DYAD_ROUND 4.0

/* RRR: J is at distance l1 from P and l2 from Q; sigma = +1 puts J left of the ray P->Q. The error: J moves by
 * 2 ein / sin γ (γ the angle at J, 1 / sin γ = l1 l2 / (h d^2), h = sqrt(h2) in units of d) and by h's rounding,
 * δ(h^2) d / (2 h), δ(h^2) = SG_DYAD_ROUND eps S (1 + |a|), S = (l1^2 + l2^2 + d^2) / d^2 = 2 (u1 + 1 - a) with
 * u1 = l1^2 / d^2; the links' angles by that and their pins' ein over the shorter link. */
static inline int sg_dyad_rrr(const double P[2], const double Q[2], double l1, double l2, int sigma, double ein,
                              double e[3], double J[2])
{
    const double dx = Q[0] - P[0], dy = Q[1] - P[1];
    const double d2 = dx * dx + dy * dy;
    if (!(d2 > 1e-30)) return SG_SINGULAR;
    const double a = 0.5 * (l1 * l1 - l2 * l2 + d2) / d2; /* along PQ, in units of d */
    const double u1 = l1 * l1 / d2;
    double h2 = u1 - a * a; /* across PQ, squared, in units of d^2 */
    if (h2 < 0.0 && h2 >= -SG_TOUCH * (l1 * l1 + l2 * l2 + d2) / d2) h2 = 0.0; /* touching within rounding */
    if (!(h2 >= 0.0)) return SG_CANNOT_ASSEMBLE;
    const double r = sqrt(h2), h = sigma * r;
    J[0] = P[0] + a * dx - h * dy;
    J[1] = P[1] + a * dy + h * dx;
    const double lm = l1 < l2 ? l1 : l2, inv = 1.0 / (r * d2 * lm), amp = l1 * l2 * lm * inv;
    const double own = (0.5 * SG_DYAD_ROUND * SG_EPS) * (2.0 * (u1 + 1.0 - a)) * (1.0 + fabs(a)) * sqrt(d2);
    const double ea = (2.0 * ein * l1 * l2 + (own + ein * r) * d2) * inv;
    if (!(ea <= e[0])) e[0] = ea;
    e[2] *= amp;
    return SG_OK;
}

/* RRP: J = L0 + s*u (u a unit vector) at distance l1 from P; sigma = +1 takes the larger s. The error: s moves by
 * (J - P).(δw + s δu) / ((J - P).u) with (J - P).u = ±sqrt(disc) (the amplification l1 / sqrt(disc)), δw <= 2 ein,
 * δu the guide's angle error, and by the discriminant's rounding over 2 sqrt(disc); the link's angle by that and
 * the same over l1. */
static inline int sg_dyad_rrp(const double P[2], double l1, const double L0[2], const double u[2], int sigma,
                              double ein, double e[3], double *s, double J[2])
{
    const double wx = L0[0] - P[0], wy = L0[1] - P[1];
    const double b = u[0] * wx + u[1] * wy;
    double disc = b * b - (wx * wx + wy * wy - l1 * l1);
    if (disc < 0.0 && disc >= -SG_TOUCH * (b * b + wx * wx + wy * wy + l1 * l1)) disc = 0.0;
    if (!(disc >= 0.0)) return SG_CANNOT_ASSEMBLE;
    const double r = sqrt(disc);
    *s = -b + sigma * r;
    J[0] = L0[0] + *s * u[0];
    J[1] = L0[1] + *s * u[1];
    const double x = 2.0 * ein + fabs(*s) * e[0];
    const double num = l1 * x + (0.5 * SG_DYAD_ROUND * SG_EPS) * (b * b + wx * wx + wy * wy + l1 * l1);
    const double inv = 1.0 / (r * l1), es = num * l1 * inv, ea = (x * r + num) * inv;
    if (!(es <= e[1])) e[1] = es;
    if (!(ea <= e[0])) e[0] = ea;
    e[2] *= l1 * l1 * inv;
    return SG_OK;
}

/* RPR (oscillating guide bar): in the bar's frame the pin runs on w0 + s*u (u unit); it must lie at
 * distance |D| from the pivot, D = pin - pivot in the world. Returns s (sigma = +1: larger s) and the
 * bar angle theta with R(theta) (w0 + s u) = D. The error: s moves by the discriminant's, 2 |D| ein and its
 * rounding, over 2 sqrt(disc) (the amplification |D| / sqrt(disc): 1 where the pin runs through the pivot);
 * theta by the pin's error and that over |D| (the bar's angle is only as good as its pin's position over the
 * pin's distance from the pivot). */
static inline int sg_dyad_rpr(const double D[2], const double w0[2], const double u[2], int sigma, double ein,
                              double e[3], double *s, double *theta)
{
    const double d2 = D[0] * D[0] + D[1] * D[1];
    if (!(d2 > 1e-30)) return SG_SINGULAR;
    const double b = u[0] * w0[0] + u[1] * w0[1];
    double disc = b * b - (w0[0] * w0[0] + w0[1] * w0[1] - d2);
    if (disc < 0.0 && disc >= -SG_TOUCH * (b * b + w0[0] * w0[0] + w0[1] * w0[1] + d2)) disc = 0.0;
    if (!(disc >= 0.0)) return SG_CANNOT_ASSEMBLE;
    const double r = sqrt(disc);
    *s = -b + sigma * r;
    const double wx = w0[0] + *s * u[0], wy = w0[1] + *s * u[1];
    *theta = atan2(D[1], D[0]) - atan2(wy, wx);
    const double dd = sqrt(d2);
    const double num = dd * ein + (0.5 * SG_DYAD_ROUND * SG_EPS) * (b * b + w0[0] * w0[0] + w0[1] * w0[1] + d2);
    const double inv = 1.0 / (r * dd), es = num * dd * inv, ea = (ein * r + num) * inv;
    if (!(es <= e[1])) e[1] = es;
    if (!(ea <= e[0])) e[0] = ea;
    e[2] *= d2 * inv;
    return SG_OK;
}

/* cos and sin of one angle in one libm call where the compiler offers it (glibc's sincos). */
static inline void sg_sincos_inl(double a, double *c, double *s)
{
#if defined(__GNUC__)
    __builtin_sincos(a, s, c);
#else
    *c = cos(a);
    *s = sin(a);
#endif
}

/* The closed-form sweep, written once for every caller: a generated file with a closed form instantiates it with
 * its own kernels (sg_<m>_sweep calls sg_closed_sweep with its constants, closed, motion, rates, observe and forces
 * kernels: constant arguments of an always-inline function, so that the file's flatten attribute inlines them, no
 * call through a pointer per position), and the runtime's sweep calls it with the descriptor's kernels where
 * opt->generic asks for the calls through the descriptor (tests: the same code, so the same values to the bit).
 * K: the kernels (sg_closed_kernels). Per position: closed form, unwrap against the last solution, motion, the
 * rates' error estimate (sg_rates_error, with the position's error its dyads bound; never polished), singular
 * check, forces (r->frc), status. r->want (not NULL: a kinematic sweep that keeps a few outputs) flags the groups
 * of observables to compute: the rates kernel and the wanted groups' observe kernel then stand for the motion
 * kernel. The SIMD loop (csrc/sg_simd.h) shares the state (sg_closed_loop, set up by sg_closed_setup), the step of
 * one position (sg_closed_step) and the finish of a solved one (sg_closed_finish). */
typedef struct sg_closed_loop {
    const sg_mechanism *m;
    const sg_options *opt;
    const double *phi, *omega, *alpha, *gv, *loads;
    const int *branch;
    double *q, *qd, *qdd, *obs, *err, *frc;
    int *status;
    const unsigned char *want; /* NULL: every observable */
    int nq, nx, nobs, nfo, nload;
    int have_last;             /* last holds the last solved coordinates */
    size_t failures;
    double c[SG_MAX_C];
    double x[SG_MAX_Q], cx[2 * SG_MAX_Q], xd[SG_MAX_Q], xdd[SG_MAX_Q], last[SG_MAX_Q];
    double no_loads[SG_MAX_LOAD]; /* zero loads for a force sweep without any (zeroed only then) */
} sg_closed_loop;

/* The scalar kernels a closed-form loop calls: a generated file's own (constant arguments of the always-inline loop,
 * inlined by its flatten attribute) or the descriptor's (sg_descriptor_kernels: calls through pointers). */
typedef struct sg_closed_kernels {
    sg_constants_fn constants;
    sg_closed_fn closed;
    sg_motion_fn motion;
    sg_rates_fn rates;
    sg_observe_fn observe;
    sg_forces_fn forces;
} sg_closed_kernels;

SG_INLINE sg_closed_kernels sg_descriptor_kernels(const sg_mechanism *m)
{
    const sg_closed_kernels k = {m->constants, m->closed, m->motion, m->rates, m->observe, m->forces};
    return k;
}

/* The loop's state for the request r: the constants (kernel constants), the held inputs with their cos, sin, the
 * wanted groups (none where forces read every observable or a constant is not finite: then every one). */
SG_INLINE void sg_closed_setup(sg_closed_loop *L, const sg_mechanism *m, const sg_request *r,
                               sg_constants_fn constants)
{
    L->m = m, L->opt = r->opt, L->phi = r->phi, L->omega = r->omega, L->alpha = r->alpha, L->gv = r->gv;
    L->loads = r->loads, L->branch = r->branch, L->q = r->q, L->qd = r->qd, L->qdd = r->qdd, L->obs = r->obs;
    L->err = r->err, L->frc = r->frc, L->status = r->status, L->want = r->want;
    L->nq = m->nq, L->nx = m->nx, L->nobs = m->nobs, L->nfo = m->nfo, L->nload = m->nload;
    L->have_last = 0, L->failures = 0;
    constants(r->p, L->c);
    for (int k = 1; k < L->nx; ++k) {
        L->x[k] = r->held[k - 1];
        L->cx[2 * k] = cos(L->x[k]);
        L->cx[2 * k + 1] = sin(L->x[k]);
        L->xd[k] = 0.0;
        L->xdd[k] = 0.0;
    }
    L->x[0] = NAN; /* no angle's cos, sin yet (set at the first position) */
    L->cx[0] = 1.0;
    L->cx[1] = 0.0;
    if (L->frc != NULL && L->loads == NULL)
        for (int k = 0; k < L->nload; ++k) L->no_loads[k] = 0.0;
    if (L->frc != NULL) L->want = NULL; /* forces read every observable */
    for (int k = 0; k < m->nc && L->want != NULL; ++k)
        if (!isfinite(L->c[k])) L->want = NULL; /* an observable of a constant alone may be all that fails */
    if (L->want != NULL && (m->ngroup < 1 || m->ngroup > SG_MAX_GROUP)) L->want = NULL;
}

/* Position i's status st and error estimate est recorded; a failed position's rows zeroed. */
SG_INLINE void sg_closed_settle(sg_closed_loop *L, size_t i, int st, double est)
{
    const int nq = L->nq, nobs = L->nobs, nfo = L->nfo;
    L->status[i] = st;
    if (L->err) L->err[i] = st == SG_OK || st == SG_SINGULAR ? est : 0.0;
    if (st == SG_OK) return;
    ++L->failures;
    double *qi = L->q + i * (size_t)nq, *qdi = L->qd + i * (size_t)nq, *qddi = L->qdd + i * (size_t)nq;
    double *oi = L->obs + i * (size_t)nobs;
    for (int j = 0; j < nq; ++j) qi[j] = qdi[j] = qddi[j] = 0.0;
    for (int j = 0; j < nobs; ++j) oi[j] = 0.0;
    if (L->frc != NULL)
        for (int j = 0; j < nfo; ++j) L->frc[i * (size_t)nfo + j] = 0.0;
}

/* Position i from its solved coordinates (its row of q; cq their cos, sin): motion (or the rates and the wanted
 * groups: the same values to the bit), the rates' error estimate and the singular check, forces, then
 * sg_closed_settle. The inputs x, cx, xd, xdd are L's, set for position i; err the closed kernel's (its position's
 * error and the dyads' amplification). */
SG_INLINE void sg_closed_finish(sg_closed_loop *L, size_t i, const double *cq, const double *err,
                                 const sg_closed_kernels K)
{
    const int nq = L->nq, nobs = L->nobs;
    const double *qi = L->q + i * (size_t)nq;
    double *qdi = L->qd + i * (size_t)nq, *qddi = L->qdd + i * (size_t)nq, *oi = L->obs + i * (size_t)nobs;
    double cond[SG_NCOND] = {1.0, 1.0, 1.0}, est = 0.0;
    int st;
    if (L->want == NULL) {
        st = K.motion(qi, cq, L->x, L->cx, L->xd, L->xdd, L->c, qdi, qddi, oi, cond);
    } else {
        st = K.rates(qi, cq, L->x, L->cx, L->xd, L->xdd, L->c, qdi, qddi, cond);
        for (int g = 0; g < L->m->ngroup && st == SG_OK; ++g)
            if (L->want[g]) st = K.observe(qi, cq, L->x, L->cx, L->xd, L->xdd, L->c, qdi, qddi, g, oi);
    }
    if (st == SG_SINGULAR) {
        est = INFINITY;
    } else if (st == SG_OK) {
        est = sg_rates_error(err[1], cond[1], err[0]);
        if (!(est <= L->opt->singular_tol) && !L->opt->keep_singular) st = SG_SINGULAR;
    }
    if (st == SG_OK && L->frc != NULL)
        st = K.forces(qi, cq, L->x, L->cx, L->xd, L->c, oi, L->gv,
                      L->loads ? L->loads + i * (size_t)L->nload : L->no_loads, L->frc + i * (size_t)L->nfo);
    sg_closed_settle(L, i, st, est);
}

/* Position i solved in closed form and finished: its inputs set (cos, sin of the shaft angle only where it
 * changed), the dyad chain, each angle coordinate unwrapped against the last solution, then sg_closed_finish (a
 * position that does not assemble: sg_closed_settle with its status). */
SG_INLINE void sg_closed_step(sg_closed_loop *L, size_t i, const sg_closed_kernels K)
{
    const int nq = L->nq;
    double *qi = L->q + i * (size_t)nq;
    double cq[2 * SG_MAX_Q];
    const double ph = L->phi[i];
    L->xd[0] = L->omega[i];
    L->xdd[0] = L->alpha[i];
    if (L->x[0] != ph) {
        L->x[0] = ph;
        sg_sincos_inl(ph, &L->cx[0], &L->cx[1]);
    }
    if (!isfinite(ph + L->omega[i] + L->alpha[i])) {
        sg_closed_settle(L, i, SG_NAN_INPUT, 0.0);
        return;
    }
    double err[2];
    const int st = K.closed(L->x, L->cx, L->c, L->branch, qi, cq, err);
    if (st != SG_OK) {
        sg_closed_settle(L, i, st, 0.0);
        return;
    }
    if (L->have_last)
        for (int j = 0; j < nq; ++j)
            if (L->m->coord_is_angle[j]) {
                const double turns = (L->last[j] - qi[j]) * (1.0 / SG_TWO_PI);
                if (fabs(turns) > 0.5) qi[j] += SG_TWO_PI * nearbyint(turns);
            }
    for (int j = 0; j < nq; ++j) L->last[j] = qi[j];
    L->have_last = 1;
    sg_closed_finish(L, i, cq, err, K);
}

/* The closed-form sweep of the request r with the kernels given (r->trig and r->cols are the SIMD loop's: this
 * loop computes its own cos, sin and writes rows only). Returns the positions that failed. */
SG_INLINE size_t sg_closed_sweep(const sg_mechanism *m, const sg_request *r, const sg_closed_kernels K)
{
    sg_closed_loop L;
    sg_closed_setup(&L, m, r, K.constants);
    const size_t n = r->n, *order = r->order;
    for (size_t k = 0; k < n; ++k) sg_closed_step(&L, order ? order[k] : k, K);
    return L.failures;
}

/* The SIMD variant of the loop and its vector helpers (where the build has them). */
#include "sg_simd.h"

#endif
