/* Context lifetime, settings defaults and names. */
#include "context.h"
#include "shade_lut.h"
#include "normal_code.h"
#include "pool.h"
#include "preintegrate.h"
#include "lod.h"
#include "resample.h"
#include "relevant.h"

#include <dlfcn.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>

vs_status vs_context_create(vs_context **out)
{
    if (!out) return VS_ERR_INVALID_ARGUMENT;
    vs_context *c = calloc(1, sizeof *c);
    if (!c) return VS_ERR_OUT_OF_MEMORY;
    *out = c;
    return VS_OK;
}

void vs_context_release(vs_context *ctx)
{
    if (!ctx) return;
    vs_pool_destroy(ctx->pool);
    vs_relevant_cache_free(ctx->relevant);
    vs_lod_cache_free(ctx->lod);
    vs_resample_cache_free(ctx->resample);
    if (ctx->shade_lut) vs_shade_lut_free(ctx->shade_lut);
    free(ctx->shade_lut);
    vs_normal_table_free(ctx->normal_table);
    free(ctx->normal_table);
    for (int i = 0; ctx->normal_codes && i < VS_NORMAL_CODES_KEEP; i++) vs_normal_codes_free(&ctx->normal_codes[i]);
    free(ctx->normal_codes);
    for (int i = 0; i < VS_PREINT_KEEP; i++) vs_preint_free(ctx->preint[i]);
    vs_tile_scratch_release(ctx->scratch, ctx->nscratch);
    if (ctx->oiio_handle) dlclose(ctx->oiio_handle); /* loaded RTLD_NODELETE: OpenImageIO's threads stay valid */
    if (ctx->dicom_handle) dlclose(ctx->dicom_handle);
    free(ctx);
}

const char *vs_version(void) { return VS_VERSION_STRING; }

/* The defaults are built in a full struct and only the caller's
 * struct_size bytes of it copied, so an older, shorter layout gets nothing
 * written past its end (src/abi.c, docs/ABI.md). */
void vs_settings_init_sized(vs_settings *out, size_t struct_size, size_t stats_size)
{
    if (!out || struct_size < sizeof out->struct_size) return;
    vs_settings d, *s = &d;
    memset(s, 0, sizeof *s);
    s->struct_size = struct_size;
    s->stats_size = stats_size;
    s->pipeline = VS_PIPELINE_POST_CD;
    s->width = 512;
    s->height = 512;
    s->zoom = 0.8;
    s->slab = 1.0;
    s->kernel_radius = 2.0;
    s->footprint_resolution = 256;
    s->depth_resolution = 256;
    s->seam = -1;
    s->iso_hi = INFINITY;
    s->ramp = -1.0;
    s->iso_opacity = 1.0f;
    s->material[0] = s->material[1] = s->material[2] = 1.0f;
    s->headlight = 1;
    s->light_dir[2] = 1.0;
    s->ambient = 0.2;
    s->diffuse = 0.6;
    s->specular = 0.2;
    s->shininess = 20.0;
    s->occlusion = 1;
    s->preintegration = -1;
    s->lod_pixels = 1.0;
    s->gs_normalize = 1;
    s->resample = -1;
    s->occlusion_threshold = 0.995;
    s->tile_counters = 1;
    s->tile_size = 64;
    s->exact_normals = 0;
    s->normal_lut_size = 256;
    s->threads = 0;
    s->isa = VS_ISA_AUTO;
    s->pin = 1;
    s->ray_step = 0.1;
    s->ray_trilinear = 0;
    s->ray_analytic = 1;
    s->view = VS_VIEW_AUTO;
    s->up[2] = 1.0;
    memcpy(out, s, struct_size < sizeof *s ? struct_size : sizeof *s);
}

static const char *const pipeline_names[] = {"pre", "post-cd", "post-gs", "post-alpha", "raycast"};

const char *vs_pipeline_name(vs_pipeline p)
{
    if ((int)p < 0 || (int)p > VS_PIPELINE_RAYCAST) return "unknown";
    return pipeline_names[p];
}

vs_status vs_pipeline_parse(const char *name, vs_pipeline *out)
{
    if (!name || !out) return VS_ERR_INVALID_ARGUMENT;
    for (int i = 0; i <= VS_PIPELINE_RAYCAST; i++)
        if (!strcmp(name, pipeline_names[i])) {
            *out = (vs_pipeline)i;
            return VS_OK;
        }
    return VS_ERR_INVALID_ARGUMENT;
}

static const char *const isa_names[] = {"auto", "scalar", "sse4", "avx2", "avx512"};

const char *vs_isa_name(vs_isa isa)
{
    if ((int)isa < 0 || (int)isa > VS_ISA_AVX512) return "unknown";
    return isa_names[isa];
}

vs_status vs_isa_parse(const char *name, vs_isa *out)
{
    if (!name || !out) return VS_ERR_INVALID_ARGUMENT;
    for (int i = 0; i <= VS_ISA_AVX512; i++)
        if (!strcmp(name, isa_names[i])) {
            *out = (vs_isa)i;
            return VS_OK;
        }
    return VS_ERR_INVALID_ARGUMENT;
}

/* VS_VIEW_ANTERIOR.. in enum order */
static const char *const view_names[] = {"anterior", "posterior", "left", "right", "superior", "inferior"};

vs_status vs_view_parse(const char *name, vs_view *out)
{
    if (!name || !out) return VS_ERR_INVALID_ARGUMENT;
    for (int i = 0; i < (int)(sizeof view_names / sizeof *view_names); i++)
        if (!strcasecmp(name, view_names[i])) {
            *out = (vs_view)(VS_VIEW_ANTERIOR + i);
            return VS_OK;
        }
    return VS_ERR_INVALID_ARGUMENT;
}

void vs_image_free(vs_image *img)
{
    if (!img) return;
    free(img->rgba);
    img->rgba = NULL;
    img->width = img->height = 0;
}
