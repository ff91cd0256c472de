// rs_color.c -- the sRGB transfer function, exact and tabulated. See rs_color.h.
#include "core/rs_color.h"

#include <math.h>
#include <pthread.h>

static double clamp01(double v) { return v > 0 ? (v < 1 ? v : 1) : 0; } // NaN -> 0

double rs_color_srgb_decode_exact(double v)
{
    v = clamp01(v);
    return v <= 0.04045 ? v / 12.92 : pow((v + 0.055) / 1.055, 2.4);
}

double rs_color_srgb_encode_exact(double v)
{
    v = clamp01(v);
    return v <= 0.0031308 ? 12.92 * v : 1.055 * pow(v, 1 / 2.4) - 0.055;
}

#define SRGB_TABLE 65536 // intervals over [0, 1]
static double srgb_dec[SRGB_TABLE + 1], srgb_enc[SRGB_TABLE + 1];
static pthread_once_t srgb_once = PTHREAD_ONCE_INIT;

static void srgb_fill(void)
{
    for (int i = 0; i <= SRGB_TABLE; i++) {
        srgb_dec[i] = rs_color_srgb_decode_exact((double)i / SRGB_TABLE);
        srgb_enc[i] = rs_color_srgb_encode_exact((double)i / SRGB_TABLE);
    }
}

static double srgb_lookup(const double *table, double v)
{
    pthread_once(&srgb_once, srgb_fill);
    if (!(v > 0)) return table[0]; // also NaN
    if (v >= 1) return table[SRGB_TABLE];
    const double x = v * SRGB_TABLE;
    const int i = (int)x;
    const double f = x - i;
    return table[i] + f * (table[i + 1] - table[i]);
}

double rs_color_srgb_decode(double v) { return srgb_lookup(srgb_dec, v); }

double rs_color_srgb_encode(double v) { return srgb_lookup(srgb_enc, v); }

double rs_color_srgb_decode_slope(double v)
{
    pthread_once(&srgb_once, srgb_fill);
    const double x = v * SRGB_TABLE;
    const int i = !(x > 0) ? 0 : x >= SRGB_TABLE ? SRGB_TABLE - 1 : (int)x; // also NaN: 0
    return (srgb_dec[i + 1] - srgb_dec[i]) * SRGB_TABLE;
}
