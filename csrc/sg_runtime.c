/* sewgen C runtime: LU, damped Newton with a Lagrange predictor, and the sweep driver (a Newton sweep's rates,
 * observables and forces SG_LANES positions at a time where the mechanism has a SIMD finish: csrc/sg_simd.h). */
/* SSE2 (every x86-64) for the continuity scan, before sg_runtime.h: its SIMD part includes the same header under
 * the SIMD target (AVX2 or AVX-512), which would make these intrinsics need it here. */
#if defined(__SSE2__)
#include <emmintrin.h>
#endif
#include "sg_runtime.h"

#include <stdint.h>
#include <string.h>

/* SG_DEBUG (the sanitizer build of CI): the sweep asserts its pointers and the order permutation's range. */
#ifdef SG_DEBUG
#include <assert.h>
#define SG_ASSERT(cond) assert(cond)
#else
#define SG_ASSERT(cond) ((void)0)
#endif

/* n doubles from src to dst (not overlapping); nothing for n = 0 (a mechanism without loops passes empty, possibly
 * NULL, arrays). The rows copied here are a few doubles (a position's coordinates, a lane's inputs), many times a
 * position: two at a time in registers, inline, where memcpy of a run-time size was a library call each. */
static inline void copy_doubles(double *dst, const double *src, int n)
{
    int i = 0;
#if defined(__SSE2__)
    for (; i + 2 <= n; i += 2) _mm_storeu_pd(dst + i, _mm_loadu_pd(src + i));
#endif
    for (; i < n; ++i) dst[i] = src[i];
}

int sg_simd_width(const sg_mechanism *m)
{
#if SG_SIMD
    if (m != NULL && m->sweep_simd == NULL && m->finish_simd == NULL) return 1;
    /* libgcc's CPU model, read: a few loads, no state of ours; the instruction set the SIMD code is built for */
    int cpu = __builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma");
#if SG_W == 8
    cpu = cpu && __builtin_cpu_supports("avx512f") && __builtin_cpu_supports("avx512vl") &&
          __builtin_cpu_supports("avx512dq");
#endif
    return cpu ? SG_W : 1;
#else
    (void)m;
    return 1;
#endif
}

int sg_lu_factor(int n, double *a, int *piv, double *det_sign)
{
    return sg_lu_factor_inl(n, a, piv, det_sign);
}

void sg_lu_solve(int n, const double *lu, const int *piv, double *b)
{
    sg_lu_solve_inl(n, lu, piv, b);
}

int sg_factor_eq(int n, double *a, int *piv, const double *rs, double *cs, double *cond)
{
    return sg_factor_eq_inl(n, a, piv, rs, cs, cond);
}

void sg_solve_eq(int n, const double *lu, const int *piv, const double *rs, const double *cs, double *b)
{
    sg_solve_eq_inl(n, lu, piv, rs, cs, b);
}

/* max |v_i| w_i; NaN propagates: a NaN entry makes the norm NaN */
static double weighted_norm(int n, const double *v, const double *w)
{
    double m = 0.0;
    for (int i = 0; i < n; ++i) {
        const double a = fabs(v[i]) * w[i];
        if (!(a <= m)) m = a;
    }
    return m;
}

/* cos and sin of q + d from those of q, for the small steps of Newton and of the predictor: the addition
 * formulas with cos d, sin d from their Taylor series (csrc/sg_runtime.h, SG_TINY_STEP ...), so a step costs no
 * libm call. Larger steps: sincos. csrc/sg_simd.h's sgv_shift_trig is this lane by lane. */
static void shift_trig(const sg_mechanism *m, const double *q, const double *cq, const double *d, double *q_out,
                       double *cq_out)
{
    for (int i = 0; i < m->nq; ++i) {
        q_out[i] = q[i] + d[i];
        if (!m->coord_is_angle[i]) {
            cq_out[2 * i] = 1.0;
            cq_out[2 * i + 1] = 0.0;
        } else if (fabs(d[i]) < SG_TINY_STEP) { /* Newton's last steps: cos d, sin d are 1, d to the bit */
            const double h = d[i], c = cq[2 * i], s = cq[2 * i + 1];
            cq_out[2 * i] = c - s * h;
            cq_out[2 * i + 1] = s + c * h;
        } else if (fabs(d[i]) < SG_SHORT_STEP) { /* the predictor's steps at fine sweeps: three terms each */
            const double h = d[i], h2 = h * h;
            const double sd = SG_SIN_SHORT(h, h2), cd = SG_COS_SHORT(h2);
            const double c = cq[2 * i], s = cq[2 * i + 1];
            cq_out[2 * i] = c * cd - s * sd;
            cq_out[2 * i + 1] = s * cd + c * sd;
        } else if (fabs(d[i]) < SG_SMALL_STEP) {
            const double h = d[i], h2 = h * h;
            const double sd = SG_SIN_SMALL(h, h2), cd = SG_COS_SMALL(h2);
            const double c = cq[2 * i], s = cq[2 * i + 1];
            cq_out[2 * i] = c * cd - s * sd;
            cq_out[2 * i + 1] = s * cd + c * sd;
        } else {
            sg_sincos_inl(q_out[i], &cq_out[2 * i], &cq_out[2 * i + 1]);
        }
    }
}

/* cos and sin of every angle coordinate (travels get 1, 0: never read). */
static void fill_trig(const sg_mechanism *m, const double *q, double *cq)
{
    for (int i = 0; i < m->nq; ++i) {
        if (m->coord_is_angle[i]) {
            sg_sincos_inl(q[i], &cq[2 * i], &cq[2 * i + 1]);
        } else {
            cq[2 * i] = 1.0;
            cq[2 * i + 1] = 0.0;
        }
    }
}

/* The full Newton step dq from (q, cq), kept if it lowers the weighted residual *norm: then q, cq, *norm (and
 * jac, unless NULL) take the trial's. A converged position's last step (polish, and a Newton start within the
 * tolerance): the position becomes exact to rounding. */
static void keep_step_if_lower(const sg_mechanism *m, double *q, double *cq, const double *dq, const double *x,
                               const double *cx, const double *c, const double *w, double *norm, double *jac)
{
    const int nq = m->nq;
    double qt[SG_MAX_Q], cqt[2 * SG_MAX_Q], rt[SG_MAX_Q], jt[SG_MAX_Q * SG_MAX_Q];
    shift_trig(m, q, cq, dq, qt, cqt);
    m->residual(qt, cqt, x, cx, c, rt, jt);
    const double nt = weighted_norm(nq, rt, w);
    if (nt < *norm) {
        copy_doubles(q, qt, nq);
        copy_doubles(cq, cqt, 2 * nq);
        if (jac != NULL) copy_doubles(jac, jt, nq * nq);
        *norm = nt;
    }
}

/* Newton's LU of dPhi/dq: the mechanism's own (kernels 'lu_factor', 'lu_solve': nq a literal, the same operations
 * in the same order, so the same bits) where it has them, else the runtime's for any n. */
static inline int lu_factor(const sg_mechanism *m, double *a, int *piv)
{
    return m->lu_factor != NULL ? m->lu_factor(a, piv) : sg_lu_factor(m->nq, a, piv, NULL);
}

static inline void lu_solve(const sg_mechanism *m, const double *lu, const int *piv, double *b)
{
    if (m->lu_solve != NULL)
        m->lu_solve(lu, piv, b);
    else
        sg_lu_solve(m->nq, lu, piv, b);
}

/* Damped Newton on Phi(q, x) = 0 from q (in place), with cq kept in step with q. Converged when every closure
 * equation's residual is below opt->tol times that equation's own loop size: w holds 1 / (size tol) per
 * equation (the 'scales' kernel's sizes, refreshed by the caller). On success jac holds dPhi/dq at the solution
 * and *resid the largest relative residual. */
static int newton(const sg_mechanism *m, double *q, double *cq, const double *x, const double *cx,
                  const double *c, const sg_options *opt, const double *w, int min_iter, double *jac,
                  double *resid)
{
    const int nq = m->nq;
    double r[SG_MAX_Q], lu[SG_MAX_Q * SG_MAX_Q];
    double qt[SG_MAX_Q], cqt[2 * SG_MAX_Q], rt[SG_MAX_Q], dq[SG_MAX_Q], step[SG_MAX_Q];
    int piv[SG_MAX_Q];
    m->residual(q, cq, x, cx, c, r, jac); /* cq: cos, sin of q, from the caller */
    double norm = weighted_norm(nq, r, w);
    for (int it = 0;; ++it) {
        if (!isfinite(norm)) return SG_NO_CONVERGENCE;
        /* min_iter's step (below) is not taken from a start already exact to rounding (the continuation's
         * prediction at fine steps): it could not make the position more accurate */
        if (norm <= 1.0 && (it >= min_iter || norm * opt->tol <= SG_RESID_FLOOR)) {
            *resid = norm * opt->tol;
            return SG_OK;
        }
        copy_doubles(lu, jac, nq * nq);
        if (lu_factor(m, lu, piv) != SG_OK) {
            if (norm <= 1.0) { /* converged already: the step asked for cannot be taken */
                *resid = norm * opt->tol;
                return SG_OK;
            }
            return SG_CANNOT_ASSEMBLE; /* no descent direction */
        }
        if (it >= opt->max_iter) return SG_NO_CONVERGENCE;
        for (int i = 0; i < nq; ++i) dq[i] = -r[i];
        lu_solve(m, lu, piv, dq);
        if (norm <= 1.0) { /* min_iter: a start within the tolerance gets one full step all the same, kept if it
                            * lowers the residual (a prediction within the tolerance is only that accurate; a
                            * step makes it as accurate as a solution Newton reached) */
            keep_step_if_lower(m, q, cq, dq, x, cx, c, w, &norm, jac);
            *resid = norm * opt->tol;
            return SG_OK;
        }
        double lambda = 1.0, nt = 0.0;
        int k;
        for (k = 0; k < 30; ++k) {
            for (int i = 0; i < nq; ++i) step[i] = lambda * dq[i];
            shift_trig(m, q, cq, step, qt, cqt);
            m->residual(qt, cqt, x, cx, c, rt, jac); /* the accepted trial leaves its dPhi/dq in jac */
            nt = weighted_norm(nq, rt, w);
            if (nt < norm) break;
            lambda *= 0.5;
        }
        if (k == 30) return SG_CANNOT_ASSEMBLE; /* the residual has a positive local minimum */
        copy_doubles(q, qt, nq);
        copy_doubles(cq, cqt, 2 * nq);
        copy_doubles(r, rt, nq);
        norm = nt;
    }
}

/* One more full Newton step at a converged position (q, cq in place), kept if it lowers the residual: the
 * position then is exact to rounding, as a closed form's, and its error no longer weighs in the rates' error
 * estimate. Taken only where that estimate would otherwise be above the singular tolerance. */
static void polish(const sg_mechanism *m, double *q, double *cq, const double *x, const double *cx, const double *c,
                   const sg_options *opt, double *resid)
{
    const int nq = m->nq;
    double r[SG_MAX_Q], w[SG_MAX_Q], jac[SG_MAX_Q * SG_MAX_Q], dq[SG_MAX_Q];
    int piv[SG_MAX_Q];
    m->scales(q, cq, x, cx, c, w);
    for (int i = 0; i < nq; ++i) w[i] = 1.0 / w[i];
    m->residual(q, cq, x, cx, c, r, jac);
    double norm = weighted_norm(nq, r, w);
    if (lu_factor(m, jac, piv) != SG_OK) return;
    for (int i = 0; i < nq; ++i) dq[i] = -r[i];
    lu_solve(m, jac, piv, dq);
    keep_step_if_lower(m, q, cq, dq, x, cx, c, w, &norm, NULL);
    *resid = norm;
    (void)opt;
}

/* The five-state Lagrange extrapolation (predict's usual case) in straight lines (csrc/sg_runtime.h
 * sg_lagrange5_*); 0 (nothing written) where two of the angles are equal. */
static int predict5(int nq, const double *x, double *const *hq, double t, double *out)
{
    double den[SG_HISTORY], w[SG_HISTORY];
    if (!sg_lagrange5_den(x, den)) return 0;
    sg_lagrange5_weights(t, x, den, w);
    for (int i = 0; i < nq; ++i) out[i] = SG_LAGRANGE5_VALUE(w, hq, i);
    return 1;
}

/* Lagrange extrapolation in the shaft angle from nh earlier states (newest first, at most SG_HISTORY): of degree
 * four from five (the continuation's step), quadratic from three (after a failed step). The positions alone, no
 * rates: the rates, observables and forces of solved positions can come later, SG_LANES at a time (csrc/sg_simd.h
 * sgv_finish), and the scalar loop solves the same positions to the bit; a block's positions are all
 * predicted from the same five states (solve_block). Measured on the JB1-3 feed's
 * coordinates, the five states' prediction is off by 3.7e-13 at 3600 positions a turn (median; the quintic
 * Hermite predictor from the two newest states' rates, which it replaced: 8.1e-13), 3.8e-9 at 360 (2.8e-12), 5e-5
 * at 72 (5.8e-8): Newton's first step takes the first two to rounding, a second step the last. */
static void predict(int nq, int nh, const double *hphi, double *const *hq, double phi_new, double *out)
{
    if (nh == 5 && predict5(nq, hphi, hq, phi_new, out)) return;
    double w[SG_HISTORY] = {1.0};
    int used = nh;
    for (; used > 1; --used) { /* repeated angles: fall back to a lower order */
        int ok = 1;
        for (int a = 0; a < used && ok; ++a) {
            double num = 1.0, den = 1.0;
            for (int b = 0; b < used; ++b) {
                if (b == a) continue;
                num *= phi_new - hphi[b];
                den *= hphi[a] - hphi[b];
            }
            /* three states: repeated angles (to 1e-14 rad squared); more: the same angle twice */
            if (used <= 3 ? !(fabs(den) > 1e-14) : !(den != 0.0)) ok = 0;
            else w[a] = num / den;
        }
        if (ok) break;
    }
    if (used <= 1) w[0] = 1.0, used = 1;
    for (int i = 0; i < nq; ++i) {
        double v = 0.0;
        for (int a = 0; a < used; ++a) v += w[a] * hq[a][i];
        out[i] = v;
    }
}

static void zero_row(double *v, int n)
{
    for (int i = 0; i < n; ++i) v[i] = 0.0;
}

/* Continuation along the shaft angle: the last solved states (the predictor's history, newest first), the
 * orientation signs of the closing loops at the sweep's first position (kernel 'blocks'), the inputs. */
typedef struct {
    const sg_mechanism *m;
    const sg_options *opt;
    const double *c;
    double *x, *cx;
    int nh;
    double hphi[SG_HISTORY];
    double *hq[SG_HISTORY];   /* newest first: pointers into store, rotated (no copies) */
    double store[SG_HISTORY][SG_MAX_Q];
    double hcq[2 * SG_MAX_Q]; /* cos, sin of the newest state */
    int has_ref;
    double ref[SG_MAX_Q];
    double lscale;             /* the largest loop size (m): what a travel's step is measured against */
    double newton_w[SG_MAX_Q]; /* 1 / (each closure equation's loop size opt->tol): Newton's weights */
    int scale_age;             /* solves since the loop sizes were taken (they move with the travels only) */
} sg_walker;

/* Largest shaft-angle step of the continuation (rad): longer steps between the requested angles are cut. */
#define SG_H_MAX 0.2
/* Smallest: a branch that cannot be followed in steps this short has ended (or met another). */
#define SG_H_MIN 1e-6
/* Largest change of an angle coordinate (rad; a travel: times the largest loop size) that a step may predict
 * or that Newton may add to the prediction: a larger one halves the step. */
#define SG_DQ_MAX 0.5
/* Below this |normalised block determinant| a loop is at its singular position: its sign says nothing. */
#define SG_BLOCK_ZERO 1e-12

static void set_input(sg_walker *w, double ph)
{
    if (w->x[0] == ph) return; /* cos, sin already those of ph */
    w->x[0] = ph;
    sg_sincos_inl(ph, &w->cx[0], &w->cx[1]);
}

static void push(sg_walker *w, double ph, const double *q, const double *cq)
{
    const int nq = w->m->nq;
    double *oldest = w->hq[SG_HISTORY - 1];
    for (int k = SG_HISTORY - 1; k > 0; --k) w->hq[k] = w->hq[k - 1], w->hphi[k] = w->hphi[k - 1];
    w->hq[0] = oldest, w->hphi[0] = ph;
    copy_doubles(w->hq[0], q, nq);
    copy_doubles(w->hcq, cq, 2 * nq);
    if (w->nh < SG_HISTORY) ++w->nh;
}

/* |d| within SG_DQ_MAX for every coordinate (travels against the loop size). */
static inline double change_limit(const sg_walker *w, int k)
{
    return w->m->coord_is_angle[k] ? SG_DQ_MAX : SG_DQ_MAX * w->lscale;
}

static int small_change(const sg_walker *w, const double *d)
{
    for (int k = 0; k < w->m->nq; ++k)
        if (!(fabs(d[k]) <= change_limit(w, k))) return 0;
    return 1;
}

/* Newton at shaft angle ph from q (cq its cos, sin), then the loops' orientation signs against the reference. */
static int solve_at(sg_walker *w, double ph, double *q, double *cq, int min_iter, double *resid)
{
    const sg_mechanism *m = w->m;
    double jac[SG_MAX_Q * SG_MAX_Q], bv[SG_MAX_Q];
    set_input(w, ph);
    if (w->scale_age <= 0) {
        double size[SG_MAX_Q];
        m->scales(q, cq, w->x, w->cx, w->c, size);
        for (int i = 0; i < m->nq; ++i) w->newton_w[i] = (1.0 / size[i]) / w->opt->tol;
        w->scale_age = 16;
    }
    --w->scale_age;
    const int st = newton(m, q, cq, w->x, w->cx, w->c, w->opt, w->newton_w, min_iter, jac, resid);
    if (st != SG_OK || m->nblock == 0) return st;
    m->blocks(jac, bv);
    if (!w->has_ref) {
        for (int k = 0; k < m->nblock; ++k)
            if (!(fabs(bv[k]) > SG_BLOCK_ZERO)) return SG_OK; /* a singular first position sets no reference */
        for (int k = 0; k < m->nblock; ++k) w->ref[k] = bv[k] > 0.0 ? 1.0 : -1.0;
        w->has_ref = 1;
        return SG_OK;
    }
    for (int k = 0; k < m->nblock; ++k)
        if (bv[k] * w->ref[k] < 0.0 && fabs(bv[k]) > SG_BLOCK_ZERO) return SG_BRANCH_JUMP;
    return SG_OK;
}

/* From the newest state to shaft angle phi_t in steps of at most SG_H_MAX, each predicted from the history and
 * corrected by Newton, halved while a step predicts or corrects too much, fails, or lands on another branch;
 * every accepted step joins the history. On success q, cq hold the solution at phi_t. */
static int advance(sg_walker *w, double phi_t, double *q, double *cq, double *resid)
{
    const int nq = w->m->nq;
    double cur = w->hphi[0];
    const double total = phi_t - cur;
    if (total == 0.0) { /* a repeated angle: the same solution (Newton only confirms it) */
        copy_doubles(q, w->hq[0], nq);
        copy_doubles(cq, w->hcq, 2 * nq);
        return solve_at(w, phi_t, q, cq, 0, resid);
    }
    const double dir = total > 0.0 ? 1.0 : -1.0;
    double h = fmin(fabs(total), SG_H_MAX);
    int last = SG_NO_CONVERGENCE;
    int quartic = 1; /* the quartic predictor until a step fails: then the quadratic one */
    for (;;) {
        const double next = h >= fabs(phi_t - cur) ? phi_t : cur + dir * h;
        double d[SG_MAX_Q], qp[SG_MAX_Q];
        const int states = quartic ? SG_HISTORY : 3;
        predict(nq, w->nh < states ? w->nh : states, w->hphi, w->hq, next, qp);
        for (int k = 0; k < nq; ++k) d[k] = qp[k] - w->hq[0][k];
        if (small_change(w, d)) {
            shift_trig(w->m, w->hq[0], w->hcq, d, q, cq);
            int st = solve_at(w, next, q, cq, quartic, resid); /* from the quartic prediction: a step at least */
            if (st == SG_OK) {
                for (int k = 0; k < nq; ++k) d[k] = q[k] - qp[k];
                if (!small_change(w, d)) st = SG_BRANCH_JUMP; /* somewhere else than where the step leads */
            }
            if (st == SG_OK) {
                push(w, next, q, cq);
                if (next == phi_t) return SG_OK;
                cur = next;
                h = fmin(2.0 * h, SG_H_MAX);
                continue;
            }
            last = st;
        }
        quartic = 0;
        h *= 0.5;
        if (h < SG_H_MIN) return last;
    }
}

/* The largest shaft-angle span from the newest state to the last position of a block (rad): the quartic
 * predictor's error grows as the fifth power of the distance (measured on the JB1-3 feed at 3600 positions a
 * turn, 0.1° apart: 3.7e-13 one step ahead, ~3e-10 eight steps ahead), and one Newton step takes the latter to
 * rounding as it takes the former. */
#define SG_BLOCK_SPAN 0.1

/* Up to SG_BLOCK positions from solving index k on, each predicted (the quartic) from the same history and solved
 * by Newton on its own: the positions of one direction, finite inputs and no farther than SG_BLOCK_SPAN from the
 * newest state. Each is checked as advance() checks a step (a prediction and a correction no larger than a step
 * may make, assembled, on the history's branch); the ones before the first that fails join the history in order.
 * Where simd and the mechanism has the SIMD Newton, that predicts, solves and checks SG_LANES lanes at a time, and
 * whatever lane it leaves takes the scalar course here (the same values either way). Returns the count of
 * accepted positions, their solutions in b; 0 where fewer than two positions make a block or the first fails:
 * the caller's step-by-step continuation then takes position k, and it takes the position that failed (b->count
 * tells whether one did). The loops' weights are refreshed at the newest state when they are due. */
static int solve_block(sg_walker *w, sg_block *b, size_t k, size_t n, const size_t *order, const double *phi,
                       const double *omega, const double *alpha, int simd)
{
    const sg_mechanism *m = w->m;
    const int nq = m->nq, nx = m->nx;
    b->count = 0;
    if (w->nh < SG_HISTORY || (m->nblock > 0 && !w->has_ref) || !(w->hphi[0] != w->hphi[1])) return 0;
    const double dir = w->hphi[0] > w->hphi[1] ? 1.0 : -1.0;
    double prev = w->hphi[0];
    int count = 0;
    for (; count < SG_BLOCK && k + (size_t)count < n; ++count) { /* the block's positions */
        const size_t i = order ? order[k + count] : k + count;
        const double ph = phi[i];
        if (!isfinite(ph + omega[i] + alpha[i]) || !((ph - prev) * dir > 0.0) ||
            !(fabs(ph - w->hphi[0]) <= SG_BLOCK_SPAN))
            break;
        b->x[count][0] = prev = ph;
    }
    if (count < 2) return 0; /* coarse steps: the step-by-step continuation */
    b->count = count;
    for (int l = 0; l < SG_BLOCK; ++l) { /* inputs (a short block's spare lanes: its last position's) */
        if (l >= count) b->x[l][0] = b->x[count - 1][0];
        sg_sincos_inl(b->x[l][0], &b->cx[l][0], &b->cx[l][1]);
        for (int j = 1; j < nx; ++j) {
            b->x[l][j] = w->x[j];
            b->cx[l][2 * j] = w->cx[2 * j];
            b->cx[l][2 * j + 1] = w->cx[2 * j + 1];
        }
    }
    if (w->scale_age <= 0) { /* solve_at's refresh, at the newest state (w->x: its inputs) */
        double size[SG_MAX_Q];
        m->scales(w->hq[0], w->hcq, w->x, w->cx, w->c, size);
        for (int j = 0; j < nq; ++j) w->newton_w[j] = (1.0 / size[j]) / w->opt->tol;
        w->scale_age = 16;
    }
    w->scale_age -= count;
    int solved = 0;
    if (simd && m->newton_simd != NULL) {
        for (int h = 0; h < SG_HISTORY; ++h) b->hphi[h] = w->hphi[h], b->hq[h] = w->hq[h];
        b->hcq = w->hcq;
        for (int j = 0; j < nq; ++j) b->lim[j] = change_limit(w, j);
        for (int f = 0; f < count; f += SG_LANES) solved |= m->newton_simd(m, b, f, w->c, w->opt, w->newton_w) << f;
    }
    int got = 0;
    for (; got < count; ++got) {
        const int l = got;
        if (!(solved >> l & 1)) { /* the scalar course: predict, step, Newton, check */
            double qp[SG_MAX_Q], d[SG_MAX_Q], jac[SG_MAX_Q * SG_MAX_Q];
            predict(nq, SG_HISTORY, w->hphi, w->hq, b->x[l][0], qp);
            for (int j = 0; j < nq; ++j) d[j] = qp[j] - w->hq[0][j];
            if (!small_change(w, d)) break;
            shift_trig(m, w->hq[0], w->hcq, d, b->q[l], b->cq[l]);
            if (newton(m, b->q[l], b->cq[l], b->x[l], b->cx[l], w->c, w->opt, w->newton_w, 1, jac, &b->resid[l]) !=
                SG_OK)
                break;
            for (int j = 0; j < nq; ++j) d[j] = b->q[l][j] - qp[j];
            if (!small_change(w, d)) break;
            if (m->nblock > 0) m->blocks(jac, b->bv[l]);
        }
        int jump = 0;
        for (int j = 0; j < m->nblock; ++j)
            jump |= b->bv[l][j] * w->ref[j] < 0.0 && fabs(b->bv[l][j]) > SG_BLOCK_ZERO;
        if (jump) break;
    }
    for (int l = got > SG_HISTORY ? got - SG_HISTORY : 0; l < got; ++l) /* the history keeps the newest five */
        push(w, b->x[l][0], b->q[l], b->cq[l]);
    if (got > 0) { /* the walker's input: the last accepted position's */
        w->x[0] = b->x[got - 1][0];
        w->cx[0] = b->cx[got - 1][0];
        w->cx[1] = b->cx[got - 1][1];
    }
    return got;
}

/* The rates and observables at a solved position: the joint motion kernel where every observable is wanted (want
 * NULL), else the rates kernel and the wanted groups of observables (kernel 'observe': want's first ngroup
 * flags; want[ngroup], whether the coordinates are read, matters to the SIMD loop only), which compute the same
 * values to the bit (derive.kernels: the joint kernel's own statements) and fail alike: the rates test q, q', q'',
 * each group its own observables, and a group that could be non-finite from finite rates and constants is always
 * wanted (descriptor group_always; sg_sweep_designs). The observables of a group not wanted are left as they
 * are. */
static inline int motion_at(const sg_mechanism *m, const unsigned char *want, const double *q, const double *cq,
                            const double *x, const double *cx, const double *xd, const double *xdd, const double *c,
                            double *qd, double *qdd, double *obs, double *cond)
{
    if (want == NULL) return m->motion(q, cq, x, cx, xd, xdd, c, qd, qdd, obs, cond);
    int st = m->rates(q, cq, x, cx, xd, xdd, c, qd, qdd, cond);
    for (int g = 0; g < m->ngroup && st == SG_OK; ++g)
        if (want[g]) st = m->observe(q, cq, x, cx, xd, xdd, c, qd, qdd, g, obs);
    return st;
}

/* The rates, observables and (fi not NULL) forces at a solved position (qi, cq: its coordinates, their cos, sin;
 * resid: Newton's last relative residual), and the rates' estimated relative error in *est: the scalar loop's step
 * after Newton, and the deferred loop's for a lane the SIMD finish does not vouch for. A position whose estimate
 * is above the singular tolerance gets one more Newton step (polish) first; the continuation's history keeps the
 * state Newton left (the deferred loop has solved the next positions from it already). Returns the position's
 * status. */
static int finish_position(sg_walker *w, const unsigned char *want, const double *x, const double *cx,
                           const double *xd, const double *xdd, const double *gv, const double *ld, double *qi,
                           double *cq, double resid, double *qdi, double *qddi, double *oi, double *fi,
                           double *est)
{
    const sg_mechanism *m = w->m;
    const sg_options *opt = w->opt;
    const double *c = w->c;
    double cond[SG_NCOND] = {1.0, 1.0, 1.0};
    *est = 0.0;
    int st = motion_at(m, want, qi, cq, x, cx, xd, xdd, c, qdi, qddi, oi, cond);
    if (st == SG_SINGULAR) {
        *est = INFINITY; /* the velocity solve itself is singular */
    } else if (st == SG_OK) {
        *est = sg_newton_error(cond, resid);
        if (!(*est <= opt->singular_tol) && resid > SG_ROUND_RESID) { /* Newton's last residual */
            polish(m, qi, cq, x, cx, c, opt, &resid);
            st = motion_at(m, want, qi, cq, x, cx, xd, xdd, c, qdi, qddi, oi, cond);
            if (st == SG_SINGULAR) *est = INFINITY;
            else *est = sg_newton_error(cond, resid);
        }
        if (st == SG_OK && !(*est <= opt->singular_tol) && !opt->keep_singular) st = SG_SINGULAR;
    }
    if (st == SG_OK && fi != NULL) st = m->forces(qi, cq, x, cx, xd, c, oi, gv, ld, fi);
    return st;
}

/* Position i's status and error estimate; a failed position's rows zeroed. Returns 1 where it failed. */
static size_t settle(const sg_mechanism *m, size_t i, int st, double est, double *q, double *qd, double *qdd,
                     double *obs, double *err, double *frc, int *status)
{
    const int nq = m->nq;
    status[i] = st;
    if (err) err[i] = st == SG_OK || st == SG_SINGULAR ? est : 0.0; /* a force-matrix singularity: est ok */
    if (st == SG_OK) return 0;
    zero_row(q + i * (size_t)nq, nq);
    zero_row(qd + i * (size_t)nq, nq);
    zero_row(qdd + i * (size_t)nq, nq);
    zero_row(obs + i * (size_t)m->nobs, m->nobs);
    if (frc != NULL) zero_row(frc + i * (size_t)m->nfo, m->nfo);
    return 1;
}

/* Lane l of L: position i solved at q (cq its cos, sin) with inputs x, cx, rates xd, xdd and Newton's last
 * relative residual. */
static inline void put_lane(const sg_mechanism *m, sg_lanes *L, int l, size_t i, const double *q, const double *cq,
                     const double *x, const double *cx, const double *xd, const double *xdd, double resid)
{
    L->index[l] = i;
    copy_doubles(L->q[l], q, m->nq);
    copy_doubles(L->cq[l], cq, 2 * m->nq);
    copy_doubles(L->x[l], x, m->nx);
    copy_doubles(L->cx[l], cx, 2 * m->nx);
    copy_doubles(L->xd[l], xd, m->nx);
    copy_doubles(L->xdd[l], xdd, m->nx);
    L->resid[l] = resid;
}

/* The deferred loop's block of solved positions (L->count of them) through the SIMD finish, then the scalar step
 * for every lane it does not vouch for. Returns the failures; L is empty after. */
static size_t finish_lanes(sg_walker *w, sg_lanes *L, const unsigned char *want, const double *gv,
                           const double *loads, const double *no_loads, double *q, double *qd, double *qdd,
                           double *obs, double *err, double *frc, int *status)
{
    const sg_mechanism *m = w->m;
    const int nq = m->nq, k = L->count - 1;
    for (int l = L->count; l < SG_LANES; ++l) /* a short block: its last position again */
        put_lane(m, L, l, L->index[k], L->q[k], L->cq[k], L->x[k], L->cx[k], L->xd[k], L->xdd[k], L->resid[k]);
    const int done = m->finish_simd(m, L, w->c, w->opt, gv, loads, qd, qdd, obs, frc, want);
    size_t failures = 0;
    for (int l = 0; l < L->count; ++l) {
        const size_t i = L->index[l];
        double est = L->est[l];
        int st = SG_OK;
        if (!(done >> l & 1)) {
            st = finish_position(w, want, L->x[l], L->cx[l], L->xd[l], L->xdd[l], gv,
                                 loads ? loads + i * (size_t)m->nload : no_loads, q + i * (size_t)nq, L->cq[l],
                                 L->resid[l], qd + i * (size_t)nq, qdd + i * (size_t)nq,
                                 obs + i * (size_t)m->nobs, frc ? frc + i * (size_t)m->nfo : NULL, &est);
        }
        failures += settle(m, i, st, est, q, qd, qdd, obs, err, frc, status);
    }
    L->count = 0;
    return failures;
}

/* The sweep of the request r: kinematics at every position, then (r->frc not NULL) the forces from the same
 * solution. r->want (NULL: every observable) flags the groups of observables to compute (a kinematic sweep that
 * keeps a few outputs: sg_sweep_designs), in every loop. A closed form goes to the closed-form loops (csrc/sg_runtime.h
 * sg_closed_sweep: the mechanism's own with its kernels inlined, or, opt->generic, the same loop through the
 * descriptor's kernels; csrc/sg_simd.h sgv_closed_sweep SG_LANES positions at a time); this function's own loop is
 * Newton's continuation. */
static size_t sweep(const sg_mechanism *m, const sg_request *r)
{
    const size_t n = r->n, *order = r->order;
    const double *phi = r->phi, *omega = r->omega, *alpha = r->alpha, *held = r->held, *p = r->p;
    const double *q_guess = r->q_guess, *gv = r->gv, *loads = r->loads;
    const int *branch = r->branch;
    const sg_options *opt = r->opt;
    double *q = r->q, *qd = r->qd, *qdd = r->qdd, *obs = r->obs, *err = r->err, *frc = r->frc;
    int *status = r->status;
    const unsigned char *want = r->want;
    const int nq = m->nq, nx = m->nx, nobs = m->nobs, nfo = m->nfo;
    double no_loads[SG_MAX_LOAD]; /* zeroed below for a force sweep without loads only: 4 kB a call otherwise */
    SG_ASSERT(phi && omega && alpha && p && branch && q_guess && opt && q && qd && qdd && obs && status);
    SG_ASSERT(nx == 1 || held);
    if (nq > SG_MAX_Q || nx > SG_MAX_Q || nx < 1 || m->nc > SG_MAX_C || m->nload > SG_MAX_LOAD ||
        m->nblock > SG_MAX_Q || !(opt->tol > 0.0) || opt->max_iter < 1 || !(opt->singular_tol > 0.0) ||
        (frc != NULL && gv == NULL)) {
        for (size_t i = 0; i < n; ++i) status[i] = SG_BAD_ARGUMENT;
        return n;
    }
    if (m->closed != NULL && !opt->newton_only) { /* the closed-form loops */
        if (opt->generic || m->sweep == NULL) return sg_closed_sweep(m, r, sg_descriptor_kernels(m));
        if (!opt->scalar && sg_simd_width(m) > 1) return m->sweep_simd(m, r); /* SG_LANES positions at a time */
        return m->sweep(m, r);
    }
    if (frc != NULL && loads == NULL)
        for (int k = 0; k < m->nload; ++k) no_loads[k] = 0.0;
    double c[SG_MAX_C];
    m->constants(p, c);
    if (frc != NULL || m->rates == NULL || m->observe == NULL) want = NULL; /* forces read every observable */
    for (int k = 0; k < m->nc && want != NULL; ++k)
        if (!isfinite(c[k])) want = NULL; /* an observable of a constant alone may be all that fails: all of them */
    double x[SG_MAX_Q], cx[2 * SG_MAX_Q], xd[SG_MAX_Q], xdd[SG_MAX_Q];
    for (int k = 1; k < nx; ++k) {
        x[k] = held[k - 1];
        cx[2 * k] = cos(x[k]);
        cx[2 * k + 1] = sin(x[k]);
        xd[k] = 0.0;
        xdd[k] = 0.0;
    }
    /* Newton's positions now, their rates, observables and forces SG_LANES at a time by the SIMD finish */
    const int deferred = m->finish_simd != NULL && !opt->scalar && sg_simd_width(m) > 1 &&
                         m->finish_simd(m, NULL, c, opt, gv, loads, qd, qdd, obs, frc, want);
    sg_lanes lanes;
    lanes.count = 0;
    sg_walker w;
    w.m = m, w.opt = opt, w.c = c, w.x = x, w.cx = cx, w.nh = 0, w.has_ref = 0, w.lscale = 0.0, w.scale_age = 0;
    for (int k = 0; k < SG_HISTORY; ++k) w.hq[k] = w.store[k];
    x[0] = NAN; /* no angle's cos, sin yet */
    if (m->closed != NULL && m->nblock > 0) {
        /* Newton on a mechanism with a closed form: the loops' orientation signs are those of the declared
         * branch, taken from the closed form at the first position (in solving order) where it assembles */
        for (size_t k = 0; k < n && !w.has_ref; ++k) {
            const size_t i = order ? order[k] : k;
            double qr[SG_MAX_Q], cqr[2 * SG_MAX_Q], r[SG_MAX_Q], jac[SG_MAX_Q * SG_MAX_Q], bv[SG_MAX_Q], err[2];
            if (!isfinite(phi[i])) continue;
            set_input(&w, phi[i]);
            if (m->closed(x, cx, c, branch, qr, cqr, err) != SG_OK) continue;
            m->residual(qr, cqr, x, cx, c, r, jac);
            m->blocks(jac, bv);
            int ok = 1;
            for (int b = 0; b < m->nblock; ++b) ok &= fabs(bv[b]) > SG_BLOCK_ZERO;
            if (!ok) continue;
            for (int b = 0; b < m->nblock; ++b) w.ref[b] = bv[b] > 0.0 ? 1.0 : -1.0;
            w.has_ref = 1;
        }
    }
    size_t failures = 0;
    int prev_failed = 0;
    const int simd_newton = !opt->scalar && sg_simd_width(m) > 1;
    size_t step_at = n; /* a position a block failed at: the step-by-step continuation takes it */
    sg_block blk;
    int block_got = 0, block_next = 0; /* the block's accepted positions, and the next one the loop takes */
    for (size_t k = 0; k < n; ++k) {
        if (block_next == block_got && !prev_failed && k != step_at) { /* SG_BLOCK from one history */
            block_got = solve_block(&w, &blk, k, n, order, phi, omega, alpha, simd_newton);
            block_next = 0;
            if (block_got < blk.count) step_at = k + (size_t)block_got;
        }
        const size_t i = order ? order[k] : k;
        SG_ASSERT(i < n);
        double *qi = q + i * (size_t)nq, *qdi = qd + i * (size_t)nq, *qddi = qdd + i * (size_t)nq;
        double *oi = obs + i * (size_t)nobs;
        double cq_own[2 * SG_MAX_Q], *cq = cq_own;
        double resid = 0.0; /* the position's relative accuracy (Newton's last relative residual) */
        int st = SG_OK;
        const double ph = phi[i];
        xd[0] = omega[i];
        xdd[0] = alpha[i];
        const int from_block = block_next < block_got;
        if (from_block) { /* solved in the block (its inputs finite; the history already holds it) */
            const int l = block_next++;
            copy_doubles(qi, blk.q[l], nq);
            cq = blk.cq[l];
            resid = blk.resid[l];
            x[0] = blk.x[l][0], cx[0] = blk.cx[l][0], cx[1] = blk.cx[l][1];
        } else {
            if (!isfinite(ph + omega[i] + alpha[i])) st = SG_NAN_INPUT;
            set_input(&w, ph);
        }
        if (!from_block && st == SG_OK) {
            if (w.nh > 0 && !prev_failed) {
                st = advance(&w, ph, qi, cq, &resid);
            } else { /* first position, or after a failure: the closed form where it assembles, else the last
                      * solution or the guess; the orientation signs are checked against the first position's */
                int have = 0, closed_st = SG_OK;
                if (m->closed != NULL) {
                    double err[2]; /* Newton's residual says how exact its solution is */
                    closed_st = m->closed(x, cx, c, branch, qi, cq, err);
                    have = closed_st == SG_OK;
                }
                if (!have && w.nh > 0) {
                    copy_doubles(qi, w.hq[0], nq);
                    copy_doubles(cq, w.hcq, 2 * nq);
                } else if (!have) {
                    copy_doubles(qi, q_guess, nq);
                    fill_trig(m, qi, cq);
                }
                w.scale_age = 0; /* a fresh start takes the loop sizes anew */
                if (w.nh == 0) { /* the loop sizes at the start: the scale of a travel's step */
                    double sc[SG_MAX_Q];
                    m->scales(qi, cq, x, cx, c, sc);
                    for (int j = 0; j < nq; ++j)
                        if (isfinite(sc[j]) && sc[j] > w.lscale) w.lscale = sc[j];
                    if (!(w.lscale > 0.0)) w.lscale = 1.0;
                }
                if (!have && m->closed != NULL && !w.has_ref)
                    st = closed_st; /* the declared branch assembles nowhere in the sweep: nothing to follow */
                else
                    st = solve_at(&w, ph, qi, cq, 0, &resid);
                if (st == SG_BRANCH_JUMP && !have && m->closed != NULL)
                    st = closed_st; /* the declared branch does not assemble here: Newton found another */
                if (st == SG_OK) {
                    w.nh = 0; /* the history restarts here */
                    push(&w, ph, qi, cq);
                }
            }
            prev_failed = st != SG_OK;
        }
        if (st == SG_OK && deferred) { /* the rates, observables and forces later, in a block of SG_LANES */
            put_lane(m, &lanes, lanes.count++, i, qi, cq, x, cx, xd, xdd, resid);
            if (lanes.count == SG_LANES)
                failures += finish_lanes(&w, &lanes, want, gv, loads, no_loads, q, qd, qdd, obs, err, frc, status);
            continue;
        }
        double est = 0.0;
        if (st == SG_OK)
            st = finish_position(&w, want, x, cx, xd, xdd, gv, loads ? loads + i * (size_t)m->nload : no_loads,
                                 qi, cq, resid, qdi, qddi, oi, frc ? frc + i * (size_t)nfo : NULL, &est);
        failures += settle(m, i, st, est, q, qd, qdd, obs, err, frc, status);
    }
    if (lanes.count > 0)
        failures += finish_lanes(&w, &lanes, want, gv, loads, no_loads, q, qd, qdd, obs, err, frc, status);
    return failures;
}

/* Sweep a mechanism over r->n shaft angles in one call: positions, velocities, accelerations, every observable
 * and, where r->gv is given, every force output (sg_abi.h sg_request says what each field holds). The positions
 * are solved in the order r->order (NULL: as given) and written to their own rows. Returns the number of
 * positions whose status is not SG_OK (or n with every status SG_BAD_ARGUMENT on bad sizes). A singular force
 * matrix gives SG_SINGULAR at that position. */
size_t sg_sweep(const sg_mechanism *m, const sg_request *r)
{
    sg_request s = *r; /* the runtime's own fields (want, trig, cols) are not the caller's to set */
    if (s.gv == NULL) s.loads = NULL, s.frc = NULL;
    s.want = NULL, s.trig = NULL, s.cols = NULL;
    return sweep(m, &s);
}

/* Batched designs ------------------------------------------------------------------------------------------
 * Flat columns of one position: q (nq), qd (nq), qdd (nq), then obs (nobs); column j of position i lives at
 * col_base(j)[i * width(j) + offset(j)] in the scratch sweep arrays. */
typedef struct {
    double *q, *qd, *qdd, *obs;
    int nq, nobs;
    const sg_columns *direct; /* not NULL: these columns live in their own arrays (the SIMD loop wrote them) */
} sg_scratch;

/* The index of flat column j among s->direct's, -1 where it is in the rows. */
static inline int direct_index(const sg_scratch *s, int j)
{
    for (int k = 0; s->direct != NULL && k < s->direct->n; ++k)
        if (s->direct->col[k] == j) return k;
    return -1;
}

static inline double *col_ptr(const sg_scratch *s, int j, size_t i)
{
    const int nq = s->nq;
    const int k = direct_index(s, j);
    if (k >= 0) return s->direct->dst[k] + i;
    if (j < nq) return s->q + i * (size_t)nq + (size_t)j;
    if (j < 2 * nq) return s->qd + i * (size_t)nq + (size_t)(j - nq);
    if (j < 3 * nq) return s->qdd + i * (size_t)nq + (size_t)(j - 2 * nq);
    return s->obs + i * (size_t)s->nobs + (size_t)(j - 3 * nq);
}

/* The distance between a column's entries of two successive positions (a position's row). */
static inline size_t col_step(const sg_scratch *s, int j)
{
    if (direct_index(s, j) >= 0) return 1;
    return (size_t)(j < 3 * s->nq ? s->nq : s->nobs);
}

/* numpy's float modulo (the sign of the divisor), as np.unwrap computes it */
static inline double py_mod(double a, double b)
{
    double r = fmod(a, b);
    if (r != 0.0) {
        if ((b < 0.0) != (r < 0.0)) r += b;
    } else {
        r = copysign(0.0, b);
    }
    return r;
}

/* sewgen.mechanism.continuous_angles on one angle column of one design's sweep (every position solved): no 2π
 * jumps along the solving order, the first position in (−π, π]; whole turns only, as np.unwrap does them. */
static void continuous_column(double *v, size_t step, size_t n, const size_t *order, int known)
{
    if (n == 0) return;
    const double pi = 3.14159265358979323846;
#define SG_AT(k) v[(order ? order[k] : (k)) * step] /* the k-th position in solving order */
    const double first = SG_AT(0);
    int need = known || !(first > -pi && first <= pi);
    for (size_t k = 1; k < n && !need; ++k) need = fabs(SG_AT(k) - SG_AT(k - 1)) > pi;
    if (!need) return;
    /* one pass: each value's correction, then the start's shift (the same two roundings as two passes) */
    const double shift = SG_TWO_PI * ceil((first - pi) / SG_TWO_PI);
    double corr = 0.0, prev = first;
    SG_AT(0) = first - shift;
    for (size_t k = 1; k < n; ++k) {
        const double raw = SG_AT(k), dd = raw - prev;
        if (!(fabs(dd) < pi)) { /* a jump (np.unwrap's correction; the modulo only where it is used) */
            double ddmod = py_mod(dd + pi, SG_TWO_PI) - pi;
            if (ddmod == -pi && dd > 0.0) ddmod = pi;
            corr += ddmod - dd;
        }
        prev = raw;
        SG_AT(k) = (raw + corr) - shift;
    }
#undef SG_AT
}

/* The largest step |v[k] − v[k−1]| (k = 1..n−1) of a column of stride step, NaN steps skipped (they never exceed
 * anything, as in continuous_column's test): four steps at a time with four maxima, no branch a position. */
static double largest_step(const double *v, size_t step, size_t n)
{
    double m0 = 0.0, m1 = 0.0, m2 = 0.0, m3 = 0.0, prev = v[0];
    size_t k = 1;
#if defined(__SSE2__)
    if (step == 1) { /* a column of its own (sg_columns): two steps an instruction; maxpd is the same ternary */
        const __m128d mag = _mm_castsi128_pd(_mm_set1_epi64x(0x7fffffffffffffffLL));
        __m128d ma = _mm_setzero_pd(), mb = _mm_setzero_pd();
        for (; k + 4 <= n; k += 4) {
            const __m128d da = _mm_and_pd(_mm_sub_pd(_mm_loadu_pd(v + k), _mm_loadu_pd(v + k - 1)), mag);
            const __m128d db = _mm_and_pd(_mm_sub_pd(_mm_loadu_pd(v + k + 2), _mm_loadu_pd(v + k + 1)), mag);
            ma = _mm_max_pd(da, ma);
            mb = _mm_max_pd(db, mb);
        }
        double lanes[4];
        _mm_storeu_pd(lanes, ma);
        _mm_storeu_pd(lanes + 2, mb);
        m0 = lanes[0], m1 = lanes[1], m2 = lanes[2], m3 = lanes[3];
        prev = v[k - 1];
    }
#endif
    for (; k + 4 <= n; k += 4) {
        const double *r = v + k * step;
        const double x0 = r[0], x1 = r[step], x2 = r[2 * step], x3 = r[3 * step];
        const double d0 = fabs(x0 - prev), d1 = fabs(x1 - x0), d2 = fabs(x2 - x1), d3 = fabs(x3 - x2);
        m0 = d0 > m0 ? d0 : m0;
        m1 = d1 > m1 ? d1 : m1;
        m2 = d2 > m2 ? d2 : m2;
        m3 = d3 > m3 ? d3 : m3;
        prev = x3;
    }
    for (; k < n; ++k) {
        const double x = v[k * step], d = fabs(x - prev);
        m0 = d > m0 ? d : m0;
        prev = x;
    }
    m0 = m1 > m0 ? m1 : m0;
    m2 = m3 > m2 ? m3 : m2;
    return m2 > m0 ? m2 : m0;
}

/* The largest step of each of the ncol columns v[c] (the same stride, rows of one array) over n positions, NaN
 * steps skipped as largest_step skips them: four columns a pass over the rows, their values of a row read
 * together (SSE2: two columns an instruction; maxpd is the same ternary), where a column at a time walked the
 * rows (kB apart) once per column. */
#define SG_ROW_SCAN 32
static void largest_steps(double *const *v, int ncol, size_t step, size_t n, double *largest)
{
    int c = 0;
#if defined(__SSE2__)
    const __m128d mag = _mm_castsi128_pd(_mm_set1_epi64x(0x7fffffffffffffffLL));
    for (; c < ncol; c += 4) { /* a last pass of fewer than four repeats its last column */
        const int last = ncol - 1;
        const double *a = v[c], *b = v[c + 1 <= last ? c + 1 : last], *e = v[c + 2 <= last ? c + 2 : last];
        const double *f = v[c + 3 <= last ? c + 3 : last];
        __m128d p0 = _mm_set_pd(b[0], a[0]), p1 = _mm_set_pd(f[0], e[0]);
        __m128d m0 = _mm_setzero_pd(), m1 = _mm_setzero_pd();
        for (size_t k = 1, at = step; k < n; ++k, at += step) {
            const __m128d x0 = _mm_set_pd(b[at], a[at]), x1 = _mm_set_pd(f[at], e[at]);
            m0 = _mm_max_pd(_mm_and_pd(_mm_sub_pd(x0, p0), mag), m0);
            m1 = _mm_max_pd(_mm_and_pd(_mm_sub_pd(x1, p1), mag), m1);
            p0 = x0, p1 = x1;
        }
        double four[4];
        _mm_storeu_pd(four, m0);
        _mm_storeu_pd(four + 2, m1);
        for (int k = 0; k < 4 && c + k < ncol; ++k) largest[c + k] = four[k];
    }
#endif
    for (; c < ncol; ++c) largest[c] = largest_step(v[c], step, n);
}

/* continuous_column on columns cols[0..ncol) (offset by add). In position order each column is first scanned
 * for a reason to change it (a start outside (−π, π] or a step over π: largest_step, or largest_steps for up to
 * SG_ROW_SCAN columns of one array's rows at once), and only such a column is made continuous; a solving order
 * other than the positions' takes continuous_column's own test. */
static void continuous_columns(const sg_scratch *s, int ncol, const int *cols, int add, size_t n,
                               const size_t *order)
{
    const double pi = 3.14159265358979323846;
    for (int c = 0; c < ncol; ++c) {
        const int j = cols[c] + add;
        double *v = col_ptr(s, j, 0);
        const size_t step = col_step(s, j);
        if (order == NULL && n > 0) {
            if (step > 1) { /* this and the next row columns of the same array: one pass over their rows */
                double *run[SG_ROW_SCAN], largest[SG_ROW_SCAN];
                int count = 0;
                while (c + count < ncol && count < SG_ROW_SCAN) {
                    const int jj = cols[c + count] + add;
                    if (col_step(s, jj) != step || (jj < 3 * s->nq) != (j < 3 * s->nq)) break;
                    run[count++] = col_ptr(s, jj, 0);
                }
                largest_steps(run, count, step, n, largest);
                for (int r = 0; r < count; ++r)
                    if (!(run[r][0] > -pi && run[r][0] <= pi && !(largest[r] > pi)))
                        continuous_column(run[r], step, n, NULL, 1);
                c += count - 1;
                continue;
            }
            if (v[0] > -pi && v[0] <= pi && !(largest_step(v, step, n) > pi)) continue;
        }
        continuous_column(v, step, n, order, order == NULL && n > 0); /* in position order: known to need it */
    }
}

/* dst[i] = v[i step] for i < n, four at a time. */
static void copy_column(const double *v, size_t step, size_t n, double *dst)
{
    size_t i = 0;
    for (; i + 4 <= n; i += 4, v += 4 * step) {
        const double a = v[0], b = v[step], c = v[2 * step], d = v[3 * step];
        dst[i] = a, dst[i + 1] = b, dst[i + 2] = c, dst[i + 3] = d;
    }
    for (; i < n; ++i, v += step) dst[i] = *v;
}

/* One reduction of one design over its n positions: kind (SG_RED_*), column a, and b >= 0 for the norm
 * sqrt(a² + b²) of two columns (a point's speed or acceleration). *idx: the first position of the extremum
 * (min, max, absmax) in the caller's order, -1 for the others. */
static double reduce_column(const sg_scratch *s, size_t n, int kind, int a, int b, long long *idx)
{
    double acc = kind == SG_RED_MIN ? INFINITY : (kind == SG_RED_MAX ? -INFINITY : 0.0);
    long long at = -1;
    const double *va = col_ptr(s, a, 0), *vb = b >= 0 ? col_ptr(s, b, 0) : NULL;
    const size_t sa = col_step(s, a), sb = b >= 0 ? col_step(s, b) : 0;
    for (size_t i = 0; i < n; ++i) {
        double v = va[i * sa];
        if (vb != NULL) {
            const double w = vb[i * sb];
            v = sqrt(v * v + w * w);
        }
        switch (kind) {
        case SG_RED_MIN:
            if (v < acc || at < 0) acc = v, at = (long long)i;
            break;
        case SG_RED_MAX:
            if (v > acc || at < 0) acc = v, at = (long long)i;
            break;
        case SG_RED_ABSMAX:
            if (fabs(v) > acc || at < 0) acc = fabs(v), at = (long long)i;
            break;
        case SG_RED_RMS:
            acc += v * v;
            break;
        default:
            acc += v;
            break;
        }
    }
    *idx = kind <= SG_RED_ABSMAX ? at : -1;
    if (kind == SG_RED_RMS) return n ? sqrt(acc / (double)n) : NAN;
    if (kind == SG_RED_MEAN) return n ? acc / (double)n : NAN;
    return n ? acc : NAN;
}

size_t sg_sweep_designs(const sg_mechanism *m, const sg_request *r)
{
    const size_t nd = r->nd, n = r->n;
    const double *held = r->held, *p = r->p;
    const int *branch = r->branch, *angle_cols = r->angle_cols, *sel = r->sel, *red = r->red;
    const size_t *order = r->order;
    const int ncheck = r->ncheck, nangle = r->nangle, nsel = r->nsel, nred = r->nred;
    double *out = r->out, *red_val = r->red_val, *work = r->work;
    const size_t out_stride = r->out_stride, red_stride = r->red_stride;
    long long *red_idx = r->red_idx, *first_bad = r->first_bad, *nbad = r->nbad, *last_bad = r->last_bad;
    int *work_status = r->work_status, *status = r->design_status;
    const int nq = m->nq, nobs = m->nobs, nx = m->nx, npar = m->np, nb = m->nbranch;
    const int width = 3 * nq + nobs;
    SG_ASSERT(r->phi && r->omega && r->alpha && p && r->q_guess && r->opt && work && work_status && status && first_bad);
    SG_ASSERT(nb == 0 || branch);
    SG_ASSERT(nx == 1 || held);
    SG_ASSERT(nsel == 0 || (sel && out));
    SG_ASSERT(nred == 0 || (red && red_val && red_idx));
    sg_scratch s;
    s.nq = nq, s.nobs = nobs, s.direct = NULL;
    s.q = work, s.qd = work + n * (size_t)nq, s.qdd = work + 2 * n * (size_t)nq, s.obs = work + 3 * n * (size_t)nq;
    double *err = work + n * (size_t)width;
    int bad_args = nq > SG_MAX_Q || m->nc > SG_MAX_C || ncheck > m->nc || nangle < 0 || nsel < 0 || nred < 0;
    for (int k = 0; k < nangle && !bad_args; ++k) bad_args = angle_cols[k] < 0 || angle_cols[k] >= width;
    for (int k = 0; k < nsel && !bad_args; ++k) bad_args = sel[k] < 0 || sel[k] >= width;
    for (int k = 0; k < nred && !bad_args; ++k)
        bad_args = red[3 * k] < SG_RED_MIN || red[3 * k] > SG_RED_MEAN || red[3 * k + 1] < 0 ||
                   red[3 * k + 1] >= width || red[3 * k + 2] < -1 || red[3 * k + 2] >= width;
    /* the groups of observables the selection and the reductions read (and those always computed): the others
     * are never computed (NULL: all of them, by the joint motion kernel) */
    unsigned char want_store[SG_MAX_GROUP + 1]; /* the groups, then whether the coordinates are read */
    const unsigned char *want = NULL;
    if (!bad_args && m->ngroup > 0 && m->ngroup <= SG_MAX_GROUP && m->group_start != NULL) {
        int all = 1;
        for (int g = 0; g < m->ngroup; ++g) want_store[g] = m->group_always[g];
        want_store[m->ngroup] = 0;
        for (int k = 0; k < nsel + 2 * nred; ++k) {
            const int col = k < nsel ? sel[k] : red[3 * ((k - nsel) / 2) + 1 + (k - nsel) % 2];
            const int j = col - 3 * nq;
            if (col >= 0 && col < nq) want_store[m->ngroup] = 1; /* a coordinate's value */
            if (j < 0) continue; /* a coordinate or its rates (or no second column) */
            int g = 0;
            while (g + 1 < m->ngroup && m->group_start[g + 1] <= j) ++g;
            want_store[g] = 1;
        }
        for (int g = 0; g < m->ngroup; ++g) all &= want_store[g];
        if (!all) want = want_store;
    }
    /* the shaft angles' cos, sin as the SIMD loop computes them, once for every design (the last 2n of work) */
    const double *trig = NULL;
#if SG_SIMD
    const sg_options *opt = r->opt;
    if (!bad_args && nd > 1 && m->closed != NULL && m->sweep_simd != NULL && !opt->newton_only && !opt->generic &&
        !opt->scalar && sg_simd_width(m) > 1) {
        sgv_trig_table(n, r->phi, work + n * (size_t)(width + 1));
        trig = work + n * (size_t)(width + 1);
    }
#endif
    /* selected columns without reductions: the SIMD loop stores them straight to out (no rows, no copy) */
    double *dst[SG_MAX_DIRECT];
    sg_columns direct = {nsel, sel, dst, 0};
    int use_direct = !bad_args && nsel > 0 && nsel <= SG_MAX_DIRECT && nred == 0;
    for (int k = 0; k < nsel && use_direct; ++k) /* a column selected twice: rows (made continuous once) */
        for (int j = 0; j < k && use_direct; ++j) use_direct = sel[j] != sel[k];
    sg_request one = *r; /* one design's sweep: the scratch rows, kinematics only */
    one.gv = NULL, one.loads = NULL, one.frc = NULL;
    one.q = s.q, one.qd = s.qd, one.qdd = s.qdd, one.obs = s.obs, one.err = err, one.status = work_status;
    one.want = want, one.trig = trig, one.cols = use_direct ? &direct : NULL;
    size_t failed = 0;
    for (size_t d = 0; d < nd; ++d) {
        const double *pd = p + d * (size_t)npar;
        const double *hd = nx > 1 ? held + d * (size_t)(nx - 1) : held;
        const int *bd = nb > 0 ? branch + d * (size_t)nb : branch;
        int st = bad_args ? SG_BAD_ARGUMENT : status[d]; /* in: nonzero skips the design (Python's checks) */
        long long first = -1, count = 0, last = -1;
        if (st == SG_OK) { /* every parameter and held input finite, every checked derived dimension real */
            for (int k = 0; k < npar && st == SG_OK; ++k)
                if (!isfinite(pd[k])) st = SG_BAD_DESIGN;
            for (int k = 0; k + 1 < nx && st == SG_OK; ++k)
                if (!isfinite(hd[k])) st = SG_BAD_DESIGN;
            for (int k = 0; k < nb && st == SG_OK; ++k)
                if (bd[k] != 1 && bd[k] != -1) st = SG_BAD_DESIGN;
            if (st == SG_OK && ncheck > 0) {
                double c[SG_MAX_C];
                m->constants(pd, c);
                for (int k = 0; k < ncheck && st == SG_OK; ++k)
                    if (!isfinite(c[k])) st = SG_BAD_DESIGN;
            }
        }
        s.direct = NULL;
        if (st == SG_OK) {
            for (int k = 0; use_direct && k < nsel; ++k) dst[k] = out + (size_t)k * out_stride + d * n;
            direct.written = 0;
            one.held = hd, one.p = pd, one.branch = bd;
            sweep(m, &one);
            if (direct.written) s.direct = &direct;
            for (size_t i = 0; i < n; ++i)
                if (work_status[i] != SG_OK) {
                    if (first < 0) first = (long long)i, st = work_status[i];
                    if (work_status[i] == st) ++count, last = (long long)i;
                }
            if (st == SG_OK) continuous_columns(&s, nangle, angle_cols, 0, n, order);
        }
        status[d] = st;
        first_bad[d] = first;
        if (nbad) nbad[d] = count;
        if (last_bad) last_bad[d] = last;
        if (st != SG_OK) ++failed;
        for (int k = 0; k < nsel; ++k) { /* a failed design's rows: NaN (its status says why) */
            double *o = out + (size_t)k * out_stride + d * n;
            if (st == SG_OK) {
                if (s.direct == NULL) copy_column(col_ptr(&s, sel[k], 0), col_step(&s, sel[k]), n, o);
            }
            else
                for (size_t i = 0; i < n; ++i) o[i] = NAN;
        }
        for (int k = 0; k < nred; ++k) {
            double *v = red_val + (size_t)k * red_stride + d;
            long long *ix = red_idx + (size_t)k * red_stride + d;
            if (st == SG_OK) {
                *v = reduce_column(&s, n, red[3 * k], red[3 * k + 1], red[3 * k + 2], ix);
            } else {
                *v = NAN;
                *ix = -1;
            }
        }
    }
    return failed;
}

int sg_sorted(size_t n, const double *phi)
{
    for (size_t i = 1; i < n; ++i)
        if (!(phi[i] >= phi[i - 1])) return 0;
    return 1;
}

/* solve()'s and kinetostatics()' lean path in one call (the Python of a call on the defaults is one buffer and
 * this): blk (n (4 + 3 nq + nobs) doubles, n nfo more with forces) gets the angles phi, the speed,
 * zero acceleration, the rates' error estimate, then q, qd, qdd (n x nq), obs (n x nobs) and, where gv (gravity,
 * 2) is not NULL, the forces without loads (n x nfo); the positions are swept in the order
 * 'order' (NULL: phi must be ascending, else SIZE_MAX is returned with nothing written, and the caller sorts)
 * and, where none fails, the angle columns made continuous. status NULL: the n statuses go to blk's tail, after
 * those doubles (blk then holds ceil(n/2) more). Returns the count of failed positions. */
size_t sg_solve_lean(const sg_mechanism *m, const sg_request *r)
{
    const size_t n = r->n;
    if (r->order == NULL && !sg_sorted(n, r->phi)) return SIZE_MAX;
    const size_t nn = n * (size_t)m->nq;
    double *blk = r->blk;
    double *ph = blk, *om = blk + n, *al = blk + 2 * n, *err = blk + 3 * n, *q = blk + 4 * n;
    double *qd = q + nn, *qdd = qd + nn, *obs = qdd + nn, *frc = obs + n * (size_t)m->nobs;
    int *status = r->status;
    if (status == NULL) status = (int *)(r->gv != NULL ? frc + n * (size_t)m->nfo : frc);
    for (size_t i = 0; i < n; ++i) {
        ph[i] = r->phi[i];
        om[i] = r->speed;
        al[i] = 0.0;
    }
    sg_request s = *r;
    s.phi = ph, s.omega = om, s.alpha = al, s.loads = NULL;
    s.q = q, s.qd = qd, s.qdd = qdd, s.obs = obs, s.err = err, s.frc = r->gv != NULL ? frc : NULL, s.status = status;
    const size_t failed = sg_sweep(m, &s);
    if (failed == 0 && (r->nqa > 0 || r->noa > 0))
        sg_make_continuous(n, m->nq, m->nobs, q, obs, r->nqa, r->qcols, r->noa, r->ocols, r->order);
    return failed;
}

/* sewgen.mechanism.continuous_angles in C (the same operations: equal to the bit): the angle columns qcols of q
 * (n x nq) and ocols of obs (n x nobs) continuous along the order, the first position in (−π, π]. */
void sg_make_continuous(size_t n, int nq, int nobs, double *q, double *obs, int nqa, const int *qcols, int noa,
                        const int *ocols, const size_t *order)
{
    sg_scratch s;
    s.nq = nq, s.nobs = nobs, s.q = q, s.qd = NULL, s.qdd = NULL, s.obs = obs, s.direct = NULL;
    continuous_columns(&s, nqa, qcols, 0, n, order);
    continuous_columns(&s, noa, ocols, 3 * nq, n, order);
}

/* The upper shaft by d'Alembert (seed 000 §二(二)1(6): the shaft as a beam on its bearings A, front, and B,
 * rear; sewgen.machine's MachineAnalysis). At each of n positions the forces on the shaft core are
 *   - the cranks' pivot forces: x at src[f_off[2j] + i f_step[j]], y at src[f_off[2j + 1] + i f_step[j]], times
 *     f_sign[j], at arm f_arm[j] = z_j - z_A;
 *   - the belt pull (belt, at belt_arm);
 *   - the d'Alembert forces m (g - a) of the core's point masses (core: ncore x (mass, radius r, cos theta,
 *     sin theta, arm)), at r (cos(phi + theta), sin(phi + theta)) turning with the shaft;
 * and the bearings' forces on the shaft are rear = -Sum arm F / span, front = -rear - Sum F (span = z_B - z_A).
 * The driving torque sums the groups' shaft torques (src[t_off[k] + i t_step[k]]), the core's inertia times
 * alpha, r x m (a - g) of its masses and the bearings' Coulomb friction mu_r sign(omega) (|front| + |rear|) (the
 * friction circle: it does not enter the radial balance).
 * out: front (n x 2), rear (n x 2), torque (n), the bearings' friction torque (n), then per core mass its
 * position, velocity and acceleration (3 x n x 2). Every sum runs in the order listed, from zero; cos and sin of
 * the shaft angle are libmvec's where the module's SIMD runs (sgv_trig_table, SG_SHAFT_CHUNK angles at a time),
 * else libm's; the planned and the general analysis both call this, so they agree to the bit. Returns 1 where
 * front, rear and torque are finite everywhere, else 0. */
/* Positions ahead that sg_shaft asks the cache for the columns it reads (each a row of a group's block apart). */
#define SG_SHAFT_AHEAD 8
/* Shaft angles whose cos, sin sg_shaft takes at once from the vector math (where the module's SIMD runs). */
#define SG_SHAFT_CHUNK 256

int sg_shaft(size_t n, const double *phi, const double *omega, const double *alpha, const double *src, int nf,
             const size_t *f_off, const size_t *f_step, const double *f_sign, const double *f_arm, int nt,
             const size_t *t_off, const size_t *t_step, const double *belt, double belt_arm, int ncore,
             const double *core, const double *gravity, double inertia, double span, double mu_r, double *out)
{
    double *front = out, *rear = out + 2 * n, *torque = out + 4 * n, *fric = out + 5 * n, *kin = out + 6 * n;
    const double gx = gravity[0], gy = gravity[1];
    int finite = 1;
#if SG_SIMD
    double trig[2 * SG_SHAFT_CHUNK]; /* cos, then sin, of the chunk's angles */
    size_t chunk_at = 0, chunk_len = 0;
    const int vector_trig = sg_simd_width(NULL) > 1;
#endif
    for (size_t i = 0; i < n; ++i) {
        double tx = 0.0, ty = 0.0, mx = 0.0, my = 0.0; /* Sum F, Sum arm F */
#if defined(__GNUC__)
        if (i + SG_SHAFT_AHEAD < n) { /* each column's value a few positions ahead: rows apart (kB strides) */
            for (int j = 0; j < nf; ++j) __builtin_prefetch(src + f_off[2 * j] + (i + SG_SHAFT_AHEAD) * f_step[j]);
            for (int k = 0; k < nt; ++k) __builtin_prefetch(src + t_off[k] + (i + SG_SHAFT_AHEAD) * t_step[k]);
        }
#endif
        for (int j = 0; j < nf; ++j) {
            const double fx = src[f_off[2 * j] + i * f_step[j]] * f_sign[j];
            const double fy = src[f_off[2 * j + 1] + i * f_step[j]] * f_sign[j];
            tx += fx, ty += fy;
            mx += f_arm[j] * fx, my += f_arm[j] * fy;
        }
        tx += belt[0], ty += belt[1];
        mx += belt_arm * belt[0], my += belt_arm * belt[1];
        double c, s, core_torque = inertia * alpha[i];
#if SG_SIMD
        if (vector_trig) {
            if (i >= chunk_at + chunk_len) {
                chunk_at = i;
                chunk_len = n - i < SG_SHAFT_CHUNK ? n - i : SG_SHAFT_CHUNK;
                sgv_trig_table(chunk_len, phi + i, trig);
            }
            c = trig[i - chunk_at];
            s = trig[chunk_len + (i - chunk_at)];
        } else
#endif
            sg_sincos_inl(phi[i], &c, &s);
        for (int k = 0; k < ncore; ++k) {
            const double *cm = core + 5 * k;
            const double mass = cm[0], r = cm[1], cb = cm[2], sb = cm[3], arm = cm[4];
            double *pos = kin + 6 * n * (size_t)k + 2 * i, *vel = pos + 2 * n, *acc = pos + 4 * n;
            const double ux = c * cb - s * sb, uy = c * sb + s * cb; /* radial unit vector */
            const double rw = r * omega[i], ra = r * alpha[i], cen = rw * omega[i];
            pos[0] = r * ux, pos[1] = r * uy;
            vel[0] = -rw * uy, vel[1] = rw * ux; /* r omega times the tangent (-uy, ux) */
            acc[0] = -ra * uy - cen * ux, acc[1] = ra * ux - cen * uy;
            const double dx = mass * (gx - acc[0]), dy = mass * (gy - acc[1]); /* d'Alembert force */
            tx += dx, ty += dy;
            mx += arm * dx, my += arm * dy;
            core_torque = core_torque + pos[0] * (-dy) - pos[1] * (-dx); /* r x m (a - g) */
        }
        const double rx = -mx / span, ry = -my / span;
        rear[2 * i] = rx, rear[2 * i + 1] = ry;
        front[2 * i] = -rx - tx, front[2 * i + 1] = -ry - ty;
        const double w = omega[i], sign = w > 0.0 ? 1.0 : w < 0.0 ? -1.0 : w;
        /* no bearing friction (the default): 0 with the sign the product would have, the bearings' magnitudes not
         * needed (a non-finite one fails the position through its components below all the same) */
        const double fr = mu_r == 0.0 ? 0.0 * sign : mu_r * sign * (hypot(front[2 * i], front[2 * i + 1]) + hypot(rx, ry));
        double t = 0.0;
        for (int k = 0; k < nt; ++k) t += src[t_off[k] + i * t_step[k]];
        t = t + core_torque + fr;
        torque[i] = t, fric[i] = fr;
        finite &= isfinite(rx + ry + front[2 * i] + front[2 * i + 1] + t);
    }
    return finite;
}

/* sewgen.loads.place_loads in C (the same operations: equal to the bit): out (n x nload) zeroed, then for each
 * of the nl loads in order and each of its ncol[l] slots (col, val: consecutive in col, val across the loads),
 * out[i nload + col] += val wherever the load is on: everywhere where its window's start win[2l] is NaN, else
 * where (phi[i] - start) mod 2 pi (numpy's modulo) <= win[2l + 1] (the window's span plus its tolerance). mask
 * (nl x n) gets 1 where the load is on, else 0. */
void sg_place_loads(size_t n, const double *phi, int nload, int nl, const double *win, const int *ncol,
                    const int *col, const double *val, double *out, unsigned char *mask)
{
    for (size_t i = 0; i < n * (size_t)nload; ++i) out[i] = 0.0;
    for (int l = 0, k0 = 0; l < nl; k0 += ncol[l], ++l) {
        const double start = win[2 * l], limit = win[2 * l + 1];
        unsigned char *on = mask + (size_t)l * n;
        for (size_t i = 0; i < n; ++i) {
            on[i] = isnan(start) || py_mod(phi[i] - start, SG_TWO_PI) <= limit;
            if (on[i])
                for (int k = k0; k < k0 + ncol[l]; ++k) out[i * (size_t)nload + (size_t)col[k]] += val[k];
        }
    }
}
