/* The public structs as this C compiler lays them out, as JSON: the Python
 * package's ctypes copies (tools/python/vsplat/_lib.py) must agree field
 * for field (tests/python/test_vsplat.py). */
#include "vsplat.h"

#include <stddef.h>
#include <stdio.h>

static int first;
#define BEGIN(T)                                                                    \
    printf("%s\"" #T "\": {\"size\": %zu, \"fields\": {", nstruct++ ? ", " : "", sizeof(T)); \
    first = 1
#define F(T, m)                                                                                    \
    printf("%s\"" #m "\": [%zu, %zu]", first ? "" : ", ", offsetof(T, m), sizeof(((T *)0)->m)); \
    first = 0
#define END() printf("}}")

int main(void)
{
    int nstruct = 0;
    printf("{");
    BEGIN(vs_settings);
    F(vs_settings, struct_size); F(vs_settings, stats_size); F(vs_settings, pipeline); F(vs_settings, width);
    F(vs_settings, height); F(vs_settings, azimuth); F(vs_settings, elevation); F(vs_settings, zoom);
    F(vs_settings, has_center); F(vs_settings, center); F(vs_settings, perspective_fov); F(vs_settings, slab);
    F(vs_settings, kernel_radius); F(vs_settings, footprint_resolution); F(vs_settings, depth_resolution);
    F(vs_settings, seam); F(vs_settings, has_iso); F(vs_settings, iso_lo); F(vs_settings, iso_hi);
    F(vs_settings, ramp); F(vs_settings, iso_opacity); F(vs_settings, material); F(vs_settings, tf);
    F(vs_settings, tf_count); F(vs_settings, headlight); F(vs_settings, light_dir); F(vs_settings, ambient);
    F(vs_settings, diffuse); F(vs_settings, specular); F(vs_settings, shininess); F(vs_settings, background);
    F(vs_settings, occlusion); F(vs_settings, occlusion_threshold); F(vs_settings, tile_counters);
    F(vs_settings, tile_size); F(vs_settings, exact_normals); F(vs_settings, normal_lut_size);
    F(vs_settings, threads); F(vs_settings, isa); F(vs_settings, pin); F(vs_settings, ray_step);
    F(vs_settings, ray_trilinear); F(vs_settings, ray_analytic); F(vs_settings, progress);
    F(vs_settings, progress_user); F(vs_settings, trace);
    F(vs_settings, view); F(vs_settings, has_up); F(vs_settings, up); F(vs_settings, roll);
    F(vs_settings, has_crop); F(vs_settings, crop_lo); F(vs_settings, crop_hi); F(vs_settings, preintegration);
    F(vs_settings, lod_pixels); F(vs_settings, resample); F(vs_settings, cd_stencil); F(vs_settings, ray_normalize);
    F(vs_settings, gs_normalize);
    END();
    BEGIN(vs_stats);
    F(vs_stats, struct_size); F(vs_stats, pipeline); F(vs_stats, isa); F(vs_stats, threads); F(vs_stats, width);
    F(vs_stats, height); F(vs_stats, voxels_total); F(vs_stats, voxels_relevant); F(vs_stats, voxels_splatted);
    F(vs_stats, voxels_culled); F(vs_stats, sheets); F(vs_stats, tiles_total); F(vs_stats, tiles_shaded);
    F(vs_stats, ms_total); F(vs_stats, ms_stage); F(vs_stats, ms_relevant); F(vs_stats, iso_lo);
    F(vs_stats, iso_hi); F(vs_stats, ramp); F(vs_stats, pin_warning); F(vs_stats, bricks_culled);
    F(vs_stats, voxels_projected); F(vs_stats, voxels_tested); F(vs_stats, footprint_floats);
    F(vs_stats, pixels_classified); F(vs_stats, pixels_shaded); F(vs_stats, bytes_read);
    F(vs_stats, bytes_written); F(vs_stats, ms_lod); F(vs_stats, lod_level); F(vs_stats, ms_resample);
    F(vs_stats, resampled);
    END();
    BEGIN(vs_load_options);
    F(vs_load_options, struct_size); F(vs_load_options, raw); F(vs_load_options, dims); F(vs_load_options, type);
    F(vs_load_options, endian); F(vs_load_options, has_spacing); F(vs_load_options, spacing);
    F(vs_load_options, series);
    END();
    BEGIN(vs_image);
    F(vs_image, width); F(vs_image, height); F(vs_image, rgba);
    END();
    BEGIN(vs_image_diff);
    F(vs_image_diff, rmse); F(vs_image_diff, psnr); F(vs_image_diff, ssim); F(vs_image_diff, max_abs);
    END();
    BEGIN(vs_tf_point);
    F(vs_tf_point, value); F(vs_tf_point, r); F(vs_tf_point, g); F(vs_tf_point, b); F(vs_tf_point, a);
    END();
    BEGIN(vs_stage_times);
    F(vs_stage_times, setup); F(vs_stage_times, rasterize); F(vs_stage_times, gradient); F(vs_stage_times, shade);
    F(vs_stage_times, composite);
    END();
    BEGIN(vs_stage_bytes);
    F(vs_stage_bytes, rasterize); F(vs_stage_bytes, gradient); F(vs_stage_bytes, shade); F(vs_stage_bytes, composite);
    END();
    printf("}\n");
    return 0;
}
