/* Front-to-back compositing (composite.h); the kernel is the table's
 * `composite` (simd/kernels.h). */
#include "composite.h"
#include "finish.h"

int vs_composite_sheet(const tile_ctx *t, const spans *sp, float *acc, shade_buf sb, float thr, int *first_row)
{
    const vs_frame *F = t->F;
    int total = 0;
    for (int y = sp->y0; y < sp->y1; y++) {
        if (sp->xa[y] == sp->xb[y]) continue;
        int o = vs_own(t, sp->xa[y], y);
        const int crossed = F->kern.composite(acc + 4 * o, sb.alpha + o, sb.g + 3 * o, sp->xb[y] - sp->xa[y], thr);
        if (crossed) {
            total += crossed;
            if (y - t->seam < *first_row) *first_row = y - t->seam;
        }
    }
    return total;
}

void vs_composite_finish(const tile_ctx *t, const float *acc)
{
    const vs_frame *F = t->F;
    const int W = F->cam.width;
    for (int y = 0; y < t->th; y++)
        for (int x = 0; x < t->tw; x++) {
            size_t o = (size_t)(t->y0 + y) * W + (t->x0 + x);
            vs_finish_pixel(acc + 4 * (y * t->tw + x), F->s->background, F->image + 4 * o);
        }
}
