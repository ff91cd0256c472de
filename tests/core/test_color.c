// test_color.c -- the sRGB transfer function (core/rs_color.h), tabulated and exact, against the
// IEC 61966-2-1 formulas written out here with pow(): brute force over 10^7 points of [0, 1]
// plus the breakpoints; the tables within 1e-6 everywhere (1/4000 of an 8-bit step; the worst is
// at the encoder's kink, 0.0031308), the exact versions within 0 (the same formula), decode of
// encode within 1e-12; values outside [0, 1] clamped, NaN read as 0. The decode slope against the
// formula's derivative, written out here, within 1.2e-4 relative away from the kink (2 table
// intervals either side of 0.04045).
#include <math.h>
#include <stdio.h>

#include "core/rs_color.h"
#include "tests/common/rs_test.h"

static double dec(double v) { return v <= 0.04045 ? v / 12.92 : pow((v + 0.055) / 1.055, 2.4); }
static double dslope(double v) { return v <= 0.04045 ? 1 / 12.92 : 2.4 / 1.055 * pow((v + 0.055) / 1.055, 1.4); }
static double enc(double v) { return v <= 0.0031308 ? 12.92 * v : 1.055 * pow(v, 1 / 2.4) - 0.055; }

int main(void)
{
    const int N = 10000000;
    double worst_dec = 0, worst_enc = 0, at_dec = 0, at_enc = 0, worst_exact = 0, worst_round = 0;
    for (int i = 0; i <= N + 4; i++) {
        const double v = i <= N ? (double)i / N : (double[]){0.04045, 0.0031308, 0.5, 1.0}[i - N - 1];
        const double ed = fabs(rs_color_srgb_decode(v) - dec(v));
        const double ee = fabs(rs_color_srgb_encode(v) - enc(v));
        if (ed > worst_dec) worst_dec = ed, at_dec = v;
        if (ee > worst_enc) worst_enc = ee, at_enc = v;
        worst_exact = fmax(worst_exact, fmax(fabs(rs_color_srgb_decode_exact(v) - dec(v)),
                                             fabs(rs_color_srgb_encode_exact(v) - enc(v))));
        worst_round = fmax(worst_round, fabs(rs_color_srgb_decode_exact(rs_color_srgb_encode_exact(v)) - v));
    }
    printf("tables: decode worst %.3g at %.9f, encode worst %.3g at %.9f; exact: %.3g; round trip %.3g "
           "(10^7 points)\n",
           worst_dec, at_dec, worst_enc, at_enc, worst_exact, worst_round);
    CHECK(worst_dec <= 1e-6 && worst_enc <= 1e-6, "tables beyond 1e-6: %.3g, %.3g", worst_dec, worst_enc);
    CHECK(worst_exact == 0, "exact differs from the formula by %.3g", worst_exact);
    CHECK(worst_round <= 1e-12, "decode(encode(v)) off by %.3g", worst_round);
    CHECK(rs_color_srgb_encode(-0.5) == 0 && rs_color_srgb_encode(1.5) == enc(1.0) && rs_color_srgb_decode(NAN) == 0 &&
              rs_color_srgb_decode_exact(NAN) == 0 && rs_color_srgb_decode_exact(1.5) == dec(1.0) &&
              rs_color_srgb_encode_exact(-1) == 0,
          "outside [0, 1] not clamped");
    double worst_slope = 0, at_slope = 0;
    for (int i = 0; i <= 1000000; i++) {
        const double v = i / 1e6;
        if (fabs(v - 0.04045) <= 2.0 / 65536) continue;
        const double e = fabs(rs_color_srgb_decode_slope(v) / dslope(v) - 1);
        if (e > worst_slope) worst_slope = e, at_slope = v;
    }
    printf("decode slope: worst relative %.3g at %.6f (10^6 points)\n", worst_slope, at_slope);
    CHECK(worst_slope <= 1.2e-4, "decode slope off by %.3g (relative) at %.6f", worst_slope, at_slope);
    return rs_test_end("core_color");
}
