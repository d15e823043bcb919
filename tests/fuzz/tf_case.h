/* How fuzz_tf.c (and tests/test_fuzz_regressions.c, which replays its
 * inputs) reads the first byte of an input: byte % 3 picks the format by
 * extension (.json, .1dt, .vtf); bit 0 of byte / 3 drops the extension
 * (".tf": the format is sniffed from the content); bits 1-2 pick the
 * volume a .1dt is spread over: a sphere, none (vs_tf_load), a constant
 * volume (an empty range), or one with NaN, +-Inf and +-FLT_MAX voxels.
 * Seeds starting with '0', '1', '2' keep the sphere and the extension. */
#ifndef VS_TF_CASE_H
#define VS_TF_CASE_H

#include "vsplat.h"

#include <float.h>
#include <math.h>

static inline const char *tf_case_suffix(unsigned char b0)
{
    static const char *const sfx[3] = {".json", ".1dt", ".vtf"};
    return ((b0 / 3) & 1) ? ".tf" : sfx[b0 % 3];
}

/* vols[0..3] made on first use (vols[1] stays NULL); the volume for b0,
 * *with_vol = 0 when vs_tf_load (no volume) is meant. */
static inline const vs_volume *tf_case_volume(vs_context *ctx, unsigned char b0, vs_volume *vols[4], int *with_vol)
{
    if (!vols[0]) {
        int d[3] = {4, 4, 2};
        if (vs_volume_scene(ctx, "sphere:8", &vols[0]) != VS_OK) return NULL;
        if (vs_volume_create(ctx, VS_F32, d, NULL, &vols[2]) != VS_OK) return NULL;
        if (vs_volume_create(ctx, VS_F32, d, NULL, &vols[3]) != VS_OK) return NULL;
        float *c = vs_volume_data(vols[2]), *h = vs_volume_data(vols[3]);
        const float hv[8] = {NAN, INFINITY, -INFINITY, FLT_MAX, -FLT_MAX, 1e-40f, 0.0f, 1.0f};
        for (int i = 0; i < 32; i++) {
            c[i] = 7.0f;
            h[i] = hv[i % 8];
        }
        vs_volume_update_range(vols[2]);
        vs_volume_update_range(vols[3]);
    }
    int k = (b0 / 6) % 4;
    *with_vol = k != 1;
    return k == 1 ? vols[0] : vols[k];
}

#endif
