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

static int is_raw_name(const char *path)
{
    static const char *const ext[] = {".raw", ".raw.gz", ".bin", ".bin.gz", ".vol", ".vol.gz"};
    for (size_t i = 0; i < sizeof ext / sizeof ext[0]; i++)
        if (vs_load_ends_with(path, ext[i])) return 1;
    return 0;
}

static vs_status dispatch(vs_context *ctx, const char *path, const vs_load_options *opt,
                          vs_volume **out)
{
    struct stat st;
    if (stat(path, &st) != 0)
        return vs_set_error(ctx, VS_ERR_IO, "%s: cannot open: %s", path, strerror(errno));
    if (S_ISDIR(st.st_mode))
        return vs_dicom_folder(path) ? vs_load_dicom(ctx, path, opt->series, out) : vs_load_folder(ctx, path, out);
    if (opt->raw) return vs_load_raw(ctx, path, opt->dims, opt->type, opt->endian, out);

    static const char *const nifti[] = {".nii", ".nii.gz", ".hdr", ".img", ".hdr.gz", ".img.gz"};
    for (size_t i = 0; i < sizeof nifti / sizeof nifti[0]; i++)
        if (vs_load_ends_with(path, nifti[i])) return vs_load_nifti(ctx, path, out);
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
        return vs_load_raw(ctx, path, dims, type, endian, out);
    }
    /* scanners name DICOM files anything (or nothing): known by content */
    if (vs_dicom_sniff(path)) return vs_load_dicom(ctx, path, opt->series, out);
    return vs_set_error(ctx, VS_ERR_UNSUPPORTED,
                        "%s: unknown volume format (expected .nii, .nii.gz, .hdr/.img, .nrrd, "
                        ".nhdr, .mha, .mhd, DICOM, .den, .tif, .tiff, .png, .tar, .raw, .raw.gz "
                        "or a folder of slices)",
                        path);
}

vs_status vs_volume_load(vs_context *ctx, const char *path, const vs_load_options *opt,
                         vs_volume **out)
{
    if (out) *out = NULL;
    if (!path || !out) return vs_set_error(ctx, VS_ERR_INVALID_ARGUMENT, "load: NULL argument");
    if (!*path) return vs_set_error(ctx, VS_ERR_INVALID_ARGUMENT, "load: empty file name");
    /* the caller's layout into the library's own (src/abi.c) */
    vs_load_options full;
    vs_load_options_init(&full);
    vs_status rc = vs_load_options_import(ctx, opt, &full);
    if (rc != VS_OK) return rc;
    opt = &full;
    if (opt->has_spacing)
        for (int a = 0; a < 3; a++)
            if (!(opt->spacing[a] > 0.0) || !isfinite(opt->spacing[a]) || opt->spacing[a] > 1e12 ||
                opt->spacing[a] < 1e-12)
                return vs_set_error(ctx, VS_ERR_INVALID_ARGUMENT,
                                    "%s: spacing override %d is %g (must be finite and > 0)", path,
                                    a, opt->spacing[a]);
    vs_volume *v = NULL;
    vs_status st = dispatch(ctx, path, opt, &v);
    if (st != VS_OK) {
        vs_volume_release(v);
        return st;
    }
    if (opt->has_spacing)
        for (int a = 0; a < 3; a++) { /* the transform keeps its directions */
            for (int r = 0; r < 3; r++) v->affine[r][a] *= opt->spacing[a] / v->spacing[a];
            v->spacing[a] = opt->spacing[a];
        }
    vs_volume_update_range(v);
    *out = v;
    return VS_OK;
}
