/* DICOM series: the files of a folder that look like DICOM are parsed one by
 * one by the GDCM module (src/io/dicom_adapter.h), grouped by
 * SeriesInstanceUID, sorted by position along the slice normal (not by
 * name), checked for even spacing, rescaled, and given their index-to-world
 * transform (DICOM's LPS turned into RAS). */
#include "context.h"
#include "dicom_adapter.h"
#include "dicom_check.h"
#include "dicom_guard.h"
#include "load.h"
#include "load_common.h"

#include <dirent.h>
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#define MAX_FILES 65536

int vs_dicom_sniff(const char *path)
{
    FILE *f = fopen(path, "rb");
    if (!f) return 0;
    unsigned char b[132];
    size_t n = fread(b, 1, sizeof b, f);
    fclose(f);
    if (n == sizeof b && memcmp(b + 128, "DICM", 4) == 0) return 1;
    if (n < 8) return 0;
    /* no preamble (as many scanners wrote them): the data set starts with a
     * little-endian tag of the meta (0002) or identifying (0008) group,
     * followed by an explicit VR (two capitals) or an implicit length */
    unsigned group = b[0] | b[1] << 8u, elem = b[2] | b[3] << 8u;
    if ((group != 0x0002 && group != 0x0008) || elem > 0x0100) return 0;
    int explicit_vr = b[4] >= 'A' && b[4] <= 'Z' && b[5] >= 'A' && b[5] <= 'Z';
    uint32_t len = b[4] | b[5] << 8u | (uint32_t)b[6] << 16u | (uint32_t)b[7] << 24u;
    return explicit_vr || len < 0x10000u;
}

typedef struct slice {
    char *path;
    vs_dicom_header h;
    double key; /* position along the slice normal */
} slice;

typedef struct series {
    const char *uid;
    const char *description;
    const char *modality;
    int count;
} series;

static int by_name(const void *a, const void *b)
{
    return strcmp(*(char *const *)a, *(char *const *)b);
}

static int by_key(const void *a, const void *b)
{
    double x = ((const slice *)a)->key, y = ((const slice *)b)->key;
    return x < y ? -1 : x > y;
}

static const char *base_name(const char *p)
{
    const char *s = strrchr(p, '/');
    return s ? s + 1 : p;
}

/* The regular files of `dir` that look like DICOM, sorted by name. */
static vs_status list_dicom(vs_context *ctx, const char *dir, char ***names, int *count)
{
    *names = NULL;
    *count = 0;
    DIR *d = opendir(dir);
    if (!d) return vs_set_error(ctx, VS_ERR_IO, "%s: cannot open the folder: %s", dir, strerror(errno));
    char **v = NULL;
    int n = 0, cap = 0;
    vs_status st = VS_OK;
    struct dirent *e;
    while ((e = readdir(d))) {
        if (e->d_name[0] == '.') continue;
        size_t len = strlen(dir) + strlen(e->d_name) + 2;
        char *p = malloc(len);
        if (!p) { st = vs_set_error(ctx, VS_ERR_OUT_OF_MEMORY, "%s: out of memory", dir); break; }
        snprintf(p, len, "%s/%s", dir, e->d_name);
        struct stat sb;
        if (stat(p, &sb) != 0 || !S_ISREG(sb.st_mode) || !vs_dicom_sniff(p)) { free(p); continue; }
        if (n == MAX_FILES) {
            free(p);
            st = vs_set_error(ctx, VS_ERR_TOO_LARGE, "%s: more than %d DICOM files in the folder", dir, MAX_FILES);
            break;
        }
        if (n == cap) {
            cap = cap ? 2 * cap : 64;
            char **w = realloc(v, (size_t)cap * sizeof *v);
            if (!w) { free(p); st = vs_set_error(ctx, VS_ERR_OUT_OF_MEMORY, "%s: out of memory", dir); break; }
            v = w;
        }
        v[n++] = p;
    }
    closedir(d);
    if (st != VS_OK) {
        for (int i = 0; i < n; i++) free(v[i]);
        free(v);
        return st;
    }
    if (v) qsort(v, (size_t)n, sizeof *v, by_name);
    *names = v;
    *count = n;
    return VS_OK;
}

int vs_dicom_folder(const char *dir)
{
    DIR *d = opendir(dir);
    if (!d) return 0;
    int found = 0;
    struct dirent *e;
    char p[4096];
    while (!found && (e = readdir(d))) {
        if (e->d_name[0] == '.') continue;
        if (snprintf(p, sizeof p, "%s/%s", dir, e->d_name) >= (int)sizeof p) continue;
        struct stat sb;
        found = stat(p, &sb) == 0 && S_ISREG(sb.st_mode) && vs_dicom_sniff(p);
    }
    closedir(d);
    return found;
}

/* "N series in the folder ...: 1) UID "description" (CT, 10 slices); ...",
 * as many as fit in the error message. */
static vs_status series_error(vs_context *ctx, const char *dir, const series *s, int ns, const char *pick)
{
    char list[sizeof ctx->error];
    size_t used = 0;
    int shown = 0;
    for (int i = 0; i < ns; i++) {
        char one[256];
        snprintf(one, sizeof one, "%s%d) %s \"%s\" (%s%s%d slice%s)", i ? "; " : "", i + 1,
                 s[i].uid[0] ? s[i].uid : "(no UID)", s[i].description, s[i].modality,
                 s[i].modality[0] ? ", " : "", s[i].count, s[i].count == 1 ? "" : "s");
        if (used + strlen(one) + 40 >= sizeof list - 200) break;
        memcpy(list + used, one, strlen(one) + 1);
        used += strlen(one);
        shown++;
    }
    if (shown < ns) snprintf(list + used, sizeof list - used, "; and %d more", ns - shown);
    if (pick)
        return vs_set_error(ctx, VS_ERR_INVALID_ARGUMENT, "%s: no series %s among the %d in the folder: %s",
                            dir, pick, ns, list);
    return vs_set_error(ctx, VS_ERR_INVALID_ARGUMENT,
                        "%s: %d DICOM series in the folder; pick one by UID or number (--series): %s", dir,
                        ns, list);
}

static double dot3(const double a[3], const double b[3]) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }

/* Every slice the same size, sample layout and orientation; positions
 * present (more than one slice); returns the slice normal. */
static vs_status check_slices(vs_context *ctx, const slice *s, int n, double normal[3])
{
    const vs_dicom_header *a = &s[0].h;
    for (int i = 0; i < n; i++) {
        const vs_dicom_header *h = &s[i].h;
        const char *p = s[i].path;
        if (h->frames != 1)
            return vs_set_error(ctx, VS_ERR_UNSUPPORTED,
                                "%s: a multi-frame DICOM file (%d frames); only series of single-frame "
                                "files are read",
                                p, h->frames);
        if (h->samples != 1)
            return vs_set_error(ctx, VS_ERR_UNSUPPORTED,
                                "%s: %d samples per pixel (%s): colour images are not volumes", p, h->samples,
                                h->photometric);
        if (h->rows != a->rows || h->cols != a->cols)
            return vs_set_error(ctx, VS_ERR_FORMAT, "%s: %dx%d pixels, but %s has %dx%d: not one volume", p,
                                h->cols, h->rows, base_name(s[0].path), a->cols, a->rows);
        /* no image codec packs more than 10000:1; refuse absurd sizes before
         * allocating for them */
        struct stat sb;
        uint64_t need = (uint64_t)h->rows * (uint64_t)h->cols * (uint64_t)(h->bits_allocated > 8 ? h->bits_allocated / 8 : 1);
        if (stat(p, &sb) == 0 && need > (uint64_t)sb.st_size * 10000u + (1u << 20))
            return vs_set_error(ctx, VS_ERR_FORMAT, "%s: %dx%d pixels cannot be stored in a file of %lld bytes", p,
                                h->cols, h->rows, (long long)sb.st_size);
        if (h->has_pixel_spacing && !(h->pixel_spacing[0] >= 1e-6 && h->pixel_spacing[0] <= 1e6 &&
                                      h->pixel_spacing[1] >= 1e-6 && h->pixel_spacing[1] <= 1e6))
            return vs_set_error(ctx, VS_ERR_FORMAT, "%s: PixelSpacing %g\\%g is not a plausible size in mm", p,
                                h->pixel_spacing[0], h->pixel_spacing[1]);
        if (h->bits_allocated != a->bits_allocated || h->pixel_representation != a->pixel_representation)
            return vs_set_error(ctx, VS_ERR_FORMAT, "%s: sample type differs from %s's", p,
                                base_name(s[0].path));
        if (n > 1 && !h->has_position)
            return vs_set_error(ctx, VS_ERR_FORMAT,
                                "%s: no ImagePositionPatient (0020,0032): cannot place the slice in the series",
                                p);
        if (n > 1 && !h->has_orientation)
            return vs_set_error(ctx, VS_ERR_FORMAT,
                                "%s: no ImageOrientationPatient (0020,0037): cannot order the slices", p);
        if (h->has_orientation)
            for (int k = 0; k < 6; k++)
                if (!a->has_orientation || fabs(h->orientation[k] - a->orientation[k]) > 1e-4)
                    return vs_set_error(ctx, VS_ERR_FORMAT, "%s: slice orientation differs from %s's", p,
                                        base_name(s[0].path));
    }
    const double *r = a->orientation, *c = a->orientation + 3;
    if (!a->has_orientation) {
        static const double id[6] = {1, 0, 0, 0, 1, 0};
        r = id;
        c = id + 3;
    }
    normal[0] = r[1] * c[2] - r[2] * c[1];
    normal[1] = r[2] * c[0] - r[0] * c[2];
    normal[2] = r[0] * c[1] - r[1] * c[0];
    double len = sqrt(dot3(normal, normal));
    if (!(len > 0.5) || fabs(dot3(r, r) - 1) > 0.01 || fabs(dot3(c, c) - 1) > 0.01 || fabs(dot3(r, c)) > 0.01)
        return vs_set_error(ctx, VS_ERR_FORMAT,
                            "%s: ImageOrientationPatient %g\\%g\\%g\\%g\\%g\\%g is not two perpendicular unit "
                            "vectors",
                            s[0].path, r[0], r[1], r[2], c[0], c[1], c[2]);
    for (int k = 0; k < 3; k++) normal[k] /= len;
    return VS_OK;
}

/* Sorted by position: even steps along the normal, every slice on the line
 * from the first to the last; *step is the third column of the transform. */
static vs_status check_positions(vs_context *ctx, slice *s, int n, const double normal[3], double step[3])
{
    for (int i = 0; i < n; i++) s[i].key = dot3(s[i].h.position, normal);
    qsort(s, (size_t)n, sizeof *s, by_key);
    double *gap = malloc((size_t)(n - 1) * sizeof *gap);
    if (!gap) return vs_set_error(ctx, VS_ERR_OUT_OF_MEMORY, "%s: out of memory", s[0].path);
    for (int i = 0; i + 1 < n; i++) gap[i] = s[i + 1].key - s[i].key;
    /* the median step, so one missing slice stands out however many there are */
    double *tmp = malloc((size_t)(n - 1) * sizeof *tmp);
    if (!tmp) {
        free(gap);
        return vs_set_error(ctx, VS_ERR_OUT_OF_MEMORY, "%s: out of memory", s[0].path);
    }
    memcpy(tmp, gap, (size_t)(n - 1) * sizeof *tmp);
    for (int i = 1; i < n - 1; i++) /* insertion sort: series are short */
        for (int j = i; j > 0 && tmp[j - 1] > tmp[j]; j--) {
            double t = tmp[j];
            tmp[j] = tmp[j - 1];
            tmp[j - 1] = t;
        }
    double med = tmp[(n - 1) / 2];
    free(tmp);
    vs_status st = VS_OK;
    for (int i = 0; i + 1 < n && st == VS_OK; i++) {
        if (gap[i] < 1e-3)
            st = vs_set_error(ctx, VS_ERR_FORMAT,
                              "%s: %s and %s lie at the same position (%g mm along the normal): two "
                              "acquisitions in one series?",
                              s[i].path, base_name(s[i].path), base_name(s[i + 1].path), s[i].key);
        else if (fabs(gap[i] - med) > 0.01 * med + 1e-3)
            st = vs_set_error(ctx, VS_ERR_FORMAT,
                              "%s: uneven slice spacing: %g mm between most slices but %g mm between %s and %s "
                              "(a missing slice?)",
                              s[i].path, med, gap[i], base_name(s[i].path), base_name(s[i + 1].path));
    }
    free(gap);
    if (st != VS_OK) return st;
    const double *p0 = s[0].h.position, *pn = s[n - 1].h.position;
    for (int k = 0; k < 3; k++) step[k] = (pn[k] - p0[k]) / (n - 1);
    double slen = sqrt(dot3(step, step));
    for (int i = 1; i < n - 1; i++) {
        double d2 = 0;
        for (int k = 0; k < 3; k++) {
            double e = s[i].h.position[k] - (p0[k] + i * step[k]);
            d2 += e * e;
        }
        if (sqrt(d2) > 0.01 * slen + 1e-3)
            return vs_set_error(ctx, VS_ERR_FORMAT,
                                "%s: slice positions are not on one line (%s is %g mm off it)", s[i].path,
                                base_name(s[i].path), sqrt(d2));
    }
    return VS_OK;
}

/* Where decoded slices go: rescaled into the float volume. */
typedef struct sink {
    const slice *s;
    float *dst;
    size_t plane;
} sink;

static void take_slice(void *user, int z, const void *buf, vs_dicom_sample type)
{
    const sink *k = user;
    const vs_dicom_header *h = &k->s[z].h;
    float *o = k->dst + (size_t)z * k->plane;
    for (size_t i = 0; i < k->plane; i++) {
        double v;
        switch (type) {
        case VS_DCM_U8: v = ((const uint8_t *)buf)[i]; break;
        case VS_DCM_I8: v = ((const int8_t *)buf)[i]; break;
        case VS_DCM_U16: v = ((const uint16_t *)buf)[i]; break;
        case VS_DCM_I16: v = ((const int16_t *)buf)[i]; break;
        case VS_DCM_U32: v = ((const uint32_t *)buf)[i]; break;
        default: v = ((const int32_t *)buf)[i]; break;
        }
        o[i] = (float)(v * h->slope + h->intercept);
    }
}

/* Read every slice's pixels, rescaled, into a float volume. */
static vs_status read_voxels(vs_context *ctx, const vs_dicom_api *api, const slice *s, int n, float *dst,
                             int *integral)
{
    const size_t plane = (size_t)s[0].h.rows * (size_t)s[0].h.cols;
    char **paths = malloc((size_t)n * sizeof *paths);
    if (!paths) return vs_set_error(ctx, VS_ERR_OUT_OF_MEMORY, "%s: out of memory", s[0].path);
    *integral = 1;
    for (int z = 0; z < n; z++) {
        paths[z] = s[z].path;
        if (s[z].h.slope != floor(s[z].h.slope) || s[z].h.intercept != floor(s[z].h.intercept)) *integral = 0;
    }
    sink k = {s, dst, plane};
    char err[256] = "";
    int failed = 0;
    vs_status st = vs_dicom_pixels_guarded(api, paths, n, s[0].h.rows, s[0].h.cols, plane * 4, take_slice, &k,
                                           &failed, err, sizeof err);
    free(paths);
    if (st != VS_OK) return vs_set_error(ctx, st, "%s: %s", s[failed].path, err);
    return VS_OK;
}

/* The smallest type that holds the rescaled values exactly: u8 for
 * unscaled 8-bit data, i16 when they fit, u16 for unscaled 16-bit data
 * beyond i16, else f32. */
static vs_type pick_type(const float *v, size_t n, int integral, int unscaled, int bits)
{
    float lo = INFINITY, hi = -INFINITY;
    for (size_t i = 0; i < n; i++) {
        if (v[i] < lo) lo = v[i];
        if (v[i] > hi) hi = v[i];
    }
    if (!integral) {
        for (size_t i = 0; i < n; i++)
            if (v[i] != floorf(v[i])) return VS_F32;
    }
    if (unscaled && bits == 8 && lo >= 0 && hi <= 255) return VS_U8;
    if (lo >= -32768 && hi <= 32767) return VS_I16;
    if (unscaled && lo >= 0 && hi <= 65535) return VS_U16;
    return VS_F32;
}

/* The series to read: the one of `only` (a file's UID), the one `pick`
 * names, or the only one. */
static vs_status choose_series(vs_context *ctx, const char *dir, slice *s, int n, const char *only,
                               const char *pick, const char **uid)
{
    series *list = calloc((size_t)n, sizeof *list);
    if (!list) return vs_set_error(ctx, VS_ERR_OUT_OF_MEMORY, "%s: out of memory", dir);
    int ns = 0;
    for (int i = 0; i < n; i++) {
        int k = 0;
        while (k < ns && strcmp(list[k].uid, s[i].h.series_uid)) k++;
        if (k == ns) {
            list[ns].uid = s[i].h.series_uid;
            list[ns].description = s[i].h.description;
            list[ns].modality = s[i].h.modality;
            ns++;
        }
        list[k].count++;
    }
    vs_status st = VS_OK;
    *uid = NULL;
    if (only) *uid = only;
    else if (pick && *pick) {
        char *end;
        long idx = strtol(pick, &end, 10);
        if (*end == '\0' && idx >= 1 && idx <= ns) *uid = list[idx - 1].uid;
        for (int k = 0; !*uid && k < ns; k++)
            if (strcmp(list[k].uid, pick) == 0) *uid = list[k].uid;
        if (!*uid) st = series_error(ctx, dir, list, ns, pick);
    } else if (ns == 1)
        *uid = list[0].uid;
    else
        st = series_error(ctx, dir, list, ns, NULL);
    free(list);
    return st;
}

static vs_status build(vs_context *ctx, const vs_dicom_api *api, const char *dir, slice *s, int n,
                       vs_volume **out)
{
    double normal[3] = {0, 0, 1}, step[3] = {0, 0, 0};
    vs_status st = check_slices(ctx, s, n, normal);
    if (st == VS_OK && n > 1) st = check_positions(ctx, s, n, normal, step);
    if (st != VS_OK) return st;
    const vs_dicom_header *h = &s[0].h;
    if (h->rows < 1 || h->cols < 1)
        return vs_set_error(ctx, VS_ERR_FORMAT, "%s: no image size (Rows, Columns)", s[0].path);
    /* column spacing along a row (i), row spacing down a column (j) */
    double di = h->has_pixel_spacing && h->pixel_spacing[1] > 0 ? h->pixel_spacing[1] : 1.0;
    double dj = h->has_pixel_spacing && h->pixel_spacing[0] > 0 ? h->pixel_spacing[0] : 1.0;
    if (n == 1) {
        double t = h->has_thickness && h->thickness > 0 ? h->thickness : 1.0;
        for (int k = 0; k < 3; k++) step[k] = normal[k] * t;
    }
    const int dims[3] = {h->cols, h->rows, n};
    const double spacing[3] = {di, dj, sqrt(dot3(step, step))};
    if (!(spacing[2] >= 1e-6 && spacing[2] <= 1e6))
        return vs_set_error(ctx, VS_ERR_FORMAT, "%s: slice spacing %g mm is not plausible", dir, spacing[2]);
    int64_t d64[3] = {dims[0], dims[1], dims[2]};
    st = vs_load_check_dims(ctx, dir, d64, 4, NULL);
    if (st != VS_OK) return st;
    vs_volume *f = NULL;
    st = vs_load_alloc(ctx, dir, VS_F32, dims, spacing, &f);
    if (st != VS_OK) return st;
    int integral = 1, unscaled = 1;
    st = read_voxels(ctx, api, s, n, f->data, &integral);
    for (int z = 0; z < n; z++)
        if (s[z].h.slope != 1.0 || s[z].h.intercept != 0.0) unscaled = 0;
    const size_t nv = (size_t)dims[0] * dims[1] * dims[2];
    vs_type t = st == VS_OK ? pick_type(f->data, nv, integral, unscaled, h->bits_allocated) : VS_F32;
    vs_volume *v = f;
    if (st == VS_OK && t != VS_F32) {
        st = vs_load_alloc(ctx, dir, t, dims, spacing, &v);
        const float *src = f->data;
        for (size_t i = 0; st == VS_OK && i < nv; i++) {
            if (t == VS_U8) ((uint8_t *)v->data)[i] = (uint8_t)src[i];
            else if (t == VS_I16) ((int16_t *)v->data)[i] = (int16_t)src[i];
            else ((uint16_t *)v->data)[i] = (uint16_t)src[i];
        }
        vs_volume_release(f);
    }
    if (st == VS_OK && (h->has_orientation || h->has_position)) {
        static const double id[6] = {1, 0, 0, 0, 1, 0};
        const double *o = h->has_orientation ? h->orientation : id;
        double m[3][4];
        for (int r = 0; r < 3; r++) {
            m[r][0] = o[r] * di;
            m[r][1] = o[3 + r] * dj;
            m[r][2] = step[r];
            m[r][3] = h->has_position ? h->position[r] : 0.0;
        }
        /* LPS to RAS: x and y change sign */
        for (int r = 0; r < 2; r++)
            for (int c = 0; c < 4; c++) m[r][c] = -m[r][c];
        st = vs_volume_set_affine(ctx, v, m);
        if (st != VS_OK) vs_set_error(ctx, st, "%s: degenerate slice geometry", dir);
    }
    if (st != VS_OK) {
        vs_volume_release(v);
        return st;
    }
    *out = v;
    return VS_OK;
}

vs_status vs_load_dicom(vs_context *ctx, const char *path, const char *pick, vs_volume **out)
{
    struct stat sb;
    if (stat(path, &sb) != 0) return vs_set_error(ctx, VS_ERR_IO, "%s: cannot open: %s", path, strerror(errno));
    const vs_dicom_api *api = vs_dicom(ctx);
    if (!api) return VS_ERR_IO;
    const int is_dir = S_ISDIR(sb.st_mode);
    /* one file names its series; the series is read from its folder */
    char *dir = NULL;
    vs_dicom_header own;
    if (is_dir) dir = strdup(path);
    else {
        char err[256] = "";
        char *one[1] = {(char *)path};
        int failed;
        vs_status st = vs_dicom_check(ctx, path);
        if (st != VS_OK) return st;
        st = vs_dicom_headers_guarded(api, one, 1, &own, &failed, err, sizeof err);
        if (st != VS_OK) return vs_set_error(ctx, st, "%s: %s", path, err);
        const char *slash = strrchr(path, '/');
        dir = slash ? strndup(path, (size_t)(slash - path) + (slash == path)) : strdup(".");
    }
    if (!dir) return vs_set_error(ctx, VS_ERR_OUT_OF_MEMORY, "%s: out of memory", path);
    char **names = NULL;
    int nn = 0;
    vs_status st = list_dicom(ctx, dir, &names, &nn);
    slice *s = st == VS_OK ? calloc((size_t)(nn ? nn : 1), sizeof *s) : NULL;
    if (st == VS_OK && !s) st = vs_set_error(ctx, VS_ERR_OUT_OF_MEMORY, "%s: out of memory", path);
    vs_dicom_header *hs = st == VS_OK ? calloc((size_t)(nn ? nn : 1), sizeof *hs) : NULL;
    if (st == VS_OK && !hs) st = vs_set_error(ctx, VS_ERR_OUT_OF_MEMORY, "%s: out of memory", path);
    for (int i = 0; st == VS_OK && i < nn; i++) st = vs_dicom_check(ctx, names[i]);
    if (st == VS_OK) {
        char err[256] = "";
        int failed = 0;
        vs_status r = vs_dicom_headers_guarded(api, names, nn, hs, &failed, err, sizeof err);
        if (r != VS_OK) st = vs_set_error(ctx, r, "%s: looks like DICOM but cannot be read: %s", names[failed], err);
    }
    int n = 0;
    for (int i = 0; st == VS_OK && i < nn; i++) {
        const vs_dicom_header h = hs[i];
        /* DICOMDIR, reports, presentation states: no image, not a slice */
        if (!h.has_pixel_data && h.rows == 0 && h.cols == 0) continue;
        if (!h.has_pixel_data) {
            st = vs_set_error(ctx, VS_ERR_FORMAT, "%s: no pixel data (a truncated file?)", names[i]);
            break;
        }
        s[n].path = names[i];
        s[n].h = h;
        names[i] = NULL;
        n++;
    }
    if (st == VS_OK && n == 0)
        st = vs_set_error(ctx, VS_ERR_FORMAT, "%s: no DICOM image in %s", path, is_dir ? "the folder" : "its folder");
    const char *chosen = NULL;
    char uid[sizeof own.series_uid] = "";
    if (st == VS_OK) st = choose_series(ctx, dir, s, n, is_dir ? NULL : own.series_uid, pick, &chosen);
    if (st == VS_OK) {
        snprintf(uid, sizeof uid, "%s", chosen); /* the slices move below */
        /* keep the chosen series' slices at the front */
        int m = 0;
        for (int i = 0; i < n; i++)
            if (strcmp(s[i].h.series_uid, uid) == 0) {
                slice t = s[m];
                s[m++] = s[i];
                s[i] = t;
            }
        if (m == 0) st = vs_set_error(ctx, VS_ERR_FORMAT, "%s: its series has no image in the folder", path);
        else st = build(ctx, api, is_dir ? dir : path, s, m, out);
    }
    free(hs);
    for (int i = 0; i < n; i++) free(s[i].path);
    for (int i = 0; i < nn; i++) free(names[i]);
    free(names);
    free(s);
    free(dir);
    return st;
}
