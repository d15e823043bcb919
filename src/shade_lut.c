/* Building the Clyne-Dennis tables and the angle-indexed shading table. */
#include "context.h"
#include "shade_lut.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

void vs_shade_lut_free(vs_shade_lut *lut)
{
    free(lut->lambda_bin);
    free(lut->radius);
    free(lut->phi_bin);
    free(lut->diffuse);
    free(lut->specular);
    lut->lambda_bin = NULL;
    lut->radius = NULL;
    lut->phi_bin = NULL;
    lut->diffuse = lut->specular = NULL;
}

/* The angle tables: gradient bytes -> lambda bin, radius, phi bin (depend on
 * nl alone). */
static void fill_angle_tables(vs_shade_lut *lut)
{
    const int nl = lut->nl;
    for (int y = -127; y <= 127; y++)
        for (int x = -127; x <= 127; x++) {
            double lam = atan2((double)y, (double)x); /* eq. 10 */
            int b = (int)lround((lam + M_PI) / (2.0 * M_PI) * nl) % nl;
            lut->lambda_bin[(y + 127) * 255 + (x + 127)] = (uint16_t)b;
            double r = sqrt((double)(x * x + y * y));
            lut->radius[(y + 127) * 255 + (x + 127)] = (uint8_t)lround(r);
        }
    for (int z = -127; z <= 127; z++)
        for (int r = 0; r <= 180; r++) {
            double phi = atan2((double)z, (double)r); /* eq. 10 */
            int b = (int)lround((phi + M_PI_2) / M_PI * (lut->np - 1));
            lut->phi_bin[(z + 127) * 181 + r] = (uint16_t)b;
        }
}

/* The shading table: Phong terms per (phi, lambda) bin for `light`. */
static void fill_light_tables(vs_shade_lut *lut, const vs_light *light)
{
    const int nl = lut->nl;
    for (int p = 0; p < lut->np; p++) {
        double phi = -M_PI_2 + M_PI * p / (lut->np - 1);
        for (int l = 0; l < nl; l++) {
            double lam = -M_PI + 2.0 * M_PI * l / nl;
            double n[3] = {cos(lam) * cos(phi), sin(lam) * cos(phi), sin(phi)}; /* eq. 11 */
            double d, sp;
            vs_light_eval(light, n, &d, &sp);
            lut->diffuse[p * nl + l] = (float)d;
            lut->specular[p * nl + l] = (float)sp;
        }
    }
    lut->light = *light;
}

vs_status vs_shade_lut_setup(vs_context *ctx, int nl, const vs_light *light, vs_shade_lut *lut)
{
    if (nl < 8 || nl > 4096)
        return vs_set_error(ctx, VS_ERR_INVALID_ARGUMENT, "normal LUT size %d must lie in [8, 4096]", nl);
    if (lut->lambda_bin && lut->nl == nl) {
        /* a headlight is the same in the eye frame for every view: the
         * tables are kept (in the context) from frame to frame */
        if (memcmp(&lut->light, light, sizeof *light) != 0) fill_light_tables(lut, light);
        return VS_OK;
    }
    vs_shade_lut_free(lut);
    lut->nl = nl;
    lut->np = nl / 2 + 1;
    /* 4 bytes of zero padding: SIMD shading reads these with 32-bit gathers */
    lut->lambda_bin = calloc(255 * 255 + 2, sizeof *lut->lambda_bin);
    lut->radius = calloc(255 * 255 + 4, 1);
    lut->phi_bin = calloc(255 * 181 + 2, sizeof *lut->phi_bin);
    lut->diffuse = malloc((size_t)lut->np * nl * sizeof(float));
    lut->specular = malloc((size_t)lut->np * nl * sizeof(float));
    if (!lut->lambda_bin || !lut->radius || !lut->phi_bin || !lut->diffuse || !lut->specular) {
        vs_shade_lut_free(lut);
        return vs_set_error(ctx, VS_ERR_OUT_OF_MEMORY, "shading tables: out of memory");
    }
    fill_angle_tables(lut);
    fill_light_tables(lut, light);
    return VS_OK;
}
