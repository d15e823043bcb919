/* Multi-frame image files (animated GIF, multi-page TIFF) through the
 * OpenImageIO adapter: vs_image_write_frames. */
#include "context.h"
#include "oiio_adapter.h"

#include <stdlib.h>
#include <string.h>

vs_status vs_image_write_frames(vs_context *ctx, const char *path, const vs_image *frames, int count, double fps)
{
    if (!path || !*path) return vs_set_error(ctx, VS_ERR_INVALID_ARGUMENT, "image write: no file name");
    if (!frames || count < 1) return vs_set_error(ctx, VS_ERR_INVALID_ARGUMENT, "%s: no frames", path);
    if (!(fps > 0.0 && fps <= 1000.0))
        return vs_set_error(ctx, VS_ERR_INVALID_ARGUMENT, "%s: frames per second %g outside (0, 1000]", path, fps);
    int w = frames[0].width, h = frames[0].height;
    if (w < 1 || h < 1 || w > VS_MAX_IMAGE_DIM || h > VS_MAX_IMAGE_DIM)
        return vs_set_error(ctx, VS_ERR_INVALID_ARGUMENT, "%s: invalid image size %dx%d", path, w, h);
    for (int i = 0; i < count; i++) {
        if (!frames[i].rgba) return vs_set_error(ctx, VS_ERR_INVALID_ARGUMENT, "%s: frame %d has no data", path, i);
        if (frames[i].width != w || frames[i].height != h)
            return vs_set_error(ctx, VS_ERR_INVALID_ARGUMENT, "%s: frame %d is %dx%d, frame 0 %dx%d", path, i,
                                frames[i].width, frames[i].height, w, h);
    }
    const vs_oiio_api *io = vs_oiio(ctx);
    if (!io) return VS_ERR_IO;
    const float **px = malloc(sizeof *px * (size_t)count);
    if (!px) return vs_set_error(ctx, VS_ERR_OUT_OF_MEMORY, "%s: out of memory", path);
    for (int i = 0; i < count; i++) px[i] = frames[i].rgba;
    char err[480];
    vs_status st = io->write_frames(path, w, h, count, px, fps, err, sizeof err);
    free(px);
    if (st != VS_OK) return vs_set_error(ctx, st, "%s", err);
    return VS_OK;
}
