/* Image files (through the OpenImageIO adapter) and image comparison. */
#include "context.h"
#include "oiio_adapter.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

static vs_status check_image(vs_context *ctx, const char *what, const vs_image *img)
{
    if (!img || !img->rgba)
        return vs_set_error(ctx, VS_ERR_INVALID_ARGUMENT, "%s: no image data", what);
    if (img->width < 1 || img->height < 1 || img->width > VS_MAX_IMAGE_DIM ||
        img->height > VS_MAX_IMAGE_DIM)
        return vs_set_error(ctx, VS_ERR_INVALID_ARGUMENT, "%s: invalid image size %dx%d", what,
                            img->width, img->height);
    return VS_OK;
}

vs_status vs_image_write(vs_context *ctx, const char *path, const vs_image *img, int bits)
{
    if (!path || !*path) return vs_set_error(ctx, VS_ERR_INVALID_ARGUMENT, "image write: no file name");
    vs_status st = check_image(ctx, path, img);
    if (st != VS_OK) return st;
    if (bits != 0 && bits != 8 && bits != 16 && bits != 32)
        return vs_set_error(ctx, VS_ERR_INVALID_ARGUMENT, "%s: bits must be 8, 16 or 32, not %d",
                            path, bits);
    char err[480];
    const vs_oiio_api *io = vs_oiio(ctx);
    if (!io) return VS_ERR_IO;
    st = io->write_rgba(path, img->width, img->height, img->rgba, bits, err, sizeof err);
    if (st != VS_OK) return vs_set_error(ctx, st, "%s", err);
    return VS_OK;
}

vs_status vs_image_read(vs_context *ctx, const char *path, vs_image *out)
{
    if (out) memset(out, 0, sizeof *out);
    if (!path || !*path || !out)
        return vs_set_error(ctx, VS_ERR_INVALID_ARGUMENT, "image read: NULL argument");
    char err[480];
    int w, h;
    float *px;
    const vs_oiio_api *io = vs_oiio(ctx);
    if (!io) return VS_ERR_IO;
    vs_status st = io->read_rgba(path, &w, &h, &px, err, sizeof err);
    if (st != VS_OK) return vs_set_error(ctx, st, "%s", err);
    out->width = w;
    out->height = h;
    out->rgba = px;
    return VS_OK;
}

/* ---- SSIM (Wang, Bovik, Sheikh, Simoncelli 2004) ----
 * Gaussian window 11x11, sigma 1.5, C1 = (0.01)^2, C2 = (0.03)^2 for data in
 * [0,1]; computed per RGBA channel and averaged over the four channels and
 * all pixels.  Near the border the window is cut to the image and
 * renormalised (instead of MATLAB's 'valid' crop), so small images work.
 * Separable: a horizontal pass per row into a ring of 11 rows, then a
 * vertical pass, so memory is O(width). */
enum { SSIM_R = 5, SSIM_W = 2 * SSIM_R + 1, SSIM_Q = 5 };

static void ssim_hrow(const vs_image *a, const vs_image *b, int c, int y, const double *w,
                      double *row /* SSIM_Q * width */)
{
    int W = a->width;
    const float *pa = a->rgba + (size_t)y * W * 4, *pb = b->rgba + (size_t)y * W * 4;
    for (int x = 0; x < W; x++) {
        double s[SSIM_Q] = {0}, ws = 0;
        for (int k = -SSIM_R; k <= SSIM_R; k++) {
            int xx = x + k;
            if (xx < 0 || xx >= W) continue;
            double u = pa[(size_t)xx * 4 + c], v = pb[(size_t)xx * 4 + c], wk = w[k + SSIM_R];
            s[0] += wk * u;
            s[1] += wk * v;
            s[2] += wk * u * u;
            s[3] += wk * v * v;
            s[4] += wk * u * v;
            ws += wk;
        }
        for (int q = 0; q < SSIM_Q; q++) row[(size_t)q * W + x] = s[q] / ws;
    }
}

static vs_status ssim(vs_context *ctx, const vs_image *a, const vs_image *b, double *out)
{
    const double C1 = 0.01 * 0.01, C2 = 0.03 * 0.03;
    int W = a->width, H = a->height;
    double w[SSIM_W];
    for (int k = -SSIM_R; k <= SSIM_R; k++) w[k + SSIM_R] = exp(-(double)(k * k) / (2.0 * 1.5 * 1.5));
    double *ring = malloc(sizeof(double) * SSIM_W * SSIM_Q * (size_t)W);
    if (!ring) return vs_set_error(ctx, VS_ERR_OUT_OF_MEMORY, "compare: out of memory");
    double total = 0.0;
    for (int c = 0; c < 4; c++) {
        /* ring slot y % SSIM_W holds the horizontal pass of row y */
        for (int y = 0; y < SSIM_R && y < H; y++)
            ssim_hrow(a, b, c, y, w, ring + (size_t)(y % SSIM_W) * SSIM_Q * W);
        for (int y = 0; y < H; y++) {
            if (y + SSIM_R < H)
                ssim_hrow(a, b, c, y + SSIM_R, w, ring + (size_t)((y + SSIM_R) % SSIM_W) * SSIM_Q * W);
            int y0 = y - SSIM_R < 0 ? 0 : y - SSIM_R, y1 = y + SSIM_R >= H ? H - 1 : y + SSIM_R;
            double ws = 0;
            for (int yy = y0; yy <= y1; yy++) ws += w[yy - y + SSIM_R];
            for (int x = 0; x < W; x++) {
                double m[SSIM_Q] = {0};
                for (int yy = y0; yy <= y1; yy++) {
                    const double *row = ring + (size_t)(yy % SSIM_W) * SSIM_Q * W;
                    double wk = w[yy - y + SSIM_R];
                    for (int q = 0; q < SSIM_Q; q++) m[q] += wk * row[(size_t)q * W + x];
                }
                for (int q = 0; q < SSIM_Q; q++) m[q] /= ws;
                double mu_a = m[0], mu_b = m[1];
                double va = m[2] - mu_a * mu_a, vb = m[3] - mu_b * mu_b, cov = m[4] - mu_a * mu_b;
                total += ((2.0 * mu_a * mu_b + C1) * (2.0 * cov + C2)) /
                         ((mu_a * mu_a + mu_b * mu_b + C1) * (va + vb + C2));
            }
        }
    }
    free(ring);
    *out = total / (4.0 * (double)W * (double)H);
    return VS_OK;
}

vs_status vs_image_compare(vs_context *ctx, const vs_image *a, const vs_image *b, vs_image_diff *out)
{
    if (!out) return vs_set_error(ctx, VS_ERR_INVALID_ARGUMENT, "compare: NULL result");
    memset(out, 0, sizeof *out);
    vs_status st = check_image(ctx, "compare: first image", a);
    if (st != VS_OK) return st;
    st = check_image(ctx, "compare: second image", b);
    if (st != VS_OK) return st;
    if (a->width != b->width || a->height != b->height)
        return vs_set_error(ctx, VS_ERR_INVALID_ARGUMENT, "compare: image sizes differ: %dx%d vs %dx%d",
                            a->width, a->height, b->width, b->height);
    size_t n = (size_t)a->width * a->height * 4;
    double sum = 0.0, mx = 0.0;
    for (size_t i = 0; i < n; i++) {
        double d = (double)a->rgba[i] - (double)b->rgba[i];
        double ad = fabs(d);
        sum += d * d;
        if (ad > mx || isnan(ad)) mx = ad;
    }
    out->rmse = sqrt(sum / (double)n);
    out->max_abs = mx;
    out->psnr = out->rmse > 0.0 ? -20.0 * log10(out->rmse) : (out->rmse == 0.0 ? INFINITY : NAN);
    return ssim(ctx, a, b, &out->ssim);
}
