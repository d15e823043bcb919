/* What the stages of the per-tile sheet loop share: the tile's geometry,
 * its sheet buffers' touched boxes and shaded spans, kernel sections, the
 * voxels waiting for their first sheet, and each stage's entry points.
 * The stages (activate.c, rasterize.c, occlusion.c, sheet_classify.c,
 * shade.c, composite.c) include this header, never tile.c's loop; which
 * stage function serves which pipeline is pipeline.c's table. */
#ifndef VS_TILE_H
#define VS_TILE_H

#include "frame.h"

#include <stddef.h>
#include <stdint.h>
#include <stdlib.h>

typedef struct rect {
    int x0, y0, x1, y1; /* half-open, buffer coordinates */
} rect;

static inline void rect_clear(rect *r)
{
    r->x0 = r->y0 = 1 << 30;
    r->x1 = r->y1 = -(1 << 30);
}
static inline int rect_empty(const rect *r) { return r->x0 >= r->x1 || r->y0 >= r->y1; }

/* Pixels of a sheet to shade: buffer rows [y0, y1), in row y the columns
 * [xa[y], xb[y]) (buffer coordinates; empty when xa[y] == xb[y]). */
typedef struct spans {
    int y0, y1;
    int *xa, *xb; /* indexed by buffer row */
} spans;

/* The geometry every rasterizer shares: where one kernel section lands. */
typedef struct section {
    float cx, cy;   /* centre in image coordinates (after the depth shift);
                       kept tile-independent so that every tiling computes
                       bit-identical weights */
    float D;        /* depth integral over the slab                          */
    float E;        /* exp(-k z1^2) - exp(-k z0^2), for the z gradient splat */
    float sc, is;   /* footprint scale (perspective; 1 when orthographic) and
                       its inverse: offsets in pixels times `is` are offsets
                       in the footprint's units (pixels at depth 0)          */
    const vs_block_geom *g; /* skewed tables at this scale, or NULL: an
                       exponential per pixel                                 */
} section;

typedef struct tile_ctx {
    const vs_frame *F;
    const vs_footprint *fp;
    int x0, y0, tw, th;  /* own pixels in image coordinates                 */
    int seam;            /* pixels of seam each side: what the in-sheet
                            differences read past the own pixels (1, or 2
                            with post-cd's four-point stencil)              */
    int bw, bh;          /* buffer size: own pixels plus the seam            */
    int stride;          /* pixels per buffer row: bw plus an apron of
                            VS_APRON pixels each side, which footprint
                            blocks may spill into (cleared, never shaded)   */
    int ox, oy;          /* image coordinates of buffer pixel (0,0)          */
    float ry0;           /* footprint half-height without shift              */
    float *blk;          /* scratch: one voxel's footprint block             */
    float *ex;           /* scratch: one footprint row of weights (bw)       */
    struct vs_gs_ripple_tile *ripple; /* post-gs: its rows' lattice ripple
                            (gs_ripple.h), or NULL                           */
    vs_worker_stats *ws; /* the worker's counters                            */
} tile_ctx;

/* The part of a footprint block inside the tile's buffer, block pixel
 * (0, 0) at buffer column bx and row by: its vectors [v0, v1) of ppv
 * pixels (of nvec; the last may spill into the apron) and its rows
 * [j0, j1) (of ny).  Empty when v0 >= v1 or j0 >= j1. */
static inline void vs_clip_cols(const tile_ctx *t, int bx, int nvec, int ppv, int *v0, int *v1)
{
    const int v = t->bw - bx <= 0 ? 0 : (t->bw - bx + ppv - 1) / ppv;
    *v0 = bx < 0 ? -bx / ppv : 0;
    *v1 = v < nvec ? v : nvec;
}
static inline void vs_clip_rows(const tile_ctx *t, int by, int ny, int *j0, int *j1)
{
    *j0 = by < 0 ? -by : 0;
    *j1 = t->bh - by < ny ? t->bh - by : ny;
}

/* Own pixel (x, y) of the buffer's coordinates in the tile's per-pixel
 * arrays (opacity, colour, accumulated image). */
static inline int vs_own(const tile_ctx *t, int x, int y) { return (y - t->seam) * t->tw + (x - t->seam); }

static inline void rect_grow(rect *bb, int xa, int xb, int y)
{
    if (xa < bb->x0) bb->x0 = xa;
    if (xb + 1 > bb->x1) bb->x1 = xb + 1;
    if (y < bb->y0) bb->y0 = y;
    if (y + 1 > bb->y1) bb->y1 = y + 1;
}

static inline void rect_merge(rect *bb, const rect *r)
{
    if (rect_empty(r)) return;
    if (r->x0 < bb->x0) bb->x0 = r->x0;
    if (r->y0 < bb->y0) bb->y0 = r->y0;
    if (r->x1 > bb->x1) bb->x1 = r->x1;
    if (r->y1 > bb->y1) bb->y1 = r->y1;
}

/* A voxel of an expanded brick, from its first sheet to its last. */
typedef struct pend {
    float x, y, z; /* view-space centre (perspective: x, y at depth 0) */
    uint32_t v;    /* linear index in the volume                    */
    uint32_t c;    /* its slot in the kept normal codes (brick order;
                      pre-shaded with F->ncode only)                  */
    int kl;        /* last sheet (lowered when the voxel is culled) */
    float w[4];    /* splat weights before the slab's depth integral */
} pend;

/* Emptied bucket arrays kept for new buckets (of this tile, the next
 * tiles and frames), so that buckets neither allocate nor grow by copying
 * once the first tiles have run: up to VS_SPARES of them and
 * VS_SPARE_BYTES together, the smallest given up for a larger one. */
enum { VS_SPARES = 32, VS_SPARE_BYTES = 8 << 20 };
typedef struct vs_spares {
    pend *p[VS_SPARES];
    int cap[VS_SPARES];
    int n;
    size_t bytes; /* their capacities together */
} vs_spares;

static inline void vs_keep_spare(vs_spares *s, pend *p, int cap)
{
    if (!p) return;
    const size_t b = (size_t)cap * sizeof(pend);
    /* room once every smaller array went? else p goes and they stay */
    size_t smaller = 0;
    int nsmaller = 0;
    for (int i = 0; i < s->n; i++)
        if (s->cap[i] < cap) {
            smaller += (size_t)s->cap[i] * sizeof(pend);
            nsmaller++;
        }
    if (b > VS_SPARE_BYTES || s->n - nsmaller == VS_SPARES || s->bytes - smaller + b > VS_SPARE_BYTES) {
        free(p);
        return;
    }
    while (s->n == VS_SPARES || s->bytes + b > VS_SPARE_BYTES) { /* the smallest first */
        int m = 0;
        for (int i = 1; i < s->n; i++)
            if (s->cap[i] < s->cap[m]) m = i;
        free(s->p[m]);
        s->bytes -= (size_t)s->cap[m] * sizeof(pend);
        s->p[m] = s->p[--s->n];
        s->cap[m] = s->cap[s->n];
    }
    s->p[s->n] = p;
    s->cap[s->n++] = cap;
    s->bytes += b;
}

static inline void vs_spares_free(vs_spares *s)
{
    for (int i = 0; i < s->n; i++) free(s->p[i]);
    s->n = 0;
    s->bytes = 0;
}

/* The voxels whose first sheet is one sheet, in the order they came. */
typedef struct pend_bucket {
    pend *p;
    int n, cap;
} pend_bucket;

/* Per tile: the voxels of expanded bricks in buckets by first sheet, each
 * bucket one array (read in order when its sheet opens).  A sheet receives
 * its voxels in (first sheet, brick, voxel) order whatever the tiling or
 * thread count, so the sums are bit-identical. */
typedef struct tile_state {
    const tile_ctx *t;
    pend_bucket *bk;  /* bucket of sheet k at k - kmin                   */
    vs_spares *spares; /* emptied arrays, for new buckets (the scratch's) */
    int kmin, kmax;
    pend **active;    /* sheet-at-a-time path: voxels overlapping the sheet */
    float (*abox)[5]; /* perspective: each active voxel's voxel_box (box
                         and scale), computed once, when it is admitted */
    int nactive, cap_active, cap_abox;
    const float *acc; /* the tile's accumulation (occlusion map = alpha)   */
    const int *sat;   /* summed-area table of opaque pixels                */
    const int *opaque;
    vs_worker_stats *ws;
    int failed;
} tile_state;

/* What a worker keeps between tiles and frames (one per worker, owned by
 * the context), so that a tile allocates nothing once the first tiles of
 * that size have run: one arena carved into the tile's buffers, whose
 * sheet buffers stay zero outside the boxes a tile touched (a tile clears
 * them when it ends), and the voxel lists that grow on demand. */
typedef struct vs_tile_scratch {
    unsigned char *arena;
    size_t cap;
    size_t zeroed;   /* the arena's first bytes that are zero but for the
                        boxes the last tile touched and cleared */
    vs_spares spares; /* emptied bucket arrays */
    pend **active;   /* sheet-at-a-time path */
    float (*abox)[5];
    int cap_active, cap_abox;
} vs_tile_scratch;

/* Per-pixel scratch of one sheet: opacity, gradient/colour. */
typedef struct shade_buf {
    float *alpha; /* tw*th */
    float *g;     /* tw*th*3: gradient, then shaded colour */
    /* pre-integrated post-cd and post-gs: per pixel, the Phong terms
     * (diffuse, specular) of sheet k + 1's gradient that shading sheet k
     * took, and that k + 1 (term_k; else INT_MIN) to reuse them there;
     * NULL unless pre-integrated post-cd or post-gs */
    float *term;
    int *term_k;
} shade_buf;


/* One sheet as the per-sheet stages see it: sheet k's buffer q (ch
 * channels; post-cd's central differences also read the sheets before and
 * after), the spans to classify, shade and composite, the tables the
 * post-shaded kernels read, and the tile's accumulation. */
typedef struct sheet_view {
    int k;
    const float *q, *prev, *next;
    const float *next2;  /* sheet k + 2 when the stages rasterize 2 ahead, else NULL */
    const float *prev2;  /* sheet k - 2 when the stages keep 2 behind, else NULL */
    const spans *sp;
    const vs_shade_tabs *tabs;
    const float *acc;
} sheet_view;

/* The stages that differ between pipelines, chosen once per frame
 * (pipeline.c): the loops call through this table instead of branching on
 * the pipeline. */
typedef struct vs_stages {
    int ch;              /* sheet-buffer channels: 1 (density) or 4        */
    int ahead;           /* sheets rasterized ahead of the one shaded (post-
                            cd's central differences read sheet k + 1, and
                            pre-integrated, sheet k + 1's read k + 2, and
                            the four-point stencil across sheets k + 2)     */
    int behind;          /* sheets kept behind the shaded one past k - 1
                            (the four-point stencil across sheets: 1)       */
    int gradient_splats; /* post-gs: sections carry the depth derivative's
                            integral E and mix density with its gradient   */
    int pre_shaded;      /* voxels are classified and shaded before splatting */
    /* splat weights of the batch's voxels in the mask `live` */
    void (*weights)(const vs_frame *F, const pend *p, unsigned live, float w[][4]);
    /* sheet at a time, general footprints without tables */
    void (*raster)(const tile_ctx *t, const section *sec, const float w4[4], float *dst, rect *bb);
    /* voxel at a time: the voxels starting at sheet `opening` into every
     * sheet of the ring they reach (activate.h) */
    void (*activate)(tile_state *ts, int opening, float *const *ring, rect *bbs, int R, int kbase);
    /* classification and gradients of a sheet's spans into sb; returns
     * how many of its pixels keep an opacity */
    uint64_t (*classify)(const tile_ctx *t, const sheet_view *sv, shade_buf sb);
    /* shading: sb's gradients (or splatted colours) to colours */
    void (*shade)(const tile_ctx *t, const sheet_view *sv, shade_buf sb);
} vs_stages;

/* The table for a pipeline (exact_normals: shade post-shaded pipelines with
 * exact normals instead of the lookup tables; preint: post-cd, post-gs and post-alpha
 * with pre-integration between sheets, the frame's `preint`). */
const vs_stages *vs_pipeline_stages(vs_pipeline p, int exact_normals, int preint, int wide_z);

#endif
