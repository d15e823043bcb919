/* The tile-parallel engine must not change the image: for every pipeline,
 * render once single-threaded, then demand identical floats for 2, 3 and 8
 * threads (libvips' threading test); across tile sizes the image is
 * identical with occlusion culling off, and with it on differs only by what
 * the culling threshold allows (a pixel stops receiving light once its
 * opacity passes the threshold, and which voxels a tile can cull depends on
 * what the tile sees: at most 1 - threshold per culled contribution, bounded
 * here by 2 (1 - threshold)).  On the real Colin27 head (skipped when the
 * data is absent) and on the synthetic `cell` scene. */
#ifndef _GNU_SOURCE
#define _GNU_SOURCE /* pthread_getaffinity_np */
#endif
#include "internal.h"
#include "testutil.h"

#include <math.h>
#include <pthread.h>
#include <sched.h>

static vs_context *ctx;
static int quick; /* VSPLAT_TEST_QUICK: fewer thread counts and tile sizes */

static int render(const vs_volume *v, const vs_settings *s, vs_image *img)
{
    vs_stats st;
    if (vs_render(ctx, v, s, img, &st) != VS_OK) {
        fprintf(stderr, "render failed: %s\n", vs_last_error(ctx));
        tu_failures++;
        return 0;
    }
    return 1;
}

static void check_volume(const char *name, const vs_volume *v, const vs_settings *base)
{
    for (int p = 0; p < 4; p++) {
        vs_settings s = *base;
        s.pipeline = (vs_pipeline)p;
        s.threads = 1;
        vs_image ref;
        if (!render(v, &s, &ref)) continue;
        const int threads[] = {2, 8, 3};
        for (int i = 0; i < (quick ? 2 : 3); i++) {
            vs_image img;
            s.threads = threads[i];
            if (!render(v, &s, &img)) continue;
            double d = tu_max_diff(&ref, &img);
            CHECK(d == 0.0, "%s %s: %d threads differ from 1 thread by %g", name, vs_pipeline_name(s.pipeline),
                  threads[i], d);
            vs_image_free(&img);
        }
        /* tile sizes */
        s.threads = 2;
        s.occlusion = 0;
        vs_image ref_nocull;
        s.tile_size = 64;
        if (render(v, &s, &ref_nocull)) {
            const int sizes[] = {16, 256, 32, 128};
            const int nsizes = quick ? 2 : 4;
            for (int i = 0; i < nsizes; i++) {
                vs_image img;
                s.tile_size = sizes[i];
                if (!render(v, &s, &img)) continue;
                double d = tu_max_diff(&ref_nocull, &img);
                CHECK(d == 0.0, "%s %s: tile %d differs from tile 64 by %g (culling off)", name,
                      vs_pipeline_name(s.pipeline), sizes[i], d);
                vs_image_free(&img);
            }
            s.occlusion = 1;
            double worst = 0;
            for (int i = 0; i < nsizes; i++) {
                vs_image img;
                s.tile_size = sizes[i];
                if (!render(v, &s, &img)) continue;
                double d = tu_max_diff(&ref_nocull, &img);
                if (d > worst) worst = d;
                vs_image_free(&img);
            }
            printf("%-8s %-10s identical for 1/2/3/8 threads; tiles 16..256: culling on changes pixels by <= %.2e\n",
                   name, vs_pipeline_name(s.pipeline), worst);
            CHECK(worst <= 2.0 * (1.0 - s.occlusion_threshold) + 1e-6, "%s %s: culling changed the image by %g",
                  name, vs_pipeline_name(s.pipeline), worst);
            vs_image_free(&ref_nocull);
        }
        vs_image_free(&ref);
    }
}

/* Exact normals take each pixel's gradient to the light without the normal
 * LUT's bins, so its last bit shows: post-gs's lattice-ripple term must be
 * a function of the pixel alone, not of where its tile's spans start.  Tile
 * sizes that are not multiples of 8 start spans at every phase of the
 * ripple's 8-pixel blocks; plain sheets and pre-integration, orthographic
 * and perspective. */
static void check_exact_normals_tiles(const char *name, const vs_volume *v, const vs_settings *base)
{
    for (int c = 0; c < 4; c++) {
        vs_settings s = *base;
        s.pipeline = VS_PIPELINE_POST_GS;
        s.exact_normals = 1;
        s.occlusion = 0;
        s.preintegration = c & 1 ? 1 : 0;
        s.perspective_fov = c & 2 ? 40.0 : 0.0;
        s.threads = 2;
        s.tile_size = 64;
        vs_image ref;
        if (!render(v, &s, &ref)) continue;
        const int sizes[] = {13, 24, 16, 100};
        double worst = 0.0;
        for (int i = 0; i < (quick ? 2 : 4); i++) {
            vs_image img;
            s.tile_size = sizes[i];
            if (!render(v, &s, &img)) continue;
            const double d = tu_max_diff(&ref, &img);
            CHECK(d == 0.0, "%s post-gs exact normals%s%s: tile %d differs from tile 64 by %g", name,
                  c & 1 ? " pre-integrated" : "", c & 2 ? " perspective" : "", sizes[i], d);
            if (d > worst) worst = d;
            vs_image_free(&img);
        }
        printf("%-8s post-gs exact normals%s%s: tiles 13/24/16/100 against 64 differ by at most %g\n", name,
               c & 1 ? ", pre-integrated" : "", c & 2 ? ", perspective" : "", worst);
        vs_image_free(&ref);
    }
}

/* With pinning, the calling thread runs as worker 0 bound to its core for
 * the length of each run; afterwards its own CPU set must be back. */
static void check_caller_binding(const vs_volume *v)
{
    cpu_set_t before, after;
    if (pthread_getaffinity_np(pthread_self(), sizeof before, &before) != 0) {
        printf("SKIP: caller binding: pthread_getaffinity_np failed\n");
        return;
    }
    vs_settings s;
    vs_settings_init(&s);
    s.width = s.height = 64;
    s.threads = 2;
    s.pin = 1;
    vs_image img;
    if (!render(v, &s, &img)) return;
    vs_image_free(&img);
    CHECK(pthread_getaffinity_np(pthread_self(), sizeof after, &after) == 0 && CPU_EQUAL(&before, &after),
          "the caller's CPU set changed across a pinned render (%d CPUs before, %d after)", CPU_COUNT(&before),
          CPU_COUNT(&after));
    printf("caller binding: %d CPUs before and after a pinned 2-thread render\n", CPU_COUNT(&after));
}

int main(void)
{
    if (vs_context_create(&ctx) != VS_OK) return 2;
    /* VSPLAT_TEST_QUICK (the sanitizer builds): smaller images, no real
     * head; the thread checks stay */
    const char *qe = getenv("VSPLAT_TEST_QUICK");
    quick = qe && *qe && strcmp(qe, "0") != 0;
    vs_settings s;
    vs_settings_init(&s);
    s.width = s.height = quick ? 64 : 128;

    vs_volume *cell;
    /* half-size cell (256x256x38, spacing 1:1:2.5): anisotropic voxels seen
     * obliquely exercise the sheared, sheet-at-a-time path */
    if (vs_volume_scene(ctx, "cell:256", &cell) == VS_OK) {
        s.azimuth = 30;
        s.elevation = 60;
        check_caller_binding(cell);
        check_volume("cell", cell, &s);
        check_exact_normals_tiles("cell", cell, &s);
        /* perspective: footprints scale and move with depth (general path) */
        s.perspective_fov = 40.0;
        check_volume("cell perspective", cell, &s);
        s.perspective_fov = 0.0;
        vs_volume_release(cell);
    } else {
        CHECK(0, "cell scene: %s", vs_last_error(ctx));
    }

    const char *data = tu_data_dir();
    if (quick) {
        printf("SKIP: Colin27 head: quick mode (VSPLAT_TEST_QUICK)\n");
    } else if (!data) {
        printf("SKIP: Colin27 head: no data folder (set VSPLAT_DATA)\n");
    } else {
        char path[8192];
        snprintf(path, sizeof path, "%s/colin27_ch2_mri_t1_head_181x217x181_u8.nii.gz", data);
        vs_volume *head;
        if (vs_volume_load(ctx, path, NULL, &head) == VS_OK) {
            s.azimuth = 180;
            s.elevation = 10;
            s.has_iso = 1;
            s.iso_lo = 45;
            s.ramp = 10;
            check_volume("colin27", head, &s);
            vs_volume_release(head);
        } else {
            printf("SKIP: Colin27 head: %s\n", vs_last_error(ctx));
        }
    }
    vs_context_release(ctx);
    TEST_DONE();
}
