/* A minimal hand-written C version of blademodel's hybrid RK4 kernel for the
 * paper's blade pair (2 blades x 2 DOF, one inclined gapped contact), both
 * friction laws. Benchmark baseline only: benchmarks/per_step.py compiles it
 * with `gcc -O3` (no -march=native, no -ffast-math) and checks that it
 * reproduces the generated kernel's final state before timing it.
 *
 * It implements the same algorithm as blademodel/numeric/loop.py, step for step:
 * fixed-step classical RK4 with h = T / S, every guard of the current mode
 * checked at each (sub)step end, the earliest crossing bracketed by bisection
 * (re-integrating from the step start) to event_tol * h, the state taken at the
 * far end of the bracket, the transition applied, the rest of the step taken.
 *
 * State: x1 y1 x2 y2 vx1 vy1 vx2 vy2 [z]; modes 0 open, 1 stick, 2 slip+, 3 slip-.
 * law 0 = Coulomb (rigid stick, Eq. 9 stick force), 1 = bilinear (Jenkins).
 * prm: m kx ky cx cy F0 omega phi1 beta phi2 Delta alpha k mu kd
 */
#include <math.h>
#include <string.h>

enum { OPEN = 0, STICK = 1, SLIPP = 2, SLIPM = 3 };

typedef struct {
    int law, n;
    double im, kx, ky, cx, cy, F0, om, ph1, ph2, cb, sb, D, sa, ca, k, mu, kd, mukkd;
} P;

static void setup(P *p, int law, const double *q) {
    p->law = law; p->n = law ? 9 : 8;
    p->im = 1.0 / q[0]; p->kx = q[1]; p->ky = q[2]; p->cx = q[3]; p->cy = q[4];
    p->F0 = q[5]; p->om = q[6]; p->ph1 = q[7]; p->cb = cos(q[8]); p->sb = sin(q[8]);
    p->ph2 = q[9]; p->D = q[10]; p->sa = sin(q[11]); p->ca = cos(q[11]);
    p->k = q[12]; p->mu = q[13]; p->kd = q[14]; p->mukkd = q[13] * q[12] / q[14];
}

/* Accelerations without contact forces (times m), penetration, velocities. */
#define BASE \
    double Q1 = p->F0 * sin(p->om * t + p->ph1), Q2 = p->F0 * sin(p->om * t + p->ph2); \
    double ax1 = Q1 * p->cb - p->cx * y[4] - p->kx * y[0]; \
    double ay1 = Q1 * p->sb - p->cy * y[5] - p->ky * y[1]; \
    double ax2 = Q2 * p->cb - p->cx * y[6] - p->kx * y[2]; \
    double ay2 = Q2 * p->sb - p->cy * y[7] - p->ky * y[3]; \
    double delta = p->sa * (y[0] - y[2]) - p->ca * (y[1] - y[3]) - p->D;

static inline void rhs(const P *p, int mode, double t, const double *y, double *o) {
    BASE
    double N = 0.0, f = 0.0;
    o[0] = y[4]; o[1] = y[5]; o[2] = y[6]; o[3] = y[7];
    if (mode != OPEN) {
        N = p->k * delta;
        if (p->law == 0) {
            if (mode == STICK) f = 0.5 * ((ax1 - ax2) * p->ca + (ay1 - ay2) * p->sa);
            else f = (mode == SLIPP ? p->mu : -p->mu) * N;
        } else {
            f = p->kd * y[8];
            if (mode == STICK) o[8] = p->ca * (y[4] - y[6]) + p->sa * (y[5] - y[7]);
            else {
                double dd = p->sa * (y[4] - y[6]) - p->ca * (y[5] - y[7]);
                o[8] = (mode == SLIPP ? p->mukkd : -p->mukkd) * dd;
            }
        }
    } else if (p->law == 1) {
        o[8] = 0.0;
    }
    o[4] = (ax1 - N * p->sa - f * p->ca) * p->im;
    o[5] = (ay1 + N * p->ca - f * p->sa) * p->im;
    o[6] = (ax2 + N * p->sa + f * p->ca) * p->im;
    o[7] = (ay2 - N * p->ca + f * p->sa) * p->im;
}

static const int N_GUARDS[4] = {1, 3, 2, 2};
static const int GUARD_DIR[4][3] = {{1, 0, 0}, {-1, -1, -1}, {-1, -1, 0}, {-1, -1, 0}};

static inline void guards(const P *p, int mode, double t, const double *y, double *g) {
    if (mode == OPEN) {
        g[0] = p->sa * (y[0] - y[2]) - p->ca * (y[1] - y[3]) - p->D;
        return;
    }
    double muN, v = p->ca * (y[4] - y[6]) + p->sa * (y[5] - y[7]);
    if (p->law == 0) {
        if (mode == STICK) {
            BASE
            double fs = 0.5 * ((ax1 - ax2) * p->ca + (ay1 - ay2) * p->sa);
            muN = p->mu * p->k * delta;
            g[0] = delta; g[1] = muN - fs; g[2] = muN + fs;
        } else {
            g[0] = p->sa * (y[0] - y[2]) - p->ca * (y[1] - y[3]) - p->D;
            g[1] = mode == SLIPP ? v : -v;
        }
    } else {
        double delta = p->sa * (y[0] - y[2]) - p->ca * (y[1] - y[3]) - p->D;
        g[0] = delta;
        if (mode == STICK) {
            muN = p->mu * p->k * delta;
            g[1] = muN - p->kd * y[8]; g[2] = muN + p->kd * y[8];
        } else {
            double zs = p->mukkd * (p->sa * (y[4] - y[6]) - p->ca * (y[5] - y[7]));
            g[1] = mode == SLIPP ? v - zs : -v - zs;
        }
    }
}

/* Coulomb: stick (with the relative tangential velocity removed, the stick
 * projection) if |f_s| <= mu N there; otherwise `otherwise`, state unchanged. */
static int coulomb_stick_or(const P *p, double t, double *y, int otherwise) {
    double ys[9];
    double v = p->ca * (y[4] - y[6]) + p->sa * (y[5] - y[7]);
    memcpy(ys, y, 8 * sizeof(double));
    ys[4] -= 0.5 * p->ca * v; ys[5] -= 0.5 * p->sa * v;
    ys[6] += 0.5 * p->ca * v; ys[7] += 0.5 * p->sa * v;
    {
        const double *y = ys;
        BASE
        double fs = 0.5 * ((ax1 - ax2) * p->ca + (ay1 - ay2) * p->sa);
        if (p->mu * p->k * delta - fabs(fs) < 0.0) return otherwise;
    }
    memcpy(y, ys, 8 * sizeof(double));
    return STICK;
}

static int transition(const P *p, int mode, int gi, double t, double *y) {
    if (gi == 0 && mode != OPEN) {            /* contact opens */
        if (p->law == 1) y[8] = 0.0;
        return OPEN;
    }
    if (p->law == 0) {
        double v = p->ca * (y[4] - y[6]) + p->sa * (y[5] - y[7]);
        if (mode == OPEN) {                   /* contact closes, in slip along sign(v) */
            if (v > 0.0) return SLIPP;
            if (v < 0.0) return SLIPM;
            return coulomb_stick_or(p, t, y, p->mu * p->k * (p->sa * (y[0] - y[2]) - p->ca * (y[1] - y[3]) - p->D) > 0.0 ? SLIPP : SLIPM);
        }
        if (mode == STICK) return gi == 1 ? SLIPP : SLIPM;
        return coulomb_stick_or(p, t, y, mode == SLIPP ? SLIPM : SLIPP);  /* v = 0 */
    }
    if (mode == OPEN) { y[8] = 0.0; return STICK; }
    if (mode == STICK) return gi == 1 ? SLIPP : SLIPM;
    return STICK;
}

static inline void rk4(const P *p, int mode, double t, const double *y, double h,
                       double *k1, double *k2, double *k3, double *k4, double *tmp, double *out) {
    int n = p->n, i;
    rhs(p, mode, t, y, k1);
    for (i = 0; i < n; i++) tmp[i] = y[i] + 0.5 * h * k1[i];
    rhs(p, mode, t + 0.5 * h, tmp, k2);
    for (i = 0; i < n; i++) tmp[i] = y[i] + 0.5 * h * k2[i];
    rhs(p, mode, t + 0.5 * h, tmp, k3);
    for (i = 0; i < n; i++) tmp[i] = y[i] + h * k3[i];
    rhs(p, mode, t + h, tmp, k4);
    for (i = 0; i < n; i++) out[i] = y[i] + h / 6.0 * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i]);
}

static inline int crossed(double g0, double g1, int d) {
    if (d < 0) return g0 >= 0.0 && g1 < 0.0;
    if (d > 0) return g0 <= 0.0 && g1 > 0.0;
    return (g0 > 0.0 && g1 <= 0.0) || (g0 < 0.0 && g1 >= 0.0);
}

static inline int first_crossing(int mode, const double *g0, const double *g1) {
    for (int i = 0; i < N_GUARDS[mode]; i++)
        if (crossed(g0[i], g1[i], GUARD_DIR[mode][i])) return i;
    return -1;
}

/* Integrate periods [start_period, end_period). y is updated in place.
 * counters: steps, events, bisections, rhs evaluations. poincare: (end-start) x n.
 * Returns status (0 ok, 1 non-finite, 2 event storm); *mode_io and *t_out updated. */
int integrate(int law, double *y, int *mode_io, const double *prm, double period, long S,
              long start_period, long end_period, double event_tol, long max_events,
              long *counters, double *poincare, double *t_out) {
    P p; setup(&p, law, prm);
    int n = p.n, mode = *mode_io, g0_valid = 0;
    double h = period / S, k1[9], k2[9], k3[9], k4[9], tmp[9], y1[9], ymid[9];
    double g0[4], g1[4], gm[4];
    double t = period * start_period;
    for (long per = start_period; per < end_period; per++) {
        for (long j = 0; j < S; j++) {
            double t_end = period * per + (j + 1) * h;
            long n_events = 0;
            while (t < t_end) {
                double dt = t_end - t;
                rk4(&p, mode, t, y, dt, k1, k2, k3, k4, tmp, y1);
                counters[3] += 4;
                if (!g0_valid) guards(&p, mode, t, y, g0);
                guards(&p, mode, t_end, y1, g1);
                int gi = first_crossing(mode, g0, g1);
                if (gi < 0) {
                    memcpy(y, y1, n * sizeof(double));
                    memcpy(g0, g1, sizeof g0);
                    g0_valid = 1;
                    t = t_end;
                    break;
                }
                double lo = 0.0, hi = 1.0;
                while ((hi - lo) * dt > event_tol * h) {
                    double mid = 0.5 * (lo + hi);
                    rk4(&p, mode, t, y, mid * dt, k1, k2, k3, k4, tmp, ymid);
                    guards(&p, mode, t + mid * dt, ymid, gm);
                    counters[2] += 1; counters[3] += 4;
                    if (first_crossing(mode, g0, gm) >= 0) {
                        hi = mid;
                        memcpy(y1, ymid, n * sizeof(double));
                        memcpy(g1, gm, sizeof g1);
                    } else {
                        lo = mid;
                    }
                }
                gi = first_crossing(mode, g0, g1);
                t = hi == 1.0 ? t_end : t + hi * dt;
                memcpy(y, y1, n * sizeof(double));
                mode = transition(&p, mode, gi, t, y);
                g0_valid = 0;
                counters[1] += 1;
                if (++n_events > max_events) { *mode_io = mode; *t_out = t; return 2; }
            }
            counters[0] += 1;
            for (int i = 0; i < n; i++)
                if (!isfinite(y[i])) { *mode_io = mode; *t_out = t; return 1; }
        }
        memcpy(poincare + (per - start_period) * n, y, n * sizeof(double));
    }
    *mode_io = mode; *t_out = t;
    return 0;
}
