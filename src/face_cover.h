/* The volume's faces when the fall-off to the value outside would show.
 *
 * Splatting's sum falls to the value outside the volume (vs_volume_base)
 * within the kernel's radius of a face, because fewer voxels reach there.
 * Where that value is visible (an iso-range that starts at the data's
 * minimum: dark membranes in electron microscopy, say), or values lie above
 * the range's upper end (a soft-tissue window around bone), the fall-off is
 * a shell at every face they touch, and sheets sample that thin shell as
 * stripes (vs_classify_faces).  So
 * there each sheet is divided by the share of the kernel's lattice sum that
 * the volume's voxels give (1 inside, 1/2 on a face): the reconstruction is
 * the kernel-weighted mean of the voxels that reach, extended to the faces,
 * and the sheets are then clipped to the volume (sheet_classify.c).  The ray
 * caster reconstructs the same way (raycast.c). */
#ifndef VS_FACE_COVER_H
#define VS_FACE_COVER_H

#include "tile.h"

/* Sheet k of the tile, complete (its touched box bb, ch channels a pixel):
 * each pixel within the kernel's reach of a face divided by the voxels'
 * share at its sheet point (the product of the three axes' shares); with
 * gradient splats (gs: density, then its view-space gradient times the
 * slab) the gradient by the quotient rule. */
void vs_face_norm_sheet(const tile_ctx *t, int k, float *buf, const rect *bb, int ch, int gs);

#endif
