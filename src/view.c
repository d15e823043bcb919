/* The camera as a program sees it: vs_view_in_index (vsplat.h), on top of
 * the settings import and the camera set-up. */
#include "abi.h"
#include "camera.h"
#include "context.h"

#include <math.h>

vs_status vs_view_in_index(vs_context *ctx, const vs_volume *vol, const vs_settings *s, double dir[3], double eye[3])
{
    if (!vol || !s || !dir || !eye) return vs_set_error(ctx, VS_ERR_INVALID_ARGUMENT, "view: NULL argument");
    vs_settings cs;
    vs_status st = vs_settings_import(ctx, s, &cs);
    if (st != VS_OK) return st;
    vs_camera cam;
    if ((st = vs_camera_setup(ctx, vol, &cs, &cam)) != VS_OK) return st;
    /* the eye sits persp_dz view units before the image centre's z = 0 point */
    const double d[3] = {cam.cx - cam.t[0], cam.cy - cam.t[1], -cam.persp_dz - cam.t[2]};
    for (int a = 0; a < 3; a++) {
        dir[a] = cam.Minv[a][2];
        eye[a] = cam.persp ? cam.Minv[a][0] * d[0] + cam.Minv[a][1] * d[1] + cam.Minv[a][2] * d[2] : NAN;
    }
    return VS_OK;
}
