// test_lens.c -- projection and unprojection through core/rs_lens.h, CAHVORE above all.
// Oracles:
//   - values: mrcal_project itself (CAHVORE without gradients), within 1e-9 px, for random
//     CAHVORE lenses (linearity 0, 0.4, -0.3; tilted axes; r and e terms) and points up to 85
//     degrees off the axis;
//   - the equidistant fisheye (linearity 0, no distortion): pixel radius f theta in closed form,
//     within 1e-9 px, for theta from 0.5 to 179 degrees;
//   - Kannala-Brandt with k3 = k4 = 0 (r1 = k1, r2 = k2): f theta (1 + k1 theta^2 + k2 theta^4),
//     within 1e-9 px;
//   - gradients d(q)/d(p) and d(q)/d(intrinsics): central differences (d(q)/d(p): step 1e-6
//     relative; d(q)/d(intrinsics): Richardson-extrapolated, steps 1e-4 and 5e-5 for the
//     dimensionless terms, smaller where the gradient exceeds 100 px), agreement 1e-6 of the gradient's scale;
//   - unprojection: the direction projects back to the pixel within 1e-9 px, over a grid that
//     covers the fisheye's whole circle up to 179 degrees; other lens models pass through to
//     mrcal_unproject unchanged (bit for bit).
// Fixed seed, printed on failure.
#include <math.h>
#include <stdio.h>
#include <string.h>

#include <mrcal/mrcal.h>

#include "core/rs_lens.h"
#include "core/rs_rng.h"
#include "tests/common/rs_test.h"

static mrcal_lensmodel_t cahvore(double linearity)
{
    mrcal_lensmodel_t m = {.type = MRCAL_LENSMODEL_CAHVORE};
    m.LENSMODEL_CAHVORE__config.linearity = linearity;
    return m;
}

// a point at angle th (radians) off the z axis, azimuth az, distance d
static mrcal_point3_t at_angle(double th, double az, double d)
{
    mrcal_point3_t p = {.x = d * sin(th) * cos(az), .y = d * sin(th) * sin(az), .z = d * cos(th)};
    return p;
}

static void check_gradients(const mrcal_lensmodel_t *m, double *in, const mrcal_point3_t *p, const char *what)
{
    mrcal_point2_t q;
    mrcal_point3_t dq_dp[2];
    double dq_di[24];
    CHECK(rs_lens_project(&q, dq_dp, dq_di, p, 1, m, in), "%s: project with gradients", what);
    for (int k = 0; k < 3; k++) {
        const double h = 1e-6 * fmax(1.0, fabs(p->xyz[k]));
        mrcal_point3_t a = *p, b = *p;
        a.xyz[k] += h;
        b.xyz[k] -= h;
        mrcal_point2_t qa, qb;
        rs_lens_project(&qa, NULL, NULL, &a, 1, m, in);
        rs_lens_project(&qb, NULL, NULL, &b, 1, m, in);
        const double gx = (qa.x - qb.x) / (2 * h), gy = (qa.y - qb.y) / (2 * h);
        const double scale = 1 + fabs(dq_dp[0].xyz[k]) + fabs(dq_dp[1].xyz[k]);
        CHECK(fabs(gx - dq_dp[0].xyz[k]) < 1e-6 * scale && fabs(gy - dq_dp[1].xyz[k]) < 1e-6 * scale,
              "%s: dq/dp[%d] analytic (%.9g, %.9g), central differences (%.9g, %.9g)", what, k, dq_dp[0].xyz[k],
              dq_dp[1].xyz[k], gx, gy);
    }
    for (int k = 0; k < 12; k++) {
        // near 180 degrees off axis q is far from linear in the e terms: smaller steps there
        const double big = fmax(1, (fabs(dq_di[k]) + fabs(dq_di[12 + k])) / 100);
        const double keep = in[k], h = k < 4 ? 1e-6 * fabs(keep) : 1e-4 / big;
        double g[2][2]; // central differences at steps h and h/2, (x, y)
        for (int s = 0; s < 2; s++) {
            mrcal_point2_t qa, qb;
            in[k] = keep + h / (1 + s);
            rs_lens_project(&qa, NULL, NULL, p, 1, m, in);
            in[k] = keep - h / (1 + s);
            rs_lens_project(&qb, NULL, NULL, p, 1, m, in);
            g[s][0] = (qa.x - qb.x) / (2 * h / (1 + s));
            g[s][1] = (qa.y - qb.y) / (2 * h / (1 + s));
        }
        in[k] = keep;
        // Richardson: (4 D(h/2) - D(h)) / 3 cancels the h^2 term
        const double gx = (4 * g[1][0] - g[0][0]) / 3, gy = (4 * g[1][1] - g[0][1]) / 3;
        const double scale = 1 + fabs(dq_di[k]) + fabs(dq_di[12 + k]);
        CHECK(fabs(gx - dq_di[k]) < 1e-6 * scale && fabs(gy - dq_di[12 + k]) < 1e-6 * scale,
              "%s: dq/dintrinsics[%d] analytic (%.9g, %.9g), central differences (%.9g, %.9g)", what, k, dq_di[k],
              dq_di[12 + k], gx, gy);
    }
}

static void check_roundtrip(const mrcal_lensmodel_t *m, const double *in, double max_theta, const char *what)
{
    double worst = 0;
    int n = 0;
    for (int i = 0; i <= 40; i++)
        for (int j = 0; j < 36; j++) {
            const double th = max_theta * i / 40.0, az = j * 2 * M_PI / 36;
            mrcal_point3_t p = at_angle(th, az, 10), v;
            mrcal_point2_t q, qb;
            rs_lens_project(&q, NULL, NULL, &p, 1, m, in);
            if (!isfinite(q.x)) continue;
            CHECK(rs_lens_unproject(&v, &q, 1, m, in), "%s: unproject", what);
            rs_lens_project(&qb, NULL, NULL, &v, 1, m, in);
            const double e = hypot(qb.x - q.x, qb.y - q.y);
            CHECK(e < 1e-9, "%s: pixel (%.6f, %.6f) at %.3f deg: back %.3g px away", what, q.x, q.y, th * 180 / M_PI,
                  e);
            if (e > worst) worst = e;
            n++;
        }
    CHECK(n > 1000, "%s: only %d pixels tried", what, n);
    printf("%s: %d pixels unprojected, worst reprojection %.2g px\n", what, n, worst);
}

int main(void)
{
    rs_test_seed = 38;
    rs_rng rng;
    rs_rng_seed(&rng, rs_test_seed);

    // 1. the equidistant fisheye: r = f theta (a GridSmart-style 1280x960 camera)
    {
        const mrcal_lensmodel_t m = cahvore(0.0);
        double in[12] = {340.0, 340.0, 640.0, 480.0};
        double worst = 0;
        for (double deg = 0.5; deg <= 179.0; deg += 0.5) {
            const double th = deg * M_PI / 180, az = rs_rng_uniform_in(&rng, 0, 2 * M_PI);
            const mrcal_point3_t p = at_angle(th, az, rs_rng_uniform_in(&rng, 1, 100));
            mrcal_point2_t q;
            CHECK(rs_lens_project(&q, NULL, NULL, &p, 1, &m, in), "equidistant project");
            const double ex = q.x - (640 + 340 * th * cos(az)), ey = q.y - (480 + 340 * th * sin(az));
            worst = fmax(worst, hypot(ex, ey));
            CHECK(hypot(ex, ey) < 1e-9, "equidistant at %.1f deg: %.3g px from f theta", deg, hypot(ex, ey));
            if ((int)(deg * 2) % 17 == 0) check_gradients(&m, in, &p, "equidistant");
        }
        printf("equidistant: worst %.2g px from f theta over 0.5..179 deg\n", worst);
        check_roundtrip(&m, in, 179 * M_PI / 180, "equidistant unprojection");
        mrcal_point2_t q = {.x = 640 + 340 * 3.2, .y = 480};
        mrcal_point3_t v;
        rs_lens_unproject(&v, &q, 1, &m, in);
        CHECK(isnan(v.x), "a pixel beyond 180 degrees unprojects to (%g %g %g), not NaN", v.x, v.y, v.z);
        CHECK(rs_lens_sees_behind(&m), "an equidistant lens sees behind 90 degrees");
    }

    // 2. Kannala-Brandt with k3 = k4 = 0 as CAHVORE: r1 = k1, r2 = k2, fx != fy
    {
        const mrcal_lensmodel_t m = cahvore(0.0);
        const double k1 = -0.021, k2 = 0.0034;
        double in[12] = {352.5, 351.0, 641.3, 479.2, 0, 0, 0, k1, k2};
        double worst = 0;
        for (double deg = 1; deg <= 100; deg += 1) {
            const double th = deg * M_PI / 180, az = rs_rng_uniform_in(&rng, 0, 2 * M_PI);
            const mrcal_point3_t p = at_angle(th, az, 20);
            mrcal_point2_t q;
            rs_lens_project(&q, NULL, NULL, &p, 1, &m, in);
            const double td = th * (1 + k1 * th * th + k2 * pow(th, 4));
            const double e = hypot(q.x - (in[2] + in[0] * td * cos(az)), q.y - (in[3] + in[1] * td * sin(az)));
            worst = fmax(worst, e);
            CHECK(e < 1e-9, "Kannala-Brandt at %.0f deg: %.3g px from the formula", deg, e);
        }
        printf("Kannala-Brandt (k1, k2): worst %.2g px from the formula over 1..100 deg\n", worst);
        check_roundtrip(&m, in, 100 * M_PI / 180, "Kannala-Brandt unprojection");
        const mrcal_point3_t p = at_angle(1.2, 0.7, 15);
        check_gradients(&m, in, &p, "Kannala-Brandt");
    }

    // 3. general CAHVORE: values against mrcal, gradients against central differences
    const double linearities[3] = {0.0, 0.4, -0.3};
    for (int t = 0; t < 60; t++) {
        const mrcal_lensmodel_t m = cahvore(linearities[t % 3]);
        double in[12] = {rs_rng_uniform_in(&rng, 300, 1500), 0, rs_rng_uniform_in(&rng, 600, 700),
                         rs_rng_uniform_in(&rng, 450, 520)};
        in[1] = in[0] * rs_rng_uniform_in(&rng, 0.98, 1.02);
        in[4] = 0.02 * rs_rng_normal(&rng);
        in[5] = 0.02 * rs_rng_normal(&rng);
        in[6] = 0.01 * rs_rng_normal(&rng);
        in[7] = 0.02 * rs_rng_normal(&rng);
        in[8] = 0.005 * rs_rng_normal(&rng);
        in[9] = 0.01 * rs_rng_normal(&rng);
        in[10] = 0.01 * rs_rng_normal(&rng);
        in[11] = 0.002 * rs_rng_normal(&rng);
        const double max_th = (m.LENSMODEL_CAHVORE__config.linearity > 0.3 ? 70 : 85) * M_PI / 180;
        char what[64];
        snprintf(what, sizeof what, "CAHVORE %d (linearity %.1f)", t, m.LENSMODEL_CAHVORE__config.linearity);
        for (int k = 0; k < 20; k++) {
            const mrcal_point3_t p =
                at_angle(rs_rng_uniform_in(&rng, 0.001, max_th), rs_rng_uniform_in(&rng, 0, 2 * M_PI), 30);
            mrcal_point2_t q, qm;
            rs_lens_project(&q, NULL, NULL, &p, 1, &m, in);
            mrcal_point3_t dq_dp[2];
            mrcal_point2_t qg;
            rs_lens_project(&qg, dq_dp, NULL, &p, 1, &m, in); // the analytic path's value
            CHECK(mrcal_project(&qm, NULL, NULL, &p, 1, &m, in), "%s: mrcal_project", what);
            const double e = hypot(qg.x - qm.x, qg.y - qm.y);
            CHECK(e < 1e-9 && q.x == qm.x, "%s: analytic (%.9f, %.9f), mrcal (%.9f, %.9f): %.3g px", what, qg.x, qg.y,
                  qm.x, qm.y, e);
            if (k < 3) check_gradients(&m, in, &p, what);
        }
        if (t < 6) check_roundtrip(&m, in, max_th, what);
    }

    // 4. other lens models pass through to mrcal unchanged
    {
        const mrcal_lensmodel_t m = {.type = MRCAL_LENSMODEL_OPENCV8};
        const double in[12] = {1200, 1210, 960, 540, -0.2, 0.05, 1e-3, -2e-3, 0.01, 0.001, -0.002, 0.0005};
        mrcal_point2_t q = {.x = 100.25, .y = 900.5};
        mrcal_point3_t v1, v2;
        rs_lens_unproject(&v1, &q, 1, &m, in);
        mrcal_unproject(&v2, &q, 1, &m, in);
        CHECK(memcmp(&v1, &v2, sizeof v1) == 0, "OPENCV8 unprojection differs from mrcal's");
        CHECK(!rs_lens_sees_behind(&m), "OPENCV8 does not see behind 90 degrees");
    }
    return rs_test_end("test_lens");
}
