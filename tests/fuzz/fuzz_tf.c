/* libFuzzer harness: transfer-function files (src/io/tf_file.c).  The first
 * byte picks the format by extension (.json, .1dt, .vtf); a function that
 * loads is then used to render a tiny volume with every pipeline, so its
 * points must be what vs_render accepts (or be refused with a status). */
#include "fuzz_common.h"

static vs_volume *fz_vol;

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);
int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    if (size < 1) return 0;
    if (!fz_ctx && vs_context_create(&fz_ctx) != VS_OK) abort();
    if (!fz_vol && vs_volume_scene(fz_ctx, "sphere:8", &fz_vol) != VS_OK) abort();
    static const char *const sfx[3] = {".json", ".1dt", ".vtf"};
    const char *path = fz_path(sfx[data[0] % 3]);
    if (!fz_write(path, data + 1, size - 1)) abort();
    vs_tf_point *pts = NULL;
    int n = -1;
    vs_status st = vs_tf_load_for_volume(fz_ctx, path, fz_vol, &pts, &n);
    unlink(path);
    if (st != VS_OK) {
        if (pts) abort();
        return 0;
    }
    if (!pts || n < 1) abort();
    vs_settings s;
    vs_settings_init(&s);
    s.width = s.height = 8;
    s.threads = 1;
    s.tf = pts;
    s.tf_count = n;
    for (int p = 0; p <= VS_PIPELINE_RAYCAST; p++) {
        s.pipeline = (vs_pipeline)p;
        vs_image img;
        if (vs_render(fz_ctx, fz_vol, &s, &img, NULL) == VS_OK) {
            for (int i = 0; i < 8 * 8 * 4; i++)
                if (!(img.rgba[i] == img.rgba[i])) abort(); /* NaN */
            vs_image_free(&img);
        }
    }
    vs_tf_free(pts);
    return 0;
}
