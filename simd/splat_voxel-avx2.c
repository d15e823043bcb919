/* One voxel into all its sheets, AVX2 (splat_voxel1, splat_voxel4,
 * splat_voxel_gs): each 8-pixel vector of a footprint row is built once in
 * a register (column weights times the row weight, zeroed outside the
 * radius) and added to every sheet; multiply then add as the scalar
 * reference (scalar.c; no FMA, kernels.h). */
#include "kernels.h"
#include "by_sheets.h"

#include <immintrin.h>

/* The common case, an 8-pixel footprint of at most 8 rows: its rows are
 * built once into registers, then added sheet by sheet (rows outer, as
 * below, measured 8 % slower in the frame here).  Inlined with the row
 * count constant, so that the rows stay in registers. */
static inline __attribute__((always_inline)) void voxel1_narrow(float *const *dst, const float *w, int ns,
                                                                 ptrdiff_t ds, const float *cw, const float *rw,
                                                                 int rows, __m256 t)
{
    const __m256 c = _mm256_loadu_ps(cw);
    __m256 h[8];
    for (int r = 0; r < rows; r++) {
        h[r] = _mm256_mul_ps(c, _mm256_set1_ps(rw[r]));
        h[r] = _mm256_and_ps(h[r], _mm256_cmp_ps(h[r], t, _CMP_GT_OQ));
    }
    for (int s = 0; s < ns; s++) {
        const __m256 ws = _mm256_set1_ps(w[s]);
        float *d = dst[s];
        for (int r = 0; r < rows; r++, d += ds)
            _mm256_storeu_ps(d, _mm256_add_ps(_mm256_loadu_ps(d), _mm256_mul_ps(ws, h[r])));
    }
}

static inline __attribute__((always_inline)) void voxel1_rows(float *const *dst, const float *w, int ns, ptrdiff_t ds,
                                                               const float *cw, const float *rw, int rows, int nvec,
                                                               float thr)
{
    const __m256 t = _mm256_set1_ps(thr);
    if (nvec == 1 && rows <= 8) {
        switch (rows) {
#define NARROW(R)                                                                                                      \
    case R: voxel1_narrow(dst, w, ns, ds, cw, rw, R, t); return;
            NARROW(1) NARROW(2) NARROW(3) NARROW(4) NARROW(5) NARROW(6) NARROW(7) NARROW(8)
#undef NARROW
        default: return; /* no rows */
        }
    }
    for (int r = 0; r < rows; r++) {
        const __m256 ry = _mm256_set1_ps(rw[r]);
        for (int v = 0; v < nvec; v++) {
            __m256 h = _mm256_mul_ps(_mm256_loadu_ps(cw + 8 * v), ry);
            h = _mm256_and_ps(h, _mm256_cmp_ps(h, t, _CMP_GT_OQ));
            for (int s = 0; s < ns; s++) {
                float *d = dst[s] + r * ds + 8 * v;
                _mm256_storeu_ps(d, _mm256_add_ps(_mm256_loadu_ps(d), _mm256_mul_ps(_mm256_set1_ps(w[s]), h)));
            }
        }
    }
}

void vs_splat_voxel1_avx2(float *const *dst, const float *w, int ns, ptrdiff_t ds, const float *cw, const float *rw,
                          int rows, int nvec, float thr)
{
#define V1(N) voxel1_rows(dst, w, N, ds, cw, rw, rows, nvec, thr)
    BY_SHEETS(V1)
#undef V1
}

/* Four channels a pixel, each 8-float vector two pixels (pixel p of row r
 * has h = cw[p] rw[r], 0 where not > thr).  grad 0: every channel h
 * (splat_voxel4); grad 1: the gradient layout (h, h dx[p], h dy[r], h)
 * (splat_voxel_gs), as a (1, dx, dy, 1) factor vector: h times 1 is h.
 * Inlined with grad constant, so splat_voxel4 has no multiply more. */
static inline __attribute__((always_inline)) void voxel4_rows(float *const *dst, const float *w, int ns, ptrdiff_t ds,
                                                               const float *cw, const float *rw, const float *dx,
                                                               const float *dy, int rows, int nvec, float thr,
                                                               int grad)
{
    const __m256 t = _mm256_set1_ps(thr), one = _mm256_set1_ps(1.0f);
    /* lane pattern of block vector q of 8 pixels: pixels 2q, 2q + 1, each in 4 channels */
    const __m256i spread[4] = {_mm256_setr_epi32(0, 0, 0, 0, 1, 1, 1, 1), _mm256_setr_epi32(2, 2, 2, 2, 3, 3, 3, 3),
                               _mm256_setr_epi32(4, 4, 4, 4, 5, 5, 5, 5), _mm256_setr_epi32(6, 6, 6, 6, 7, 7, 7, 7)};
    __m256 w8[VS_MAX_SHEETS_VOXEL];
    for (int s = 0; s < ns; s++) w8[s] = _mm256_broadcast_ps((const __m128 *)(const void *)(w + 4 * s));
    for (int r = 0; r < rows; r++) {
        const __m256 ry = _mm256_set1_ps(rw[r]);
        const __m256 fy = grad ? _mm256_blend_ps(one, _mm256_set1_ps(dy[r]), 0x44) : one;
        for (int v = 0; v < nvec; v += 4) {
            __m256 h = _mm256_mul_ps(_mm256_loadu_ps(cw + 2 * v), ry);
            h = _mm256_and_ps(h, _mm256_cmp_ps(h, t, _CMP_GT_OQ));
            const __m256 x8 = grad ? _mm256_loadu_ps(dx + 2 * v) : one;
            const int nq = nvec - v < 4 ? nvec - v : 4;
            for (int q = 0; q < nq; q++) {
                __m256 hq = _mm256_permutevar8x32_ps(h, spread[q]);
                if (grad) hq = _mm256_mul_ps(hq, _mm256_blend_ps(fy, _mm256_permutevar8x32_ps(x8, spread[q]), 0x22));
                for (int s = 0; s < ns; s++) {
                    float *d = dst[s] + r * ds + 8 * (v + q);
                    _mm256_storeu_ps(d, _mm256_add_ps(_mm256_loadu_ps(d), _mm256_mul_ps(w8[s], hq)));
                }
            }
        }
    }
}

void vs_splat_voxel4_avx2(float *const *dst, const float *w, int ns, ptrdiff_t ds, const float *cw, const float *rw,
                          int rows, int nvec, float thr)
{
#define V4(N) voxel4_rows(dst, w, N, ds, cw, rw, NULL, NULL, rows, nvec, thr, 0)
    BY_SHEETS(V4)
#undef V4
}

void vs_splat_voxel_gs_avx2(float *const *dst, const float *w, int ns, ptrdiff_t ds, const float *cw, const float *rw,
                            const float *dx, const float *dy, int rows, int nvec, float thr)
{
#define VGS(N) voxel4_rows(dst, w, N, ds, cw, rw, dx, dy, rows, nvec, thr, 1)
    BY_SHEETS(VGS)
#undef VGS
}
