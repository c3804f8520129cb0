/* sewgen C runtime: LU, damped Newton with a quadratic predictor, and the sweep driver. */
#include "sg_runtime.h"

#include <string.h>

#define SG_PIVOT_RTOL 1e-11
#define SG_TWO_PI 6.283185307179586476925286766559

int sg_lu_factor(int n, double *a, int *piv, double *det_sign)
{
    double colmax[SG_MAX_Q];
    double sign = 1.0;
    for (int j = 0; j < n; ++j) {
        double cm = 0.0;
        for (int i = 0; i < n; ++i) {
            const double v = fabs(a[i * n + j]);
            if (v > cm) cm = v;
        }
        colmax[j] = cm;
    }
    for (int k = 0; k < n; ++k) {
        int pr = k;
        double best = fabs(a[k * n + k]);
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
            for (int j = 0; j < n; ++j) {
                const double t = a[k * n + j];
                a[k * n + j] = a[pr * n + j];
                a[pr * n + j] = t;
            }
        }
        const double inv = 1.0 / a[k * n + k];
        if (a[k * n + k] < 0.0) sign = -sign;
        for (int i = k + 1; i < n; ++i) {
            const double f = a[i * n + k] * inv;
            a[i * n + k] = f;
            if (f != 0.0)
                for (int j = k + 1; j < n; ++j) a[i * n + j] -= f * a[k * n + j];
        }
    }
    if (det_sign) *det_sign = sign;
    return SG_OK;
}

void sg_lu_solve(int n, const double *lu, const int *piv, double *b)
{
    for (int k = 0; k < n; ++k) {
        if (piv[k] != k) {
            const double t = b[k];
            b[k] = b[piv[k]];
            b[piv[k]] = t;
        }
        for (int i = k + 1; i < n; ++i) b[i] -= lu[i * n + k] * b[k];
    }
    for (int k = n - 1; k >= 0; --k) {
        double s = b[k];
        for (int j = k + 1; j < n; ++j) s -= lu[k * n + j] * b[j];
        b[k] = s / lu[k * n + k];
    }
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

/* Damped Newton on Phi(q, x) = 0 from q (in place). On success *det_sign is the sign of det(dPhi/dq). */
static int newton(const sg_mechanism *m, double *q, const double *x, const double *p,
                  const sg_options *opt, double *det_sign)
{
    const int nq = m->nq;
    double r[SG_MAX_Q], jac[SG_MAX_Q * SG_MAX_Q], lu[SG_MAX_Q * SG_MAX_Q];
    double qt[SG_MAX_Q], rt[SG_MAX_Q], dq[SG_MAX_Q];
    int piv[SG_MAX_Q];
    m->residual(q, x, p, r, jac);
    double norm = inf_norm(nq, r);
    for (int it = 0;; ++it) {
        if (!isfinite(norm)) return SG_NO_CONVERGENCE;
        memcpy(lu, jac, sizeof(double) * (size_t)(nq * nq));
        const int st = sg_lu_factor(nq, lu, piv, det_sign);
        if (norm <= opt->tol) return st == SG_OK ? SG_OK : SG_SINGULAR;
        if (st != SG_OK) return SG_CANNOT_ASSEMBLE; /* no descent direction away from a solution */
        if (it >= opt->max_iter) return SG_NO_CONVERGENCE;
        for (int i = 0; i < nq; ++i) dq[i] = -r[i];
        sg_lu_solve(nq, lu, piv, dq);
        double lambda = 1.0, nt = 0.0;
        int k;
        for (k = 0; k < 30; ++k) {
            for (int i = 0; i < nq; ++i) qt[i] = q[i] + lambda * dq[i];
            m->residual(qt, x, p, rt, jac);
            nt = inf_norm(nq, rt);
            if (nt < norm) break;
            lambda *= 0.5;
        }
        if (k == 30) return SG_CANNOT_ASSEMBLE; /* the residual has a positive local minimum */
        memcpy(q, qt, sizeof(double) * (size_t)nq);
        memcpy(r, rt, sizeof(double) * (size_t)nq);
        norm = nt;
    }
}

/* Quadratic (Lagrange) extrapolation in the shaft angle from up to three earlier solutions. */
static void predict(int nq, int nh, const double *hphi, const double *hq, double phi, double *out)
{
    double w[3] = {1.0, 0.0, 0.0};
    int used = nh;
    for (;;) {
        int ok = 1;
        for (int a = 0; a < used && ok; ++a) {
            double num = 1.0, den = 1.0;
            for (int b = 0; b < used; ++b) {
                if (b == a) continue;
                num *= phi - hphi[b];
                den *= hphi[a] - hphi[b];
            }
            if (!(fabs(den) > 1e-14)) ok = 0;
            else w[a] = num / den;
        }
        if (ok || used == 1) break;
        --used; /* repeated angles: fall back to a lower order */
        w[0] = 1.0;
    }
    if (used == 1) w[0] = 1.0;
    for (int i = 0; i < nq; ++i) {
        double v = 0.0;
        for (int a = 0; a < used; ++a) v += w[a] * hq[a * nq + i];
        out[i] = v;
    }
}

static void zero_row(double *v, int n)
{
    for (int i = 0; i < n; ++i) v[i] = 0.0;
}

static int all_finite(const double *v, int n)
{
    for (int i = 0; i < n; ++i)
        if (!isfinite(v[i])) return 0;
    return 1;
}

size_t sg_sweep(const sg_mechanism *m, size_t n, const double *phi, const double *omega,
                const double *alpha, const double *held, const double *p, const int *branch,
                const double *q_guess, const sg_options *opt, double *q, double *qd, double *qdd,
                double *obs, int *status)
{
    const int nq = m->nq, nx = m->nx, nobs = m->nobs;
    if (nq > SG_MAX_Q || nx > SG_MAX_Q || nx < 1 || !(opt->tol > 0.0) || opt->max_iter < 1) {
        for (size_t i = 0; i < n; ++i) status[i] = SG_BAD_ARGUMENT;
        return n;
    }
    const int use_closed = m->closed != NULL && !opt->newton_only;
    double x[SG_MAX_Q], xd[SG_MAX_Q], xdd[SG_MAX_Q];
    for (int k = 1; k < nx; ++k) {
        x[k] = held[k - 1];
        xd[k] = 0.0;
        xdd[k] = 0.0;
    }
    double hphi[3], hq[3 * SG_MAX_Q]; /* newest first */
    int nh = 0;
    double ref_sign = 0.0;
    size_t failures = 0;
    for (size_t i = 0; i < n; ++i) {
        double *qi = q + i * (size_t)nq, *qdi = qd + i * (size_t)nq, *qddi = qdd + i * (size_t)nq;
        double *oi = obs + i * (size_t)nobs;
        int st = SG_OK;
        x[0] = phi[i];
        xd[0] = omega[i];
        xdd[0] = alpha[i];
        if (!isfinite(phi[i]) || !isfinite(omega[i]) || !isfinite(alpha[i])) st = SG_NAN_INPUT;
        if (st == SG_OK && use_closed) {
            st = m->closed(x, p, branch, qi);
            if (st == SG_OK && nh > 0) /* keep angles continuous: unwrap against the last solution */
                for (int k = 0; k < nq; ++k)
                    if (m->coord_is_angle[k]) qi[k] += SG_TWO_PI * nearbyint((hq[k] - qi[k]) / SG_TWO_PI);
        } else if (st == SG_OK) {
            double sign = 0.0;
            if (nh > 0) {
                predict(nq, nh, hphi, hq, phi[i], qi);
            } else if (m->closed == NULL || m->closed(x, p, branch, qi) != SG_OK) {
                memcpy(qi, q_guess, sizeof(double) * (size_t)nq);
            }
            st = newton(m, qi, x, p, opt, &sign);
            if (st == SG_OK) {
                if (ref_sign == 0.0) ref_sign = sign;
                else if (sign != ref_sign) st = SG_BRANCH_JUMP;
            }
        }
        if (st == SG_OK) st = m->motion(qi, x, xd, xdd, p, qdi, qddi, oi);
        if (st == SG_OK && !(all_finite(qi, nq) && all_finite(qdi, nq) && all_finite(qddi, nq) &&
                             all_finite(oi, nobs)))
            st = SG_NONFINITE;
        status[i] = st;
        if (st != SG_OK) {
            ++failures;
            zero_row(qi, nq);
            zero_row(qdi, nq);
            zero_row(qddi, nq);
            zero_row(oi, nobs);
            continue;
        }
        /* history for the predictor and the unwrap, newest first */
        const int keep = nh < 3 ? nh + 1 : 3;
        for (int a = keep - 1; a > 0; --a) {
            hphi[a] = hphi[a - 1];
            memcpy(hq + a * nq, hq + (a - 1) * nq, sizeof(double) * (size_t)nq);
        }
        hphi[0] = phi[i];
        memcpy(hq, qi, sizeof(double) * (size_t)nq);
        nh = keep;
    }
    return failures;
}
