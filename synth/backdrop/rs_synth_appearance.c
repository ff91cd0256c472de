// rs_synth_appearance.c -- exposure, white balance, noise, blur and JPEG quality of a background,
// applied to a rendered vehicle layer (rs_synth_appearance.h, docs/appearance.md).
#include "synth/backdrop/rs_synth_appearance.h"

#include <math.h>
#include <stdbool.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "core/rs_color.h"
#include "core/rs_io.h"
#include "core/rs_rng.h"
#include "core/rs_stats.h"

// Immerkaer's kernel: cancels locally linear content, gain 6 on white noise.
static const double immerkaer_M[9] = {1, -2, 1, -2, 4, -2, 1, -2, 1};

rs_status rs_synth_estimate_noise(double *sigma, const rs_image *img, rs_err *err)
{
    const double *M = immerkaer_M;
    *sigma = NAN;
    const int W = img->width, H = img->height, C = img->channels < 4 ? img->channels : 3;
    if (W < 3 || H < 3) return rs_err_set(err, RS_ERR_DEGENERATE, "noise: image smaller than 3x3");
    rs_image f = {0};
    rs_status st = rs_synth_image_filter(&f, img, M, 3, 3, err);
    if (st) return st;
    float *v = malloc(sizeof(float) * (size_t)(W - 2) * (H - 2) * C);
    if (!v) {
        rs_image_free(&f);
        return rs_err_set(err, RS_ERR_NOMEM, "out of memory");
    }
    size_t n = 0;
    for (int y = 1; y < H - 1; y++)
        for (int x = 1; x < W - 1; x++)
            for (int c = 0; c < C; c++) v[n++] = fabsf(f.data[((size_t)y * W + x) * img->channels + c]);
    *sigma = 1.482602218505602 * rs_stats_median_f(v, n) / 6.0;
    free(v);
    rs_image_free(&f);
    return RS_OK;
}

// The white-noise sigma of Immerkaer residuals |r| (n,), reordered: their RMS over the 90 %
// smallest, / sqrt(0.6231) (a Gaussian's variance truncated at its 90 % point, +-1.645 sigma), / 6
// (the kernel's gain). Unlike the median of |r|, which takes only a few values when a JPEG has
// left two or three 8-bit codes of noise, it varies smoothly with the noise.
static double trimmed_sigma(float *absr, size_t n)
{
    const float q = rs_stats_select_f(absr, n, (size_t)(0.9 * (n - 1)));
    double ss = 0;
    size_t m = 0;
    for (size_t i = 0; i < n; i++)
        if (absr[i] <= q) ss += (double)absr[i] * absr[i], m++;
    return m ? sqrt(ss / m / 0.6231) / 6.0 : 0;
}

// The noise 1-sigma measured (as in rs_synth_estimate_noise_model) on a flat 3-channel patch of
// stored level `level` with white Gaussian noise of `sigma` (the draws `normal`: seed 40, made
// once by jpeg_unseen_sigma for its bisection), JPEG round-tripped at `quality`. *out NaN on error.
#define JPEG_PATCH       64
#define JPEG_PATCH_DRAWS (3 * JPEG_PATCH * JPEG_PATCH)
static rs_status jpeg_measured_sigma(double *out, double level, double sigma, const double *normal, int quality,
                                     rs_err *err)
{
    *out = NAN;
    rs_image p = {0}, j = {0}, f = {0};
    rs_status st = rs_image_alloc(&p, JPEG_PATCH, JPEG_PATCH, 3, err);
    if (st) return st;
    for (size_t i = 0; i < JPEG_PATCH_DRAWS; i++) {
        const double v = level + sigma * normal[i];
        p.data[i] = (float)(v < 0 ? 0 : v > 1 ? 1 : v);
    }
    float *v = malloc(sizeof(float) * 3 * JPEG_PATCH * JPEG_PATCH);
    if (!v) st = rs_err_set(err, RS_ERR_NOMEM, "out of memory");
    if (!st && !(st = rs_synth_image_jpeg_roundtrip(&j, &p, quality, err)) &&
        !(st = rs_synth_image_filter(&f, &j, immerkaer_M, 3, 3, err))) {
        size_t n = 0;
        for (int y = 1; y < JPEG_PATCH - 1; y++)
            for (int x = 1; x < JPEG_PATCH - 1; x++)
                for (int c = 0; c < 3; c++) v[n++] = fabsf(f.data[((size_t)y * JPEG_PATCH + x) * 3 + c]);
        *out = trimmed_sigma(v, n);
    }
    free(v);
    rs_image_free(&p);
    rs_image_free(&j);
    rs_image_free(&f);
    return st;
}

// The white-noise sigma that measures `seen` after a JPEG round trip at `quality` on a flat patch
// of `level`: bisection in log sigma over [seen, 64 seen] (the measured sigma grows with the true
// one; a JPEG at quality 75 leaves a tenth of a 0.01 sigma).
static rs_status jpeg_unseen_sigma(double *sigma, double level, double seen, int quality, rs_err *err)
{
    double *normal = malloc(sizeof(double) * JPEG_PATCH_DRAWS);
    if (!normal) return rs_err_set(err, RS_ERR_NOMEM, "out of memory");
    rs_rng rng;
    rs_rng_seed(&rng, 40);
    for (size_t i = 0; i < JPEG_PATCH_DRAWS; i++) normal[i] = rs_rng_normal(&rng);
    double lo = seen, hi = 64 * seen, m;
    rs_status st = jpeg_measured_sigma(&m, level, hi, normal, quality, err);
    if (!st && m < seen) { // even 64 x: the JPEG leaves almost nothing; keep the largest
        *sigma = hi;
        free(normal);
        return RS_OK;
    }
    for (int it = 0; it < 10 && !st; it++) { // 64^(1/1024): within 0.4 %
        const double mid = sqrt(lo * hi);
        if ((st = jpeg_measured_sigma(&m, level, mid, normal, quality, err))) break;
        if (m < seen)
            lo = mid;
        else
            hi = mid;
    }
    free(normal);
    if (!st) *sigma = sqrt(lo * hi);
    return st;
}

#define NOISE_BINS 16

rs_status rs_synth_estimate_noise_model(double *a, double *b, const rs_image *img, int jpeg_quality, rs_err *err)
{
    static const double box5[25] = {0.04, 0.04, 0.04, 0.04, 0.04, 0.04, 0.04, 0.04, 0.04, 0.04, 0.04, 0.04, 0.04,
                                    0.04, 0.04, 0.04, 0.04, 0.04, 0.04, 0.04, 0.04, 0.04, 0.04, 0.04, 0.04};
    *a = *b = NAN;
    const int W = img->width, H = img->height, C = img->channels < 4 ? img->channels : 3, CC = img->channels;
    if (W < 8 || H < 8) return rs_err_set(err, RS_ERR_DEGENERATE, "noise model: image smaller than 8x8");
    rs_image r = {0}, m = {0};
    float *grad = NULL, *res = NULL, *tmp = NULL;
    int *bin = NULL;
    rs_status st;
    if ((st = rs_synth_image_filter(&r, img, immerkaer_M, 3, 3, err)) ||
        (st = rs_synth_image_filter(&m, img, box5, 5, 5, err)))
        goto done;
    // every second pixel of every second row (a quarter: the memory of an estimate made in the
    // parent of synth's workers stays in its heap; 260,000 samples at 720 x 480 are plenty)
    const size_t N = (size_t)((W - 5) / 2) * ((H - 5) / 2) * C;
    // one block (grad, res, tmp, bin): one allocation to return, not four to fragment the heap
    grad = malloc((3 * sizeof(float) + sizeof(int)) * N);
    res = grad ? grad + N : NULL;
    tmp = grad ? res + N : NULL;
    bin = grad ? (int *)(tmp + N) : NULL;
    if (!grad) {
        st = rs_err_set(err, RS_ERR_NOMEM, "out of memory");
        goto done;
    }
    // counting sort of the samples by level bin
    size_t count[NOISE_BINS + 1] = {0}, start[NOISE_BINS + 1] = {0};
    double level_sum[NOISE_BINS] = {0};
    size_t n = 0;
    for (int y = 3; y < H - 3; y += 2)
        for (int x = 3; x < W - 3; x += 2)
            for (int c = 0; c < C; c++, n++) {
                const size_t p = ((size_t)y * W + x) * CC + c;
                const float lv = m.data[p];
                int k = (int)(lv * NOISE_BINS);
                bin[n] = k < 0 ? 0 : k >= NOISE_BINS ? NOISE_BINS - 1 : k;
                count[bin[n]]++;
            }
    for (int k = 1; k <= NOISE_BINS; k++) start[k] = start[k - 1] + count[k - 1];
    size_t fill[NOISE_BINS];
    memcpy(fill, start, sizeof(fill));
    n = 0;
    for (int y = 3; y < H - 3; y += 2)
        for (int x = 3; x < W - 3; x += 2)
            for (int c = 0; c < C; c++, n++) {
                const size_t p = ((size_t)y * W + x) * CC + c, dx = CC, dy = (size_t)W * CC;
                const size_t i = fill[bin[n]]++;
                grad[i] = fabsf(m.data[p + dx] - m.data[p - dx]) + fabsf(m.data[p + dy] - m.data[p - dy]);
                res[i] = fabsf(r.data[p]);
                level_sum[bin[n]] += m.data[p];
            }
    // per bin: the smoother half's robust sigma
    double sw = 0, swv = 0, swvv = 0, swy = 0, swvy = 0;
    int Nbins = 0;
    for (int k = 0; k < NOISE_BINS && !st; k++) {
        const size_t nk = count[k];
        const double v = nk ? level_sum[k] / nk : 0;
        if (nk < 300 || v < 0.03 || v > 0.97) continue;
        memcpy(tmp, grad + start[k], sizeof(float) * nk);
        const float gmed = rs_stats_select_f(tmp, nk, nk / 2);
        size_t ns = 0;
        for (size_t i = 0; i < nk; i++)
            if (grad[start[k] + i] <= gmed) tmp[ns++] = res[start[k] + i];
        if (ns < 150) continue;
        double sk = trimmed_sigma(tmp, ns);
        if (jpeg_quality > 0 && sk > 0 && (st = jpeg_unseen_sigma(&sk, v, sk, jpeg_quality, err))) break;
        const double var = sk * sk, w = (double)ns / fmax(var * var, 1e-20);
        sw += w, swv += w * v, swvv += w * v * v, swy += w * var, swvy += w * v * var;
        Nbins++;
    }
    if (st) goto done;
    if (Nbins == 0) {
        st = rs_err_set(err, RS_ERR_DEGENERATE, "noise model: no level with 300 smooth pixels");
        goto done;
    }
    const double det = sw * swvv - swv * swv;
    double A = swy / sw, B = 0;
    if (Nbins >= 2 && det > 1e-12 * sw * swvv) {
        A = (swvv * swy - swv * swvy) / det;
        B = (sw * swvy - swv * swy) / det;
        if (B < 0) { // read noise alone
            A = swy / sw;
            B = 0;
        } else if (A < 0) { // shot noise alone
            A = 0;
            B = swvy / swvv;
        }
    }
    *a = A;
    *b = B;
done:
    free(grad); // (res, tmp, bin: the same block)
    rs_image_free(&r);
    rs_image_free(&m);
    return st;
}

rs_status rs_synth_estimate_blockiness(double *ratio, const rs_image *img, rs_err *err)
{
    *ratio = NAN;
    const int W = img->width, H = img->height, C = img->channels, Cm = C >= 3 ? 3 : 1;
    if (W < 16 || H < 16) return rs_err_set(err, RS_ERR_DEGENERATE, "blockiness: image smaller than 16x16");
    double across[2] = {0, 0}, inside[2] = {0, 0};
    size_t n_across[2] = {0, 0}, n_inside[2] = {0, 0};
#define LUMA(x, y)                                                                                          \
    (img->data[((size_t)(y)*W + (x)) * C] +                                                                 \
     (Cm == 3 ? img->data[((size_t)(y)*W + (x)) * C + 1] + img->data[((size_t)(y)*W + (x)) * C + 2] : 0)) / \
        Cm
    for (int y = 0; y < H; y++)
        for (int x = 0; x + 1 < W; x++) { // horizontal neighbours: a boundary between x = 8k-1 and 8k
            const double d = fabs(LUMA(x + 1, y) - LUMA(x, y));
            const int k = (x + 1) % 8 == 0 ? 0 : 1;
            if (!k)
                across[0] += d, n_across[0]++;
            else
                inside[0] += d, n_inside[0]++;
        }
    for (int y = 0; y + 1 < H; y++)
        for (int x = 0; x < W; x++) {
            const double d = fabs(LUMA(x, y + 1) - LUMA(x, y));
            if ((y + 1) % 8 == 0)
                across[1] += d, n_across[1]++;
            else
                inside[1] += d, n_inside[1]++;
        }
#undef LUMA
    if (!(inside[0] > 0) || !(inside[1] > 0))
        return rs_err_set(err, RS_ERR_DEGENERATE, "blockiness: a flat image (no difference inside the blocks)");
    *ratio = 0.5 * (across[0] / n_across[0] / (inside[0] / n_inside[0]) +
                    across[1] / n_across[1] / (inside[1] / n_inside[1]));
    return RS_OK;
}

// Luma (mean of the first three channels, or the only one) as a 1-channel image.
static rs_status luma(rs_image *out, const rs_image *img, rs_err *err)
{
    rs_status st = rs_image_alloc(out, img->width, img->height, 1, err);
    if (st) return st;
    const int C = img->channels, Cm = C >= 3 ? 3 : 1;
    for (size_t p = 0; p < (size_t)img->width * img->height; p++) {
        double s = 0;
        for (int c = 0; c < Cm; c++) s += img->data[p * C + c];
        out->data[p] = (float)(s / Cm);
    }
    return RS_OK;
}

// Gradient magnitude by central differences (kernel [-1/2, 0, 1/2] in x and y).
static rs_status gradient(rs_image *mag, const rs_image *g, rs_err *err)
{
    static const double kx[3] = {-0.5, 0, 0.5};
    rs_image gx = {0}, gy = {0};
    rs_status st;
    if ((st = rs_synth_image_filter(&gx, g, kx, 3, 1, err)) || (st = rs_synth_image_filter(&gy, g, kx, 1, 3, err)) ||
        (st = rs_image_alloc(mag, g->width, g->height, 1, err)))
        goto done;
    for (size_t p = 0; p < (size_t)g->width * g->height; p++) mag->data[p] = hypotf(gx.data[p], gy.data[p]);
    // keep the dominant axis in the sign: > 0 mostly horizontal gradient, stored separately below
    for (size_t p = 0; p < (size_t)g->width * g->height; p++)
        if (fabsf(gy.data[p]) > fabsf(gx.data[p])) mag->data[p] = -mag->data[p];
done:
    rs_image_free(&gx);
    rs_image_free(&gy);
    return st;
}

// How far on each side of an edge pixel the blur estimate checks that the edge is an isolated
// step (3 x the re-blur's sigma).
#define BLUR_STEP_PX 6

rs_status rs_synth_estimate_blur(double *sigma_px, const rs_image *img, rs_err *err)
{
    const double sr = 2.0;
    *sigma_px = NAN;
    const int W = img->width, H = img->height;
    rs_image g = {0}, gb = {0}, m = {0}, mb = {0};
    float *sel = NULL, *est = NULL;
    rs_status st;
    if ((st = luma(&g, img, err)) || (st = rs_synth_image_blur(&gb, &g, sr, err)) || (st = gradient(&m, &g, err)) ||
        (st = gradient(&mb, &gb, err)))
        goto done;
    const size_t N = (size_t)W * H;
    sel = malloc(sizeof(float) * N);
    est = malloc(sizeof(float) * N);
    if (!sel || !est) {
        st = rs_err_set(err, RS_ERR_NOMEM, "out of memory");
        goto done;
    }
    for (size_t p = 0; p < N; p++) sel[p] = fabsf(m.data[p]);
    const float thr = 0.5f * rs_stats_select_f(sel, N, (size_t)(0.99 * (N - 1)));
    size_t n = 0;
    const int margin = 10;
    for (int y = margin; y < H - margin; y++)
        for (int x = margin; x < W - margin; x++) {
            const size_t p = (size_t)y * W + x;
            const float a = fabsf(m.data[p]);
            if (!(a > thr) || a <= 0) continue;
            const size_t d = m.data[p] > 0 ? 1 : (size_t)W; // along the dominant axis
            if (a < fabsf(m.data[p - d]) || a < fabsf(m.data[p + d])) continue;
            // an isolated step only: the luma difference across the edge, +-j px along the axis,
            // must still be 80 % of its largest at j = BLUR_STEP_PX; a thin line (a lane
            // marking 2 - 4 px wide far away) or close texture falls back, and its gradient,
            // which the re-blur lowers more than a step's, would read too little blur (the
            // demo twin blurred by 1.2 px read 0.60 px with its far markings counted)
            double dmax = 0, dK = 0;
            for (int j = 1; j <= BLUR_STEP_PX; j++) {
                dK = fabs((double)g.data[p + j * d] - g.data[p - j * d]);
                dmax = dK > dmax ? dK : dmax;
            }
            if (dK < 0.8 * dmax) continue;
            const double R = a / fabsf(mb.data[p]);
            if (!(R > 1.0 + 1e-6)) continue;
            const double s2 = sr * sr / (R * R - 1) - 1.0 / 3.0;
            est[n++] = (float)(s2 > 0 ? sqrt(s2) : 0);
        }
    if (n < 20) {
        st = rs_err_set(err, RS_ERR_DEGENERATE, "blur: only %zu edge pixels (need 20)", n);
        goto done;
    }
    *sigma_px = rs_stats_median_f(est, n);
done:
    free(sel);
    free(est);
    rs_image_free(&g);
    rs_image_free(&gb);
    rs_image_free(&m);
    rs_image_free(&mb);
    return st;
}

rs_status rs_synth_estimate_gain(double gain[3], const rs_image *t, const rs_image *ref, const uint8_t *mask,
                                 rs_err *err)
{
    gain[0] = gain[1] = gain[2] = NAN;
    if (t->channels < 3 || (ref && (ref->channels < 3 || ref->width != t->width || ref->height != t->height)))
        return rs_err_set(err, RS_ERR_INVALID, "gain: images must be RGB(A) of the same size (%dx%dx%d vs %dx%dx%d)",
                          t->width, t->height, t->channels, ref ? ref->width : 0, ref ? ref->height : 0,
                          ref ? ref->channels : 0);
    double st[3] = {0, 0, 0}, sr[3] = {0, 0, 0};
    size_t n = 0;
    for (size_t p = 0; p < (size_t)t->width * t->height; p++) {
        if (mask && !mask[p]) continue;
        const float *a = t->data + p * t->channels, *b = ref ? ref->data + p * ref->channels : a;
        bool ok = true;
        for (int c = 0; c < 3; c++) ok = ok && a[c] > 0.02f && a[c] < 0.98f && b[c] > 0.02f && b[c] < 0.98f;
        if (!ok) continue;
        for (int c = 0; c < 3; c++) {
            st[c] += rs_color_srgb_decode(a[c]);
            sr[c] += rs_color_srgb_decode(b[c]);
        }
        n++;
    }
    if (n < 100) return rs_err_set(err, RS_ERR_DEGENERATE, "gain: only %zu unclipped pixels (need 100)", n);
    const double grey = (st[0] + st[1] + st[2]) / 3.0;
    for (int c = 0; c < 3; c++) gain[c] = ref ? st[c] / sr[c] : st[c] / grey;
    return RS_OK;
}

// ---- JPEG quality ----

// Natural (row-major) index of the k-th coefficient in zigzag order (ITU-T T.81 figure 5).
static const unsigned char zigzag[64] = {0,  1,  8,  16, 9,  2,  3,  10, 17, 24, 32, 25, 18, 11, 4,  5,
                                         12, 19, 26, 33, 40, 48, 41, 34, 27, 20, 13, 6,  7,  14, 21, 28,
                                         35, 42, 49, 56, 57, 50, 43, 36, 29, 22, 15, 23, 30, 37, 44, 51,
                                         58, 59, 52, 45, 38, 31, 39, 46, 53, 60, 61, 54, 47, 55, 62, 63};

// ITU-T T.81 Annex K, tables K.1 (luminance) and K.2 (chrominance), natural order.
static const unsigned char std_table[2][64] = {
    {16, 11,  10,  16, 24, 40, 51, 61, 12,  12,  14,  19,  26, 58, 60, 55,  14,  13,  16,  24, 40, 57,
     69, 56,  14,  17, 22, 29, 51, 87, 80,  62,  18,  22,  37, 56, 68, 109, 103, 77,  24,  35, 55, 64,
     81, 104, 113, 92, 49, 64, 78, 87, 103, 121, 120, 101, 72, 92, 95, 98,  112, 100, 103, 99},
    {17, 18, 24, 47, 99, 99, 99, 99, 18, 21, 26, 66, 99, 99, 99, 99, 24, 26, 56, 99, 99, 99,
     99, 99, 47, 66, 99, 99, 99, 99, 99, 99, 99, 99, 99, 99, 99, 99, 99, 99, 99, 99, 99, 99,
     99, 99, 99, 99, 99, 99, 99, 99, 99, 99, 99, 99, 99, 99, 99, 99, 99, 99, 99, 99}};

// IJG's table entry at quality q (libjpeg's jpeg_quality_scaling + jpeg_add_quant_table,
// force_baseline).
static int ijg_entry(int std, int q)
{
    const long scale = q < 50 ? 5000 / q : 200 - 2 * q;
    long v = (std * scale + 50) / 100;
    return v < 1 ? 1 : v > 255 ? 255 : (int)v;
}

rs_status rs_synth_estimate_jpeg_quality(int *quality, int *exact, const char *path, rs_err *err)
{
    *quality = 0;
    *exact = 0;
    char *data = NULL;
    size_t len = 0;
    rs_status st = rs_io_read_file(&data, &len, path, err);
    if (st) return st;
    const unsigned char *b = (const unsigned char *)data;
    if (len < 4 || b[0] != 0xFF || b[1] != 0xD8) {
        free(data);
        return RS_OK; // not a JPEG
    }
    int table[4][64];
    int have[4] = {0, 0, 0, 0};
    size_t p = 2;
    while (p + 4 <= len && b[p] == 0xFF) {
        const int marker = b[p + 1];
        const size_t seg = ((size_t)b[p + 2] << 8) | b[p + 3];
        if (marker == 0xDA || marker == 0xD9 || seg < 2 || p + 2 + seg > len) break; // start of scan: all tables seen
        if (marker == 0xDB) {
            size_t q = p + 4;
            while (q < p + 2 + seg) {
                const int prec = b[q] >> 4, id = b[q] & 15, sz = prec ? 2 : 1;
                if (id > 3 || q + 1 + 64 * sz > p + 2 + seg) break;
                for (int k = 0; k < 64; k++)
                    table[id][zigzag[k]] = prec ? (b[q + 1 + 2 * k] << 8 | b[q + 2 + 2 * k]) : b[q + 1 + k];
                have[id] = 1;
                q += 1 + 64 * sz;
            }
        }
        p += 2 + seg;
    }
    free(data);
    if (!have[0]) return rs_err_set(err, RS_ERR_PARSE, "%s: a JPEG without a quantisation table (DQT)", path);
    long best = -1;
    for (int q = 1; q <= 100; q++) {
        long d = 0;
        for (int t = 0; t < 2; t++)
            if (have[t])
                for (int k = 0; k < 64; k++) d += labs((long)table[t][k] - ijg_entry(std_table[t][k], q));
        if (best < 0 || d < best) {
            best = d;
            *quality = q;
        }
    }
    *exact = best == 0;
    return RS_OK;
}

// ---- all together ----

rs_status rs_synth_appearance_estimate(rs_synth_appearance *out, const char *background_path, const rs_image *image,
                                       const rs_image *reference, rs_err *err)
{
    memset(out, 0, sizeof(*out));
    rs_image read = {0};
    const rs_image *bg = image ? image : &read;
    int exact;
    rs_status st;
    if ((!image && (st = rs_image_read(&read, background_path, err))) ||
        (st = rs_synth_estimate_gain(out->gain, bg, reference, NULL, err)) ||
        (st = rs_synth_estimate_noise(&out->noise_sigma, bg, err)) ||
        (st = rs_synth_estimate_blur(&out->blur_sigma_px, bg, err)) ||
        (st = rs_synth_estimate_jpeg_quality(&out->jpeg_quality, &exact, background_path, err)) ||
        (st = rs_synth_estimate_noise_model(&out->noise_a, &out->noise_b, bg, out->jpeg_quality, err)) ||
        (st = rs_synth_estimate_blockiness(&out->blockiness, bg, err)))
        rs_err_prefix(err, "%s", background_path);
    out->jpeg_exact = exact;
    rs_image_free(&read);
    return st;
}

double rs_synth_appearance_noise_sigma(const rs_synth_appearance *a, double v)
{
    if (a->noise_a <= 0 && a->noise_b <= 0) return a->noise_sigma;
    const double var = a->noise_a + a->noise_b * v;
    return var > 0 ? sqrt(var) : 0;
}

rs_status rs_synth_appearance_layer(rs_image *img, const rs_synth_appearance *a, double layer_blur_sigma_px,
                                    rs_err *err)
{
    if (img->channels != 4)
        return rs_err_set(err, RS_ERR_INVALID, "appearance: the layer must be RGBA (has %d)", img->channels);
    const size_t N = (size_t)img->width * img->height;
    float *d = img->data;
    // gain, and premultiply for the blur
    for (size_t p = 0; p < N; p++)
        for (int c = 0; c < 3; c++) d[4 * p + c] *= (float)(a->gain[c] * d[4 * p + 3]);
    const double s2 = a->blur_sigma_px * a->blur_sigma_px - layer_blur_sigma_px * layer_blur_sigma_px;
    if (s2 > 1e-6) {
        rs_image b = {0};
        rs_status st = rs_synth_image_blur(&b, img, sqrt(s2), err);
        if (st) return st;
        memcpy(d, b.data, sizeof(float) * 4 * N);
        rs_image_free(&b);
    }
    for (size_t p = 0; p < N; p++) { // back to straight alpha
        const float al = d[4 * p + 3];
        for (int c = 0; c < 3; c++) d[4 * p + c] = al > 0 ? d[4 * p + c] / al : 0;
    }
    return RS_OK;
}

rs_status rs_synth_appearance_apply(rs_image *img, const rs_synth_appearance *a, double layer_blur_sigma_px,
                                    uint64_t seed, rs_err *err)
{
    rs_status st = rs_synth_appearance_layer(img, a, layer_blur_sigma_px, err);
    if (st) return st;
    const size_t N = (size_t)img->width * img->height;
    float *d = img->data;
    rs_rng rng;
    rs_rng_seed(&rng, seed);
    for (size_t p = 0; p < N; p++) {
        const float al = d[4 * p + 3];
        for (int c = 0; c < 3; c++) {
            float v = d[4 * p + c];
            if (al > 0 && a->noise_sigma > 0) {
                // sigma in stored units -> linear light at this value: dDecode/dv
                const double slope = rs_color_srgb_decode_slope(rs_color_srgb_encode(v < 0 ? 0 : v > 1 ? 1 : v));
                v += (float)(a->noise_sigma * slope * rs_rng_normal(&rng));
            }
            d[4 * p + c] = v < 0 ? 0 : v;
        }
    }
    return RS_OK;
}

rs_status rs_synth_appearance_jpeg(rs_image *srgb, const rs_synth_appearance *a, rs_err *err)
{
    if (a->jpeg_quality <= 0) return RS_OK;
    rs_image out = {0};
    rs_status st = rs_synth_image_jpeg_roundtrip(&out, srgb, a->jpeg_quality, err);
    if (st) return st;
    rs_image_free(srgb);
    *srgb = out;
    return RS_OK;
}
