/* libFuzzer harness: transfer-function files (src/io/tf_file.c).  The first
 * byte picks the format and the volume (tf_case.h): by extension (.json,
 * .1dt, .vtf) or sniffed from the content, read for a sphere, for no volume
 * (vs_tf_load), for a constant volume or one with non-finite voxels.  A
 * function that loads is then used to render that tiny volume with every
 * pipeline, so its points must be what vs_render accepts (or be refused
 * with a status), and the image must be finite with alpha in [0,1]. */
#include "fuzz_common.h"
#include "tf_case.h"

static vs_volume *fz_vols[4];

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);
int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    if (size < 1) return 0;
    if (!fz_ctx && vs_context_create(&fz_ctx) != VS_OK) abort();
    int with_vol;
    const vs_volume *vol = tf_case_volume(fz_ctx, data[0], fz_vols, &with_vol);
    if (!vol) abort();
    const char *path = fz_path(tf_case_suffix(data[0]));
    if (!fz_write(path, data + 1, size - 1)) abort();
    vs_tf_point *pts = NULL;
    int n = -1;
    vs_status st = with_vol ? vs_tf_load_for_volume(fz_ctx, path, vol, &pts, &n) : vs_tf_load(fz_ctx, path, &pts, &n);
    unlink(path);
    if (st != VS_OK) {
        if (pts || !*vs_last_error(fz_ctx)) abort();
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
        if (vs_render(fz_ctx, vol, &s, &img, NULL) == VS_OK) {
            for (int i = 0; i < 8 * 8; i++) {
                const float *px = img.rgba + 4 * i;
                if (!isfinite(px[0]) || !isfinite(px[1]) || !isfinite(px[2]) || !(px[3] >= 0.0f && px[3] <= 1.0f))
                    abort();
            }
            vs_image_free(&img);
        }
    }
    vs_tf_free(pts);
    return 0;
}
