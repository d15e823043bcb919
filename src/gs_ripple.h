/* Post-gs without the kernel's lattice ripple.  The Gaussian summed over
 * the voxel lattice is not constant: it ripples with the lattice (about
 * 0.16 % an index axis), and a gradient splat carries the ripple's
 * gradient times the value, which draws the lattice as a grid on smooth
 * surfaces.  Each pixel's gradient less its value times the ripple's is
 * the gradient of the normalised sum (the ray caster's ray_normalize),
 * to first order in the ripple. */
#ifndef VS_GS_RIPPLE_H
#define VS_GS_RIPPLE_H

#include "frame.h"

/* F->ripple for the frame: on for post-gs with settings' gs_normalize */
void vs_gs_ripple_setup(vs_frame *F);
/* The ripple along sheet k's row from image pixel (x, y) towards +x, for
 * the classify_gs kernel (kernels.h vs_ripple_row); returns R.  With
 * perspective the lanes are the sheet's, made in *sheet unless *sheet_k
 * is k already (start it at INT_MIN). */
const vs_ripple_row *vs_gs_ripple_at(const vs_frame *F, int k, int x, int y, vs_ripple_row *R, vs_ripple_lanes *sheet,
                                     int *sheet_k);

#endif
