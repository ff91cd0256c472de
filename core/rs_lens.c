// rs_lens.c -- projection and unprojection (core/rs_lens.h): mrcal's, with CAHVORE's gradients
// and unprojection computed here.
#include "core/rs_lens.h"

#include <math.h>
#include <string.h>

// ---------------------------------------------------------------------------------------------
// forward-mode derivatives: a value and its derivatives along ND directions
//   0..2: the point p (x, y, z); 3..10: alpha, beta, r0, r1, r2, e0, e1, e2 (intrinsics 4..11)

enum { ND = 11 };
typedef struct {
    double v;
    double d[ND];
} dual;

static dual dconst(double v)
{
    dual r = {.v = v};
    return r;
}
static dual dvar(double v, int i)
{
    dual r = {.v = v};
    r.d[i] = 1.0;
    return r;
}
static dual dadd(dual a, dual b)
{
    dual r = {.v = a.v + b.v};
    for (int i = 0; i < ND; i++) r.d[i] = a.d[i] + b.d[i];
    return r;
}
static dual dsub(dual a, dual b)
{
    dual r = {.v = a.v - b.v};
    for (int i = 0; i < ND; i++) r.d[i] = a.d[i] - b.d[i];
    return r;
}
static dual dmul(dual a, dual b)
{
    dual r = {.v = a.v * b.v};
    for (int i = 0; i < ND; i++) r.d[i] = a.d[i] * b.v + a.v * b.d[i];
    return r;
}
static dual dscale(dual a, double s)
{
    dual r = {.v = a.v * s};
    for (int i = 0; i < ND; i++) r.d[i] = a.d[i] * s;
    return r;
}
static dual ddiv(dual a, dual b)
{
    dual r = {.v = a.v / b.v};
    for (int i = 0; i < ND; i++) r.d[i] = (a.d[i] - r.v * b.d[i]) / b.v;
    return r;
}
// f(a) with f(a.v) = fv, f'(a.v) = df
static dual dchain(dual a, double fv, double df)
{
    dual r = {.v = fv};
    for (int i = 0; i < ND; i++) r.d[i] = df * a.d[i];
    return r;
}
static dual dsqrt(dual a)
{
    const double s = sqrt(a.v);
    return dchain(a, s, s > 0 ? 0.5 / s : 0.0);
}

// ---------------------------------------------------------------------------------------------
// CAHVORE projection of one point (the equations of core/rs_lens.h)

typedef struct {
    double fx, fy, cx, cy, linearity;
    dual alpha, beta, r[3], e[3];
} cahvore;

static cahvore cahvore_of(const double *intrinsics, double linearity)
{
    cahvore c = {
        .fx = intrinsics[0], .fy = intrinsics[1], .cx = intrinsics[2], .cy = intrinsics[3], .linearity = linearity};
    c.alpha = dvar(intrinsics[4], 3);
    c.beta = dvar(intrinsics[5], 4);
    for (int k = 0; k < 3; k++) {
        c.r[k] = dvar(intrinsics[6 + k], 5 + k);
        c.e[k] = dvar(intrinsics[9 + k], 8 + k);
    }
    return c;
}

// E(theta) = e0 + e1 theta^2 + e2 theta^4 with theta a dual
static dual entrance(const cahvore *c, dual th)
{
    const dual t2 = dmul(th, th);
    return dadd(c->e[0], dmul(t2, dadd(c->e[1], dmul(t2, c->e[2]))));
}

// Solves g(theta) = omega sin theta - l cos theta - (theta - sin theta) E(theta) = 0 for the value
// by Newton's method from atan2(l, omega) (as mrcal does), then theta's derivatives by the
// implicit function theorem. False when it does not converge.
static bool cahvore_theta(dual *theta, const cahvore *c, dual omega, dual l)
{
    const double e0 = c->e[0].v, e1 = c->e[1].v, e2 = c->e[2].v;
    double th = atan2(l.v, omega.v), upsilon = 0;
    int it;
    for (it = 0; it < 100; it++) {
        const double s = sin(th), co = cos(th), t2 = th * th;
        const double E = e0 + e1 * t2 + e2 * t2 * t2, dE = 2 * e1 * th + 4 * e2 * t2 * th;
        upsilon = omega.v * co + l.v * s - (1 - co) * E - (th - s) * dE;
        const double g = omega.v * s - l.v * co - (th - s) * E;
        const double step = g / upsilon;
        th -= step;
        if (!isfinite(th)) return false;
        if (fabs(step) < 1e-12) break;
    }
    if (it == 100 || !(fabs(upsilon) > 0)) return false;
    // dg at fixed theta, along every direction; dtheta = -dg / upsilon
    const dual thc = dconst(th);
    const double s = sin(th), co = cos(th);
    const dual g = dsub(dsub(dscale(omega, s), dscale(l, co)), dscale(entrance(c, thc), th - s));
    *theta = dchain(g, th, 0.0);
    for (int i = 0; i < ND; i++) theta->d[i] = -g.d[i] / upsilon;
    return true;
}

// q (2 duals) of the camera-frame point p; false (q NaN) where CAHVORE does not project it.
static bool cahvore_project1(dual q[2], const cahvore *c, const double p[3])
{
    dual P[3], n2 = dconst(0);
    for (int k = 0; k < 3; k++) {
        P[k] = dvar(p[k], k);
        n2 = dadd(n2, dmul(P[k], P[k]));
    }
    const dual n = dsqrt(n2);
    if (!(n.v > 0)) return false;
    dual v[3];
    for (int k = 0; k < 3; k++) v[k] = ddiv(P[k], n);
    const dual sa = dchain(c->alpha, sin(c->alpha.v), cos(c->alpha.v));
    const dual ca = dchain(c->alpha, cos(c->alpha.v), -sin(c->alpha.v));
    const dual sb = dchain(c->beta, sin(c->beta.v), cos(c->beta.v));
    const dual cb = dchain(c->beta, cos(c->beta.v), -sin(c->beta.v));
    const dual o[3] = {dmul(cb, sa), sb, dmul(cb, ca)};
    const dual omega = dadd(dadd(dmul(v[0], o[0]), dmul(v[1], o[1])), dmul(v[2], o[2]));
    dual ll[3], l2 = dconst(0);
    for (int k = 0; k < 3; k++) {
        ll[k] = dsub(v[k], dmul(omega, o[k]));
        l2 = dadd(l2, dmul(ll[k], ll[k]));
    }
    const dual l = dsqrt(l2);
    dual theta;
    if (!cahvore_theta(&theta, c, omega, l)) return false;
    const double L = c->linearity;
    if (theta.v * fabs(L) > M_PI / 2) return false;
    dual u[3];
    if (theta.v > 1e-8) {
        dual chi;
        if (L < -1e-15)
            chi = dscale(dchain(theta, sin(L * theta.v), L * cos(L * theta.v)), 1 / L);
        else if (L > 1e-15) {
            const double t = tan(L * theta.v);
            chi = dscale(dchain(theta, t, L * (1 + t * t)), 1 / L);
        } else
            chi = theta;
        const dual chi2 = dmul(chi, chi);
        const dual mu = dadd(c->r[0], dmul(chi2, dadd(c->r[1], dmul(chi2, c->r[2]))));
        const dual zetap = ddiv(l, chi), one_mu = dadd(dconst(1), mu);
        for (int k = 0; k < 3; k++) u[k] = dadd(dmul(zetap, o[k]), dmul(one_mu, ll[k]));
    } else
        memcpy(u, v, sizeof(u));
    if (!(fabs(u[2].v) > 0)) return false;
    q[0] = dadd(dscale(ddiv(u[0], u[2]), c->fx), dconst(c->cx));
    q[1] = dadd(dscale(ddiv(u[1], u[2]), c->fy), dconst(c->cy));
    return isfinite(q[0].v) && isfinite(q[1].v);
}

static void cahvore_project(mrcal_point2_t *q, mrcal_point3_t *dq_dp, double *dq_dintrinsics, const mrcal_point3_t *p,
                            int N, double linearity, const double *intrinsics)
{
    const cahvore c = cahvore_of(intrinsics, linearity);
    for (int i = 0; i < N; i++) {
        dual qd[2];
        const bool ok = cahvore_project1(qd, &c, p[i].xyz);
        q[i].x = ok ? qd[0].v : NAN;
        q[i].y = ok ? qd[1].v : NAN;
        for (int r = 0; r < 2; r++) {
            if (dq_dp)
                for (int k = 0; k < 3; k++) dq_dp[2 * i + r].xyz[k] = ok ? qd[r].d[k] : NAN;
            if (!dq_dintrinsics) continue;
            double *row = &dq_dintrinsics[(2 * i + r) * 12];
            memset(row, 0, 12 * sizeof(double));
            if (!ok) {
                for (int k = 0; k < 12; k++) row[k] = NAN;
                continue;
            }
            const double f = r == 0 ? c.fx : c.fy, cen = r == 0 ? c.cx : c.cy;
            row[r] = (qd[r].v - cen) / f; // dq/df: u_x/u_z (or u_y/u_z)
            row[2 + r] = 1.0;             // dq/dc
            for (int k = 0; k < 8; k++) row[4 + k] = qd[r].d[3 + k];
        }
    }
}

bool rs_lens_project(mrcal_point2_t *q, mrcal_point3_t *dq_dp, double *dq_dintrinsics, const mrcal_point3_t *p, int N,
                     const mrcal_lensmodel_t *lensmodel, const double *intrinsics)
{
    if (lensmodel->type != MRCAL_LENSMODEL_CAHVORE)
        return mrcal_project(q, dq_dp, dq_dintrinsics, p, N, lensmodel, intrinsics);
    if (!dq_dp && !dq_dintrinsics) return mrcal_project(q, NULL, NULL, p, N, lensmodel, intrinsics);
    cahvore_project(q, dq_dp, dq_dintrinsics, p, N, lensmodel->LENSMODEL_CAHVORE__config.linearity, intrinsics);
    return true;
}

// ---------------------------------------------------------------------------------------------
// CAHVORE unprojection

// The direction, in the axis frame of o, of normalised image radius rho (= |q - c| / f) under
// the radial model alone (E = 0): chi (1 + mu(chi)) = rho by Newton from chi = rho; NaN when no
// angle of the lens reaches rho.
static double radial_theta(double rho, const double *intrinsics, double L)
{
    const double r0 = intrinsics[6], r1 = intrinsics[7], r2 = intrinsics[8];
    double chi = rho / (1 + r0);
    for (int it = 0; it < 50; it++) {
        const double c2 = chi * chi;
        const double g = chi * (1 + r0 + r1 * c2 + r2 * c2 * c2) - rho;
        const double dg = 1 + r0 + 3 * r1 * c2 + 5 * r2 * c2 * c2;
        if (!(fabs(dg) > 0)) return NAN;
        const double step = g / dg;
        chi -= step;
        if (fabs(step) < 1e-15 * (1 + fabs(chi))) break;
    }
    if (!isfinite(chi) || chi < 0) return NAN;
    if (L < -1e-15) return fabs(L * chi) <= 1 ? asin(L * chi) / L : NAN;
    if (L > 1e-15) return atan(L * chi) / L;
    return chi;
}

static void unit(double v[3])
{
    const double n = sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
    for (int k = 0; k < 3; k++) v[k] /= n;
}

static void cahvore_unproject1(mrcal_point3_t *out, const mrcal_point2_t *q, const mrcal_lensmodel_t *lensmodel,
                               const double *intrinsics)
{
    const double L = lensmodel->LENSMODEL_CAHVORE__config.linearity;
    const double x = (q->x - intrinsics[2]) / intrinsics[0], y = (q->y - intrinsics[3]) / intrinsics[1];
    const double rho = hypot(x, y), th = radial_theta(rho, intrinsics, L);
    out->x = out->y = out->z = NAN;
    if (!isfinite(th) || th >= M_PI) return;
    // the direction about the optical axis o, then rotated onto it: o = R_y(alpha) R_x(-beta) z
    double a[3] = {rho > 0 ? sin(th) * x / rho : 0, rho > 0 ? sin(th) * y / rho : 0, cos(th)};
    const double al = intrinsics[4], be = intrinsics[5];
    const double b1[3] = {a[0], a[1] * cos(be) + a[2] * sin(be), -a[1] * sin(be) + a[2] * cos(be)};
    double v[3] = {b1[0] * cos(al) + b1[2] * sin(al), b1[1], -b1[0] * sin(al) + b1[2] * cos(al)};
    // Gauss-Newton in the tangent plane of v (basis t1, t2) on the full projection
    for (int it = 0; it < 30; it++) {
        mrcal_point3_t p = {.x = v[0], .y = v[1], .z = v[2]}, dq_dp[2];
        mrcal_point2_t qp;
        cahvore_project(&qp, dq_dp, NULL, &p, 1, L, intrinsics);
        if (!isfinite(qp.x)) return;
        const double e0 = qp.x - q->x, e1 = qp.y - q->y;
        if (fabs(e0) + fabs(e1) < 1e-10) {
            out->x = v[0];
            out->y = v[1];
            out->z = v[2];
            return;
        }
        double t1[3] = {0, 0, 0}, t2[3];
        t1[fabs(v[0]) < 0.9 ? 0 : 1] = 1;
        const double d = t1[0] * v[0] + t1[1] * v[1] + t1[2] * v[2];
        for (int k = 0; k < 3; k++) t1[k] -= d * v[k];
        unit(t1);
        t2[0] = v[1] * t1[2] - v[2] * t1[1];
        t2[1] = v[2] * t1[0] - v[0] * t1[2];
        t2[2] = v[0] * t1[1] - v[1] * t1[0];
        double J[4];
        for (int r = 0; r < 2; r++) {
            J[2 * r] = dq_dp[r].x * t1[0] + dq_dp[r].y * t1[1] + dq_dp[r].z * t1[2];
            J[2 * r + 1] = dq_dp[r].x * t2[0] + dq_dp[r].y * t2[1] + dq_dp[r].z * t2[2];
        }
        const double det = J[0] * J[3] - J[1] * J[2];
        if (!(fabs(det) > 0)) return;
        const double da = -(J[3] * e0 - J[1] * e1) / det, db = -(-J[2] * e0 + J[0] * e1) / det;
        for (int k = 0; k < 3; k++) v[k] += da * t1[k] + db * t2[k];
        unit(v);
    }
}

bool rs_lens_unproject(mrcal_point3_t *v, const mrcal_point2_t *q, int N, const mrcal_lensmodel_t *lensmodel,
                       const double *intrinsics)
{
    if (lensmodel->type != MRCAL_LENSMODEL_CAHVORE) return mrcal_unproject(v, q, N, lensmodel, intrinsics);
    for (int i = 0; i < N; i++) cahvore_unproject1(&v[i], &q[i], lensmodel, intrinsics);
    return true;
}

bool rs_lens_sees_behind(const mrcal_lensmodel_t *lensmodel)
{
    return lensmodel->type == MRCAL_LENSMODEL_CAHVORE && fabs(lensmodel->LENSMODEL_CAHVORE__config.linearity) < 1;
}
