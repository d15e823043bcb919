/* AVX2 classification of a sheet's pixels (kernels.h classify_cd,
 * classify_gs), 8 pixels a step, bit-identical to scalar.c: the opacity
 * table's coordinate in double as the reference, truncation by cvtt, one
 * multiply and one add per element, IEEE division.  Tails go to the
 * scalar reference or to masked loads and stores (pixels are
 * independent).  A vector whose pixels all lie below the opacity table's
 * zero run skips its look-ups and leaves its gradients alone (kernels.h). */
#include "kernels.h"
#include "tab_coord-avx2.h"

#include <immintrin.h>

/* (x, y, z) per lane -> x0 y0 z0 x1 ... z7 in three vectors */
static inline void store3(float *p, __m256 x, __m256 y, __m256 z)
{
    const __m256i i0 = _mm256_setr_epi32(0, 0, 0, 1, 1, 1, 2, 2);
    const __m256i i1 = _mm256_setr_epi32(2, 3, 3, 3, 4, 4, 4, 5);
    const __m256i i2 = _mm256_setr_epi32(5, 5, 6, 6, 6, 7, 7, 7);
    __m256 o0 = _mm256_blend_ps(_mm256_blend_ps(_mm256_permutevar8x32_ps(x, i0), _mm256_permutevar8x32_ps(y, i0), 0x92),
                                _mm256_permutevar8x32_ps(z, i0), 0x24);
    __m256 o1 = _mm256_blend_ps(_mm256_blend_ps(_mm256_permutevar8x32_ps(x, i1), _mm256_permutevar8x32_ps(y, i1), 0x24),
                                _mm256_permutevar8x32_ps(z, i1), 0x49);
    __m256 o2 = _mm256_blend_ps(_mm256_blend_ps(_mm256_permutevar8x32_ps(x, i2), _mm256_permutevar8x32_ps(y, i2), 0x49),
                                _mm256_permutevar8x32_ps(z, i2), 0x92);
    _mm256_storeu_ps(p, o0);
    _mm256_storeu_ps(p + 8, o1);
    _mm256_storeu_ps(p + 16, o2);
}

/* the opacity table at coordinate x (as lookup_alpha in scalar.c) */
static inline __m256 lookup_alpha_at8(const vs_shade_tabs *T, __m256 x)
{
    const __m256 top_x = _mm256_set1_ps((float)(VS_KTAB - 1));
    __m256 top = _mm256_cmp_ps(x, top_x, _CMP_GE_OQ);
    x = _mm256_andnot_ps(top, x); /* index 0 where the table's end is used */
    __m256i j = _mm256_cvttps_epi32(x);
    __m256 f = _mm256_sub_ps(x, _mm256_cvtepi32_ps(j));
    __m256 t0 = _mm256_i32gather_ps(T->alpha, j, 4), t1 = _mm256_i32gather_ps(T->alpha + 1, j, 4);
    return _mm256_blendv_ps(_mm256_add_ps(t0, _mm256_mul_ps(f, _mm256_sub_ps(t1, t0))),
                            _mm256_set1_ps(T->alpha[VS_KTAB - 1]), top);
}

/* lanes [0, k) set */
static inline __m256i prefix8(int k)
{
    return _mm256_cmpgt_epi32(_mm256_set1_epi32(k), _mm256_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7));
}

/* The opacity table at v (as lookup_alpha in scalar.c); *none set when
 * every lane lies below the table's zero run, whose look-ups are skipped
 * (most classified vectors of an opaque surface's sheets). */
static inline __m256 classify_alpha8(const vs_shade_tabs *T, __m256 v, int *none)
{
    const __m256 x = tab_coord8(v, _mm256_set1_pd(T->vmin), _mm256_set1_pd(T->scale));
    *none = _mm256_movemask_ps(_mm256_cmp_ps(x, _mm256_set1_ps(T->alpha_zero_x), _CMP_LT_OQ)) == 0xff;
    return *none ? _mm256_setzero_ps() : lookup_alpha_at8(T, x);
}

/* as scalar.c's wide_diff: (0.5 + 2w) d1 - w d2, multiply, multiply, subtract */
static inline __m256 wide_diff8(float w, __m256 d1, __m256 d2)
{
    return _mm256_sub_ps(_mm256_mul_ps(_mm256_set1_ps(0.5f + 2.0f * w), d1), _mm256_mul_ps(_mm256_set1_ps(w), d2));
}

/* 8 pixels, or the first m of them (masked loads and stores: no access
 * past the span); without an opacity table the gradients only */
static inline void classify8(float *alpha, float *g, const float *q, const float *qp, const float *qn,
                             const float *qp2, const float *qn2, ptrdiff_t stride, int m, const vs_shade_tabs *T)
{
    const __m256 half = _mm256_set1_ps(0.5f), two_slab = _mm256_set1_ps(T->two_slab);
    const __m256i in = prefix8(m);
#define LD(p) (m == 8 ? _mm256_loadu_ps(p) : _mm256_maskload_ps(p, in))
    if (T->alpha) {
        int none;
        const __m256 a = classify_alpha8(T, LD(q), &none);
        if (m == 8)
            _mm256_storeu_ps(alpha, a);
        else
            _mm256_maskstore_ps(alpha, in, a);
        if (none) return; /* no gradient is read here */
    }
    __m256 gx, gy;
    if (T->cd_wide > 0.0f) {
        gx = wide_diff8(T->cd_wide, _mm256_sub_ps(LD(q + 1), LD(q - 1)), _mm256_sub_ps(LD(q + 2), LD(q - 2)));
        gy = wide_diff8(T->cd_wide, _mm256_sub_ps(LD(q + stride), LD(q - stride)),
                        _mm256_sub_ps(LD(q + 2 * stride), LD(q - 2 * stride)));
    } else {
        gx = _mm256_mul_ps(half, _mm256_sub_ps(LD(q + 1), LD(q - 1)));
        gy = _mm256_mul_ps(half, _mm256_sub_ps(LD(q + stride), LD(q - stride)));
    }
    const __m256 gz = T->cd_wide_z > 0.0f ? _mm256_div_ps(wide_diff8(T->cd_wide_z, _mm256_sub_ps(LD(qn), LD(qp)),
                                                                     _mm256_sub_ps(LD(qn2), LD(qp2))),
                                                          _mm256_set1_ps(T->slab))
                                          : _mm256_div_ps(_mm256_sub_ps(LD(qn), LD(qp)), two_slab);
#undef LD
    if (m == 8) {
        store3(g, gx, gy, gz);
    } else {
        float tmp[24];
        store3(tmp, gx, gy, gz);
        for (int k = 0; k < 3; k++) _mm256_maskstore_ps(g + 8 * k, prefix8(3 * m - 8 * k), _mm256_loadu_ps(tmp + 8 * k));
    }
}

void vs_classify_cd_avx2(float *alpha, float *g, const float *q, const float *qp, const float *qn, const float *qp2,
                         const float *qn2, ptrdiff_t stride, int n, const vs_shade_tabs *T)
{
    /* qp2, qn2 are read only with cd_wide_z; NULL stays NULL */
    const int z2 = T->cd_wide_z > 0.0f;
    int i = 0;
    for (; i + 8 <= n; i += 8)
        classify8(alpha + i, g + 3 * i, q + i, qp + i, qn + i, z2 ? qp2 + i : NULL, z2 ? qn2 + i : NULL, stride, 8, T);
    if (i < n)
        classify8(alpha + i, g + 3 * i, q + i, qp + i, qn + i, z2 ? qp2 + i : NULL, z2 ? qn2 + i : NULL, stride, n - i,
                  T);
}

/* post-gs: (density, gx, gy, gz) per pixel, transposed to one vector per
 * channel (pixel order 0 2 4 6 1 3 5 7, put back by one permute each) */
/* the ripple's v (kernels.h vs_ripple_row) of block c's 8 pixels */
static inline void ripple8(const vs_ripple_row *R, int c, __m256 v[3])
{
    const vs_ripple_lanes *L = R->L;
    float P[3], Q[3];
    vs_ripple_block(R, c, P, Q);
    __m256 A[3];
    for (int a = 0; a < 3; a++)
        A[a] = _mm256_add_ps(_mm256_mul_ps(_mm256_set1_ps(P[a]), _mm256_loadu_ps(L->cl[a])),
                             _mm256_mul_ps(_mm256_set1_ps(Q[a]), _mm256_loadu_ps(L->sl[a])));
    for (int j = 0; j < 3; j++)
        v[j] = _mm256_add_ps(_mm256_add_ps(_mm256_mul_ps(_mm256_set1_ps(L->m[0][j]), A[0]),
                                           _mm256_mul_ps(_mm256_set1_ps(L->m[1][j]), A[1])),
                             _mm256_mul_ps(_mm256_set1_ps(L->m[2][j]), A[2]));
}

/* The ripple of a span's 8 pixels from i (i a multiple of 8): lanes m..7
 * of block i / 8 then 0..m-1 of the next.  The next block's, made for a
 * span not aligned to the blocks, is kept in nx for the pixels from i + 8
 * (have: the block it holds, -1 none). */
typedef struct ripple_span {
    __m256i idx;  /* lane l takes lane (l + m) & 7 */
    __m256 from_next; /* lanes l >= 8 - m: from the next block */
    __m256 nx[3];
    int have;
} ripple_span;

static inline void ripple_span_init(ripple_span *rs, int m)
{
    const __m256i l = _mm256_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7);
    rs->idx = _mm256_and_si256(_mm256_add_epi32(l, _mm256_set1_epi32(m)), _mm256_set1_epi32(7));
    rs->from_next = _mm256_castsi256_ps(_mm256_cmpgt_epi32(l, _mm256_set1_epi32(7 - m)));
    rs->have = -1;
}

static inline void ripple_at(const vs_ripple_row *R, ripple_span *rs, int i, __m256 v[3])
{
    const int c = i >> 3;
    if (!R->m) {
        ripple8(R, c, v);
        return;
    }
    __m256 cur[3];
    if (rs->have == c)
        for (int j = 0; j < 3; j++) cur[j] = rs->nx[j];
    else
        ripple8(R, c, cur);
    ripple8(R, c + 1, rs->nx);
    rs->have = c + 1;
    for (int j = 0; j < 3; j++)
        v[j] = _mm256_blendv_ps(_mm256_permutevar8x32_ps(cur[j], rs->idx), _mm256_permutevar8x32_ps(rs->nx[j], rs->idx),
                                rs->from_next);
}

void vs_classify_gs_avx2(float *alpha, float *g, const float *q4, int n, const vs_shade_tabs *T,
                         const vs_ripple_row *R)
{
    const __m256i back = _mm256_setr_epi32(0, 4, 1, 5, 2, 6, 3, 7);
    const __m256 slab = _mm256_set1_ps(T->slab);
    __m256 v[3];
    ripple_span rs;
    if (R) ripple_span_init(&rs, R->m);
    int i = 0;
    for (; i + 8 <= n; i += 8) {
        const float *p = q4 + 4 * i;
        __m256 r0 = _mm256_loadu_ps(p), r1 = _mm256_loadu_ps(p + 8), r2 = _mm256_loadu_ps(p + 16),
               r3 = _mm256_loadu_ps(p + 24);
        __m256 t0 = _mm256_unpacklo_ps(r0, r1), t1 = _mm256_unpackhi_ps(r0, r1);
        __m256 t2 = _mm256_unpacklo_ps(r2, r3), t3 = _mm256_unpackhi_ps(r2, r3);
        __m256 d = _mm256_permutevar8x32_ps(_mm256_shuffle_ps(t0, t2, 0x44), back);
        __m256 gx = _mm256_permutevar8x32_ps(_mm256_shuffle_ps(t0, t2, 0xee), back);
        __m256 gy = _mm256_permutevar8x32_ps(_mm256_shuffle_ps(t1, t3, 0x44), back);
        __m256 gz = _mm256_permutevar8x32_ps(_mm256_shuffle_ps(t1, t3, 0xee), back);
        if (T->alpha) {
            int none;
            _mm256_storeu_ps(alpha + i, classify_alpha8(T, d, &none));
            if (none) continue;
        }
        if (R) ripple_at(R, &rs, i, v);
        gx = _mm256_div_ps(gx, slab);
        gy = _mm256_div_ps(gy, slab);
        gz = _mm256_div_ps(gz, slab);
        if (R) {
            gx = _mm256_sub_ps(gx, _mm256_mul_ps(d, v[0]));
            gy = _mm256_sub_ps(gy, _mm256_mul_ps(d, v[1]));
            gz = _mm256_sub_ps(gz, _mm256_mul_ps(d, v[2]));
        }
        store3(g + 3 * i, gx, gy, gz);
    }
    if (i == n) return;
    vs_classify_gs_scalar(alpha + i, g + 3 * i, q4 + 4 * i, n - i, T, NULL);
    if (!R) return;
    ripple_at(R, &rs, i, v);
    float vl[3][8];
    for (int j = 0; j < 3; j++) _mm256_storeu_ps(vl[j], v[j]);
    for (int l = 0; i + l < n; l++)
        for (int j = 0; j < 3; j++) g[3 * (i + l) + j] -= q4[4 * (i + l)] * vl[j][l];
}
