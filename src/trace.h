/* Recording a timeline of frames (vs_trace, include/vsplat.h): spans of
 * the frame's serial parts and, per worker, of every tile and the stages
 * inside it.  Each worker appends to its own buffer (no locks); vs_render
 * merges them into the caller's vs_trace after the join.  With no trace
 * asked for, nothing is recorded and no clock is read for it. */
#ifndef VS_TRACE_H
#define VS_TRACE_H

#include "vsplat.h"

#include <stddef.h>
#include <stdint.h>

typedef enum vs_span_name {
    VS_SPAN_FRAME,     /* vs_render, on the calling thread                 */
    VS_SPAN_SETUP,     /* camera, classification, kernel and shading tables */
    VS_SPAN_RELEVANT,  /* building the relevant-voxel list                  */
    VS_SPAN_LOD,       /* building levels of detail (first frame to use one) */
    VS_SPAN_BIN,       /* bricks projected and binned into tiles            */
    VS_SPAN_TILES,     /* the tiles on the pool                             */
    VS_SPAN_RAYCAST,   /* the ray caster's rows on the pool                 */
    VS_SPAN_TILE,      /* one tile, on a worker                             */
    VS_SPAN_PROJECT,   /* bricks opened at a sheet: projected and bucketed  */
    VS_SPAN_SPLAT,     /* activation (occlusion tests, placement) and the
                          footprints added into the sheet buffers          */
    VS_SPAN_CLASSIFY,  /* classification and gradients of a sheet           */
    VS_SPAN_SHADE,     /* shading of a sheet                                */
    VS_SPAN_COMPOSITE, /* compositing of a sheet                            */
    VS_SPAN_OCCLUSION, /* the occlusion map's summed-area table rebuilt     */
    VS_SPAN_COUNT
} vs_span_name;

typedef struct vs_span {
    double t0, t1;    /* vs_now_ms() */
    int32_t tile;     /* tile index, or -1 */
    int16_t worker;   /* thread: 0 is the calling thread */
    int16_t name;     /* vs_span_name */
} vs_span;

/* A growable list of spans (one per worker during a frame). */
typedef struct vs_span_buf {
    _Alignas(64) vs_span *s; /* own cache line: workers append at once */
    size_t n, cap;
    int failed; /* out of memory: spans were dropped */
} vs_span_buf;

/* Room for more spans; 0 (and b->failed) when out of memory. */
int vs_span_grow(vs_span_buf *b);

static inline void vs_span_add(vs_span_buf *b, int name, int worker, int tile, double t0, double t1)
{
    if (b->n == b->cap && !vs_span_grow(b)) return;
    vs_span *s = &b->s[b->n++];
    s->t0 = t0;
    s->t1 = t1;
    s->tile = tile;
    s->worker = (int16_t)worker;
    s->name = (int16_t)name;
}

/* Append a worker's spans to the trace; 0 when out of memory. */
int vs_trace_append(vs_trace *t, const vs_span_buf *b);
/* Count a frame (vs_render's frame number in the trace's args). */
void vs_trace_frame_done(vs_trace *t);

#endif
