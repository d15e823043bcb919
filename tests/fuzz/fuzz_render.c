/* libFuzzer harness: the renderer.  The input is decoded into a small
 * volume with hostile voxel values and hostile settings (render_case.h);
 * a broken promise (a non-finite colour, alpha outside [0,1], images that
 * differ between 1 and N threads, an error without a message) aborts, and
 * so does a crash, a sanitizer report, a leak or a hang (-timeout). */
#include "render_case.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);
int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    static vs_context *ctxs[4]; /* by thread count */
    for (int t = 1; t < 4; t++)
        if (!ctxs[t] && vs_context_create(&ctxs[t]) != VS_OK) abort();
    char why[512];
    vs_status st;
    if (rc_check(ctxs, data, size, &st, why, sizeof why)) {
        fprintf(stderr, "fuzz_render: %s\n", why);
        abort();
    }
    return 0;
}
