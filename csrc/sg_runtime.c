/* sewgen C runtime: LU, damped Newton with a quadratic predictor, and the sweep driver. */
#include "sg_runtime.h"

#include <string.h>

#define SG_TWO_PI 6.283185307179586476925286766559

int sg_lu_factor(int n, double *a, int *piv, double *det_sign)
{
    return sg_lu_factor_inl(n, a, piv, det_sign);
}

void sg_lu_solve(int n, const double *lu, const int *piv, double *b)
{
    sg_lu_solve_inl(n, lu, piv, b);
}

static double inf_norm(int n, const double *v)
{
    double m = 0.0;
    for (int i = 0; i < n; ++i) {
        const double a = fabs(v[i]);
        if (!(a <= m)) m = a; /* NaN propagates: a NaN entry makes the norm NaN */
    }
    return m;
}

/* cos and sin of one angle in one libm call where the compiler offers it (glibc's sincos). */
static inline void sg_cos_sin(double a, double *c, double *s)
{
#if defined(__GNUC__)
    __builtin_sincos(a, s, c);
#else
    *c = cos(a);
    *s = sin(a);
#endif
}

/* cos and sin of q + d from those of q, for the small steps of Newton and of the predictor: the addition
 * formulas with cos d, sin d from their Taylor series (|d| < 1e-2: the first omitted terms, d^10/10! and
 * d^9/9!, are below 1e-26 relative), so a step costs no libm call. Larger steps: sincos. */
#define SG_SMALL_STEP 1e-2

static void shift_trig(const sg_mechanism *m, const double *q, const double *cq, const double *d, double *q_out,
                       double *cq_out)
{
    for (int i = 0; i < m->nq; ++i) {
        q_out[i] = q[i] + d[i];
        if (!m->coord_is_angle[i]) {
            cq_out[2 * i] = 1.0;
            cq_out[2 * i + 1] = 0.0;
        } else if (fabs(d[i]) < SG_SMALL_STEP) {
            const double h = d[i], h2 = h * h;
            const double sd = h * (1.0 - h2 / 6.0 * (1.0 - h2 / 20.0 * (1.0 - h2 / 42.0)));
            const double cd = 1.0 - h2 / 2.0 * (1.0 - h2 / 12.0 * (1.0 - h2 / 30.0 * (1.0 - h2 / 56.0)));
            const double c = cq[2 * i], s = cq[2 * i + 1];
            cq_out[2 * i] = c * cd - s * sd;
            cq_out[2 * i + 1] = s * cd + c * sd;
        } else {
            sg_cos_sin(q_out[i], &cq_out[2 * i], &cq_out[2 * i + 1]);
        }
    }
}

/* cos and sin of every angle coordinate (travels get 1, 0: never read). */
static void fill_trig(const sg_mechanism *m, const double *q, double *cq)
{
    for (int i = 0; i < m->nq; ++i) {
        if (m->coord_is_angle[i]) {
            sg_cos_sin(q[i], &cq[2 * i], &cq[2 * i + 1]);
        } else {
            cq[2 * i] = 1.0;
            cq[2 * i + 1] = 0.0;
        }
    }
}

/* Damped Newton on Phi(q, x) = 0 from q (in place), with cq kept in step with q.
 * On success *det_sign is the sign of det(dPhi/dq) (at the last iterate but one after a full final step). */
static int newton(const sg_mechanism *m, double *q, double *cq, const double *x, const double *cx,
                  const double *c, const sg_options *opt, double *det_sign)
{
    const int nq = m->nq;
    double r[SG_MAX_Q], jac[SG_MAX_Q * SG_MAX_Q], lu[SG_MAX_Q * SG_MAX_Q];
    double qt[SG_MAX_Q], cqt[2 * SG_MAX_Q], rt[SG_MAX_Q], dq[SG_MAX_Q], step[SG_MAX_Q];
    int piv[SG_MAX_Q];
    m->residual(q, cq, x, cx, c, r, jac); /* cq: cos, sin of q, from the caller */
    double norm = inf_norm(nq, r);
    for (int it = 0;; ++it) {
        if (!isfinite(norm)) return SG_NO_CONVERGENCE;
        memcpy(lu, jac, sizeof(double) * (size_t)(nq * nq));
        const int st = sg_lu_factor_inl(nq, lu, piv, det_sign);
        if (norm <= opt->tol) return st == SG_OK ? SG_OK : SG_SINGULAR;
        if (st != SG_OK) return SG_CANNOT_ASSEMBLE; /* no descent direction away from a solution */
        if (it >= opt->max_iter) return SG_NO_CONVERGENCE;
        for (int i = 0; i < nq; ++i) dq[i] = -r[i];
        sg_lu_solve_inl(nq, lu, piv, dq);
        double lambda = 1.0, nt = 0.0;
        int k;
        for (k = 0; k < 30; ++k) {
            for (int i = 0; i < nq; ++i) step[i] = lambda * dq[i];
            shift_trig(m, q, cq, step, qt, cqt);
            m->residual(qt, cqt, x, cx, c, rt, jac);
            nt = inf_norm(nq, rt);
            if (nt < norm) break;
            lambda *= 0.5;
        }
        if (k == 30) return SG_CANNOT_ASSEMBLE; /* the residual has a positive local minimum */
        memcpy(q, qt, sizeof(double) * (size_t)nq);
        memcpy(cq, cqt, sizeof(double) * (size_t)(2 * nq));
        memcpy(r, rt, sizeof(double) * (size_t)nq);
        norm = nt;
        /* Converged by a full step: det Phi_q keeps the sign of the factor just used (the step is below the
         * tolerance's scale); a singular Phi_q at the solution is caught by the motion kernel's own LU. */
        if (norm <= opt->tol && lambda == 1.0) return SG_OK;
    }
}

/* Quadratic (Lagrange) extrapolation in the shaft angle from up to three earlier solutions, given as
 * row indices into the output array q (newest first). */
static void predict(int nq, int nh, const size_t *hist, const double *phi, const double *q, double phi_new,
                    double *out)
{
    double w[3] = {1.0, 0.0, 0.0};
    int used = nh;
    for (; used > 1; --used) { /* repeated angles: fall back to a lower order */
        int ok = 1;
        for (int a = 0; a < used && ok; ++a) {
            double num = 1.0, den = 1.0;
            for (int b = 0; b < used; ++b) {
                if (b == a) continue;
                num *= phi_new - phi[hist[b]];
                den *= phi[hist[a]] - phi[hist[b]];
            }
            if (!(fabs(den) > 1e-14)) ok = 0;
            else w[a] = num / den;
        }
        if (ok) break;
    }
    if (used <= 1) w[0] = 1.0, used = 1;
    for (int i = 0; i < nq; ++i) {
        double v = 0.0;
        for (int a = 0; a < used; ++a) v += w[a] * q[hist[a] * (size_t)nq + i];
        out[i] = v;
    }
}

static void zero_row(double *v, int n)
{
    for (int i = 0; i < n; ++i) v[i] = 0.0;
}

/* The sweep: kinematics at every position, then (frc != NULL) the forces from the same solution. */
static size_t sweep(const sg_mechanism *m, size_t n, const double *phi, const double *omega,
                    const double *alpha, const double *held, const double *p, const int *branch,
                    const double *q_guess, const sg_options *opt, const double *gv, const double *loads,
                    double *q, double *qd, double *qdd, double *obs, double *frc, int *status)
{
    const int nq = m->nq, nx = m->nx, nobs = m->nobs, nfo = m->nfo;
    double no_loads[SG_MAX_LOAD] = {0.0};
    if (nq > SG_MAX_Q || nx > SG_MAX_Q || nx < 1 || m->nc > SG_MAX_C || m->nload > SG_MAX_LOAD ||
        !(opt->tol > 0.0) || opt->max_iter < 1 || (frc != NULL && gv == NULL)) {
        for (size_t i = 0; i < n; ++i) status[i] = SG_BAD_ARGUMENT;
        return n;
    }
    const int use_closed = m->closed != NULL && !opt->newton_only;
    double c[SG_MAX_C];
    m->constants(p, c);
    double x[SG_MAX_Q], cx[2 * SG_MAX_Q], xd[SG_MAX_Q], xdd[SG_MAX_Q], cq[2 * SG_MAX_Q], cq_last[2 * SG_MAX_Q];
    for (int k = 1; k < nx; ++k) {
        x[k] = held[k - 1];
        cx[2 * k] = cos(x[k]);
        cx[2 * k + 1] = sin(x[k]);
        xd[k] = 0.0;
        xdd[k] = 0.0;
    }
    size_t hist[3]; /* rows of the last good solutions, newest first */
    int nh = 0;
    double ref_sign = 0.0;
    size_t failures = 0;
    for (size_t i = 0; i < n; ++i) {
        double *qi = q + i * (size_t)nq, *qdi = qd + i * (size_t)nq, *qddi = qdd + i * (size_t)nq;
        double *oi = obs + i * (size_t)nobs;
        int st = SG_OK;
        const double ph = phi[i];
        x[0] = ph;
        xd[0] = omega[i];
        xdd[0] = alpha[i];
        if (!isfinite(ph + omega[i] + alpha[i])) st = SG_NAN_INPUT;
        cx[0] = cos(ph);
        cx[1] = sin(ph);
        if (st == SG_OK && use_closed) {
            st = m->closed(x, cx, c, branch, qi, cq);
            if (st == SG_OK && nh > 0) { /* keep angles continuous: unwrap against the last solution */
                const double *prev = q + hist[0] * (size_t)nq;
                for (int k = 0; k < nq; ++k)
                    if (m->coord_is_angle[k]) {
                        const double turns = (prev[k] - qi[k]) * (1.0 / SG_TWO_PI);
                        if (fabs(turns) > 0.5) qi[k] += SG_TWO_PI * nearbyint(turns);
                    }
            }
        } else if (st == SG_OK) {
            double sign = 0.0;
            if (nh > 0) { /* predictor; cos, sin shifted from the last solution's */
                const double *prev = q + hist[0] * (size_t)nq;
                double d[SG_MAX_Q];
                predict(nq, nh, hist, phi, q, ph, qi);
                for (int k = 0; k < nq; ++k) d[k] = qi[k] - prev[k];
                shift_trig(m, prev, cq_last, d, qi, cq);
            } else { /* first position: the closed form where it assembles, else the guess */
                if (m->closed == NULL || m->closed(x, cx, c, branch, qi, cq) != SG_OK)
                    memcpy(qi, q_guess, sizeof(double) * (size_t)nq);
                fill_trig(m, qi, cq);
            }
            st = newton(m, qi, cq, x, cx, c, opt, &sign);
            if (st == SG_OK) {
                if (ref_sign == 0.0) ref_sign = sign;
                else if (sign != ref_sign) st = SG_BRANCH_JUMP;
            }
        }
        if (st == SG_OK) st = m->motion(qi, cq, x, cx, xd, xdd, c, qdi, qddi, oi);
        if (st == SG_OK && frc != NULL)
            st = m->forces(qi, cq, x, cx, xd, c, oi, gv, loads ? loads + i * (size_t)m->nload : no_loads,
                           frc + i * (size_t)nfo);
        status[i] = st;
        if (st != SG_OK) {
            ++failures;
            zero_row(qi, nq);
            zero_row(qdi, nq);
            zero_row(qddi, nq);
            zero_row(oi, nobs);
            if (frc != NULL) zero_row(frc + i * (size_t)nfo, nfo);
            continue;
        }
        memcpy(cq_last, cq, sizeof(double) * (size_t)(2 * nq));
        hist[2] = hist[1];
        hist[1] = hist[0];
        hist[0] = i;
        if (nh < 3) ++nh;
    }
    return failures;
}

/* Sweep a mechanism over n shaft angles in one call: positions, velocities, accelerations and every
 * observable. phi/omega/alpha have n entries; held has nx-1; q_guess (nq) starts Newton where no closed
 * form exists. Outputs are row-major (n x nq, n x nobs); status has n entries. Returns the number of
 * positions whose status is not SG_OK (or n with every status SG_BAD_ARGUMENT on bad sizes). */
size_t sg_sweep(const sg_mechanism *m, size_t n, const double *phi, const double *omega,
                const double *alpha, const double *held, const double *p, const int *branch,
                const double *q_guess, const sg_options *opt, double *q, double *qd, double *qdd,
                double *obs, int *status)
{
    return sweep(m, n, phi, omega, alpha, held, p, branch, q_guess, opt, NULL, NULL, q, qd, qdd, obs, NULL,
                 status);
}

/* sg_sweep plus kinetostatics in the same pass: gv is gravity (2), loads is n x nload (NULL: no loads),
 * frc receives n x nfo force outputs. A singular force matrix gives SG_SINGULAR at that position. */
size_t sg_sweep_forces(const sg_mechanism *m, size_t n, const double *phi, const double *omega,
                       const double *alpha, const double *held, const double *p, const int *branch,
                       const double *q_guess, const sg_options *opt, const double *gv, const double *loads,
                       double *q, double *qd, double *qdd, double *obs, double *frc, int *status)
{
    return sweep(m, n, phi, omega, alpha, held, p, branch, q_guess, opt, gv, loads, q, qd, qdd, obs, frc,
                 status);
}
