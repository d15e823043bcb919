/* The octahedral normal codes' directions and the per-view table of their
 * Phong terms (normal_code.h). */
#include "normal_code.h"
#include "context.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <sys/mman.h>

void vs_normal_decode(int code, double n[3])
{
    if (code < 0 || code >= VS_NORMAL_ZERO) {
        n[0] = n[1] = n[2] = 0.0;
        return;
    }
    const double h = 0.5 * (VS_NORMAL_SIDE - 1);
    const double s = (code % VS_NORMAL_SIDE) / h - 1.0, t = (code / VS_NORMAL_SIDE) / h - 1.0;
    n[0] = 0.5 * (s + t);
    n[1] = 0.5 * (s - t);
    n[2] = 1.0 - fabs(n[0]) - fabs(n[1]);
}

vs_status vs_normal_table_setup(vs_context *ctx, const vs_light *l, const double right[3], const double up[3],
                                const double dir[3], vs_normal_table *tab)
{
    double key[19] = {l->L[0], l->L[1], l->L[2], l->H[0], l->H[1], l->H[2], l->ka,  l->kd,  l->ks, l->n,
                      right[0], right[1], right[2], up[0],   up[1],   up[2],   dir[0], dir[1], dir[2]};
    if (tab->terms && memcmp(key, tab->key, sizeof key) == 0) return VS_OK;
    if (!tab->terms && !(tab->terms = malloc(sizeof *tab->terms * VS_NORMAL_CODES)))
        return vs_set_error(ctx, VS_ERR_OUT_OF_MEMORY, "normal shading table: out of memory");
    for (int c = 0; c < VS_NORMAL_CODES; c++) {
        double w[3], n[3], d, s;
        vs_normal_decode(c, w);
        /* into the eye frame: right, down, forward (as a voxel's gradient
         * was before it had a code) */
        n[0] = w[0] * right[0] + w[1] * right[1] + w[2] * right[2];
        n[1] = -(w[0] * up[0] + w[1] * up[1] + w[2] * up[2]);
        n[2] = w[0] * dir[0] + w[1] * dir[1] + w[2] * dir[2];
        vs_light_eval(l, n, &d, &s);
        tab->terms[c][0] = (float)d;
        tab->terms[c][1] = (float)s;
    }
    memcpy(tab->key, key, sizeof key);
    return VS_OK;
}

void vs_normal_table_free(vs_normal_table *tab)
{
    if (!tab) return;
    free(tab->terms);
    tab->terms = NULL;
}

_Atomic uint16_t *vs_normal_codes_get(vs_context *ctx, const struct vs_volume *vol)
{
    size_t n = (size_t)1 << (3 * VS_BRICK_BITS); /* whole bricks */
    for (int a = 0; a < 3; a++) n *= ((size_t)vol->dims[a] + VS_BRICK - 1) >> VS_BRICK_BITS;
    if (n > VS_NORMAL_CODES_MAX_BYTES / sizeof(uint16_t)) return NULL;
    _Static_assert(sizeof(_Atomic uint16_t) == sizeof(uint16_t), "codes are counted as 2 bytes");
    vs_normal_codes *slots = ctx->normal_codes;
    if (!slots && !(slots = ctx->normal_codes = calloc(VS_NORMAL_CODES_KEEP, sizeof *slots))) return NULL;
    const uint64_t now = ++ctx->normal_codes_clock;
    int pick = 0;
    for (int s = 0; s < VS_NORMAL_CODES_KEEP; s++) {
        vs_normal_codes *c = &slots[s];
        if (c->code && vs_volume_stamp_same_field(&c->from, vol)) {
            c->used = now;
            return c->code;
        }
        if (slots[s].used < slots[pick].used) pick = s;
    }
    /* the least recently used slot, and room under the budget */
    vs_normal_codes *c = &slots[pick];
    vs_normal_codes_free(c);
    size_t kept = 0;
    for (int s = 0; s < VS_NORMAL_CODES_KEEP; s++)
        if (slots[s].code) kept += slots[s].n;
    while (kept + n > VS_NORMAL_CODES_ALL_BYTES / sizeof(uint16_t)) {
        int old = -1;
        for (int s = 0; s < VS_NORMAL_CODES_KEEP; s++)
            if (slots[s].code && (old < 0 || slots[s].used < slots[old].used)) old = s;
        kept -= slots[old].n;
        vs_normal_codes_free(&slots[old]);
    }
    /* zero pages until written: a brick no frame splats costs nothing (a
     * calloc of this size may come from a heap that grew, and be written
     * in full) */
    void *m = mmap(NULL, n * sizeof *c->code, PROT_READ | PROT_WRITE, MAP_PRIVATE | MAP_ANONYMOUS, -1, 0);
    if (m == MAP_FAILED) return NULL;
    c->code = m;
    vs_volume_stamp_take(&c->from, vol);
    c->used = now;
    c->n = n;
    return c->code;
}

void vs_normal_codes_free(vs_normal_codes *c)
{
    if (c->code) munmap((void *)c->code, c->n * sizeof *c->code);
    memset(c, 0, sizeof *c);
}
