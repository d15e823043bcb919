/* The gradient a pre-shaded voxel is lit by (pre, post-alpha): that of the
 * field splatting reconstructs, at the voxel's centre. */
#ifndef VS_VOXEL_GRADIENT_H
#define VS_VOXEL_GRADIENT_H

#include <stddef.h>

struct vs_volume;

/* The gradient at the voxel of linear index idx, of the sum of the
 * kernel 2^(-2 r^2) over the voxels, what lies outside the volume and
 * non-finite voxels reading as vs_volume_base, in index units, halved
 * (so data spanning +-FLT_MAX stays finite) and up to the kernel's
 * constant factor: the direction the exact-Gaussian ray caster samples
 * there (src/raycast.c).  The 32 neighbours within 2 voxels: the default
 * kernel's (--kernel-radius 2) reach, used for every radius (farther
 * neighbours weigh 2^-8 of a face neighbour or less; a radius under 2 does
 * not reach the diagonal ones, which still tilt the normal only as the
 * field's smoothing would). */
void vs_voxel_gradient(const struct vs_volume *v, size_t idx, float g[3]);

#endif
