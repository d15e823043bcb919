/* Embedding vsplat: render a synthetic sphere, optionally with a transfer
 * function file, check the image, and write it.
 *
 *   example_embed [TF_FILE [OUT.png]]
 *
 * Build against an installed vsplat:
 *   CMake:      find_package(vsplat REQUIRED)
 *               target_link_libraries(app PRIVATE vsplat::vsplat)   (or vsplat::vsplat_static)
 *   pkg-config: cc example_embed.c $(pkg-config --cflags --libs vsplat)
 *
 * Prints one line "example_embed: vsplat X.Y.Z rendered WxH, centre alpha A,
 * N voxels splatted" and exits 0 if the sphere covers the image centre. */
#include <vsplat.h>

#include <stdio.h>
#include <stdlib.h>

static int fail(vs_context *ctx, const char *what)
{
    fprintf(stderr, "example_embed: %s: %s\n", what, vs_last_error(ctx));
    return 1;
}

int main(int argc, char **argv)
{
    vs_context *ctx = NULL;
    if (vs_context_create(&ctx) != VS_OK) {
        fprintf(stderr, "example_embed: cannot create a context\n");
        return 1;
    }
    vs_volume *vol = NULL;
    if (vs_volume_scene(ctx, "sphere:24", &vol) != VS_OK) {
        int rc = fail(ctx, "scene");
        vs_context_release(ctx);
        return rc;
    }

    vs_settings s;
    vs_settings_init(&s);
    s.width = s.height = 64;
    s.threads = 1;
    s.pipeline = VS_PIPELINE_POST_CD;

    vs_tf_point *tf = NULL;
    int ntf = 0;
    if (argc > 1) {
        if (vs_tf_load_for_volume(ctx, argv[1], vol, &tf, &ntf) != VS_OK) {
            int rc = fail(ctx, "transfer function");
            vs_volume_release(vol);
            vs_context_release(ctx);
            return rc;
        }
        s.tf = tf;
        s.tf_count = ntf;
    }

    vs_image img = {0, 0, NULL};
    vs_stats st;
    int rc = 0;
    if (vs_render(ctx, vol, &s, &img, &st) != VS_OK) {
        rc = fail(ctx, "render");
    } else {
        const float *c = img.rgba + ((size_t)(img.height / 2) * img.width + img.width / 2) * 4;
        printf("example_embed: vsplat %s rendered %dx%d, centre alpha %.2f, %llu voxels splatted%s\n",
               vs_version(), img.width, img.height, c[3], (unsigned long long)st.voxels_splatted,
               ntf ? ", transfer function from file" : "");
        if (!(c[3] > 0.5f)) {
            fprintf(stderr, "example_embed: the sphere does not cover the image centre\n");
            rc = 1;
        }
        if (!rc && argc > 2 && vs_image_write(ctx, argv[2], &img, 8) != VS_OK) rc = fail(ctx, argv[2]);
    }
    vs_image_free(&img);
    vs_tf_free(tf);
    vs_volume_release(vol);
    vs_context_release(ctx);
    return rc;
}
