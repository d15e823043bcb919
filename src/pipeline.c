/* The four splatting pipelines as tables of stage functions (tile.h's
 * vs_stages): what differs between them is chosen here once per frame, so
 * the sheet loop and the stages do not branch on the pipeline.
 *   pre         classify and shade voxels, splat colour and opacity
 *   post-cd     splat density; classify, central differences, shade
 *   post-gs     splat density and its gradient (gradient splats)
 *   post-alpha  splat shaded colour and density; classify the density */
#include "activate.h"
#include "rasterize.h"
#include "shade.h"
#include "sheet_classify.h"

#include <stddef.h>

static const vs_stages post_cd[2] = {
    {.ch = 1, .ahead = 1, .weights = vs_weights_density, .raster = vs_raster1,
     .activate = vs_activate_density,
     .classify = vs_classify_post_cd, .shade = vs_shade_post_lut},
    {.ch = 1, .ahead = 1, .weights = vs_weights_density, .raster = vs_raster1,
     .activate = vs_activate_density,
     .classify = vs_classify_post_cd, .shade = vs_shade_post_exact},
};
/* with the four-point stencil across sheets (plain sheets): k - 2 to k + 2 */
static const vs_stages post_cd_z[2] = {
    {.ch = 1, .ahead = 2, .behind = 1, .weights = vs_weights_density, .raster = vs_raster1,
     .activate = vs_activate_density,
     .classify = vs_classify_post_cd, .shade = vs_shade_post_lut},
    {.ch = 1, .ahead = 2, .behind = 1, .weights = vs_weights_density, .raster = vs_raster1,
     .activate = vs_activate_density,
     .classify = vs_classify_post_cd, .shade = vs_shade_post_exact},
};
static const vs_stages post_gs[2] = {
    {.ch = 4, .gradient_splats = 1, .weights = vs_weights_density, .raster = vs_raster_gs,
     .activate = vs_activate_gradient,
     .classify = vs_classify_post_gs, .shade = vs_shade_post_lut},
    {.ch = 4, .gradient_splats = 1, .weights = vs_weights_density, .raster = vs_raster_gs,
     .activate = vs_activate_gradient,
     .classify = vs_classify_post_gs, .shade = vs_shade_post_exact},
};
/* with pre-integration between sheet k and k + 1 (post-gs and post-alpha
 * then keep sheet k + 1 too, post-cd sheet k + 2 for sheet k + 1's central
 * difference); one shading function serves tables and exact normals */
static const vs_stages post_cd_pi = {.ch = 1, .ahead = 2, .weights = vs_weights_density, .raster = vs_raster1,
                                     .activate = vs_activate_density, .classify = vs_classify_post_cd,
                                     .shade = vs_shade_post_preint};
static const vs_stages post_gs_pi = {.ch = 4, .ahead = 1, .gradient_splats = 1, .weights = vs_weights_density,
                                     .raster = vs_raster_gs, .activate = vs_activate_gradient,
                                     .classify = vs_classify_post_gs, .shade = vs_shade_post_preint};
static const vs_stages pre = {.ch = 4, .pre_shaded = 1, .weights = vs_weights_pre, .raster = vs_raster4,
                              .activate = vs_activate_rgba,
                              .classify = vs_classify_pre, .shade = vs_shade_pre};
static const vs_stages post_alpha = {.ch = 4, .pre_shaded = 1, .weights = vs_weights_post_alpha,
                                     .raster = vs_raster4, .activate = vs_activate_rgba, .classify = vs_classify_post_alpha,
                                     .shade = vs_shade_post_alpha};

static const vs_stages post_alpha_pi = {.ch = 4, .ahead = 1, .pre_shaded = 1, .weights = vs_weights_post_alpha,
                                        .raster = vs_raster4, .activate = vs_activate_rgba,
                                        .classify = vs_classify_post_alpha, .shade = vs_shade_post_alpha_preint};

const vs_stages *vs_pipeline_stages(vs_pipeline p, int exact_normals, int preint, int wide_z)
{
    const int e = exact_normals != 0;
    switch (p) {
    case VS_PIPELINE_PRE: return &pre;
    case VS_PIPELINE_POST_CD: return preint ? &post_cd_pi : wide_z ? &post_cd_z[e] : &post_cd[e];
    case VS_PIPELINE_POST_GS: return preint ? &post_gs_pi : &post_gs[e];
    case VS_PIPELINE_POST_ALPHA: return preint ? &post_alpha_pi : &post_alpha;
    default: return NULL; /* the ray caster has no sheets */
    }
}
