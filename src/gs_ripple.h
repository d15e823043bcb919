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

/* What one tile's rows share (kernels.h vs_ripple_row), in the tile's
 * scratch: each 8-pixel block's and each row's turn from the phase at
 * image pixel (0, 0) of a sheet, made from its block or row number alone
 * so that every tile gives a pixel the same bits; with perspective the
 * sheet's lanes too (the tables then follow the sheet). */
typedef struct vs_gs_ripple_tile {
    int k;              /* the sheet the tables are for (INT_MIN: none;
                           orthographic: made once, for every sheet)   */
    int kc;             /* the sheet C0, S0 are for                    */
    float C0[3], S0[3]; /* phase of pixel (0, 0) at sheet kc           */
    int b0, nb;         /* xr[i]: image block b0 + i's, i < nb          */
    int y0, nr;         /* yr[i]: image row y0 + i's, i < nr            */
    float (*xr)[6], (*yr)[6]; /* cos of axis a at [.][a], sin at [.][3 + a] */
    vs_ripple_lanes L;
} vs_gs_ripple_tile;

/* Floats of a tile's vs_gs_ripple_tile tables: its own tw x th pixels. */
size_t vs_gs_ripple_tile_floats(int tw, int th);
/* A tile's state over those floats, for own pixels from (x0, y0). */
void vs_gs_ripple_tile_init(vs_gs_ripple_tile *T, float *tables, int x0, int y0, int tw, int th);

/* The ripple along sheet k's row y from image pixel x towards +x, for the
 * classify_gs kernel; (x, y) is one of the tile's own pixels.  Returns R. */
const vs_ripple_row *vs_gs_ripple_at(const vs_frame *F, int k, int x, int y, vs_ripple_row *R, vs_gs_ripple_tile *T);

#endif
