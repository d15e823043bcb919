/* One density voxel into all its sheets, AVX-512: two 8-pixel vectors of a
 * footprint row per register (an odd last one in a 256-bit register), built
 * once and added to every sheet; multiply then add as the scalar reference
 * (scalar.c; no FMA, kernels.h).  One-vector rows stay 256-bit. */
#include "kernels.h"
#include "by_sheets.h"

#include <immintrin.h>

static inline __attribute__((always_inline)) void voxel1_wide(float *const *dst, const float *w, int ns, ptrdiff_t ds,
                                                               const float *cw, const float *rw, int rows, int nvec,
                                                               float thr)
{
    const __m512 t = _mm512_set1_ps(thr);
    const __m256 t8 = _mm256_set1_ps(thr);
    for (int r = 0; r < rows; r++) {
        const __m512 ry = _mm512_set1_ps(rw[r]);
        int v = 0;
        for (; v + 2 <= nvec; v += 2) {
            __m512 h = _mm512_mul_ps(_mm512_loadu_ps(cw + 8 * v), ry);
            h = _mm512_maskz_mov_ps(_mm512_cmp_ps_mask(h, t, _CMP_GT_OQ), h);
            for (int s = 0; s < ns; s++) {
                float *d = dst[s] + r * ds + 8 * v;
                _mm512_storeu_ps(d, _mm512_add_ps(_mm512_loadu_ps(d), _mm512_mul_ps(_mm512_set1_ps(w[s]), h)));
            }
        }
        if (v < nvec) {
            __m256 h = _mm256_mul_ps(_mm256_loadu_ps(cw + 8 * v), _mm256_set1_ps(rw[r]));
            h = _mm256_and_ps(h, _mm256_cmp_ps(h, t8, _CMP_GT_OQ));
            for (int s = 0; s < ns; s++) {
                float *d = dst[s] + r * ds + 8 * v;
                _mm256_storeu_ps(d, _mm256_add_ps(_mm256_loadu_ps(d), _mm256_mul_ps(_mm256_set1_ps(w[s]), h)));
            }
        }
    }
}

void vs_splat_voxel1_avx512(float *const *dst, const float *w, int ns, ptrdiff_t ds, const float *cw, const float *rw,
                            int rows, int nvec, float thr)
{
    if (nvec == 1) {
        vs_splat_voxel1_avx2(dst, w, ns, ds, cw, rw, rows, nvec, thr);
        return;
    }
#define V1(N) voxel1_wide(dst, w, N, ds, cw, rw, rows, nvec, thr)
    BY_SHEETS(V1)
#undef V1
}
