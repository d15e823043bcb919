/* One splatting frame: everything the per-tile sheet loop reads, built once
 * per vs_render call and shared read-only by the workers. */
#ifndef VS_FRAME_H
#define VS_FRAME_H

#include "block.h"
#include "footprint.h"
#include "kernels.h"
#include "shade_lut.h"
#include "relevant.h"

#include <stdatomic.h>

/* Per-worker counters, summed after the join (no atomics in the hot loop);
 * each on its own cache lines so workers never share one. */
typedef struct vs_worker_stats {
    _Alignas(64) uint64_t splatted, culled, sheets, tiles_total, tiles_shaded;
    uint64_t bricks_culled, projected, tested, floats, px_classified, px_shaded;
    double ms_rasterize, ms_gradient, ms_shade, ms_composite;
} vs_worker_stats;

/* Post-gs: what a frame needs to take the kernel's lattice ripple out of
 * the splatted gradients (gs_ripple.h). */
enum { VS_RIPPLE_TAB = 256 };
typedef struct vs_gs_ripple {
    int on;
    double u0[3], ux[3], uy[3], uz[3]; /* index a of the depth-0 image point
                                          (x, y) at depth z: u0 + ux x + uy y + uz z */
    vs_ripple_lanes L;    /* axis a's term ca cos 2 pi u + cb sin 2 pi u (u its
                             index at the slab's front), taken to view space
                             by m = Minv / slab^2; orthographic: the lanes
                             (kernels.h vs_ripple_lanes)                    */
    float cs[VS_RIPPLE_TAB][2]; /* cos, sin of 2 pi i / TAB               */
} vs_gs_ripple;

typedef struct vs_frame {
    const vs_settings *s;
    vs_pipeline pipeline;
    vs_camera cam;
    double spacing[3];               /* voxel spacing (gradients to world units) */
    vs_classify *cls;
    vs_light light;
    vs_footprint fp;
    int use_blocks;                  /* voxel at a time: separable footprints with
                                        footprint blocks (src/block.h), or
                                        sheared_blocks                           */
    int sheared_blocks;              /* voxel at a time, an axis-aligned footprint
                                        whose centre moves with depth: a section
                                        per sheet from the skewed tables (blk
                                        unused)                                  */
    vs_block_geom blk;
    int use_skewed;                  /* general footprints: one block per
                                        section from skewed tables            */
    vs_block_geom skew;              /* orthographic: the tables            */
    vs_block_geom *sheet_skew;       /* perspective: tables per sheet, scaled
                                        by its depth (ny == 0: none, too large) */
    int sheet_k0, nsheet_skew;       /* sheet of sheet_skew[0], how many       */
    int skew_maxvec, skew_maxrows;   /* largest block over the tables in use   */
    vs_shade_lut lut;
    const float (*nterms)[2];        /* pre-shaded, table normals: Phong terms
                                        per normal code (normal_code.h)       */
    _Atomic uint16_t *ncode;         /* and the voxels' codes plus one (0: not
                                        yet), or NULL: coded per voxel          */
    float nscale[3];                 /* vs_normal_code_scale of vol            */
    vs_kernels kern;                 /* inner loops for the chosen ISA            */
    const vs_relevant_cache *rel;
    const struct vs_volume *vol;     /* what the voxels' values are read from   */
    float alpha_corr[VS_TF_TABLE];   /* classification opacity corrected for the slab */
    float alpha_zero_x;              /* alpha_corr reads 0 below this coordinate */
    float opacity_corr[1025];        /* 1-(1-a)^slab over a in [0,1] (pre-shaded)      */
    const struct vs_preint *preint;  /* pre-integrated classification between
                                        sheets (post-cd, -gs, -alpha), or NULL  */
    /* Post-classified pipelines splat value - base (vs_volume_base: the
     * volume's minimum when negative) and add it back where a sheet is
     * classified: at the volume's faces, where fewer voxels reach, the
     * reconstruction falls to the minimum (CT's air stays air) rather than
     * to 0, as the ray caster's does.  0 for pre-shaded splatting. */
    double base;
    int clip_to_volume;              /* the faces would show (vs_classify_faces),
                                        or a crop box: pixels whose sheet point
                                        lies outside stay clear                */
    const struct vs_volume *cover;   /* the faces would show: sheets are divided
                                        near them by this grid's voxels' share
                                        (face_cover.h): the splatted one, or for
                                        the cubic copy and its levels (which
                                        reach past the faces) the volume; else
                                        NULL                                   */
    int cover_in0[3], cover_in1[3];  /* its voxels inside the volume's faces   */
    double cover_scale[3];           /* the kernel's width in its voxels: a
                                        level of the cubic copy reconstructs the
                                        volume's field blurred to its spacing  */
    double clip_lo[3], clip_hi[3];   /* the box clip_to_volume keeps (index space) */
    int clip_hi_open[3];             /* 1: a point on clip_hi is outside (a crop
                                        face shared with the next brick)       */
    int show0, show1;                /* the sheets [show0, show1) shaded and
                                        composited: one depth band of a view
                                        split by level of detail (lod_depth.h);
                                        the rest are only splatted as far as
                                        the band's sheets need them            */
    const float *under;              /* a band behind nearer ones: their picture
                                        (straight RGBA, width*height), which the
                                        tiles' compositing and occlusion start
                                        from; NULL: from nothing               */

    /* per brick of relevant voxels: view-space bounds of its voxel centres
     * (x, y pixels; z view units), for binning and brick-level culling */
    struct vs_brick_view {
        float x0, x1, y0, y1, z0, z1;
        float sc; /* largest footprint scale of its voxels (perspective; else 1) */
        int kf, kl; /* the first and last sheet its voxels' kernels reach */
    } *bview;

    /* tiles */
    int tile, tiles_x, tiles_y, ntiles;
    uint32_t *tile_start;            /* ntiles + 1                               */
    uint32_t *tile_entries;          /* brick indices, per tile in brick order   */
    int *tile_order;                 /* tasks in order of estimated work, largest
                                        first (results do not depend on it)     */
    double pad_x, pad_y;             /* footprint half-extent + seam, pixels     */
    float cd_wide;                   /* post-cd: weight of the four-point in-sheet
                                        differences (vs_shade_tabs), 0: none   */
    float cd_wide_z;                 /* post-cd, plain sheets: the same across
                                        sheets (vs_shade_tabs), 0: none        */
    int seam_px;                     /* tile buffers' seam each side: the reach
                                        of the in-sheet differences (1 or 2)   */

    float *image;                    /* width*height*4 straight RGBA output      */
    atomic_int cancel;
    atomic_int error;                /* a worker ran out of memory               */
    atomic_int tiles_done;
    vs_worker_stats *wstats;         /* one per worker                           */
    struct vs_tile_scratch *scratch; /* one per worker, the context's            */
    struct vs_span_buf *spans;       /* one per worker when tracing, else NULL   */
    const struct vs_stages *stages;  /* what differs between the pipelines
                                        (pipeline.c)                            */
    vs_gs_ripple ripple;
} vs_frame;

/* How far past a voxel's centre (x and y, pixels) its footprint and the
 * tile seam reach when the footprint is seen sc times larger (perspective):
 * the footprint scales, the seam is pixels of the tile whatever the depth.
 * sc = 1 gives pad_x, pad_y exactly. */
static inline void vs_frame_reach(const vs_frame *F, float sc, float *px, float *py)
{
    const float s1 = sc - 1.0f;
    *px = (float)F->pad_x + (float)(F->pad_x - F->seam_px) * s1;
    *py = (float)F->pad_y + (float)(F->pad_y - F->seam_px) * s1;
}

/* Pixels of sheet-buffer apron left and right of a tile's buffer: a
 * footprint block vector (8 floats) spills at most 7 pixels past it. */
#define VS_APRON 8
/* Most sheets one kernel may reach on the voxel-at-a-time path. */
#define VS_MAX_VSPAN 64

/* Render tile `task` of the frame (a vs_task_fn). */
void vs_tile_render(void *frame, int worker, int task);
/* Reports the frame's progress (tiles done) to the settings' callback and
 * sets the cancel flag if it asks: between tiles on the calling thread, and
 * while that thread waits for the other workers (vs_pool_run_watched). */
void vs_tile_progress(void *frame);

#endif
