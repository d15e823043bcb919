/* Voxel normals as 16-bit codes on the octahedron (181 x 181 cells on its
 * upper half, the direction in the volume's axis frame, spacing applied),
 * and a table of
 * the light's Phong terms per code for the current view (normal_code.c).
 * Shading a pre-shaded voxel is then one look-up: no rotation into the eye
 * frame and no chain of dependent Clyne-Dennis look-ups per voxel. */
#ifndef VS_NORMAL_CODE_H
#define VS_NORMAL_CODE_H

#include "light.h"
#include "relevant.h"
#include "volume.h"
#include "voxel_gradient.h"

#include <float.h>
#include <stdatomic.h>
#include <stdint.h>

#ifndef VS_NORMAL_SIDE
#define VS_NORMAL_SIDE 181
#endif
#define VS_NORMAL_ZERO (VS_NORMAL_SIDE * VS_NORMAL_SIDE) /* no direction */
#define VS_NORMAL_CODES (VS_NORMAL_ZERO + 1)
_Static_assert(VS_NORMAL_CODES < 65535, "a kept code is stored plus one in 16 bits");

/* The code of a gradient.  Lighting is two-sided, so g and -g shade alike
 * and only the half with gz >= 0 is coded: its octahedron face, the
 * diamond |x| + |y| <= 1 of the L1-normalised gradient, turned 45 degrees
 * onto the square (x + y, x - y), and the nearest of its side^2 cells.  A
 * gradient with a NaN or infinite component, or under 1e-30 (as in
 * vs_light_eval), has no direction: VS_NORMAL_ZERO, which faces the eye. */
static inline int vs_normal_code(float gx, float gy, float gz)
{
    float ax = gx < 0 ? -gx : gx, ay = gy < 0 ? -gy : gy, az = gz < 0 ? -gz : gz;
    if (!(ax <= FLT_MAX && ay <= FLT_MAX && az <= FLT_MAX)) return VS_NORMAL_ZERO;
    float sum = ax + ay + az;
    if (!(sum <= FLT_MAX)) { /* finite components whose sum overflows */
        gx *= 0.25f;
        gy *= 0.25f;
        sum = 0.25f * ax + 0.25f * ay + 0.25f * az;
    }
    if (!(sum >= 1e-30f)) return VS_NORMAL_ZERO;
    if (gz < 0.0f) {
        gx = -gx;
        gy = -gy;
    }
    const float h = 0.5f * (VS_NORMAL_SIDE - 1), k = h / sum;
    const int u = (int)((gx + gy) * k + h + 0.5f), v = (int)((gx - gy) * k + h + 0.5f);
    return v * VS_NORMAL_SIDE + u;
}

/* A code's direction (not unit length; VS_NORMAL_ZERO: 0). */
void vs_normal_decode(int code, double n[3]);

/* The Phong terms of every code for a light and a camera, kept in the
 * context and rebuilt only when either changed. */
typedef struct vs_normal_table {
    float (*terms)[2]; /* [VS_NORMAL_CODES]: diffuse, specular */
    double key[19];    /* the light and the camera axes it was built for */
} vs_normal_table;

/* Fills *tab (zeroed, or an earlier table) for the light in the eye frame
 * and the camera axes (volume axis frame) right, up, dir. */
vs_status vs_normal_table_setup(vs_context *ctx, const vs_light *l, const double right[3], const double up[3],
                                const double dir[3], vs_normal_table *tab);
void vs_normal_table_free(vs_normal_table *tab);

/* Every voxel's code, kept in the context for the last few volumes and
 * filled in as frames splat the voxels (shade.c): a voxel's gradient then
 * costs a later frame one 2-byte load instead of 32 value loads.  The
 * codes depend on the values, the spacing and the value outside the volume
 * (which the declared range sets) alone, so a new classification or view
 * keeps them.  They are stored brick by brick
 * (the relevant-voxel bricks, VS_BRICK^3 voxels each, in brick-grid order;
 * inside a brick by a voxel's vs_voxel position), so that only the bricks
 * a frame splats take memory: the array is zero pages until written.
 * Volumes whose codes would take over VS_NORMAL_CODES_MAX_BYTES get none
 * (each frame codes its voxels itself, with the same result). */
#define VS_NORMAL_CODES_KEEP 3
#define VS_NORMAL_CODES_MAX_BYTES ((size_t)32 << 20)
/* all slots together: a volume at the limit and its levels of detail,
 * which a perspective view's depth bands ask for in every frame */
#define VS_NORMAL_CODES_ALL_BYTES (VS_NORMAL_CODES_MAX_BYTES + VS_NORMAL_CODES_MAX_BYTES / 4)
_Static_assert(ATOMIC_SHORT_LOCK_FREE == 2, "kept codes are plain 16-bit stores and loads");
typedef struct vs_normal_codes {
    vs_volume_stamp from;        /* key: the volume, its voxels, spacing and
                                    outside value (vs_volume_stamp_same_field) */
    uint64_t used;               /* when last used (least recently replaced) */
    _Atomic uint16_t *code;      /* [n]: code + 1, 0 while unknown; mapped
                                    anonymous memory, so untouched bricks
                                    stay unbacked however the heap grew    */
    size_t n;
} vs_normal_codes;
/* The codes of vol from the context's slots, a new zeroed array if
 * missing; NULL if too large or out of memory (not an error). */
_Atomic uint16_t *vs_normal_codes_get(vs_context *ctx, const struct vs_volume *vol);
void vs_normal_codes_free(vs_normal_codes *c);

/* The slot in the kept codes of the brick whose lowest voxel is (i0, j0,
 * k0), a multiple of VS_BRICK: a voxel's slot is this plus its vs_voxel. */
static inline uint32_t vs_normal_code_slot(const struct vs_volume *vol, int i0, int j0, int k0)
{
    const uint32_t nbi = ((uint32_t)vol->dims[0] + VS_BRICK - 1) >> VS_BRICK_BITS;
    const uint32_t nbj = ((uint32_t)vol->dims[1] + VS_BRICK - 1) >> VS_BRICK_BITS;
    return ((((uint32_t)k0 >> VS_BRICK_BITS) * nbj + ((uint32_t)j0 >> VS_BRICK_BITS)) * nbi +
            ((uint32_t)i0 >> VS_BRICK_BITS))
           << (3 * VS_BRICK_BITS);
}

/* What a voxel's gradient (voxel_gradient.h) is multiplied by before coding: the
 * spacing's inverse times the finest spacing (the same direction, and
 * factors of at most 1 cannot overflow a finite gradient); once a frame. */
static inline void vs_normal_code_scale(const struct vs_volume *vol, float sc[3])
{
    const double f = vs_volume_finest(vol);
    for (int a = 0; a < 3; a++) sc[a] = (float)(f / vol->spacing[a]);
}

/* The code of the voxel of linear index idx, with sc from
 * vs_normal_code_scale. */
static inline int vs_voxel_normal_code(const struct vs_volume *vol, const float sc[3], size_t idx)
{
    float g[3];
    vs_voxel_gradient(vol, idx, g);
    return vs_normal_code(g[0] * sc[0], g[1] * sc[1], g[2] * sc[2]);
}

#endif
