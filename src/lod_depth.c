/* Levels of detail by depth (lod_depth.h): the bands of a perspective
 * view, the background under their picture, their statistics summed. */
#include "lod_depth.h"
#include "finish.h"

#include <math.h>

/* The level the image's scale at depth z (view units) allows. */
static int level_at(const struct vs_volume *vol, const vs_settings *s, const vs_camera *cam, double z)
{
    return vs_lod_choose_at(vol, s, cam, vs_camera_scale(cam, z > cam->near_z ? z : cam->near_z));
}

int vs_lod_bands(const struct vs_volume *vol, const vs_settings *s, const vs_camera *cam,
                 vs_lod_band band[VS_LOD_MAX + 1])
{
    if (!cam->persp) {
        band[0] = (vs_lod_band){vs_lod_choose(vol, s, cam), -INFINITY, INFINITY};
        return 1;
    }
    double zn = INFINITY, zf = -INFINITY;
    for (int c = 0; c < 8; c++) {
        const double idx[3] = {c & 1 ? vol->dims[0] - 1 : 0, c & 2 ? vol->dims[1] - 1 : 0,
                               c & 4 ? vol->dims[2] - 1 : 0};
        double v[3];
        vs_camera_index_to_view0(cam, idx, v);
        if (v[2] < zn) zn = v[2];
        if (v[2] > zf) zf = v[2];
    }
    if (zn < cam->near_z) zn = cam->near_z;
    /* the nearest corner's level (vs_lod_choose's), then coarser ones */
    band[0] = (vs_lod_band){level_at(vol, s, cam, zn), -INFINITY, INFINITY};
    int n = 1;
    while (zn < zf && level_at(vol, s, cam, zf) > band[n - 1].level) {
        /* the first depth where a coarser level will do: the level grows
         * with depth, so bisect to a thousandth of a view unit */
        double lo = zn, hi = zf;
        while (hi - lo > 1e-3 * (1.0 + fabs(hi)))
            if (level_at(vol, s, cam, 0.5 * (lo + hi)) > band[n - 1].level)
                hi = 0.5 * (lo + hi);
            else
                lo = 0.5 * (lo + hi);
        const double zmm = hi / cam->z_per_mm;
        band[n - 1].z1 = zmm;
        band[n] = (vs_lod_band){level_at(vol, s, cam, hi), zmm, INFINITY};
        zn = hi;
        n++;
    }
    return n;
}

/* sheet k holds the slab [k, k + 1) * slab */
static int sheet_at(double zmm, double z_per_mm, double slab, int inf)
{
    if (!isfinite(zmm)) return zmm < 0 ? -inf : inf;
    const double k = ceil(zmm * z_per_mm / slab - 1e-6);
    return k < -inf ? -inf : k > inf ? inf : (int)k;
}

void vs_lod_band_sheets(const vs_lod_band *b, double z_per_mm, double slab, int *show0, int *show1)
{
    *show0 = sheet_at(b->z0, z_per_mm, slab, 1 << 30);
    *show1 = sheet_at(b->z1, z_per_mm, slab, 1 << 30);
}

void vs_image_background(float *img, size_t npix, const float bg[4])
{
    for (size_t i = 0; i < npix; i++) {
        float *p = img + 4 * i;
        const float acc[4] = {p[0] * p[3], p[1] * p[3], p[2] * p[3], p[3]};
        vs_finish_pixel(acc, bg, p);
    }
}

void vs_stats_add(vs_stats *sum, const vs_stats *b)
{
    sum->voxels_relevant += b->voxels_relevant;
    sum->voxels_splatted += b->voxels_splatted;
    sum->voxels_culled += b->voxels_culled;
    sum->sheets += b->sheets;
    sum->tiles_total += b->tiles_total;
    sum->tiles_shaded += b->tiles_shaded;
    sum->ms_total += b->ms_total;
    sum->ms_stage.setup += b->ms_stage.setup;
    sum->ms_stage.rasterize += b->ms_stage.rasterize;
    sum->ms_stage.gradient += b->ms_stage.gradient;
    sum->ms_stage.shade += b->ms_stage.shade;
    sum->ms_stage.composite += b->ms_stage.composite;
    sum->ms_relevant += b->ms_relevant;
    sum->pin_warning |= b->pin_warning;
    sum->bricks_culled += b->bricks_culled;
    sum->voxels_projected += b->voxels_projected;
    sum->voxels_tested += b->voxels_tested;
    sum->footprint_floats += b->footprint_floats;
    sum->pixels_classified += b->pixels_classified;
    sum->pixels_shaded += b->pixels_shaded;
    sum->bytes_read.rasterize += b->bytes_read.rasterize;
    sum->bytes_read.gradient += b->bytes_read.gradient;
    sum->bytes_read.shade += b->bytes_read.shade;
    sum->bytes_read.composite += b->bytes_read.composite;
    sum->bytes_written.rasterize += b->bytes_written.rasterize;
    sum->bytes_written.gradient += b->bytes_written.gradient;
    sum->bytes_written.shade += b->bytes_written.shade;
    sum->bytes_written.composite += b->bytes_written.composite;
}
