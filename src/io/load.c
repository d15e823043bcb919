/* Volume loading front end: options, format dispatch by extension (or raw
 * when asked), then the steps common to every format (value range, spacing
 * override).  The per-format readers live in load_*.c. */
#include "abi.h"
#include "context.h"
#include "load.h"
#include "load_common.h"

#include <ctype.h>
#include <errno.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

/* Writes at most struct_size bytes, like vs_settings_init_sized. */
void vs_load_options_init_sized(vs_load_options *out, size_t struct_size)
{
    if (!out || struct_size < sizeof out->struct_size) return;
    vs_load_options d, *o = &d;
    memset(o, 0, sizeof *o);
    o->struct_size = struct_size;
    o->type = VS_U8;
    o->endian = VS_ENDIAN_LITTLE;
    for (int a = 0; a < 3; a++) o->spacing[a] = 1.0;
    memcpy(out, o, struct_size < sizeof *o ? struct_size : sizeof *o);
}

/* Parses "..._64x64x93_i16le..." from a file name, so the named raw files
 * load without options.  Takes the last match in the base name. */
static int parse_name_dims(const char *path, int dims[3], vs_type *type, vs_endian *endian)
{
    const char *base = strrchr(path, '/');
    base = base ? base + 1 : path;
    int found = 0;
    for (const char *p = base; *p; p++) {
        if (!isdigit((unsigned char)*p) || (p > base && isdigit((unsigned char)p[-1]))) continue;
        long v[3];
        const char *q = p;
        int ok = 1;
        for (int a = 0; a < 3 && ok; a++) {
            char *end;
            if (!isdigit((unsigned char)*q)) { ok = 0; break; }
            errno = 0;
            v[a] = strtol(q, &end, 10);
            if (errno || v[a] < 1 || v[a] > VS_MAX_DIM) ok = 0;
            q = end;
            if (a < 2) {
                if (*q != 'x') ok = 0;
                else q++;
            }
        }
        if (!ok || *q != '_') continue;
        q++;
        static const struct { const char *name; vs_type t; } types[] = {
            {"u8", VS_U8}, {"i16", VS_I16}, {"u16", VS_U16}, {"f32", VS_F32}};
        int ti = -1;
        for (int k = 0; k < 4; k++)
            if (strncmp(q, types[k].name, strlen(types[k].name)) == 0) {
                ti = k;
                q += strlen(types[k].name);
                break;
            }
        if (ti < 0) continue;
        vs_endian e = VS_ENDIAN_LITTLE;
        if (strncmp(q, "le", 2) == 0) q += 2;
        else if (strncmp(q, "be", 2) == 0) {
            e = VS_ENDIAN_BIG;
            q += 2;
        }
        if (*q != '\0' && *q != '_' && *q != '.') continue;
        for (int a = 0; a < 3; a++) dims[a] = (int)v[a];
        *type = types[ti].t;
        *endian = e;
        found = 1;
    }
    return found;
}

/* The name ends with one of the n suffixes (any case). */
static int ends_with_any(const char *path, const char *const *ext, size_t n)
{
    for (size_t i = 0; i < n; i++)
        if (vs_load_ends_with(path, ext[i])) return 1;
    return 0;
}

static int is_nifti_name(const char *path)
{
    static const char *const ext[] = {".nii", ".nii.gz", ".hdr", ".img", ".hdr.gz", ".img.gz"};
    return ends_with_any(path, ext, sizeof ext / sizeof ext[0]);
}

static int is_raw_name(const char *path)
{
    static const char *const ext[] = {".raw", ".raw.gz", ".bin", ".bin.gz", ".vol", ".vol.gz"};
    return ends_with_any(path, ext, sizeof ext / sizeof ext[0]);
}

static vs_status dispatch(vs_context *ctx, const char *path, const vs_load_options *opt,
                          vs_volume **out)
{
    struct stat st;
    if (stat(path, &st) != 0)
        return vs_set_error(ctx, VS_ERR_IO, "%s: cannot open: %s", path, strerror(errno));
    if (S_ISDIR(st.st_mode))
        return vs_dicom_folder(path) ? vs_load_dicom(ctx, path, opt->series, out) : vs_load_folder(ctx, path, out);
    if (opt->raw) return vs_load_raw(ctx, path, opt->dims, opt->type, opt->endian, NULL, out);

    if (is_nifti_name(path)) return vs_load_nifti(ctx, path, NULL, out);
    if (vs_load_ends_with(path, ".nrrd") || vs_load_ends_with(path, ".nhdr"))
        return vs_load_nrrd(ctx, path, out);
    if (vs_load_ends_with(path, ".den")) return vs_load_den(ctx, path, out);
    if (vs_load_ends_with(path, ".mha") || vs_load_ends_with(path, ".mhd"))
        return vs_load_metaimage(ctx, path, out);
    if (vs_load_ends_with(path, ".dcm")) return vs_load_dicom(ctx, path, opt->series, out);
    if (vs_load_ends_with(path, ".tar")) return vs_load_tar(ctx, path, out);
    if (vs_load_ends_with(path, ".tif") || vs_load_ends_with(path, ".tiff") ||
        vs_load_ends_with(path, ".png"))
        return vs_load_image_pages(ctx, path, out);
    if (is_raw_name(path)) {
        int dims[3];
        vs_type type;
        vs_endian endian;
        if (!parse_name_dims(path, dims, &type, &endian))
            return vs_set_error(ctx, VS_ERR_INVALID_ARGUMENT,
                                "%s: headerless raw file: give its dimensions and voxel type "
                                "(raw options), or name it like NAME_XxYxZ_u8.raw",
                                path);
        return vs_load_raw(ctx, path, dims, type, endian, NULL, out);
    }
    /* scanners name DICOM files anything (or nothing): known by content */
    if (vs_dicom_sniff(path)) return vs_load_dicom(ctx, path, opt->series, out);
    return vs_set_error(ctx, VS_ERR_UNSUPPORTED,
                        "%s: unknown volume format (expected .nii, .nii.gz, .hdr/.img, .nrrd, "
                        ".nhdr, .mha, .mhd, DICOM, .den, .tif, .tiff, .png, .tar, .raw, .raw.gz "
                        "or a folder of slices)",
                        path);
}

/* The formats that can be read in part: raw and NIfTI, whose voxels lie
 * at a known offset in one (maybe gzip'd) file. */
static vs_status dispatch_box(vs_context *ctx, const char *path, const vs_load_options *opt, vs_load_box *box,
                              vs_volume **out)
{
    struct stat st;
    if (stat(path, &st) != 0)
        return vs_set_error(ctx, VS_ERR_IO, "%s: cannot open: %s", path, strerror(errno));
    if (opt->raw) return vs_load_raw(ctx, path, opt->dims, opt->type, opt->endian, box, out);
    if (is_nifti_name(path)) return vs_load_nifti(ctx, path, box, out);
    int dims[3];
    vs_type type;
    vs_endian endian;
    if (!S_ISDIR(st.st_mode) && is_raw_name(path) && parse_name_dims(path, dims, &type, &endian))
        return vs_load_raw(ctx, path, dims, type, endian, box, out);
    return vs_set_error(ctx, VS_ERR_UNSUPPORTED,
                        "%s: only raw and NIfTI files can be read in part (load the whole volume)", path);
}

/* The caller's options in the library's layout (src/abi.c), checked. */
static vs_status import_options(vs_context *ctx, const char *path, const vs_load_options *opt,
                                vs_load_options *full)
{
    vs_load_options_init(full);
    vs_status rc = vs_load_options_import(ctx, opt, full);
    if (rc != VS_OK) return rc;
    if (full->has_spacing)
        for (int a = 0; a < 3; a++)
            if (!(full->spacing[a] > 0.0) || !isfinite(full->spacing[a]) || full->spacing[a] > 1e12 ||
                full->spacing[a] < 1e-12)
                return vs_set_error(ctx, VS_ERR_INVALID_ARGUMENT,
                                    "%s: spacing override %d is %g (must be finite and > 0)", path,
                                    a, full->spacing[a]);
    return VS_OK;
}

/* What every read ends with: the spacing override, the value range. */
static void finish(const vs_load_options *opt, vs_volume *v)
{
    if (opt->has_spacing)
        for (int a = 0; a < 3; a++) { /* the transform keeps its directions */
            for (int r = 0; r < 3; r++) v->affine[r][a] *= opt->spacing[a] / v->spacing[a];
            v->spacing[a] = opt->spacing[a];
        }
    vs_volume_update_range(v);
}

vs_status vs_volume_file_dims(vs_context *ctx, const char *path, const vs_load_options *opt, int dims[3])
{
    if (!path || !dims) return vs_set_error(ctx, VS_ERR_INVALID_ARGUMENT, "file dims: NULL argument");
    vs_load_options full;
    vs_status rc = import_options(ctx, path, opt, &full);
    if (rc != VS_OK) return rc;
    vs_load_box box;
    memset(&box, 0, sizeof box);
    box.dims_only = 1;
    vs_volume *v = NULL;
    rc = dispatch_box(ctx, path, &full, &box, &v);
    vs_volume_release(v);
    if (rc == VS_OK) memcpy(dims, box.dims, sizeof box.dims);
    return rc;
}

vs_status vs_volume_load_box(vs_context *ctx, const char *path, const vs_load_options *opt, const int lo[3],
                             const int hi[3], vs_volume **out)
{
    if (out) *out = NULL;
    if (!path || !lo || !hi || !out) return vs_set_error(ctx, VS_ERR_INVALID_ARGUMENT, "load box: NULL argument");
    vs_load_options full;
    vs_status rc = import_options(ctx, path, opt, &full);
    if (rc != VS_OK) return rc;
    vs_load_box box;
    memset(&box, 0, sizeof box);
    memcpy(box.lo, lo, sizeof box.lo);
    memcpy(box.hi, hi, sizeof box.hi);
    vs_volume *v = NULL;
    rc = dispatch_box(ctx, path, &full, &box, &v);
    if (rc != VS_OK) {
        vs_volume_release(v);
        return rc;
    }
    finish(&full, v);
    /* the box lies where it lies in the file: its first voxel's place */
    if (v->has_orientation)
        for (int r = 0; r < 3; r++)
            for (int a = 0; a < 3; a++) v->affine[r][3] += v->affine[r][a] * lo[a];
    *out = v;
    return VS_OK;
}

vs_status vs_volume_load(vs_context *ctx, const char *path, const vs_load_options *opt,
                         vs_volume **out)
{
    if (out) *out = NULL;
    if (!path || !out) return vs_set_error(ctx, VS_ERR_INVALID_ARGUMENT, "load: NULL argument");
    if (!*path) return vs_set_error(ctx, VS_ERR_INVALID_ARGUMENT, "load: empty file name");
    vs_load_options full;
    vs_status rc = import_options(ctx, path, opt, &full);
    if (rc != VS_OK) return rc;
    vs_volume *v = NULL;
    vs_status st = dispatch(ctx, path, &full, &v);
    if (st != VS_OK) {
        vs_volume_release(v);
        return st;
    }
    finish(&full, v);
    *out = v;
    return VS_OK;
}
