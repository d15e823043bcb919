/* Per-worker tile scratch is kept by the context across tiles and frames
 * (src/tile.c): an arena whose sheet buffers must be zero again when a
 * tile starts, voxel lists that keep their capacity.  Whatever ran before,
 * a frame must give the image a fresh context gives it, bit for bit.  A
 * sequence of frames that changes pipeline, camera, footprint path, tile
 * size, occlusion and thread count is rendered forwards and backwards on
 * one context and each image compared with its own fresh render; among
 * them the sequence that once wrote through a list sized by an earlier
 * orthographic frame (a sheet-at-a-time frame, then a perspective one). */
#include "testutil.h"

typedef struct frame_case {
    const char *scene;
    vs_pipeline pipeline;
    double fov, slab;
    int tile, threads, occlusion, size;
    double az, el;
} frame_case;

static const frame_case cases[] = {
    {"sphere:40", VS_PIPELINE_POST_CD, 0, 0.02, 64, 1, 1, 96, 20, 10},  /* sheet at a time: vspan > 64 */
    {"sphere:40", VS_PIPELINE_POST_CD, 40, 1, 64, 1, 1, 96, 20, 10},    /* perspective after it */
    {"sphere:40", VS_PIPELINE_PRE, 0, 1, 16, 2, 1, 128, 0, 0},          /* voxel at a time */
    {"cell", VS_PIPELINE_POST_GS, 0, 1, 19, 2, 1, 128, 33, 21},         /* general footprints */
    {"cell", VS_PIPELINE_POST_ALPHA, 0, 1, 64, 1, 0, 96, 90, 0},        /* sheared, no occlusion */
    {"head:48", VS_PIPELINE_POST_GS, 30, 0.5, 8, 2, 1, 80, 150, 20},    /* perspective, small tiles */
    {"sphere:40", VS_PIPELINE_POST_GS, 0, 0.05, 37, 2, 1, 96, 45, 30},  /* sheet at a time, 4 channels */
    {"head:48", VS_PIPELINE_PRE, 35, 1, 64, 2, 0, 128, 200, -15},       /* perspective, no occlusion */
};
#define NCASES ((int)(sizeof cases / sizeof cases[0]))

static int render(vs_context *ctx, const frame_case *c, vs_image *img)
{
    vs_volume *v = tu_scene(ctx, c->scene);
    if (!v) return 0;
    vs_settings s;
    vs_settings_init(&s);
    s.pipeline = c->pipeline;
    s.perspective_fov = c->fov;
    s.slab = c->slab;
    s.tile_size = c->tile;
    s.threads = c->threads;
    s.occlusion = c->occlusion;
    s.width = s.height = c->size;
    s.azimuth = c->az;
    s.lod_pixels = 0; /* the footprint paths at full resolution, however small */
    s.elevation = c->el;
    const vs_status st = vs_render(ctx, v, &s, img, NULL);
    CHECK(st == VS_OK, "%s %s: %s", c->scene, vs_pipeline_name(c->pipeline), vs_last_error(ctx));
    vs_volume_release(v);
    return st == VS_OK;
}

int main(void)
{
    vs_image fresh[NCASES];
    for (int i = 0; i < NCASES; i++) {
        vs_context *ctx = NULL;
        if (vs_context_create(&ctx) != VS_OK) return 2;
        if (!render(ctx, &cases[i], &fresh[i])) fresh[i].rgba = NULL;
        vs_context_release(ctx);
    }
    vs_context *ctx = NULL;
    if (vs_context_create(&ctx) != VS_OK) return 2;
    int compared = 0;
    for (int pass = 0; pass < 2; pass++)
        for (int n = 0; n < NCASES; n++) {
            const int i = pass ? NCASES - 1 - n : n;
            vs_image img;
            if (!fresh[i].rgba || !render(ctx, &cases[i], &img)) continue;
            const double d = tu_max_diff(&fresh[i], &img);
            CHECK(d == 0.0, "case %d (%s %s, %s) after %d frames on one context differs from a fresh context by %g",
                  i, cases[i].scene, vs_pipeline_name(cases[i].pipeline), pass ? "backwards" : "forwards",
                  pass * NCASES + n, d);
            compared++;
            vs_image_free(&img);
        }
    vs_context_release(ctx);
    int covered = 0;
    for (int i = 0; i < NCASES; i++) {
        if (!fresh[i].rgba) continue;
        int n = 0;
        for (size_t p = 0; p < (size_t)fresh[i].width * fresh[i].height; p++) n += fresh[i].rgba[4 * p + 3] > 0;
        covered += n > fresh[i].width * fresh[i].height / 50;
        vs_image_free(&fresh[i]);
    }
    CHECK(covered == NCASES, "only %d of %d cases show anything", covered, NCASES);
    printf("%d frames on one context, forwards and backwards, equal to fresh contexts bit for bit\n", compared);
    TEST_DONE();
}
