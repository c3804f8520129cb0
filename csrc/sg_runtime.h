/* sewgen C runtime: pivoted LU, closed-form dyads, damped Newton with a predictor, sweep driver.
 *
 * Hand-written; the generated kernels (generated/sg_<mechanism>.c) include this header and fill one
 * sg_mechanism descriptor each. Everything exported is prefixed sg_. C99, no allocation, no globals.
 */
#ifndef SG_RUNTIME_H
#define SG_RUNTIME_H

#include <math.h>
#include <stddef.h>

/* Per-position status codes (sewgen.errors maps each to a typed Python error). */
enum sg_status {
    SG_OK = 0,
    SG_CANNOT_ASSEMBLE = 1, /* the loop does not close at this input (a dyad's circles do not meet) */
    SG_SINGULAR = 2,        /* the constraint Jacobian is singular here (toggle / dead-centre position) */
    SG_BRANCH_JUMP = 3,     /* Newton landed on another assembly branch than the previous position */
    SG_NAN_INPUT = 4,       /* a shaft angle, speed or acceleration is not finite */
    SG_NO_CONVERGENCE = 5,  /* Newton ran out of iterations */
    SG_NONFINITE = 6,       /* a result came out non-finite (the motion kernel tests every output) */
    SG_BAD_ARGUMENT = 7     /* sizes or options out of range: nothing was computed */
};

/* Largest number of coordinates (also the largest LU: force blocks included) and of hoisted constants a
 * mechanism may have (stack work arrays). */
#define SG_MAX_Q 48
#define SG_MAX_C 2048
/* Largest number of load slots per position. */
#define SG_MAX_LOAD 512

/* Kernel arguments: q coordinates; cq[2i], cq[2i+1] = cos, sin of angle coordinate i; x inputs and cx
 * their cos, sin likewise; c the constants that sg_<m>_constants hoisted out of the parameters p. */
typedef void (*sg_constants_fn)(const double *p, double *c);
typedef int (*sg_closed_fn)(const double *x, const double *cx, const double *c, const int *branch, double *q,
                            double *cq);
typedef void (*sg_residual_fn)(const double *q, const double *cq, const double *x, const double *cx,
                               const double *c, double *r, double *jac);
typedef int (*sg_motion_fn)(const double *q, const double *cq, const double *x, const double *cx,
                            const double *xd, const double *xdd, const double *c, double *qd, double *qdd,
                            double *obs);
/* Kinetostatics at a solved position: reads the motion kernel's observables obs, gravity gv[2] (m/s^2)
 * and the loads ld (nload); writes the reactions f (nf) then the derived outputs (nfo in all). */
typedef int (*sg_forces_fn)(const double *q, const double *cq, const double *x, const double *cx,
                            const double *xd, const double *c, const double *obs, const double *gv,
                            const double *ld, double *out);
typedef void (*sg_force_matrix_fn)(const double *q, const double *cq, const double *x, const double *cx,
                                   const double *c, const double *obs, const double *gv, const double *ld,
                                   double *A, double *b);

/* One mechanism as the generated code describes it. */
typedef struct sg_mechanism {
    const char *name;
    int nq;      /* coordinates: link angles (rad) and slider travels (m) */
    int nx;      /* inputs: x[0] = shaft angle, then held inputs */
    int np;      /* parameters (SI) */
    int nc;      /* constants hoisted out of the parameters */
    int nobs;    /* observables per position (points, bodies), see the manifest */
    int nbranch; /* closed-form dyads, each with an assembly sign */
    int nf;      /* force unknowns: reactions and driving torques */
    int nfo;     /* force outputs per position: nf, then torques, powers, shaking, energies (manifest) */
    int nload;   /* load slots per position: fx, fy per point of a moving body, torque per moving body */
    const unsigned char *coord_is_angle;
    sg_constants_fn constants;
    sg_closed_fn closed;     /* NULL where the loops do not split into dyads */
    sg_residual_fn residual; /* loop-closure residual and its Jacobian dPhi/dq (row-major) */
    sg_motion_fn motion;     /* velocities, accelerations and observables at a solved position */
    sg_forces_fn forces;     /* joint reactions, driving torques, shaking force, energies */
    sg_force_matrix_fn force_matrix; /* A (nf x nf, row-major) and b of A f = b, for inspection */
} sg_mechanism;

typedef struct sg_options {
    double tol;     /* loop residual tolerance (m); Newton stops below it */
    int max_iter;   /* Newton iterations per position */
    int newton_only; /* 1: Newton even where a closed form exists (tests, benchmarks) */
} sg_options;

/* LU with partial pivoting, in place, row-major n x n. Returns SG_SINGULAR when a pivot is below
 * 1e-11 of its column's largest original entry (column-scale invariant: columns may be rad or m).
 * Always inline, so that a kernel's call with a literal n unrolls; sg_lu_factor/sg_lu_solve are the exported
 * copies. */
#define SG_PIVOT_RTOL 1e-11
#if defined(__GNUC__)
#define SG_INLINE static inline __attribute__((always_inline))
#else
#define SG_INLINE static inline
#endif

SG_INLINE int sg_lu_factor_inl(int n, double *a, int *piv, double *det_sign)
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

/* The factor swaps whole rows (L's multipliers too, as LAPACK's dgetrf), so every interchange is applied
 * to b before the forward substitution. */
SG_INLINE void sg_lu_solve_inl(int n, const double *lu, const int *piv, double *b)
{
    for (int k = 0; k < n; ++k) {
        if (piv[k] != k) {
            const double t = b[k];
            b[k] = b[piv[k]];
            b[piv[k]] = t;
        }
    }
    for (int k = 0; k < n; ++k)
        for (int i = k + 1; i < n; ++i) b[i] -= lu[i * n + k] * b[k];
    for (int k = n - 1; k >= 0; --k) {
        double s = b[k];
        for (int j = k + 1; j < n; ++j) s -= lu[k * n + j] * b[j];
        b[k] = s / lu[k * n + k];
    }
}

int sg_lu_factor(int n, double *a, int *piv, double *det_sign);
void sg_lu_solve(int n, const double *lu, const int *piv, double *b);

/* Closed-form dyads (seed 001 §三, Makino's vector triangles; BV4 is the RRR dyad). ------------------ */

/* RRR: J is at distance l1 from P and l2 from Q; sigma = +1 puts J left of the ray P->Q. */
static inline int sg_dyad_rrr(const double P[2], const double Q[2], double l1, double l2, int sigma,
                              double J[2])
{
    const double dx = Q[0] - P[0], dy = Q[1] - P[1];
    const double d2 = dx * dx + dy * dy;
    if (!(d2 > 1e-30)) return SG_SINGULAR;
    const double a = 0.5 * (l1 * l1 - l2 * l2 + d2) / d2; /* along PQ, in units of d */
    const double h2 = l1 * l1 / d2 - a * a;                /* across PQ, squared, in units of d^2 */
    if (!(h2 >= 0.0)) return SG_CANNOT_ASSEMBLE;
    const double h = sigma * sqrt(h2);
    J[0] = P[0] + a * dx - h * dy;
    J[1] = P[1] + a * dy + h * dx;
    return SG_OK;
}

/* RRP: J = L0 + s*u (u a unit vector) at distance l1 from P; sigma = +1 takes the larger s. */
static inline int sg_dyad_rrp(const double P[2], double l1, const double L0[2], const double u[2],
                              int sigma, double *s, double J[2])
{
    const double wx = L0[0] - P[0], wy = L0[1] - P[1];
    const double b = u[0] * wx + u[1] * wy;
    const double disc = b * b - (wx * wx + wy * wy - l1 * l1);
    if (!(disc >= 0.0)) return SG_CANNOT_ASSEMBLE;
    *s = -b + sigma * sqrt(disc);
    J[0] = L0[0] + *s * u[0];
    J[1] = L0[1] + *s * u[1];
    return SG_OK;
}

/* RPR (oscillating guide bar): in the bar's frame the pin runs on w0 + s*u (u unit); it must lie at
 * distance |D| from the pivot, D = pin - pivot in the world. Returns s (sigma = +1: larger s) and the
 * bar angle theta with R(theta) (w0 + s u) = D. */
static inline int sg_dyad_rpr(const double D[2], const double w0[2], const double u[2], int sigma,
                              double *s, double *theta)
{
    const double d2 = D[0] * D[0] + D[1] * D[1];
    if (!(d2 > 1e-30)) return SG_SINGULAR;
    const double b = u[0] * w0[0] + u[1] * w0[1];
    const double disc = b * b - (w0[0] * w0[0] + w0[1] * w0[1] - d2);
    if (!(disc >= 0.0)) return SG_CANNOT_ASSEMBLE;
    *s = -b + sigma * sqrt(disc);
    const double wx = w0[0] + *s * u[0], wy = w0[1] + *s * u[1];
    *theta = atan2(D[1], D[0]) - atan2(wy, wx);
    return SG_OK;
}

/* Sweep a mechanism over n shaft angles in one call: positions, velocities, accelerations and every
 * observable. phi/omega/alpha have n entries; held has nx-1; q_guess (nq) starts Newton where no closed
 * form exists. Outputs are row-major (n x nq, n x nobs); status has n entries. Returns the number of
 * positions whose status is not SG_OK (or n with every status SG_BAD_ARGUMENT on bad sizes). */
size_t sg_sweep(const sg_mechanism *m, size_t n, const double *phi, const double *omega,
                const double *alpha, const double *held, const double *p, const int *branch,
                const double *q_guess, const sg_options *opt, double *q, double *qd, double *qdd,
                double *obs, int *status);

/* sg_sweep plus kinetostatics in the same pass: gv is gravity (2), loads is n x nload (NULL: no loads),
 * frc receives n x nfo force outputs. A singular force matrix gives SG_SINGULAR at that position. */
size_t sg_sweep_forces(const sg_mechanism *m, size_t n, const double *phi, const double *omega,
                       const double *alpha, const double *held, const double *p, const int *branch,
                       const double *q_guess, const sg_options *opt, const double *gv, const double *loads,
                       double *q, double *qd, double *qdd, double *obs, double *frc, int *status);

#endif
