/* The struct_size scheme of vs_settings, vs_stats and vs_load_options
 * (docs/ABI.md).  Fields are only ever appended, so every layout an older
 * header had is this one cut after some field, its size rounded up to the
 * struct's alignment.  Those sizes, from the first field after the header
 * fields up to the full struct, are the layouts this library knows; any
 * other size (0 from a zeroed struct, garbage, a cut through a field, or a
 * newer header's larger struct) is refused. */
#include "abi.h"
#include "context.h"

#include <string.h>

#define END_S(m) VS_FIELD_END(vs_settings, m)
#define END_T(m) VS_FIELD_END(vs_stats, m)
#define END_L(m) VS_FIELD_END(vs_load_options, m)

/* The end of every field, in order: append a line here with each new field
 * (the assertions below catch a forgotten last one).  A new release's first
 * field must start at or after the previous release's sizeof (pad if need
 * be), so that no old program's tail padding is read as a setting. */
static const size_t settings_ends[] = {
    END_S(pipeline), END_S(width), END_S(height), END_S(azimuth), END_S(elevation), END_S(zoom),
    END_S(has_center), END_S(center), END_S(perspective_fov), END_S(slab), END_S(kernel_radius),
    END_S(footprint_resolution), END_S(depth_resolution), END_S(seam), END_S(has_iso), END_S(iso_lo),
    END_S(iso_hi), END_S(ramp), END_S(iso_opacity), END_S(material), END_S(tf), END_S(tf_count),
    END_S(headlight), END_S(light_dir), END_S(ambient), END_S(diffuse), END_S(specular), END_S(shininess),
    END_S(background), END_S(occlusion), END_S(occlusion_threshold), END_S(tile_counters),
    END_S(tile_size), END_S(exact_normals), END_S(normal_lut_size), END_S(threads), END_S(isa), END_S(pin),
    END_S(ray_step), END_S(ray_trilinear), END_S(ray_analytic), END_S(progress), END_S(progress_user), END_S(trace),
    END_S(view), END_S(has_up), END_S(up), END_S(roll), END_S(has_crop), END_S(crop_lo), END_S(crop_hi),
    END_S(preintegration), END_S(lod_pixels), END_S(resample), END_S(cd_stencil),
    END_S(ray_normalize), END_S(gs_normalize)};
static const size_t stats_ends[] = {
    END_T(pipeline), END_T(isa), END_T(threads), END_T(width), END_T(height), END_T(voxels_total),
    END_T(voxels_relevant), END_T(voxels_splatted), END_T(voxels_culled), END_T(sheets),
    END_T(tiles_total), END_T(tiles_shaded), END_T(ms_total), END_T(ms_stage), END_T(ms_relevant),
    END_T(iso_lo), END_T(iso_hi), END_T(ramp), END_T(pin_warning), END_T(bricks_culled),
    END_T(voxels_projected), END_T(voxels_tested), END_T(footprint_floats), END_T(pixels_classified),
    END_T(pixels_shaded), END_T(bytes_read), END_T(bytes_written), END_T(ms_lod),
    END_T(lod_level), END_T(ms_resample), END_T(resampled)};
static const size_t load_ends[] = {END_L(raw),         END_L(dims),    END_L(type),  END_L(endian),
                                   END_L(has_spacing), END_L(spacing), END_L(series)};

#define ROUND(n, T) (((n) + _Alignof(T) - 1) / _Alignof(T) * _Alignof(T))
_Static_assert(ROUND(END_S(gs_normalize), vs_settings) == sizeof(vs_settings),
               "a field appended to vs_settings: add it to settings_ends");
_Static_assert(ROUND(END_T(resampled), vs_stats) == sizeof(vs_stats),
               "a field appended to vs_stats: add it to stats_ends");
_Static_assert(ROUND(END_L(series), vs_load_options) == sizeof(vs_load_options),
               "a field appended to vs_load_options: add it to load_ends");
_Static_assert(offsetof(vs_settings, struct_size) == 0 && offsetof(vs_stats, struct_size) == 0 &&
                   offsetof(vs_load_options, struct_size) == 0,
               "struct_size comes first");

static int layout_known(size_t size, const size_t *ends, size_t n, size_t align)
{
    for (size_t i = 0; i < n; i++)
        if (size == (ends[i] + align - 1) / align * align) return 1;
    return 0;
}

#define KNOWN(size, ends, T) layout_known(size, ends, sizeof ends / sizeof *ends, _Alignof(T))

int vs_stats_layout_known(size_t size) { return KNOWN(size, stats_ends, vs_stats); }

vs_status vs_settings_import(vs_context *ctx, const vs_settings *s, vs_settings *full)
{
    if (!KNOWN(s->struct_size, settings_ends, vs_settings))
        return vs_set_error(ctx, VS_ERR_INVALID_ARGUMENT,
                            "vs_settings of %zu bytes: not a layout this vsplat %s knows; initialise it "
                            "with vs_settings_init()",
                            s->struct_size, VS_VERSION_STRING);
    if (!vs_stats_layout_known(s->stats_size))
        return vs_set_error(ctx, VS_ERR_INVALID_ARGUMENT,
                            "vs_settings.stats_size %zu: not a vs_stats layout this vsplat %s knows; "
                            "initialise the settings with vs_settings_init()",
                            s->stats_size, VS_VERSION_STRING);
    vs_settings_init_sized(full, sizeof *full, sizeof(vs_stats));
    memcpy(full, s, s->struct_size);
    full->struct_size = sizeof *full;
    /* a program built before levels of detail renders as it did: it has
     * no field to turn them off */
    if (s->struct_size < END_S(lod_pixels)) full->lod_pixels = 0.0;
    if (s->struct_size < END_S(resample)) full->resample = 0; /* nor to resample */
    return VS_OK;
}

void vs_stats_export(const vs_stats *full, vs_stats *out, size_t size)
{
    vs_stats t = *full;
    t.struct_size = size;
    memcpy(out, &t, size);
}

vs_status vs_load_options_import(vs_context *ctx, const vs_load_options *o, vs_load_options *full)
{
    if (!o) return VS_OK;
    if (!KNOWN(o->struct_size, load_ends, vs_load_options))
        return vs_set_error(ctx, VS_ERR_INVALID_ARGUMENT,
                            "vs_load_options of %zu bytes: not a layout this vsplat %s knows; initialise "
                            "it with vs_load_options_init()",
                            o->struct_size, VS_VERSION_STRING);
    memcpy(full, o, o->struct_size);
    full->struct_size = sizeof *full;
    return VS_OK;
}
