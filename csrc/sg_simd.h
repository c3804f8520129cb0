/* sewgen C runtime, SIMD part: SG_LANES shaft positions at once, 8 in AVX-512 registers or 4 in
 * AVX2 ones.
 *
 * Built where the compiler is GCC-compatible on x86-64 and the C library has glibc's vector math library
 * (libmvec: SG_HAVE_MVEC, set by sewgen/build.py, with SG_SIMD_LEVEL 512 for AVX-512 F, VL and DQ or 256 for
 * AVX2: the catalog is built once for each, a user's mechanism for the CPU it runs on); everything here is
 * compiled for that level (a pragma, SG_SIMD_BEGIN, not a module flag), so the module still loads on any x86-64,
 * and csrc/sg_runtime.c calls the SIMD loop only where the CPU has the level (sg_simd_width). Eight lanes on an
 * AVX-512 CPU rather than four: half the instructions a position (the loop was issue-bound), 32 vector registers
 * (fewer spills) and one libmvec call for eight angles.
 * No -ffast-math: GCC vector extensions with the ISO C default of no FMA contraction, NaN tests kept.
 *
 * A generated file with a closed form passes sgv_closed_sweep the vector twins of its closed, motion
 * and forces kernels (sewgen/derive/kernels.py), which compute every lane whatever happens and return a lane
 * mask of what they vouch for. The loop takes a block's vector results only where they are clearly good: the
 * inputs finite, every dyad closing with a margin (SG_SIMD_MARGIN: the scalar loop decides triangles that only
 * just close or fail), the rates' estimated error at most a quarter of opt->singular_tol, every force block
 * above its pivot tolerance and every output finite. Anything else goes through the scalar step of
 * csrc/sg_runtime.h, so statuses, first failing angles and the singular decision are always the scalar loop's;
 * the values of vector lanes agree with the scalar loop's to rounding (libmvec's sin, cos, atan2 are within
 * 4 ulp), and a given input gives the same result on a given machine every time.
 */
#ifndef SG_SIMD_H
#define SG_SIMD_H

#if defined(SG_HAVE_MVEC) && defined(__GNUC__) && defined(__x86_64__)
#define SG_SIMD 1
#else
#define SG_SIMD 0
#endif

/* The descriptor's sweep_simd and finish_simd: the function where SIMD is built, NULL elsewhere. */
#if SG_SIMD
#define SG_SIMD_HOOK(fn) fn
#else
#define SG_SIMD_HOOK(fn) 0
#endif

#if SG_SIMD
/* The instruction set of the SIMD code (SG_SIMD_LEVEL, set by sewgen/build.py: AVX-512 or AVX2), switched on for
 * it alone by SG_SIMD_BEGIN ... SG_SIMD_END (here and around a generated file's vector twins). */
#define SG_PRAGMA(x) _Pragma(#x)
#if SG_LANES == 8
#define SG_SIMD_BEGIN SG_PRAGMA(GCC push_options) SG_PRAGMA(GCC target("avx2,fma,avx512f,avx512vl,avx512dq"))
#else
#define SG_SIMD_BEGIN SG_PRAGMA(GCC push_options) SG_PRAGMA(GCC target("avx2,fma"))
#endif
#define SG_SIMD_END SG_PRAGMA(GCC pop_options)

SG_SIMD_BEGIN
#include <immintrin.h>
#include <string.h>

/* Lanes per vector (SG_LANES, csrc/sg_runtime.h): 8 in an AVX-512 register, else 4 in an AVX2 one. The vector of
 * doubles, a lane mask (all bits set: true), and the same vector as AVX2 registers of four lanes (SG_H of them:
 * the transposes between rows and lanes work on those). */
#define SG_W SG_LANES
#define SG_H (SG_W / 4)
typedef double sg_vd __attribute__((vector_size(8 * SG_W)));
typedef long long sg_vm __attribute__((vector_size(8 * SG_W)));
typedef union {
    sg_vd v;
    __m256d h[SG_H];
} sg_vhalves;
#if SG_W == 8
#define SG_SPLAT(a) a, a, a, a, a, a, a, a
#define SG_SHIFT_IN_MASK {8, 0, 1, 2, 3, 4, 5, 6}
#else
#define SG_SPLAT(a) a, a, a, a
#define SG_SHIFT_IN_MASK {4, 0, 1, 2}
#endif

/* A triangle whose height squared is below this fraction of its sides' squares goes to the scalar loop. */
#define SG_SIMD_MARGIN 1e-10

#define SG_VINLINE static inline __attribute__((always_inline))

/* glibc's vector math (libmvec: x86_64 ABI "e", AVX-512, 8 doubles; "d", AVX2, 4 doubles), the square root and
 * the lanes of a mask as bits (lane l in bit l), at the module's level. */
#if SG_W == 8
__m512d _ZGVeN8v_sin(__m512d x);
__m512d _ZGVeN8v_cos(__m512d x);
__m512d _ZGVeN8vv_atan2(__m512d y, __m512d x);
SG_VINLINE sg_vd sgv_atan2(sg_vd y, sg_vd x) { return (sg_vd)_ZGVeN8vv_atan2((__m512d)y, (__m512d)x); }
SG_VINLINE void sgv_sincos(sg_vd a, sg_vd *c, sg_vd *s)
{
    *c = (sg_vd)_ZGVeN8v_cos((__m512d)a);
    *s = (sg_vd)_ZGVeN8v_sin((__m512d)a);
}
SG_VINLINE sg_vd sgv_sqrt(sg_vd a) { return (sg_vd)_mm512_sqrt_pd((__m512d)a); }
SG_VINLINE int sgv_bits(sg_vm m) { return (int)_mm512_movepi64_mask((__m512i)m); }
#else
__m256d _ZGVdN4v_sin(__m256d x);
__m256d _ZGVdN4v_cos(__m256d x);
__m256d _ZGVdN4vv_atan2(__m256d y, __m256d x);
SG_VINLINE sg_vd sgv_atan2(sg_vd y, sg_vd x) { return (sg_vd)_ZGVdN4vv_atan2((__m256d)y, (__m256d)x); }
SG_VINLINE void sgv_sincos(sg_vd a, sg_vd *c, sg_vd *s)
{
    *c = (sg_vd)_ZGVdN4v_cos((__m256d)a);
    *s = (sg_vd)_ZGVdN4v_sin((__m256d)a);
}
SG_VINLINE sg_vd sgv_sqrt(sg_vd a) { return (sg_vd)_mm256_sqrt_pd((__m256d)a); }
SG_VINLINE int sgv_bits(sg_vm m) { return _mm256_movemask_pd((__m256d)m); }
#endif
/* AVX2 register h (four lanes) of a vector, read and written (the row transposes) */
SG_VINLINE __m256d sgv_half(const sg_vd *v, int h) { return ((const sg_vhalves *)v)->h[h]; }
SG_VINLINE void sgv_set_half(sg_vd *v, int h, __m256d x) { ((sg_vhalves *)v)->h[h] = x; }

SG_VINLINE sg_vd sgv_set1(double a) { return (sg_vd){SG_SPLAT(a)}; }
SG_VINLINE sg_vm sgv_iset1(long long a) { return (sg_vm){SG_SPLAT(a)}; }
SG_VINLINE sg_vm sgv_true(void) { return sgv_iset1(-1); }
SG_VINLINE sg_vm sgv_false(void) { return sgv_iset1(0); }
SG_VINLINE sg_vd sgv_select(sg_vm m, sg_vd a, sg_vd b) { return (sg_vd)(((sg_vm)a & m) | ((sg_vm)b & ~m)); }
SG_VINLINE int sgv_all(sg_vm m) { return sgv_bits(m) == (1 << SG_W) - 1; }
SG_VINLINE int sgv_none(sg_vm m) { return sgv_bits(m) == 0; }
/* {first, v[0], ..., v[SG_W - 2]}: each lane's predecessor, first before lane 0 */
SG_VINLINE sg_vd sgv_shift_in(double first, sg_vd v)
{
    return __builtin_shuffle(v, sgv_set1(first), (sg_vm)SG_SHIFT_IN_MASK);
}
/* SG_W doubles from p (unaligned), and to p */
SG_VINLINE sg_vd sgv_loadu(const double *p)
{
    sg_vd v;
    memcpy(&v, p, sizeof v);
    return v;
}
SG_VINLINE void sgv_storeu(double *p, sg_vd v) { memcpy(p, &v, sizeof v); }
SG_VINLINE sg_vm sgv_isfinite(sg_vd a) { return (a - a) == sgv_set1(0.0); } /* inf - inf, NaN: NaN */
SG_VINLINE sg_vd sgv_fabs(sg_vd a) { return (sg_vd)((sg_vm)a & sgv_iset1(0x7fffffffffffffffLL)); }
SG_VINLINE sg_vd sgv_fmax(sg_vd a, sg_vd b) { return sgv_select(a > b, a, b); }

/* The forces twin of a mechanism whose forces have no vector form: never called (its sg_<m>_forces_in_simd says
 * no, and a force sweep then runs scalar), there to fill the sgv_kernels of a file without them. */
SG_VINLINE sg_vm sgv_no_forces(const sg_vd *q, const sg_vd *cq, const sg_vd *x, const sg_vd *cx, const sg_vd *xd,
                               const double *c, const sg_vd *obs, const double *gv, const sg_vd *ld, sg_vd *out)
{
    (void)q, (void)cq, (void)x, (void)cx, (void)xd, (void)c, (void)obs, (void)gv, (void)ld, (void)out;
    return sgv_false();
}

/* The closed-form dyads of csrc/sg_runtime.h, lane by lane, with the same operations (their error bounds too);
 * the mask says which lanes close by more than SG_SIMD_MARGIN (the others carry a flat triangle's values, never
 * read). */
SG_VINLINE sg_vm sgv_dyad_rrr(const sg_vd P[2], const sg_vd Q[2], sg_vd l1, sg_vd l2, int sigma, sg_vd ein,
                              sg_vd e[3], sg_vd J[2])
{
    const sg_vd dx = Q[0] - P[0], dy = Q[1] - P[1];
    const sg_vd d2 = dx * dx + dy * dy;
    const sg_vd a = 0.5 * (l1 * l1 - l2 * l2 + d2) / d2;
    const sg_vd u1 = l1 * l1 / d2;
    const sg_vd h2 = u1 - a * a;
    const sg_vm ok = (d2 > sgv_set1(1e-30)) & (h2 > SG_SIMD_MARGIN * (l1 * l1 + l2 * l2 + d2) / d2);
    const sg_vd r = sgv_sqrt(sgv_select(ok, h2, sgv_set1(0.0))), h = (double)sigma * r;
    J[0] = P[0] + a * dx - h * dy;
    J[1] = P[1] + a * dy + h * dx;
    const sg_vd lm = sgv_select(l1 < l2, l1, l2), inv = 1.0 / (r * d2 * lm), amp = l1 * l2 * lm * inv;
    const sg_vd own = (0.5 * SG_DYAD_ROUND * SG_EPS) * (2.0 * (u1 + 1.0 - a)) * (1.0 + sgv_fabs(a)) * sgv_sqrt(d2);
    const sg_vd ea = (2.0 * ein * l1 * l2 + (own + ein * r) * d2) * inv;
    e[0] = sgv_select(~(ea <= e[0]), ea, e[0]);
    e[2] *= amp;
    return ok;
}

SG_VINLINE sg_vm sgv_dyad_rrp(const sg_vd P[2], sg_vd l1, const sg_vd L0[2], const sg_vd u[2], int sigma, sg_vd ein,
                              sg_vd e[3], sg_vd *s, sg_vd J[2])
{
    const sg_vd wx = L0[0] - P[0], wy = L0[1] - P[1];
    const sg_vd b = u[0] * wx + u[1] * wy;
    const sg_vd disc = b * b - (wx * wx + wy * wy - l1 * l1);
    const sg_vm ok = disc > SG_SIMD_MARGIN * (b * b + wx * wx + wy * wy + l1 * l1);
    const sg_vd r = sgv_sqrt(sgv_select(ok, disc, sgv_set1(0.0)));
    *s = -b + (double)sigma * r;
    J[0] = L0[0] + *s * u[0];
    J[1] = L0[1] + *s * u[1];
    const sg_vd x = 2.0 * ein + sgv_fabs(*s) * e[0];
    const sg_vd num = l1 * x + (0.5 * SG_DYAD_ROUND * SG_EPS) * (b * b + wx * wx + wy * wy + l1 * l1);
    const sg_vd inv = 1.0 / (r * l1), es = num * l1 * inv, ea = (x * r + num) * inv;
    e[1] = sgv_select(~(es <= e[1]), es, e[1]);
    e[0] = sgv_select(~(ea <= e[0]), ea, e[0]);
    e[2] *= l1 * l1 * inv;
    return ok;
}

SG_VINLINE sg_vm sgv_dyad_rpr(const sg_vd D[2], const sg_vd w0[2], const sg_vd u[2], int sigma, sg_vd ein,
                              sg_vd e[3], sg_vd *s, sg_vd *theta)
{
    const sg_vd d2 = D[0] * D[0] + D[1] * D[1];
    const sg_vd b = u[0] * w0[0] + u[1] * w0[1];
    const sg_vd disc = b * b - (w0[0] * w0[0] + w0[1] * w0[1] - d2);
    const sg_vm ok = (d2 > sgv_set1(1e-30)) & (disc > SG_SIMD_MARGIN * (b * b + w0[0] * w0[0] + w0[1] * w0[1] + d2));
    const sg_vd r = sgv_sqrt(sgv_select(ok, disc, sgv_set1(0.0)));
    *s = -b + (double)sigma * r;
    const sg_vd wx = w0[0] + *s * u[0], wy = w0[1] + *s * u[1];
    *theta = sgv_atan2(D[1], D[0]) - sgv_atan2(wy, wx);
    const sg_vd dd = sgv_sqrt(d2);
    const sg_vd num = dd * ein + (0.5 * SG_DYAD_ROUND * SG_EPS) * (b * b + w0[0] * w0[0] + w0[1] * w0[1] + d2);
    const sg_vd inv = 1.0 / (r * dd), es = num * dd * inv, ea = (ein * r + num) * inv;
    e[1] = sgv_select(~(es <= e[1]), es, e[1]);
    e[0] = sgv_select(~(ea <= e[0]), ea, e[0]);
    e[2] *= d2 * inv;
    return ok;
}

/* LU with partial pivoting of an n x n matrix of lanes, in place, each lane with its own pivot rows (found by
 * compares, swapped by selects; the multipliers of a zero entry are subtracted too, which changes nothing
 * finite): the pivot rows in piv, each pivot's magnitude in best; U's diagonal kept, or its reciprocal where
 * reciprocal (sg_factor_eq_inl's form). The elimination of sg_lu_factor_inl and sg_factor_eq_inl. */
SG_VINLINE void sgv_eliminate(int n, sg_vd *a, sg_vm *piv, sg_vd *best, int reciprocal)
{
    for (int k = 0; k < n; ++k) {
        sg_vm pr = sgv_iset1(k);
        sg_vd bk = sgv_fabs(a[k * n + k]);
        for (int i = k + 1; i < n; ++i) {
            const sg_vd v = sgv_fabs(a[i * n + k]);
            const sg_vm gt = v > bk;
            bk = sgv_select(gt, v, bk);
            pr = (pr & ~gt) | (sgv_iset1(i) & gt);
        }
        piv[k] = pr;
        best[k] = bk;
        for (int i = k + 1; i < n; ++i) {
            const sg_vm sw = pr == sgv_iset1(i);
            for (int j = 0; j < n; ++j) {
                const sg_vd t = a[k * n + j];
                a[k * n + j] = sgv_select(sw, a[i * n + j], t);
                a[i * n + j] = sgv_select(sw, t, a[i * n + j]);
            }
        }
        const sg_vd inv = 1.0 / a[k * n + k];
        if (reciprocal) a[k * n + k] = inv;
        for (int i = k + 1; i < n; ++i) {
            const sg_vd f = a[i * n + k] * inv;
            a[i * n + k] = f;
            for (int j = k + 1; j < n; ++j) a[i * n + j] -= f * a[k * n + j];
        }
    }
}

/* Solve with a factor of sgv_eliminate (b overwritten): each lane's interchanges, then the two substitutions. */
SG_VINLINE void sgv_substitute(int n, const sg_vd *lu, const sg_vm *piv, sg_vd *b, int reciprocal)
{
    for (int k = 0; k < n; ++k)
        for (int i = k + 1; i < n; ++i) {
            const sg_vm sw = piv[k] == sgv_iset1(i);
            const sg_vd t = b[k];
            b[k] = sgv_select(sw, b[i], t);
            b[i] = sgv_select(sw, t, b[i]);
        }
    for (int k = 0; k < n; ++k)
        for (int i = k + 1; i < n; ++i) b[i] -= lu[i * n + k] * b[k];
    for (int k = n - 1; k >= 0; --k) {
        sg_vd s = b[k];
        for (int j = k + 1; j < n; ++j) s -= lu[k * n + j] * b[j];
        b[k] = reciprocal ? s * lu[k * n + k] : s / lu[k * n + k];
    }
}

/* sg_factor_eq2_inl lane by lane, operation for operation (the same values to the bit). */
SG_VINLINE sg_vm sgv_factor_eq2(sg_vd *a, const sg_vd *rs, sg_vd *cs, sg_vd *cond)
{
    const sg_vd b00 = a[0] * rs[0], b01 = a[1] * rs[0], b10 = a[2] * rs[1], b11 = a[3] * rs[1];
    const sg_vd f00 = sgv_fabs(b00), f01 = sgv_fabs(b01), f10 = sgv_fabs(b10), f11 = sgv_fabs(b11);
    const sg_vd m0 = sgv_fmax(f00, f10), m1 = sgv_fmax(f01, f11);
    const sg_vd det = b00 * b11 - b01 * b10, mm = m0 * m1;
    const sg_vd r = 1.0 / (mm * det), inv = r * mm, imm = r * det;
    const sg_vd n1a = f00 * m1 + f01 * m0, n1b = f10 * m1 + f11 * m0;
    const sg_vd n2a = m0 * (f11 + f01), n2b = m1 * (f10 + f00);
    *cond = sgv_fmax(n1a, n1b) * sgv_fmax(n2a, n2b) * sgv_fabs(r);
    cs[0] = m1 * imm;
    cs[1] = m0 * imm;
    cs[2] = m0;
    cs[3] = m1;
    a[0] = b11 * inv;
    a[1] = -b01 * inv;
    a[2] = -b10 * inv;
    a[3] = b00 * inv;
    return (sgv_fabs(det) > SG_PIVOT_RTOL * mm) & sgv_isfinite(*cond);
}

/* sg_lu_bound_inl lane by lane: the LU of an equilibrated matrix (U's diagonal as its reciprocal) and the bound
 * of ||A^-1||_inf; the mask is the lanes whose pivots are all above SG_PIVOT_RTOL. */
SG_VINLINE sg_vm sgv_lu_bound(int n, sg_vd *a, sg_vm *piv, sg_vd *inorm_out)
{
    const sg_vd zero = sgv_set1(0.0);
    sg_vm ok = sgv_true();
    sg_vd best[SG_MAX_Q], y[SG_MAX_Q];
    sgv_eliminate(n, a, piv, best, 1);
    for (int k = 0; k < n; ++k) ok &= best[k] > sgv_set1(SG_PIVOT_RTOL);
    sg_vd inorm = zero;
    for (int i = 0; i < n; ++i) {
        sg_vd s = sgv_set1(1.0);
        for (int j = 0; j < i; ++j) s += sgv_fabs(a[i * n + j]) * y[j];
        y[i] = s;
    }
    for (int i = n - 1; i >= 0; --i) {
        sg_vd s = y[i];
        for (int j = i + 1; j < n; ++j) s += sgv_fabs(a[i * n + j]) * y[j];
        y[i] = s * sgv_fabs(a[i * n + i]);
        inorm = sgv_select(~(y[i] <= inorm), y[i], inorm);
    }
    *inorm_out = inorm;
    return ok;
}

/* sg_lu_apply_inl lane by lane: b overwritten by A^-1 b with a factor of sgv_lu_bound. */
SG_VINLINE void sgv_lu_apply(int n, const sg_vd *lu, const sg_vm *piv, sg_vd *b) { sgv_substitute(n, lu, piv, b, 1); }

/* sg_factor_eq_inl lane by lane: the same scaling, pivoting and condition bound (n = 2: sgv_factor_eq2); the
 * mask is the lanes the scalar factor would accept. */
SG_VINLINE sg_vm sgv_factor_eq(int n, sg_vd *a, sg_vm *piv, const sg_vd *rs, sg_vd *cs, sg_vd *cond)
{
    if (n == 2) return sgv_factor_eq2(a, rs, cs, cond);
    const sg_vd zero = sgv_set1(0.0);
    sg_vm ok = sgv_true();
    for (int j = 0; j < n; ++j) {
        sg_vd m = zero;
        for (int i = 0; i < n; ++i) {
            a[i * n + j] *= rs[i];
            const sg_vd v = sgv_fabs(a[i * n + j]);
            m = sgv_select(~(v <= m), v, m); /* NaN propagates */
        }
        ok &= (m > zero) & (m < sgv_set1(INFINITY));
        cs[j] = 1.0 / m;
        cs[n + j] = m;
        for (int i = 0; i < n; ++i) a[i * n + j] *= cs[j];
    }
    sg_vd anorm = zero;
    for (int i = 0; i < n; ++i) {
        sg_vd s = zero;
        for (int j = 0; j < n; ++j) s += sgv_fabs(a[i * n + j]);
        anorm = sgv_select(~(s <= anorm), s, anorm);
    }
    sg_vd inorm;
    ok &= sgv_lu_bound(n, a, piv, &inorm);
    *cond = anorm * inorm;
    return ok & sgv_isfinite(*cond);
}

/* sg_solve_eq_inl lane by lane (n = 2: the product with sgv_factor_eq2's inverse). */
SG_VINLINE void sgv_solve_eq(int n, const sg_vd *lu, const sg_vm *piv, const sg_vd *rs, const sg_vd *cs, sg_vd *b)
{
    if (n == 2) {
        const sg_vd b0 = b[0] * rs[0], b1 = b[1] * rs[1];
        b[0] = lu[0] * b0 + lu[1] * b1;
        b[1] = lu[2] * b0 + lu[3] * b1;
        return;
    }
    for (int i = 0; i < n; ++i) b[i] *= rs[i];
    sgv_substitute(n, lu, piv, b, 1);
    for (int j = 0; j < n; ++j) b[j] *= cs[j];
}

/* sg_rates_scale_inl lane by lane, operation for operation (the scalar kernels' values to the bit). */
SG_VINLINE void sgv_rates_scale(int n, unsigned long long angles, sg_vd turn, const sg_vd *cs, const sg_vd *qd,
                                const sg_vd *qdd, sg_vd *cond)
{
    const sg_vd zero = sgv_set1(0.0);
    sg_vd y1 = zero, y2 = zero, yt = zero, om = turn, lam = sgv_set1(1.0);
    for (int j = 0; j < n; ++j) {
        const sg_vd w = sgv_fabs(qd[j]), v = w * cs[n + j], a = sgv_fabs(qdd[j]) * cs[n + j];
        y1 = sgv_select(~(v <= y1), v, y1);
        y2 = sgv_select(~(a <= y2), a, y2);
        if (angles >> j & 1) {
            om = sgv_select(w > om, w, om);
            lam = sgv_select(cs[j] > lam, cs[j], lam);
        } else {
            yt = sgv_select(v > yt, v, yt);
        }
    }
    const sg_vd terms = (2.0 * n) * om * y1, scale = sgv_select(terms > y2, terms, y2);
    cond[1] = sgv_select(scale > zero, (2.0 * n) * (om + lam * yt) * y1 / scale, sgv_set1(1.0));
    cond[2] = lam;
}

/* sg_rates_error and sg_newton_error lane by lane, operation for operation. */
SG_VINLINE sg_vd sgv_rates_error(sg_vd amp, sg_vd mu, sg_vd ej)
{
    const sg_vd ev = amp * (SG_EPS + ej);
    const sg_vd ea = amp * ((2.0 * ev + SG_EPS) * mu + ej);
    return sgv_select(ev > ea, ev, ea);
}

SG_VINLINE sg_vd sgv_newton_error(const sg_vd *cond, sg_vd resid)
{
    const sg_vd floor = sgv_set1(SG_ROUND_RESID), rho = sgv_select(resid > floor, resid, floor);
    return sgv_rates_error(cond[0], cond[1], (cond[0] + cond[2]) * rho);
}

/* sg_lu_factor_cm_inl lane by lane: the pivot test against colmax, each column's largest |entry| (of all of Φ_q
 * for a block of it: Newton's block factor, sewgen/derive/blockfactor.py); the mask of the lanes it accepts. */
SG_VINLINE sg_vm sgv_lu_factor_cm(int n, sg_vd *a, sg_vm *piv, const sg_vd *colmax)
{
    sg_vd best[SG_MAX_Q];
    sgv_eliminate(n, a, piv, best, 0);
    sg_vm ok = sgv_true();
    for (int k = 0; k < n; ++k) ok &= best[k] > SG_PIVOT_RTOL * colmax[k];
    return ok;
}

/* sg_lu_factor_inl lane by lane (the pivot test against each column's largest original entry). */
SG_VINLINE sg_vm sgv_lu_factor(int n, sg_vd *a, sg_vm *piv)
{
    sg_vd colmax[SG_MAX_Q];
    for (int j = 0; j < n; ++j) {
        sg_vd cm = sgv_set1(0.0);
        for (int i = 0; i < n; ++i) cm = sgv_fmax(sgv_fabs(a[i * n + j]), cm);
        colmax[j] = cm;
    }
    return sgv_lu_factor_cm(n, a, piv, colmax);
}

/* sg_lu_solve_inl lane by lane. */
SG_VINLINE void sgv_lu_solve(int n, const sg_vd *lu, const sg_vm *piv, sg_vd *b) { sgv_substitute(n, lu, piv, b, 0); }

/* count vectors of lanes from rows of SG_W positions: v[j][l] = src[l][j] (sgv_store_rows' inverse); each AVX2
 * register of four lanes from its four rows, four columns at a time transposed in registers. */
SG_VINLINE void sgv_load_rows(const double *const src[SG_W], int count, sg_vd *v)
{
    int j = 0;
    for (; j + 4 <= count; j += 4)
        for (int h = 0; h < SG_H; ++h) {
            const double *const *row = src + 4 * h;
            const __m256d r0 = _mm256_loadu_pd(row[0] + j), r1 = _mm256_loadu_pd(row[1] + j);
            const __m256d r2 = _mm256_loadu_pd(row[2] + j), r3 = _mm256_loadu_pd(row[3] + j);
            const __m256d t0 = _mm256_unpacklo_pd(r0, r1), t1 = _mm256_unpackhi_pd(r0, r1);
            const __m256d t2 = _mm256_unpacklo_pd(r2, r3), t3 = _mm256_unpackhi_pd(r2, r3);
            sgv_set_half(&v[j], h, _mm256_permute2f128_pd(t0, t2, 0x20));
            sgv_set_half(&v[j + 1], h, _mm256_permute2f128_pd(t1, t3, 0x20));
            sgv_set_half(&v[j + 2], h, _mm256_permute2f128_pd(t0, t2, 0x31));
            sgv_set_half(&v[j + 3], h, _mm256_permute2f128_pd(t1, t3, 0x31));
        }
    for (; j < count; ++j)
        for (int l = 0; l < SG_W; ++l) v[j][l] = src[l][j];
}

/* Rows of SG_W positions from count vectors of lanes: dst[l][j] = v[j][l]; per AVX2 register of four lanes, four
 * columns at a time transposed in registers (two unpacks and two lane permutes per four) and stored as one
 * 32-byte row piece per lane. */
SG_VINLINE void sgv_store_rows(const sg_vd *v, int count, double *const dst[SG_W])
{
    for (int h = 0; h < SG_H; ++h) {
        double *const *row = dst + 4 * h;
        int j = 0;
        for (; j + 4 <= count; j += 4) {
            const __m256d r0 = sgv_half(&v[j], h), r1 = sgv_half(&v[j + 1], h);
            const __m256d r2 = sgv_half(&v[j + 2], h), r3 = sgv_half(&v[j + 3], h);
            const __m256d t0 = _mm256_unpacklo_pd(r0, r1), t1 = _mm256_unpackhi_pd(r0, r1);
            const __m256d t2 = _mm256_unpacklo_pd(r2, r3), t3 = _mm256_unpackhi_pd(r2, r3);
            _mm256_storeu_pd(row[0] + j, _mm256_permute2f128_pd(t0, t2, 0x20));
            _mm256_storeu_pd(row[1] + j, _mm256_permute2f128_pd(t1, t3, 0x20));
            _mm256_storeu_pd(row[2] + j, _mm256_permute2f128_pd(t0, t2, 0x31));
            _mm256_storeu_pd(row[3] + j, _mm256_permute2f128_pd(t1, t3, 0x31));
        }
        if (j + 2 <= count) { /* two columns: one 16-byte piece a lane */
            const __m256d r0 = sgv_half(&v[j], h), r1 = sgv_half(&v[j + 1], h);
            const __m256d lo = _mm256_unpacklo_pd(r0, r1), hi = _mm256_unpackhi_pd(r0, r1);
            _mm_storeu_pd(row[0] + j, _mm256_castpd256_pd128(lo));
            _mm_storeu_pd(row[1] + j, _mm256_castpd256_pd128(hi));
            _mm_storeu_pd(row[2] + j, _mm256_extractf128_pd(lo, 1));
            _mm_storeu_pd(row[3] + j, _mm256_extractf128_pd(hi, 1));
            j += 2;
        }
        if (j < count) { /* the last column */
            const __m256d r = sgv_half(&v[j], h);
            const __m128d a = _mm256_castpd256_pd128(r), b = _mm256_extractf128_pd(r, 1);
            _mm_storel_pd(row[0] + j, a);
            _mm_storeh_pd(row[1] + j, a);
            _mm_storel_pd(row[2] + j, b);
            _mm_storeh_pd(row[3] + j, b);
        }
    }
}

/* count vectors of lanes from an sg_lanes field: lane l's row starts stride doubles after lane l - 1's. */
SG_VINLINE void sgv_load_lanes(const double *first, size_t stride, int count, sg_vd *v)
{
    const double *rows[SG_W];
    for (int l = 0; l < SG_W; ++l) rows[l] = first + (size_t)l * stride;
    sgv_load_rows(rows, count, v);
}

/* A block's observables (NOBS vectors) to its lanes' rows: all of them (nwanted < 0), else only the groups listed
 * in wanted (a selective sweep: the rest of the rows stay as they are). */
SG_VINLINE void sgv_store_observables(const sg_mechanism *m, const int *wanted, int nwanted, const sg_vd *vobs,
                                      int nobs, double *const robs[SG_W])
{
    if (nwanted < 0) {
        sgv_store_rows(vobs, nobs, robs);
        return;
    }
    for (int t = 0; t < nwanted; ++t) {
        const int g0 = m->group_start[wanted[t]];
        double *rg[SG_W];
        for (int l = 0; l < SG_W; ++l) rg[l] = robs[l] + g0;
        sgv_store_rows(vobs + g0, m->group_start[wanted[t] + 1] - g0, rg);
    }
}

/* cos, sin of n angles as the SIMD loop computes them (each lane on its own: the values do not depend on the
 * block): cos to out[0..n), sin to out[n..2n); a last partial block padded with its last angle. */
static __attribute__((unused)) void sgv_trig_table(size_t n, const double *phi, double *out)
{
    for (size_t k = 0; k < n; k += SG_W) {
        sg_vd a, c, s;
        for (int l = 0; l < SG_W; ++l) a[l] = phi[k + l < n ? k + l : n - 1];
        sgv_sincos(a, &c, &s);
        for (int l = 0; l < SG_W && k + l < n; ++l) {
            out[k + l] = c[l];
            out[n + k + l] = s[l];
        }
    }
}

/* A lane's selected columns from its rows (a lane the scalar step solved, in a sweep writing sg_columns). */
static inline void sg_columns_from_rows(const sg_columns *cols, int nq, size_t i, const double *qi,
                                        const double *qdi, const double *qddi, const double *oi)
{
    for (int k = 0; k < cols->n; ++k) cols->dst[k][i] = *SG_FLAT_COLUMN(cols->col[k], nq, qi, qdi, qddi, oi);
}

/* The SIMD twins' types (the signatures sewgen/derive/kernels.py VECTOR_SIGNATURES gives them; the compiler checks
 * the two agree where a generated file passes its twins to the loops below). */
typedef sg_vm (*sgv_closed_fn)(const sg_vd *x, const sg_vd *cx, const double *c, const int *branch, int angles,
                               sg_vd *q, sg_vd *cq, sg_vd *err);
typedef sg_vm (*sgv_motion_fn)(const sg_vd *q, const sg_vd *cq, const sg_vd *x, const sg_vd *cx, const sg_vd *xd,
                               const sg_vd *xdd, const double *c, sg_vd *qd, sg_vd *qdd, sg_vd *obs, sg_vd *cond);
typedef sg_vm (*sgv_rates_fn)(const sg_vd *q, const sg_vd *cq, const sg_vd *x, const sg_vd *cx, const sg_vd *xd,
                              const sg_vd *xdd, const double *c, sg_vd *qd, sg_vd *qdd, sg_vd *cond);
typedef sg_vm (*sgv_observe_fn)(const sg_vd *q, const sg_vd *cq, const sg_vd *x, const sg_vd *cx, const sg_vd *xd,
                                const sg_vd *xdd, const double *c, const sg_vd *qd, const sg_vd *qdd, int group,
                                sg_vd *obs);
typedef sg_vm (*sgv_forces_fn)(const sg_vd *q, const sg_vd *cq, const sg_vd *x, const sg_vd *cx, const sg_vd *xd,
                               const double *c, const sg_vd *obs, const double *gv, const sg_vd *ld, sg_vd *out);
typedef void (*sgv_residual_fn)(const sg_vd *q, const sg_vd *cq, const sg_vd *x, const sg_vd *cx, const double *c,
                                sg_vd *r, sg_vd *jac);
typedef sg_vm (*sgv_lu_factor_fn)(sg_vd *a, sg_vm *piv);
typedef void (*sgv_lu_solve_fn)(const sg_vd *lu, const sg_vm *piv, sg_vd *b);
typedef void (*sgv_blocks_fn)(const sg_vd *jac, sg_vd *out);
typedef int (*sgv_forces_in_simd_fn)(const double *c);

/* A mechanism's vector twins, as one generated file passes them to the loops below (constant arguments of
 * always-inline functions: its flatten attribute inlines every one). nobs and nfo: its observables and force
 * outputs (literals: the vectors' arrays on the stack are sized by them). */
typedef struct sgv_kernels {
    sgv_closed_fn closed;
    sgv_motion_fn motion;
    sgv_rates_fn rates;
    sgv_observe_fn observe;
    sgv_forces_fn forces;
    sgv_forces_in_simd_fn forces_in_simd;
    int nobs, nfo;
} sgv_kernels;

/* A mechanism's vector twins for the SIMD Newton (constant arguments, inlined; nq a literal: the Jacobian's vectors
 * on the stack are sized by it). */
typedef struct sgv_newton_kernels {
    sgv_residual_fn residual;
    sgv_lu_factor_fn lu_factor;
    sgv_lu_solve_fn lu_solve;
    sgv_blocks_fn blocks;
    int nq;
} sgv_newton_kernels;

/* The SIMD closed-form sweep: blocks of SG_W positions in solving order (the last block padded with its last
 * position), the vector kernels of K (closed; motion, or with r->want the rates and the wanted groups' observe,
 * whose rows alone are stored; for forces, r->frc, forces with the loads transposed in), and the scalar step of
 * csrc/sg_runtime.h (sg_closed_step, sg_closed_finish) for every block or lane the vector kernels do not vouch for
 * (see the top of this file). A force sweep the vector forces cannot do (K's forces_in_simd: friction on, or no
 * vector form) runs the scalar loop scalar_sweep whole. The scalar fallbacks call the descriptor's own kernels
 * (m->closed, m->motion, ...: the same code, so the same values to the bit) rather than inlining a third copy of
 * them: they run only for lanes the vector kernels refuse, and the copies doubled the file's compile time, under
 * the sanitizers above all. Angle coordinates are unwrapped lane after lane against the last solution, as the
 * scalar loop does (tested a vector at once: where no lane is over half a turn from the one before, the scalar
 * loop changes none). A kinematic sweep given r->cols (sg_columns, at most SG_MAX_DIRECT) stores those columns'
 * vectors straight to their arrays, SG_W contiguous positions at a time, and no row: a lane the scalar step
 * solves gets its rows, then its columns from them. */
SG_VINLINE size_t sgv_closed_sweep(const sg_mechanism *m, const sg_request *r, sg_constants_fn constants,
                                   sg_sweep_fn scalar_sweep, const sgv_kernels K)
{
    const sg_closed_kernels D = sg_descriptor_kernels(m); /* the scalar step's: calls through the descriptor */
    sg_closed_loop L;
    sg_closed_setup(&L, m, r, constants);
    const double *c = L.c;
    if (L.frc != NULL && !K.forces_in_simd(c)) return scalar_sweep(m, r);
    const int nq = L.nq, nx = L.nx, nobs = L.nobs, nload = L.nload;
    const size_t n = r->n, *order = r->order;
    const double *phi = L.phi, *omega = L.omega, *alpha = L.alpha, *loads = L.loads, *gv = L.gv, *trig = r->trig;
    const unsigned char *want = L.want;
    double *q = L.q, *qd = L.qd, *qdd = L.qdd, *obs = L.obs, *err = L.err, *frc = L.frc;
    int *status = L.status;
    sg_columns *cols = r->cols;
    sg_vd vx[SG_MAX_Q], vcx[2 * SG_MAX_Q], vxd[SG_MAX_Q], vxdd[SG_MAX_Q], vld[SG_MAX_LOAD];
    for (int k = 1; k < nx; ++k) {
        vx[k] = sgv_set1(L.x[k]);
        vcx[2 * k] = sgv_set1(L.cx[2 * k]);
        vcx[2 * k + 1] = sgv_set1(L.cx[2 * k + 1]);
        vxd[k] = vxdd[k] = sgv_set1(0.0);
    }
    if (frc != NULL && loads == NULL)
        for (int k = 0; k < nload; ++k) vld[k] = sgv_set1(0.0);
    const sg_vd accept = sgv_set1(0.25 * L.opt->singular_tol);
    /* the angles (the dyads' atan2) where anything reads them: every output, the caller's coordinates
     * (want[ngroup]), a wanted group or the rates that read an angle itself (group_angles) */
    int angles = want == NULL || want[m->ngroup] || m->group_angles[m->ngroup];
    for (int g = 0; g < m->ngroup && !angles; ++g) angles = want[g] && m->group_angles[g];
    /* the angle coordinates the loop unwraps (none where it skips the angles: their values are never read, and a
     * lane the scalar step solves unwraps against the last one it solved, or zero) */
    int angle_q[SG_MAX_Q], nangle = 0;
    for (int j = 0; j < nq; ++j) {
        L.last[j] = 0.0;
        if (angles && m->coord_is_angle[j]) angle_q[nangle++] = j;
    }
    sg_vd vq[SG_MAX_Q], vcq[2 * SG_MAX_Q], vqd[SG_MAX_Q], vqdd[SG_MAX_Q], vobs[K.nobs + 1], verr[2];
    const sg_vd *csrc[SG_MAX_DIRECT]; /* the vector each direct column is stored from */
    if (cols != NULL && (frc != NULL || cols->n < 1 || cols->n > SG_MAX_DIRECT)) cols = NULL;
    for (int k = 0; cols != NULL && k < cols->n; ++k) csrc[k] = SG_FLAT_COLUMN(cols->col[k], nq, vq, vqd, vqdd, vobs);
    if (cols != NULL) cols->written = 1;
    const int ncol = cols != NULL ? cols->n : 0;
    double *const *cdst = cols != NULL ? cols->dst : NULL;
    /* the wanted groups in a list, once a sweep (ngroup <= SG_MAX_GROUP wherever want is set) */
    int wanted[SG_MAX_GROUP], nwanted = 0;
    for (int g = 0; want != NULL && g < m->ngroup; ++g)
        if (want[g]) wanted[nwanted++] = g;
    for (size_t k = 0; k < n; k += SG_W) {
        const int lanes = n - k < SG_W ? (int)(n - k) : SG_W;
        const int contiguous = order == NULL && lanes == SG_W;
        size_t idx[SG_W];
        sg_vd ph, om, al;
        if (contiguous) { /* loads: no lane-by-lane stores read back */
            for (int l = 0; l < SG_W; ++l) idx[l] = k + (size_t)l;
            ph = sgv_loadu(phi + k);
            om = sgv_loadu(omega + k);
            al = sgv_loadu(alpha + k);
        } else {
            for (int l = 0; l < SG_W; ++l) {
                const size_t kk = k + (size_t)(l < lanes ? l : lanes - 1);
                idx[l] = order ? order[kk] : kk;
                ph[l] = phi[idx[l]];
                om[l] = omega[idx[l]];
                al[l] = alpha[idx[l]];
            }
        }
        int vector_block = sgv_all(sgv_isfinite(ph + om + al));
        if (vector_block) {
            vx[0] = ph;
            vxd[0] = om;
            vxdd[0] = al;
            if (trig != NULL && contiguous) { /* sg_sweep_designs' table */
                vcx[0] = sgv_loadu(trig + k);
                vcx[1] = sgv_loadu(trig + n + k);
            } else {
                sgv_sincos(ph, &vcx[0], &vcx[1]);
            }
            vector_block = sgv_all(K.closed(vx, vcx, c, L.branch, angles, vq, vcq, verr));
        }
        if (!vector_block) {
            for (int l = 0; l < lanes; ++l) {
                const size_t i = idx[l];
                sg_closed_step(&L, i, D);
                if (cols != NULL)
                    sg_columns_from_rows(cols, nq, i, q + i * (size_t)nq, qd + i * (size_t)nq, qdd + i * (size_t)nq,
                                         obs + i * (size_t)nobs);
            }
            continue;
        }
        for (int a = 0; a < nangle; ++a) { /* no lane a half turn from the one before: none moves */
            const int j = angle_q[a];
            const sg_vd v = vq[j];
            const sg_vd prev = sgv_shift_in(L.have_last ? L.last[j] : v[0], v);
            if (!sgv_none(sgv_fabs((prev - v) * (1.0 / SG_TWO_PI)) > sgv_set1(0.5)))
                for (int l = L.have_last ? 0 : 1; l < SG_W; ++l) {
                    const double ref = l > 0 ? vq[j][l - 1] : L.last[j];
                    const double turns = (ref - vq[j][l]) * (1.0 / SG_TWO_PI);
                    if (fabs(turns) > 0.5) vq[j][l] += SG_TWO_PI * nearbyint(turns);
                }
            L.last[j] = vq[j][SG_W - 1];
        }
        L.have_last = 1;
        sg_vd vout[K.nfo + 1], vcond[SG_NCOND];
        sg_vm ok;
        if (want == NULL) {
            ok = K.motion(vq, vcq, vx, vcx, vxd, vxdd, c, vqd, vqdd, vobs, vcond);
        } else { /* the rates and the wanted groups: the motion twin's values to the bit */
            ok = K.rates(vq, vcq, vx, vcx, vxd, vxdd, c, vqd, vqdd, vcond);
            for (int t = 0; t < nwanted; ++t) ok &= K.observe(vq, vcq, vx, vcx, vxd, vxdd, c, vqd, vqdd, wanted[t], vobs);
        }
        const sg_vd vest = sgv_rates_error(verr[1], vcond[1], verr[0]); /* the position's error: the dyads' */
        ok &= vest <= accept;
        if (frc != NULL) {
            if (loads != NULL) {
                const double *rld[SG_W];
                for (int l = 0; l < SG_W; ++l) rld[l] = loads + idx[l] * (size_t)nload;
                sgv_load_rows(rld, nload, vld);
            }
            ok &= K.forces(vq, vcq, vx, vcx, vxd, c, vobs, gv, vld, vout);
        }
        if (cols != NULL) { /* the columns' SG_W positions at once (a padded lane: not stored) */
            if (contiguous)
                for (int j = 0; j < ncol; ++j) sgv_storeu(cdst[j] + k, *csrc[j]);
            else
                for (int j = 0; j < ncol; ++j)
                    for (int l = 0; l < lanes; ++l) cdst[j][idx[l]] = (*csrc[j])[l];
        } else { /* every lane's rows from registers (a padded lane repeats the last real one's row); a lane the
                  * vector kernels do not vouch for is rewritten below by the scalar motion and forces at its
                  * solved position */
            double *rq[SG_W], *rqd[SG_W], *rqdd[SG_W], *robs[SG_W], *rfrc[SG_W];
            for (int l = 0; l < SG_W; ++l) {
                rq[l] = q + idx[l] * (size_t)nq;
                rqd[l] = qd + idx[l] * (size_t)nq;
                rqdd[l] = qdd + idx[l] * (size_t)nq;
                robs[l] = obs + idx[l] * (size_t)nobs;
                rfrc[l] = frc != NULL ? frc + idx[l] * (size_t)L.nfo : NULL;
            }
            sgv_store_rows(vq, nq, rq);
            sgv_store_rows(vqd, nq, rqd);
            sgv_store_rows(vqdd, nq, rqdd);
            sgv_store_observables(m, wanted, want == NULL ? -1 : nwanted, vobs, K.nobs, robs);
            if (frc != NULL) sgv_store_rows(vout, K.nfo, rfrc);
        }
        if (contiguous && sgv_all(ok)) { /* the usual block: all its statuses at once */
            for (int l = 0; l < SG_W; ++l) status[k + (size_t)l] = SG_OK;
            if (err) sgv_storeu(err + k, vest);
            continue;
        }
        for (int l = 0; l < lanes; ++l) {
            const size_t i = idx[l];
            if (ok[l]) {
                status[i] = SG_OK;
                if (err) err[i] = vest[l];
                continue;
            }
            double *qi = q + i * (size_t)nq, cq[2 * SG_MAX_Q];
            for (int j = 0; j < nq; ++j) qi[j] = vq[j][l]; /* the lane's solved coordinates */
            for (int j = 0; j < 2 * nq; ++j) cq[j] = vcq[j][l];
            L.x[0] = ph[l];
            L.cx[0] = vcx[0][l];
            L.cx[1] = vcx[1][l];
            L.xd[0] = om[l];
            L.xdd[0] = al[l];
            const double lerr[2] = {verr[0][l], verr[1][l]};
            sg_closed_finish(&L, i, cq, lerr, D);
            if (cols != NULL) sg_columns_from_rows(cols, nq, i, qi, qd + i * (size_t)nq, qdd + i * (size_t)nq,
                                                   obs + i * (size_t)nobs);
        }
    }
    return L.failures;
}

/* The SIMD loop of a mechanism Newton solves (no closed form): csrc/sg_runtime.c's sweep solves the positions (in
 * blocks predicted from one history, sgv_newton, or step by step) and hands them over SG_W at a time in an sg_lanes;
 * this finishes them with the vector kernels of K (motion, K.nobs observables; with want, the rates and the wanted
 * groups' observe, whose rows alone are stored) and, for forces (frc not NULL), K.forces (K.nfo outputs, loads
 * transposed in): the scalar kernels' operations lane by lane (Φ_q's block factor too), so the same values to the
 * bit. Every lane's rows are written; the bit mask returned says which lanes it vouches for: the factor and every
 * output finite, and the rates' estimated error at most a quarter of opt->singular_tol. The runtime runs its scalar
 * step on the other lanes, which decides the singular ones. lanes NULL: whether it can finish this sweep's
 * positions (K.forces_in_simd: a force sweep without friction). */
SG_VINLINE int sgv_finish(const sg_mechanism *m, sg_lanes *lanes, const double *c, const sg_options *opt,
                          const double *gv, const double *loads, double *qd, double *qdd, double *obs, double *frc,
                          const unsigned char *want, const sgv_kernels K)
{
    if (lanes == NULL) return frc == NULL || K.forces_in_simd(c);
    const int nq = m->nq, nx = m->nx, nobs = m->nobs, nfo = m->nfo, nload = m->nload;
    sg_vd vq[SG_MAX_Q], vcq[2 * SG_MAX_Q], vx[SG_MAX_Q], vcx[2 * SG_MAX_Q], vxd[SG_MAX_Q], vxdd[SG_MAX_Q];
    sgv_load_lanes(lanes->q[0], SG_MAX_Q, nq, vq);
    sgv_load_lanes(lanes->cq[0], 2 * SG_MAX_Q, 2 * nq, vcq);
    sgv_load_lanes(lanes->x[0], SG_MAX_Q, nx, vx);
    sgv_load_lanes(lanes->cx[0], 2 * SG_MAX_Q, 2 * nx, vcx);
    sgv_load_lanes(lanes->xd[0], SG_MAX_Q, nx, vxd);
    sgv_load_lanes(lanes->xdd[0], SG_MAX_Q, nx, vxdd);
    sg_vd vqd[SG_MAX_Q], vqdd[SG_MAX_Q], vobs[K.nobs + 1], vout[K.nfo + 1], vcond[SG_NCOND], vres;
    sg_vm ok;
    int wanted[SG_MAX_GROUP], nwanted = 0;
    if (want == NULL) {
        ok = K.motion(vq, vcq, vx, vcx, vxd, vxdd, c, vqd, vqdd, vobs, vcond);
    } else { /* the rates and the wanted groups: the motion twin's values to the bit */
        ok = K.rates(vq, vcq, vx, vcx, vxd, vxdd, c, vqd, vqdd, vcond);
        for (int g = 0; g < m->ngroup; ++g)
            if (want[g]) {
                wanted[nwanted++] = g;
                ok &= K.observe(vq, vcq, vx, vcx, vxd, vxdd, c, vqd, vqdd, g, vobs);
            }
    }
    for (int l = 0; l < SG_W; ++l) vres[l] = lanes->resid[l]; /* the scalar loop's estimate, from Newton's residual */
    const sg_vd vest = sgv_newton_error(vcond, vres);
    ok &= vest <= sgv_set1(0.25 * opt->singular_tol);
    double *rqd[SG_W], *rqdd[SG_W], *robs[SG_W], *rfrc[SG_W];
    for (int l = 0; l < SG_W; ++l) {
        const size_t i = lanes->index[l];
        rqd[l] = qd + i * (size_t)nq;
        rqdd[l] = qdd + i * (size_t)nq;
        robs[l] = obs + i * (size_t)nobs;
        rfrc[l] = frc != NULL ? frc + i * (size_t)nfo : NULL;
    }
    if (frc != NULL) {
        sg_vd vld[SG_MAX_LOAD];
        if (loads != NULL) {
            const double *rld[SG_W];
            for (int l = 0; l < SG_W; ++l) rld[l] = loads + lanes->index[l] * (size_t)nload;
            sgv_load_rows(rld, nload, vld);
        } else {
            for (int k = 0; k < nload; ++k) vld[k] = sgv_set1(0.0);
        }
        ok &= K.forces(vq, vcq, vx, vcx, vxd, c, vobs, gv, vld, vout);
        sgv_store_rows(vout, K.nfo, rfrc);
    }
    sgv_store_rows(vqd, nq, rqd);
    sgv_store_rows(vqdd, nq, rqdd);
    sgv_store_observables(m, wanted, want == NULL ? -1 : nwanted, vobs, K.nobs, robs);
    for (int l = 0; l < SG_W; ++l) lanes->est[l] = vest[l];
    return sgv_bits(ok) & ((1 << lanes->count) - 1);
}

/* max_i |v_i| w_i lane by lane, NaN propagating (csrc/sg_runtime.c weighted_norm). */
SG_VINLINE sg_vd sgv_weighted_norm(int n, const sg_vd *v, const double *w)
{
    sg_vd m = sgv_set1(0.0);
    for (int i = 0; i < n; ++i) {
        const sg_vd a = sgv_fabs(v[i]) * w[i];
        m = sgv_select(~(a <= m), a, m);
    }
    return m;
}

/* csrc/sg_runtime.c's shift_trig lane by lane: q + d and its cos, sin by the same series (csrc/sg_runtime.h),
 * each lane's chosen by its own |d|; a lane with a larger step (or a NaN) takes libm's sincos, as there. */
SG_VINLINE void sgv_shift_trig(const sg_mechanism *m, const sg_vd *q, const sg_vd *cq, const sg_vd *d, int n,
                               sg_vd *q_out, sg_vd *cq_out)
{
    for (int i = 0; i < n; ++i) {
        q_out[i] = q[i] + d[i];
        if (!m->coord_is_angle[i]) {
            cq_out[2 * i] = sgv_set1(1.0);
            cq_out[2 * i + 1] = sgv_set1(0.0);
            continue;
        }
        const sg_vd h = d[i], h2 = h * h, c = cq[2 * i], s = cq[2 * i + 1], ad = sgv_fabs(h);
        const sg_vm tiny = ad < sgv_set1(SG_TINY_STEP), small = ad < sgv_set1(SG_SMALL_STEP);
        const sg_vm short_ = ad < sgv_set1(SG_SHORT_STEP);
        const sg_vd sd3 = SG_SIN_SHORT(h, h2), cd3 = SG_COS_SHORT(h2);
        const sg_vd sd4 = SG_SIN_SMALL(h, h2), cd4 = SG_COS_SMALL(h2);
        sg_vd co = sgv_select(short_, c * cd3 - s * sd3, c * cd4 - s * sd4);
        sg_vd so = sgv_select(short_, s * cd3 + c * sd3, s * cd4 + c * sd4);
        co = sgv_select(tiny, c - s * h, co);
        so = sgv_select(tiny, s + c * h, so);
        if (!sgv_all(small))
            for (int l = 0; l < SG_W; ++l)
                if (!small[l]) sg_sincos_inl(q_out[i][l], &co[l], &so[l]);
        cq_out[2 * i] = co;
        cq_out[2 * i + 1] = so;
    }
}

/* csrc/sg_runtime.h's sg_lagrange5_weights at SG_W shaft angles t: the same operations lane by lane. */
SG_VINLINE void sgv_lagrange5_weights(sg_vd t, const double *x, const double *den, sg_vd *w)
{
    const sg_vd e0 = t - x[0], e1 = t - x[1], e2 = t - x[2], e3 = t - x[3], e4 = t - x[4];
    const sg_vd p01 = e0 * e1, p012 = p01 * e2, s34 = e3 * e4, s234 = e2 * s34;
    w[0] = e1 * s234 / den[0], w[1] = e0 * s234 / den[1], w[2] = p01 * s34 / den[2];
    w[3] = p012 * e4 / den[3], w[4] = p012 * e3 / den[4];
}

/* Newton at SG_W positions of a block at once (csrc/sg_runtime.c solve_block: lanes first .. first + SG_W - 1 of
 * b; weights w): the scalar course lane by lane, the same operations, so the same values to the bit. Each lane's
 * start is the five-state prediction from b's history (sg_lagrange5_den, sgv_lagrange5_weights) and the step to it from the newest state
 * (sgv_shift_trig), a change no larger than b->lim allows; then the scalar newton()'s usual course at such a
 * prediction with the vector kernels of N (residual, lu_factor, lu_solve; nq = N.nq), one full step: kept if it
 * lowers the residual where the start is within the tolerance (min_iter), else accepted if it lowers the residual
 * into the tolerance; and the correction no larger than b->lim either. A lane that takes that course gets its
 * solution, Newton's relative residual and its loops' orientation determinants (kernel 'blocks', from the Φ_q it
 * ends with) in b; the returned bit mask names those lanes. Any other lane (a damped step, more
 * iterations, a singular factor, a non-finite residual, too large a change, equal angles in the history) is left
 * to the scalar course. */
SG_VINLINE int sgv_newton(const sg_mechanism *m, sg_block *b, int first, const double *c, const sg_options *opt,
                          const double *w, const sgv_newton_kernels N)
{
    const int nx = m->nx, nq = N.nq;
    const double *const *hq = b->hq;
    double den[SG_HISTORY];
    if (!sg_lagrange5_den(b->hphi, den)) return 0; /* equal angles in the history: predict()'s lower orders, scalar */
    sg_vd vq[nq], vcq[2 * nq], vx[SG_MAX_Q], vcx[2 * SG_MAX_Q], vqp[nq], h0[nq], hc[2 * nq];
    sgv_load_lanes(b->x[first], SG_MAX_Q, nx, vx);
    sgv_load_lanes(b->cx[first], 2 * SG_MAX_Q, 2 * nx, vcx);
    sg_vd wt[SG_HISTORY], dq[nq];
    sgv_lagrange5_weights(vx[0], b->hphi, den, wt);
    sg_vm ok = sgv_true();
    for (int i = 0; i < nq; ++i) {
        vqp[i] = SG_LAGRANGE5_VALUE(wt, hq, i);
        h0[i] = sgv_set1(hq[0][i]);
        dq[i] = vqp[i] - hq[0][i];
        ok &= sgv_fabs(dq[i]) <= sgv_set1(b->lim[i]);
    }
    for (int i = 0; i < 2 * nq; ++i) hc[i] = sgv_set1(b->hcq[i]);
    sgv_shift_trig(m, h0, hc, dq, nq, vq, vcq);
    sg_vd r[nq], jac[nq * nq], lu[nq * nq], tq[nq], tcq[2 * nq], rt[nq];
    sg_vd jt[nq * nq];
    sg_vm piv[nq];
    N.residual(vq, vcq, vx, vcx, c, r, jac);
    const sg_vd one = sgv_set1(1.0), tol = sgv_set1(opt->tol);
    const sg_vd norm = sgv_weighted_norm(nq, r, w);
    const sg_vm within = norm <= one;
    const sg_vm exact = within & (norm * tol <= sgv_set1(SG_RESID_FLOOR)); /* no step taken */
    for (int k = 0; k < nq * nq; ++k) lu[k] = jac[k];
    const sg_vm factored = N.lu_factor(lu, piv);
    for (int k = 0; k < nq; ++k) dq[k] = -r[k];
    N.lu_solve(lu, piv, dq);
    sgv_shift_trig(m, vq, vcq, dq, nq, tq, tcq);
    N.residual(tq, tcq, vx, vcx, c, rt, jt);
    const sg_vd nt = sgv_weighted_norm(nq, rt, w);
    const sg_vm lower = nt < norm, take = ~exact & lower;
    ok &= exact | (sgv_isfinite(norm) & factored & (within | (lower & (nt <= one))));
    for (int k = 0; k < nq; ++k) {
        vq[k] = sgv_select(take, tq[k], vq[k]);
        ok &= sgv_fabs(vq[k] - vqp[k]) <= sgv_set1(b->lim[k]);
    }
    const int lanes = b->count - first < SG_W ? b->count - first : SG_W;
    const int mask = sgv_bits(ok) & ((1 << lanes) - 1);
    if (mask == 0) return 0;
    for (int k = 0; k < 2 * nq; ++k) vcq[k] = sgv_select(take, tcq[k], vcq[k]);
    const sg_vd resid = sgv_select(take, nt, norm) * tol;
    const int nblock = m->nblock;
    sg_vd vbv[SG_MAX_Q];
    if (nblock > 0) { /* the loops' signs from the Φ_q the lane ends with */
        for (int k = 0; k < nq * nq; ++k) jac[k] = sgv_select(take, jt[k], jac[k]);
        N.blocks(jac, vbv);
    }
    double *pq[SG_W], *pcq[SG_W], *pbv[SG_W];
    for (int l = 0; l < SG_W; ++l) { /* straight to the rows of b's lanes (a spare lane's too) */
        pq[l] = b->q[first + l];
        pcq[l] = b->cq[first + l];
        pbv[l] = b->bv[first + l];
        b->resid[first + l] = resid[l];
    }
    sgv_store_rows(vq, nq, pq);
    sgv_store_rows(vcq, 2 * nq, pcq);
    if (nblock > 0) sgv_store_rows(vbv, nblock, pbv);
    return mask;
}

SG_SIMD_END
#endif /* SG_SIMD */

#endif
