/* Volume loaders: the real files of MANIFEST.md, small files of every format
 * written here (exact round trips), and hostile input (must fail quickly
 * with a message naming the file, never crash). */
#include "internal.h"
#include "oiio_adapter.h"
#include "testutil.h"

#include <math.h>
#include <stdint.h>
#include <time.h>
#include <unistd.h>
#include <bzlib.h>
#include <zlib.h>

#include <teem/nrrd.h>

static char tmp[1024];

static void path_of(char *buf, size_t cap, const char *name)
{
    snprintf(buf, cap, "%s/%s", tmp, name);
}

static void write_gz(const char *path, const void *data, size_t n)
{
    gzFile g = gzopen(path, "wb");
    if (!g || gzwrite(g, data, (unsigned)n) != (int)n) exit(1);
    gzclose(g);
}

static int ends_with_gz(const char *path)
{
    size_t n = strlen(path);
    return n > 3 && strcmp(path + n - 3, ".gz") == 0;
}

static vs_volume *load(vs_context *ctx, const char *path, const vs_load_options *o)
{
    vs_volume *v = NULL;
    vs_status st = vs_volume_load(ctx, path, o, &v);
    CHECK(st == VS_OK && v, "%s: %s", path, vs_last_error(ctx));
    return st == VS_OK ? v : NULL;
}

static void check_shape(const vs_volume *v, const char *what, int x, int y, int z, vs_type t,
                        double sx, double sy, double sz, double tol)
{
    if (!v) return;
    int d[3];
    double s[3];
    vs_volume_dims(v, d);
    vs_volume_spacing(v, s);
    CHECK(d[0] == x && d[1] == y && d[2] == z, "%s: dims %dx%dx%d, expected %dx%dx%d", what, d[0],
          d[1], d[2], x, y, z);
    CHECK(vs_volume_type(v) == t, "%s: type %s, expected %s", what, vs_type_name(vs_volume_type(v)),
          vs_type_name(t));
    CHECK(fabs(s[0] - sx) <= tol && fabs(s[1] - sy) <= tol && fabs(s[2] - sz) <= tol,
          "%s: spacing %g,%g,%g, expected %g,%g,%g", what, s[0], s[1], s[2], sx, sy, sz);
}

/* ---- the real data ---- */

typedef struct real_file {
    const char *name;
    int x, y, z;
    vs_type type;
    double sx, sy, sz;
    int raw;          /* needs raw options (the table's dims, type, spacing) */
    double lo, hi;    /* value range to check if hi > lo */
} real_file;

static void test_real(vs_context *ctx)
{
    const char *dir = tu_data_dir();
    if (!dir) {
        printf("SKIP: real data not found (set VSPLAT_DATA)\n");
        return;
    }
    static const real_file files[] = {
        {"unc_mrbrain_volpack_brainsmall_128x128x84_u8.den", 128, 128, 84, VS_U8, 1, 1, 1, 0, 0, 0},
        {"colin27_ch2_mri_t1_head_181x217x181_u8.nii.gz", 181, 217, 181, VS_U8, 1, 1, 1, 0, 0, 0},
        {"vtkjs_lidc2_ct_chest_256x256x133_u8.raw.gz", 256, 256, 133, VS_U8, 1.40625, 1.40625, 2.5, 1, 0, 0},
        {"openscivis_csafe_heptane_sim_302x302x302_u8.nii.gz", 302, 302, 302, VS_U8, 1, 1, 1, 0, 0, 0},
        {"invesalius_cranium_ct_head_256x256x108_i16le.raw.gz", 256, 256, 108, VS_I16, 0.9570312,
         0.9570312, 1.5, 1, -1024, 2986},
        {"vtkjs_headsq_head_64x64x93_i16le.raw.gz", 64, 64, 93, VS_I16, 3.2, 3.2, 1.5, 1, 0, 3926},
        {"openscivis_bonsai_ct_256x256x256_u8.nii.gz", 256, 256, 256, VS_U8, 1, 1, 1, 0, 0, 0},
        {"openscivis_engine_ct_256x256x128_u8.nii.gz", 256, 256, 128, VS_U8, 1, 1, 1, 0, 0, 0},
        {"isbi2012_sstem_drosophila_vnc_512x512x30_u8_png.tar", 512, 512, 30, VS_U8, 1, 1, 1, 0, 0, 0},
        {"snt_spotspine_confocal_dendrite_116x157x41_u8.tif", 116, 157, 41, VS_U8, 0.06, 0.06, 0.21, 0, 0, 0},
    };
    char path[8192];
    for (size_t i = 0; i < sizeof files / sizeof files[0]; i++) {
        const real_file *f = &files[i];
        snprintf(path, sizeof path, "%s/%s", dir, f->name);
        vs_load_options o;
        vs_load_options_init(&o);
        if (f->raw) {
            o.raw = 1;
            o.dims[0] = f->x;
            o.dims[1] = f->y;
            o.dims[2] = f->z;
            o.type = f->type;
            o.endian = VS_ENDIAN_LITTLE;
            o.has_spacing = 1;
            o.spacing[0] = f->sx;
            o.spacing[1] = f->sy;
            o.spacing[2] = f->sz;
        }
        double t0 = tu_now_s();
        vs_volume *v = load(ctx, path, &o);
        double dt = tu_now_s() - t0;
        if (!v) continue;
        check_shape(v, f->name, f->x, f->y, f->z, f->type, f->sx, f->sy, f->sz, 1e-4);
        double lo, hi;
        vs_volume_range(v, &lo, &hi);
        CHECK(hi > lo, "%s: constant volume %g..%g", f->name, lo, hi);
        if (f->hi > f->lo)
            CHECK(lo == f->lo && hi == f->hi, "%s: range %g..%g, expected %g..%g", f->name, lo, hi,
                  f->lo, f->hi);
        int d[3];
        double s[3];
        vs_volume_dims(v, d);
        vs_volume_spacing(v, s);
        printf("  %-52s %dx%dx%d %s spacing %g,%g,%g range %g..%g (%.0f ms)\n", f->name, d[0], d[1],
               d[2], vs_type_name(vs_volume_type(v)), s[0], s[1], s[2], lo, hi, dt * 1e3);
        vs_volume_release(v);
    }
    /* The named raw files also load without options (dims/type from the name). */
    snprintf(path, sizeof path, "%s/%s", dir, "vtkjs_headsq_head_64x64x93_i16le.raw.gz");
    vs_volume *v = load(ctx, path, NULL);
    check_shape(v, "headsq by name", 64, 64, 93, VS_I16, 1, 1, 1, 0);
    vs_volume_release(v);
    /* Spacing override applies to any format. */
    snprintf(path, sizeof path, "%s/%s", dir, "unc_mrbrain_volpack_brainsmall_128x128x84_u8.den");
    vs_load_options o;
    vs_load_options_init(&o);
    o.has_spacing = 1;
    o.spacing[2] = 1.3;
    v = load(ctx, path, &o);
    check_shape(v, "den with spacing", 128, 128, 84, VS_U8, 1, 1, 1.3, 0);
    vs_volume_release(v);
}

/* ---- round trips of small files written here ---- */

enum { NX = 7, NY = 5, NZ = 3 };

/* NIfTI-1 single-file writer (348-byte header, vox_offset 352).  The build
 * gives tests no nifticlib include path, so the header is written here from
 * the NIfTI-1 specification; the loader reads it back with nifticlib. */
enum { DT_U8 = 2, DT_I16 = 4, DT_F32 = 16, DT_F64 = 64, DT_U16 = 512 };
static void put(unsigned char *p, const void *v, int n, int big)
{
    for (int i = 0; i < n; i++) p[i] = ((const unsigned char *)v)[big ? n - 1 - i : i];
}

/* big: write header and data big-endian; pair: PATH.hdr + PATH.img ("ni1")
 * where path is given without extension. */
static void write_nifti_ex(const char *path, int big, int pair, int ndim, const int dims[4],
                           int datatype, int bitpix, const float pixdim[3], float slope,
                           float inter, const void *data, size_t nbytes)
{
    unsigned char h[352];
    memset(h, 0, sizeof h);
    int32_t i32 = 348;
    put(h, &i32, 4, big);
    int16_t dim[8] = {(int16_t)ndim, 1, 1, 1, 1, 1, 1, 1};
    for (int a = 0; a < ndim; a++) dim[a + 1] = (int16_t)dims[a];
    for (int a = 0; a < 8; a++) put(h + 40 + 2 * a, &dim[a], 2, big);
    int16_t dt = (int16_t)datatype, bp = (int16_t)bitpix;
    put(h + 70, &dt, 2, big);
    put(h + 72, &bp, 2, big);
    float pd[8] = {1, pixdim[0], pixdim[1], pixdim[2], 1, 1, 1, 1};
    for (int a = 0; a < 8; a++) put(h + 76 + 4 * a, &pd[a], 4, big);
    float vox_offset = pair ? 0 : 352;
    put(h + 108, &vox_offset, 4, big);
    put(h + 112, &slope, 4, big);
    put(h + 116, &inter, 4, big);
    memcpy(h + 344, pair ? "ni1" : "n+1", 4);
    size_t hsize = pair ? 348 : 352;
    int elem = bitpix / 8;
    unsigned char *all = malloc(hsize + nbytes);
    memcpy(all, h, hsize);
    unsigned char *d = pair ? all : all + hsize;
    for (size_t i = 0; i < nbytes; i += (size_t)elem) put(d + i, (const unsigned char *)data + i, elem, big);
    if (pair) {
        char p2[1200];
        snprintf(p2, sizeof p2, "%s.img", path);
        tu_write_file(p2, d, nbytes);
        snprintf(p2, sizeof p2, "%s.hdr", path);
        tu_write_file(p2, h, hsize);
    } else if (ends_with_gz(path)) {
        write_gz(path, all, hsize + nbytes);
    } else {
        tu_write_file(path, all, hsize + nbytes);
    }
    free(all);
}

static void write_nifti(const char *path, int ndim, const int dims[4], int datatype, int bitpix,
                        const float pixdim[3], float slope, float inter, const void *data,
                        size_t nbytes)
{
    write_nifti_ex(path, 0, 0, ndim, dims, datatype, bitpix, pixdim, slope, inter, data, nbytes);
}

static void test_nifti(vs_context *ctx)
{
    char path[1100];
    enum { N = NX * NY * NZ };
    const int dims[4] = {NX, NY, NZ, 2};
    const float sp[3] = {0.5f, -0.75f, 2.0f}; /* negative: spacing uses |pixdim| */
    const float unit[3] = {1, 1, 1};
    int16_t i16[N];
    for (int i = 0; i < N; i++) i16[i] = (int16_t)(i * 37 - 500);
    const char *names[] = {"t_i16.nii", "t_i16.nii.gz"};
    for (int k = 0; k < 2; k++) {
        path_of(path, sizeof path, names[k]);
        write_nifti(path, 3, dims, DT_I16, 16, sp, 0.0f, 0.0f, i16, sizeof i16);
        vs_volume *v = load(ctx, path, NULL);
        check_shape(v, names[k], NX, NY, NZ, VS_I16, 0.5, 0.75, 2.0, 0);
        if (v) CHECK(memcmp(vs_volume_data(v), i16, sizeof i16) == 0, "%s: data differ", names[k]);
        vs_volume_release(v);
    }
    /* scl_slope turns u16 into f32; a 4-D file gives its first volume */
    uint16_t u16[2 * N];
    for (int i = 0; i < 2 * N; i++) u16[i] = (uint16_t)(i * 300);
    path_of(path, sizeof path, "t_u16_scaled_4d.nii");
    write_nifti(path, 4, dims, DT_U16, 16, unit, 2.0f, -1.0f, u16, sizeof u16);
    vs_volume *v = load(ctx, path, NULL);
    check_shape(v, "scaled 4-D nifti", NX, NY, NZ, VS_F32, 1, 1, 1, 0);
    if (v) {
        int bad = 0;
        for (int i = 0; i < N; i++) bad += ((float *)vs_volume_data(v))[i] != (float)(2.0 * u16[i] - 1.0);
        CHECK(bad == 0, "scaled nifti: %d voxels differ", bad);
    }
    vs_volume_release(v);
    /* identity scaling keeps u16 */
    path_of(path, sizeof path, "t_u16.nii");
    write_nifti(path, 3, dims, DT_U16, 16, unit, 1.0f, 0.0f, u16, N * 2);
    v = load(ctx, path, NULL);
    check_shape(v, "u16 nifti", NX, NY, NZ, VS_U16, 1, 1, 1, 0);
    if (v) CHECK(memcmp(vs_volume_data(v), u16, N * 2) == 0, "u16 nifti: data differ");
    vs_volume_release(v);
    /* f64 becomes f32 */
    double f64[N];
    for (int i = 0; i < N; i++) f64[i] = i * 0.25 - 3.0;
    path_of(path, sizeof path, "t_f64.nii.gz");
    write_nifti(path, 3, dims, DT_F64, 64, unit, 0.0f, 0.0f, f64, sizeof f64);
    v = load(ctx, path, NULL);
    check_shape(v, "f64 nifti", NX, NY, NZ, VS_F32, 1, 1, 1, 0);
    if (v) {
        int bad = 0;
        for (int i = 0; i < N; i++) bad += ((float *)vs_volume_data(v))[i] != (float)f64[i];
        CHECK(bad == 0, "f64 nifti: %d voxels differ", bad);
    }
    vs_volume_release(v);
    /* u8 with NaN slope (as in the real files): no scaling */
    uint8_t u8[N];
    for (int i = 0; i < N; i++) u8[i] = (uint8_t)(i * 5);
    path_of(path, sizeof path, "t_u8_nan_slope.nii");
    write_nifti(path, 3, dims, DT_U8, 8, unit, NAN, 0.0f, u8, sizeof u8);
    v = load(ctx, path, NULL);
    check_shape(v, "u8 nifti", NX, NY, NZ, VS_U8, 1, 1, 1, 0);
    if (v) CHECK(memcmp(vs_volume_data(v), u8, sizeof u8) == 0, "u8 nifti: data differ");
    vs_volume_release(v);
    /* big-endian i16 with spacing, and a .hdr/.img pair (loaded by either name) */
    path_of(path, sizeof path, "t_be_i16.nii");
    write_nifti_ex(path, 1, 0, 3, dims, DT_I16, 16, sp, 0.0f, 0.0f, i16, sizeof i16);
    v = load(ctx, path, NULL);
    check_shape(v, "big-endian nifti", NX, NY, NZ, VS_I16, 0.5, 0.75, 2.0, 0);
    if (v) CHECK(memcmp(vs_volume_data(v), i16, sizeof i16) == 0, "big-endian nifti: data differ");
    vs_volume_release(v);
    path_of(path, sizeof path, "t_pair");
    write_nifti_ex(path, 1, 1, 3, dims, DT_I16, 16, sp, 0.0f, 0.0f, i16, sizeof i16);
    for (int k = 0; k < 2; k++) {
        path_of(path, sizeof path, k ? "t_pair.img" : "t_pair.hdr");
        v = load(ctx, path, NULL);
        check_shape(v, path, NX, NY, NZ, VS_I16, 0.5, 0.75, 2.0, 0);
        if (v) CHECK(memcmp(vs_volume_data(v), i16, sizeof i16) == 0, "%s: data differ", path);
        vs_volume_release(v);
    }
    path_of(path, sizeof path, "t_pair.img");
    unlink(path);
    path_of(path, sizeof path, "t_pair.hdr");
    tu_expect_load_fail(ctx, path, NULL, "nifti pair without .img");
    /* zero spacing on a real axis is rejected */
    const float zero[3] = {1, 0, 1};
    path_of(path, sizeof path, "zero_pixdim.nii");
    write_nifti(path, 3, dims, DT_U8, 8, zero, 0.0f, 0.0f, u8, sizeof u8);
    tu_expect_load_fail(ctx, path, NULL, "nifti zero pixdim");
}

static void test_nrrd(vs_context *ctx)
{
    char path[1100];
    static uint16_t u16[NX * NY * NZ];
    static double f64[NX * NY * NZ];
    for (int i = 0; i < NX * NY * NZ; i++) {
        u16[i] = (uint16_t)(i * 611);
        f64[i] = i * 0.5 - 7.0;
    }
    const char *names[] = {"t_u16.nrrd", "t_u16.nhdr"};
    for (int k = 0; k < 2; k++) {
        Nrrd *n = nrrdNew();
        CHECK(nrrdWrap_va(n, u16, nrrdTypeUShort, 3, (size_t)NX, (size_t)NY, (size_t)NZ) == 0, "wrap");
        nrrdAxisInfoSet_va(n, nrrdAxisInfoSpacing, 0.5, 0.75, 2.0);
        path_of(path, sizeof path, names[k]);
        CHECK(nrrdSave(path, n, NULL) == 0, "nrrdSave %s", path);
        nrrdNix(n);
        vs_volume *v = load(ctx, path, NULL);
        check_shape(v, names[k], NX, NY, NZ, VS_U16, 0.5, 0.75, 2.0, 0);
        if (v) CHECK(memcmp(vs_volume_data(v), u16, sizeof u16) == 0, "%s: data differ", names[k]);
        vs_volume_release(v);
    }
    {
        Nrrd *n = nrrdNew();
        CHECK(nrrdWrap_va(n, f64, nrrdTypeDouble, 3, (size_t)NX, (size_t)NY, (size_t)NZ) == 0, "wrap");
        NrrdIoState *nio = nrrdIoStateNew();
        nio->encoding = nrrdEncodingGzip;
        path_of(path, sizeof path, "t_f64_gz.nrrd");
        CHECK(nrrdSave(path, n, nio) == 0, "nrrdSave %s", path);
        nrrdIoStateNix(nio);
        nrrdNix(n);
        vs_volume *v = load(ctx, path, NULL);
        check_shape(v, "f64 nrrd", NX, NY, NZ, VS_F32, 1, 1, 1, 0);
        if (v) {
            int bad = 0;
            for (int i = 0; i < NX * NY * NZ; i++) bad += ((float *)vs_volume_data(v))[i] != (float)f64[i];
            CHECK(bad == 0, "f64 nrrd: %d voxels differ", bad);
        }
        vs_volume_release(v);
    }
}

/* A header, then bzip2 streams of the given pieces of data (several
 * streams: as pbzip2 writes them). */
static void write_bz2(const char *path, const char *header, const void *data, size_t n, int streams)
{
    FILE *f = fopen(path, "wb");
    if (!f || fputs(header, f) < 0) exit(1);
    for (int s = 0; s < streams; s++) {
        const size_t a = n * (size_t)s / (size_t)streams, b = n * (size_t)(s + 1) / (size_t)streams;
        unsigned cap = (unsigned)((b - a) * 101 / 100 + 700);
        char *z = malloc(cap);
        if (!z || BZ2_bzBuffToBuffCompress(z, &cap, (char *)data + a, (unsigned)(b - a), 9, 0, 0) != BZ_OK) exit(1);
        if (fwrite(z, 1, cap, f) != cap) exit(1);
        free(z);
    }
    fclose(f);
}

/* Data in several files (a %d template, a LIST), raw and bzip2, and bzip2
 * data in the forms Teem writes and pbzip2 writes, big-endian, after a
 * byte skip: each loads to the same samples. */
static void test_nrrd_data_files(vs_context *ctx)
{
    char path[1100], hdr[512];
    enum { N = NX * NY * NZ, SLICE = NX * NY };
    static uint16_t u16[N];
    static unsigned char be[2 * N];
    for (int i = 0; i < N; i++) {
        u16[i] = (uint16_t)(i * 977 + 5);
        be[2 * i] = (unsigned char)(u16[i] >> 8);
        be[2 * i + 1] = (unsigned char)(u16[i] & 255);
    }
    struct {
        const char *name;
        int bzip2;
    } forms[] = {{"t_tmpl.nhdr", 0}, {"t_list.nhdr", 0}, {"t_tmpl_bz2.nhdr", 1}, {"t_list_bz2.nhdr", 1}};
    for (int k = 0; k < 4; k++) {
        const int list = k & 1, bz = forms[k].bzip2;
        int n = snprintf(hdr, sizeof hdr,
                         "NRRD0004\ntype: ushort\ndimension: 3\nsizes: %d %d %d\nendian: big\nencoding: %s\n", NX, NY,
                         NZ, bz ? "bzip2" : "raw");
        n += list ? snprintf(hdr + n, sizeof hdr - (size_t)n, "data file: LIST\n")
                  : snprintf(hdr + n, sizeof hdr - (size_t)n, "data file: s%d_%%03d.dat %d 1 -1\n", k, NZ);
        for (int z = 0; z < NZ; z++) { /* the template counts down: file NZ holds slice 0 */
            char name[64];
            snprintf(name, sizeof name, list ? "l%d_%d.dat" : "s%d_%03d.dat", k, list ? z : NZ - z);
            if (list) n += snprintf(hdr + n, sizeof hdr - (size_t)n, "%s\n", name);
            path_of(path, sizeof path, name);
            if (bz) write_bz2(path, "", be + 2 * SLICE * z, 2 * SLICE, 1);
            else tu_write_file(path, be + 2 * SLICE * z, 2 * SLICE);
        }
        path_of(path, sizeof path, forms[k].name);
        tu_write_file(path, hdr, strlen(hdr));
        vs_volume *v = load(ctx, path, NULL);
        check_shape(v, forms[k].name, NX, NY, NZ, VS_U16, 1, 1, 1, 0);
        if (v) CHECK(memcmp(vs_volume_data(v), u16, sizeof u16) == 0, "%s: data differ", forms[k].name);
        vs_volume_release(v);
    }
    /* Teem's own bzip2 writer, attached and detached */
    const char *names[] = {"t_bz2.nrrd", "t_bz2.nhdr"};
    for (int k = 0; k < 2; k++) {
        Nrrd *nr = nrrdNew();
        CHECK(nrrdWrap_va(nr, u16, nrrdTypeUShort, 3, (size_t)NX, (size_t)NY, (size_t)NZ) == 0, "wrap");
        NrrdIoState *nio = nrrdIoStateNew();
        nio->encoding = nrrdEncodingBzip2;
        path_of(path, sizeof path, names[k]);
        CHECK(nrrdSave(path, nr, nio) == 0, "nrrdSave %s", path);
        nrrdIoStateNix(nio);
        nrrdNix(nr);
        vs_volume *v = load(ctx, path, NULL);
        check_shape(v, names[k], NX, NY, NZ, VS_U16, 1, 1, 1, 0);
        if (v) CHECK(memcmp(vs_volume_data(v), u16, sizeof u16) == 0, "%s: data differ", names[k]);
        vs_volume_release(v);
    }
    /* three concatenated streams after a byte skip of 6 decoded bytes,
     * and trailing bytes after the last stream */
    static unsigned char skipped[6 + 2 * N];
    memcpy(skipped, "prefix", 6);
    memcpy(skipped + 6, be, sizeof be);
    snprintf(hdr, sizeof hdr,
             "NRRD0004\ntype: ushort\ndimension: 3\nsizes: %d %d %d\nendian: big\nbyte skip: 6\nencoding: bzip2\n\n", NX,
             NY, NZ);
    path_of(path, sizeof path, "t_pbzip2.nrrd");
    write_bz2(path, hdr, skipped, sizeof skipped, 3);
    FILE *f = fopen(path, "ab");
    if (f) {
        fputs("trailing bytes", f);
        fclose(f);
    }
    vs_volume *v = load(ctx, path, NULL);
    check_shape(v, "t_pbzip2.nrrd", NX, NY, NZ, VS_U16, 1, 1, 1, 0);
    if (v) CHECK(memcmp(vs_volume_data(v), u16, sizeof u16) == 0, "t_pbzip2.nrrd: data differ");
    vs_volume_release(v);
    /* a line skip before compressed data: in the one data file Teem
     * leaves open, and in each file of a template; and a 2-D NRRD, read
     * into the volume in place */
    for (int k = 0; k < 3; k++) {
        const char *name = k == 0 ? "t_lines_gz.nhdr" : k == 1 ? "t_lines_tmpl.nhdr" : "t_2d.nrrd";
        if (k == 0) {
            snprintf(hdr, sizeof hdr,
                     "NRRD0004\ntype: ushort\ndimension: 3\nsizes: %d %d %d\nendian: big\nline skip: 2\n"
                     "encoding: gzip\ndata file: t_lines.dat\n",
                     NX, NY, NZ);
            path_of(path, sizeof path, "t_lines.dat");
            tu_write_file(path, "a line\nanother line\n", 20);
            gzFile g = gzopen(path, "ab");
            if (!g || gzwrite(g, be, sizeof be) != (int)sizeof be) exit(1);
            gzclose(g);
        } else if (k == 1) {
            snprintf(hdr, sizeof hdr,
                     "NRRD0004\ntype: ushort\ndimension: 3\nsizes: %d %d %d\nendian: big\nline skip: 1\n"
                     "encoding: bzip2\ndata file: t_lines_%%d.dat 0 %d 1\n",
                     NX, NY, NZ, NZ - 1);
            for (int z = 0; z < NZ; z++) {
                char name_z[64];
                snprintf(name_z, sizeof name_z, "t_lines_%d.dat", z);
                path_of(path, sizeof path, name_z);
                write_bz2(path, "slice header line\n", be + 2 * SLICE * z, 2 * SLICE, 1);
            }
        } else {
            snprintf(hdr, sizeof hdr, "NRRD0004\ntype: ushort\ndimension: 2\nsizes: %d %d\nendian: big\nencoding: raw\n\n",
                     NX, NY);
        }
        path_of(path, sizeof path, name);
        if (k == 2) {
            f = fopen(path, "wb");
            if (!f || fputs(hdr, f) < 0 || fwrite(be, 1, 2 * SLICE, f) != 2 * SLICE) exit(1);
            fclose(f);
        } else {
            tu_write_file(path, hdr, strlen(hdr));
        }
        vs_volume *w = load(ctx, path, NULL);
        check_shape(w, name, NX, NY, k == 2 ? 1 : NZ, VS_U16, 1, 1, 1, 0);
        if (w)
            CHECK(memcmp(vs_volume_data(w), u16, (k == 2 ? SLICE : N) * sizeof *u16) == 0, "%s: data differ", name);
        vs_volume_release(w);
    }
    /* "byte skip: -N-1": the data end N bytes before the decoded end (here
     * after a prefix, and before a 2-byte trailer), as gzip members, as
     * bzip2 streams, and as plain bytes labelled gzip (zlib's transparent
     * mode, as Teem reads them) */
    static unsigned char framed[6 + 2 * N + 2];
    memcpy(framed, "prefix", 6);
    memcpy(framed + 6, be, sizeof be);
    memcpy(framed + 6 + 2 * N, "tr", 2);
    const char *skip_names[] = {"t_gz_tail.nrrd", "t_bz2_tail.nrrd", "t_gz_plain_tail.nrrd"};
    for (int k = 0; k < 3; k++) {
        snprintf(hdr, sizeof hdr,
                 "NRRD0004\ntype: ushort\ndimension: 3\nsizes: %d %d %d\nendian: big\nbyte skip: -3\nencoding: %s\n\n",
                 NX, NY, NZ, k == 1 ? "bzip2" : "gzip");
        path_of(path, sizeof path, skip_names[k]);
        if (k == 1) {
            write_bz2(path, hdr, framed, sizeof framed, 2);
        } else {
            f = fopen(path, "wb");
            if (!f || fputs(hdr, f) < 0) exit(1);
            if (k == 2 && fwrite(framed, 1, sizeof framed, f) != sizeof framed) exit(1);
            fclose(f);
            for (int m = 0; k == 0 && m < 2; m++) { /* two gzip members */
                gzFile g = gzopen(path, "ab");
                const size_t a = m ? 100 : 0, b = m ? sizeof framed : 100;
                if (!g || gzwrite(g, framed + a, (unsigned)(b - a)) != (int)(b - a)) exit(1);
                gzclose(g);
            }
        }
        v = load(ctx, path, NULL);
        check_shape(v, skip_names[k], NX, NY, NZ, VS_U16, 1, 1, 1, 0);
        if (v) CHECK(memcmp(vs_volume_data(v), u16, sizeof u16) == 0, "%s: data differ", skip_names[k]);
        vs_volume_release(v);
    }
}

static void test_raw_den(vs_context *ctx)
{
    char path[1100];
    enum { N = NX * NY * NZ };
    /* big-endian u16, plain and gzip */
    unsigned char be[2 * N];
    for (int i = 0; i < N; i++) {
        uint16_t x = (uint16_t)(i * 997 + 3);
        be[2 * i] = (unsigned char)(x >> 8);
        be[2 * i + 1] = (unsigned char)(x & 255);
    }
    vs_load_options o;
    vs_load_options_init(&o);
    o.raw = 1;
    o.dims[0] = NX;
    o.dims[1] = NY;
    o.dims[2] = NZ;
    o.type = VS_U16;
    o.endian = VS_ENDIAN_BIG;
    const char *names[] = {"t_be.raw", "t_be.raw.gz"};
    for (int k = 0; k < 2; k++) {
        path_of(path, sizeof path, names[k]);
        if (k == 0) tu_write_file(path, be, sizeof be);
        else write_gz(path, be, sizeof be);
        vs_volume *v = load(ctx, path, &o);
        check_shape(v, names[k], NX, NY, NZ, VS_U16, 1, 1, 1, 0);
        if (v) {
            int bad = 0;
            for (int i = 0; i < N; i++) bad += ((uint16_t *)vs_volume_data(v))[i] != (uint16_t)(i * 997 + 3);
            CHECK(bad == 0, "%s: %d voxels differ", names[k], bad);
        }
        vs_volume_release(v);
    }
    /* f32 little-endian, dims and type from the name */
    float f[N];
    for (int i = 0; i < N; i++) f[i] = (float)i * 0.125f - 1.0f;
    path_of(path, sizeof path, "named_7x5x3_f32le.raw");
    tu_write_file(path, f, sizeof f);
    vs_volume *v = load(ctx, path, NULL);
    check_shape(v, "named f32 raw", NX, NY, NZ, VS_F32, 1, 1, 1, 0);
    if (v) CHECK(memcmp(vs_volume_data(v), f, sizeof f) == 0, "named f32 raw: data differ");
    vs_volume_release(v);

    /* .den */
    unsigned char den[62 + N];
    memset(den, 0, sizeof den);
    den[0] = 1;
    den[50] = NX;
    den[52] = NY;
    den[54] = NZ;
    den[58] = N & 255;
    den[59] = N >> 8;
    for (int i = 0; i < N; i++) den[62 + i] = (unsigned char)(i * 7);
    path_of(path, sizeof path, "t.den");
    tu_write_file(path, den, sizeof den);
    v = load(ctx, path, NULL);
    check_shape(v, "den", NX, NY, NZ, VS_U8, 1, 1, 1, 0);
    if (v) CHECK(memcmp(vs_volume_data(v), den + 62, N) == 0, "den: data differ");
    vs_volume_release(v);
}

/* ---- part of a file (vs_volume_load_box) ---- */

/* The box of `whole` a box read must equal voxel for voxel, with the
 * whole's type and spacing, its transform moved to lo, its own range. */
static void check_box(vs_context *ctx, const char *path, const vs_load_options *o, const vs_volume *whole,
                      const int lo[3], const int hi[3])
{
    vs_volume *b = NULL;
    vs_status st = vs_volume_load_box(ctx, path, o, lo, hi, &b);
    CHECK(st == VS_OK && b, "%s box %d-%d,%d-%d,%d-%d: %s", path, lo[0], hi[0], lo[1], hi[1], lo[2], hi[2],
          vs_last_error(ctx));
    if (!b) return;
    int wd[3], bd[3];
    vs_volume_dims(whole, wd);
    vs_volume_dims(b, bd);
    const size_t elem = vs_type_size(vs_volume_type(whole));
    CHECK(vs_volume_type(b) == vs_volume_type(whole), "%s box: type", path);
    CHECK(bd[0] == hi[0] - lo[0] && bd[1] == hi[1] - lo[1] && bd[2] == hi[2] - lo[2], "%s box: dims %dx%dx%d", path,
          bd[0], bd[1], bd[2]);
    int bad = 0;
    double mn = INFINITY, mx = -INFINITY;
    for (int k = lo[2]; k < hi[2]; k++)
        for (int j = lo[1]; j < hi[1]; j++)
            for (int i = lo[0]; i < hi[0]; i++) {
                const size_t w = ((size_t)k * wd[1] + j) * wd[0] + i;
                const size_t x = ((size_t)(k - lo[2]) * bd[1] + (j - lo[1])) * bd[0] + (i - lo[0]);
                bad += memcmp((const char *)vs_volume_data((vs_volume *)whole) + w * elem,
                              (const char *)vs_volume_data(b) + x * elem, elem) != 0;
                const double v = vs_volume_at(whole, w);
                if (v < mn) mn = v;
                if (v > mx) mx = v;
            }
    CHECK(bad == 0, "%s box %d-%d,%d-%d,%d-%d: %d voxels differ", path, lo[0], hi[0], lo[1], hi[1], lo[2], hi[2],
          bad);
    double blo, bhi;
    vs_volume_range(b, &blo, &bhi);
    CHECK(blo == mn && bhi == mx, "%s box: range %g..%g, the box holds %g..%g", path, blo, bhi, mn, mx);
    double mw[12], mb[12];
    const int ow = vs_volume_affine(whole, mw), ob = vs_volume_affine(b, mb);
    CHECK(ow == ob, "%s box: oriented %d, the whole %d", path, ob, ow);
    for (int r = 0; r < 3; r++) {
        double t = mw[4 * r + 3];
        if (ow)
            for (int a = 0; a < 3; a++) t += mw[4 * r + a] * lo[a];
        CHECK(fabs(mb[4 * r + 3] - t) < 1e-9, "%s box: translation %d is %g, expected %g", path, r, mb[4 * r + 3], t);
        for (int a = 0; a < 3; a++)
            CHECK(mb[4 * r + a] == mw[4 * r + a], "%s box: transform column %d differs", path, a);
    }
    vs_volume_release(b);
}

static void test_box(vs_context *ctx)
{
    enum { BX = 13, BY = 11, BZ = 9, BN = BX * BY * BZ };
    char path[1100];
    int16_t v16[BN];
    for (int i = 0; i < BN; i++) v16[i] = (int16_t)((i * 7919) % 3001 - 1200);
    const int dims[4] = {BX, BY, BZ, 1};
    const float sp[3] = {0.8f, 0.9f, 2.5f};
    /* an oblique sform: the box's translation must move along its columns */
    path_of(path, sizeof path, "box.nii");
    write_nifti(path, 3, dims, DT_I16, 16, sp, 0.0f, 0.0f, v16, sizeof v16);
    {
        FILE *f = fopen(path, "r+b");
        const int16_t code = 1;
        const float srow[12] = {0.0f, 0.9f, 0.0f, -20.0f, -0.8f, 0.0f, 0.0f, 15.0f, 0.0f, 0.0f, 2.5f, 7.0f};
        if (!f || fseek(f, 254, SEEK_SET) || fwrite(&code, 2, 1, f) != 1 || fseek(f, 280, SEEK_SET) ||
            fwrite(srow, 4, 12, f) != 12 || fclose(f))
            exit(1);
    }
    char gzpath[1100], rawpath[1100], rawgz[1100];
    path_of(gzpath, sizeof gzpath, "box.nii.gz");
    {
        FILE *f = fopen(path, "rb");
        unsigned char all[352 + sizeof v16];
        if (!f || fread(all, 1, sizeof all, f) != sizeof all) exit(1);
        fclose(f);
        write_gz(gzpath, all, sizeof all);
    }
    path_of(rawpath, sizeof rawpath, "box_13x11x9_i16le.raw");
    tu_write_file(rawpath, v16, sizeof v16);
    path_of(rawgz, sizeof rawgz, "box_13x11x9_i16le.raw.gz");
    write_gz(rawgz, v16, sizeof v16);
    const int boxes[][6] = {
        {0, 13, 0, 11, 0, 9}, /* all of it               */
        {2, 9, 3, 4, 1, 8},   /* rows                    */
        {0, 13, 2, 7, 3, 9},  /* x spanned: slice runs   */
        {12, 13, 10, 11, 8, 9}, /* the last voxel        */
        {0, 13, 0, 11, 4, 5}, /* one slice               */
    };
    vs_load_options spaced;
    vs_load_options_init(&spaced);
    spaced.has_spacing = 1;
    spaced.spacing[0] = 0.5;
    spaced.spacing[1] = 0.25;
    spaced.spacing[2] = 3.0;
    const char *files[] = {path, gzpath, rawpath, rawgz};
    for (int f = 0; f < 4; f++)
        for (int opt = 0; opt < 2; opt++) {
            const vs_load_options *o = opt ? &spaced : NULL;
            vs_volume *whole = load(ctx, files[f], o);
            if (!whole) continue;
            CHECK(vs_volume_affine(whole, (double[12]){0}) == (f < 2), "%s: oriented", files[f]);
            int fd[3] = {0, 0, 0};
            CHECK(vs_volume_file_dims(ctx, files[f], o, fd) == VS_OK && fd[0] == BX && fd[1] == BY && fd[2] == BZ,
                  "%s: file dims %dx%dx%d: %s", files[f], fd[0], fd[1], fd[2], vs_last_error(ctx));
            for (size_t b = 0; b < sizeof boxes / sizeof boxes[0]; b++) {
                const int lo[3] = {boxes[b][0], boxes[b][2], boxes[b][4]}, hi[3] = {boxes[b][1], boxes[b][3], boxes[b][5]};
                check_box(ctx, files[f], o, whole, lo, hi);
            }
            vs_volume_release(whole);
        }

    /* errors: a box outside or empty; a format read whole; a short file */
    vs_volume *b = NULL;
    const int lo[3] = {0, 0, 0}, out[3] = {BX, BY, BZ + 1}, empty[3] = {BX, 0, BZ};
    CHECK(vs_volume_load_box(ctx, path, NULL, lo, out, &b) == VS_ERR_INVALID_ARGUMENT && !b &&
              strstr(vs_last_error(ctx), "outside"),
          "box past the end: %s", vs_last_error(ctx));
    CHECK(vs_volume_load_box(ctx, rawpath, NULL, lo, empty, &b) == VS_ERR_INVALID_ARGUMENT && !b,
          "empty box: %s", vs_last_error(ctx));
    char nrrd[1100];
    path_of(nrrd, sizeof nrrd, "box.nhdr");
    const char hdr[] = "NRRD0004\ntype: int16\nendian: little\ndimension: 3\nsizes: 13 11 9\nencoding: raw\n"
                       "data file: box_13x11x9_i16le.raw\n";
    tu_write_file(nrrd, hdr, sizeof hdr - 1);
    int fd[3];
    CHECK(vs_volume_file_dims(ctx, nrrd, NULL, fd) == VS_ERR_UNSUPPORTED &&
              strstr(vs_last_error(ctx), "raw and NIfTI"),
          "NRRD in part: %s", vs_last_error(ctx));
    CHECK(vs_volume_load_box(ctx, nrrd, NULL, lo, out, &b) == VS_ERR_UNSUPPORTED && !b, "NRRD box");
    char cut[1100];
    path_of(cut, sizeof cut, "box_cut.nii.gz");
    {
        FILE *f = fopen(path, "rb");
        unsigned char all[352 + sizeof v16 / 2];
        if (!f || fread(all, 1, sizeof all, f) != sizeof all) exit(1);
        fclose(f);
        write_gz(cut, all, sizeof all);
    }
    const int first[3] = {BX, BY, 2}, tail_lo[3] = {0, 0, 6};
    CHECK(vs_volume_load_box(ctx, cut, NULL, lo, first, &b) == VS_OK && b, "cut .nii.gz, its first slices: %s",
          vs_last_error(ctx));
    vs_volume_release(b);
    b = NULL;
    CHECK(vs_volume_load_box(ctx, cut, NULL, tail_lo, dims, &b) == VS_ERR_FORMAT && !b &&
              strstr(vs_last_error(ctx), "truncated"),
          "cut .nii.gz, its last slices: %s", vs_last_error(ctx));

    /* the default iso from the bricks' histograms is the whole volume's */
    vs_volume *whole = load(ctx, rawpath, NULL);
    if (whole) {
        double wlo, whi, hist[VS_HISTOGRAM_BINS] = {0};
        vs_volume_range(whole, &wlo, &whi);
        for (int z = 0; z < BZ; z += 4) {
            const int l[3] = {0, 0, z}, h[3] = {BX, BY, z + 4 < BZ ? z + 4 : BZ};
            vs_volume *part = NULL;
            if (vs_volume_load_box(ctx, rawpath, NULL, l, h, &part) != VS_OK) continue;
            vs_volume_set_range(part, wlo, whi);
            vs_volume_histogram(part, hist);
            vs_volume_release(part);
        }
        const double iso = vs_histogram_iso(hist, wlo, whi), want = vs_volume_default_iso(whole);
        CHECK(iso == want, "iso from the parts' histograms %.17g, the whole volume's %.17g", iso, want);
        /* a declared range narrower than the data must not index past the bins */
        vs_volume_set_range(whole, 0.0, 10.0);
        const double narrow = vs_volume_default_iso(whole);
        CHECK(narrow >= 0.0 && narrow <= 10.0, "narrow range: iso %g", narrow);
        vs_volume_release(whole);
    }
}

/* Minimal ustar writer for the tests (the loader parses these). */
static size_t tar_add(unsigned char *out, const char *name, const unsigned char *data, size_t n)
{
    unsigned char *h = out;
    memset(h, 0, 512);
    snprintf((char *)h, 100, "%s", name);
    snprintf((char *)h + 100, 8, "%07o", 0644);
    snprintf((char *)h + 108, 8, "%07o", 0);
    snprintf((char *)h + 116, 8, "%07o", 0);
    snprintf((char *)h + 124, 12, "%011lo", (unsigned long)n);
    snprintf((char *)h + 136, 12, "%011o", 0);
    h[156] = '0';
    memcpy(h + 257, "ustar", 6);
    memcpy(h + 263, "00", 2);
    memset(h + 148, ' ', 8);
    unsigned sum = 0;
    for (int i = 0; i < 512; i++) sum += h[i];
    snprintf((char *)h + 148, 8, "%06o", sum & 0777777u);
    memcpy(out + 512, data, n);
    size_t padded = (n + 511) / 512 * 512;
    memset(out + 512 + n, 0, padded - n);
    return 512 + padded;
}

static void test_stacks(vs_context *ctx)
{
    char path[1100], err[400];
    const vs_oiio_api *io = vs_oiio(ctx);
    if (!io) {
        CHECK(0, "image I/O module: %s", vs_last_error(ctx));
        return;
    }
    enum { W = 9, H = 6, P = 3 };
    /* 3-page u16 ImageJ-style TIFF */
    uint16_t pages[P * W * H];
    for (int i = 0; i < P * W * H; i++) pages[i] = (uint16_t)(i * 211);
    path_of(path, sizeof path, "t_stack.tif");
    vs_status st = io->write_pages(path, W, H, 1, P, VS_PIX_U16, pages, 4.0, 2.0,
                                       "ImageJ=1.53t\nimages=3\nslices=3\nunit=micron\nspacing=2.5\n",
                                       err, sizeof err);
    CHECK(st == VS_OK, "write tiff: %s", err);
    vs_volume *v = load(ctx, path, NULL);
    check_shape(v, "3-page tiff", W, H, P, VS_U16, 0.25, 0.5, 2.5, 1e-6);
    if (v) CHECK(memcmp(vs_volume_data(v), pages, sizeof pages) == 0, "3-page tiff: data differ");
    vs_volume_release(v);

    /* folder of 8-bit PNGs in natural order: 1, 2, 10 (not 1, 10, 2) */
    uint8_t sl[P][W * H];
    for (int z = 0; z < P; z++)
        for (int i = 0; i < W * H; i++) sl[z][i] = (uint8_t)(z * 80 + i);
    path_of(path, sizeof path, "folder");
    mkdir(path, 0755);
    const char *fnames[P] = {"1.png", "2.png", "10.png"};
    for (int z = 0; z < P; z++) {
        char p[1200];
        snprintf(p, sizeof p, "%s/%s", path, fnames[z]);
        st = io->write_pages(p, W, H, 1, 1, VS_PIX_U8, sl[z], 0, 0, NULL, err, sizeof err);
        CHECK(st == VS_OK, "write png: %s", err);
    }
    {
        char p[1200];
        snprintf(p, sizeof p, "%s/README.txt", path);
        tu_write_file(p, "not a slice", 11);
    }
    v = load(ctx, path, NULL);
    check_shape(v, "png folder", W, H, P, VS_U8, 1, 1, 1, 0);
    if (v) CHECK(memcmp(vs_volume_data(v), sl, sizeof sl) == 0, "png folder: order or data differ");
    vs_volume_release(v);

    /* tar of PNGs: member order is z order ("b" before "a" on purpose) */
    unsigned char *tar = calloc(1, 64 * 1024);
    size_t off = 0;
    const char *members[P] = {"b.png", "a.png", "c.png"};
    for (int z = 0; z < P; z++) {
        char p[1200];
        size_t n;
        snprintf(p, sizeof p, "%s/%s", path, fnames[z]);
        unsigned char *png = tu_read_file(p, &n);
        off += tar_add(tar + off, members[z], png, n);
        free(png);
    }
    off += 1024; /* two zero blocks */
    path_of(path, sizeof path, "t_slices.tar");
    tu_write_file(path, tar, off);
    v = load(ctx, path, NULL);
    check_shape(v, "png tar", W, H, P, VS_U8, 1, 1, 1, 0);
    if (v) CHECK(memcmp(vs_volume_data(v), sl, sizeof sl) == 0, "png tar: order or data differ");
    vs_volume_release(v);

    /* tar with a corrupt header: flip a name byte without fixing the checksum */
    tar[3] ^= 0x55;
    path_of(path, sizeof path, "corrupt_header.tar");
    tu_write_file(path, tar, off);
    tu_expect_load_fail(ctx, path, NULL, "tar corrupt header");
    /* tar cut in the middle of a member */
    tar[3] ^= 0x55;
    path_of(path, sizeof path, "cut_member.tar");
    tu_write_file(path, tar, 700);
    tu_expect_load_fail(ctx, path, NULL, "tar cut after a member");
    path_of(path, sizeof path, "cut_data.tar");
    tu_write_file(path, tar, 530);
    tu_expect_load_fail(ctx, path, NULL, "tar cut in member data");
    path_of(path, sizeof path, "cut_header.tar");
    tu_write_file(path, tar, 300);
    tu_expect_load_fail(ctx, path, NULL, "tar cut in a header");
    free(tar);

    /* RGB slice -> Rec. 709 luminance */
    uint8_t rgb[W * H * 3];
    for (int i = 0; i < W * H; i++) {
        rgb[3 * i] = 200;
        rgb[3 * i + 1] = 100;
        rgb[3 * i + 2] = (uint8_t)i;
    }
    path_of(path, sizeof path, "t_rgb.png");
    st = io->write_pages(path, W, H, 3, 1, VS_PIX_U8, rgb, 0, 0, NULL, err, sizeof err);
    CHECK(st == VS_OK, "write rgb png: %s", err);
    v = load(ctx, path, NULL);
    check_shape(v, "rgb png", W, H, 1, VS_U8, 1, 1, 1, 0);
    if (v) {
        int bad = 0;
        for (int i = 0; i < W * H; i++) {
            double g = 0.2126 * 200 + 0.7152 * 100 + 0.0722 * i;
            bad += ((uint8_t *)vs_volume_data(v))[i] != (uint8_t)floor(g + 0.5);
        }
        CHECK(bad == 0, "rgb png: %d luminance values differ", bad);
    }
    vs_volume_release(v);

    /* slices of different sizes in a folder */
    path_of(path, sizeof path, "mixed");
    mkdir(path, 0755);
    {
        char p[1200];
        snprintf(p, sizeof p, "%s/0.png", path);
        io->write_pages(p, W, H, 1, 1, VS_PIX_U8, sl[0], 0, 0, NULL, err, sizeof err);
        snprintf(p, sizeof p, "%s/1.png", path);
        io->write_pages(p, H, W, 1, 1, VS_PIX_U8, sl[1], 0, 0, NULL, err, sizeof err);
    }
    tu_expect_load_fail(ctx, path, NULL, "folder of mixed sizes");
}

/* ---- hostile input ---- */

static void test_hostile(vs_context *ctx)
{
    char path[1100];
    vs_load_options o;
    vs_load_options_init(&o);
    o.raw = 1;
    o.dims[0] = 10;
    o.dims[1] = 10;
    o.dims[2] = 10;
    o.type = VS_I16;
    unsigned char buf[4096];
    for (size_t i = 0; i < sizeof buf; i++) buf[i] = (unsigned char)(i * 131 + 7);

    path_of(path, sizeof path, "short.raw");
    tu_write_file(path, buf, 1999);
    tu_expect_load_fail(ctx, path, &o, "raw too short");
    CHECK(strstr(vs_last_error(ctx), "truncated") != NULL, "short raw: %s", vs_last_error(ctx));
    path_of(path, sizeof path, "long.raw");
    tu_write_file(path, buf, 2003);
    tu_expect_load_fail(ctx, path, &o, "raw too long");
    CHECK(strstr(vs_last_error(ctx), "3 extra bytes") != NULL, "long raw: %s", vs_last_error(ctx));
    path_of(path, sizeof path, "short.raw.gz");
    write_gz(path, buf, 1000);
    tu_expect_load_fail(ctx, path, &o, "raw.gz too short");
    path_of(path, sizeof path, "long.raw.gz");
    write_gz(path, buf, 2100);
    tu_expect_load_fail(ctx, path, &o, "raw.gz too long");
    CHECK(strstr(vs_last_error(ctx), "100 extra bytes") != NULL, "long raw.gz: %s", vs_last_error(ctx));
    o.dims[0] = 0;
    path_of(path, sizeof path, "zero_dim.raw");
    tu_write_file(path, buf, 10);
    tu_expect_load_fail(ctx, path, &o, "raw zero dimension");
    o.dims[0] = o.dims[1] = o.dims[2] = 16000;
    path_of(path, sizeof path, "huge.raw.gz");
    write_gz(path, buf, 4096);
    tu_expect_load_fail(ctx, path, &o, "raw.gz claiming 16000^3");
    path_of(path, sizeof path, "noopts.raw");
    tu_write_file(path, buf, 1000);
    tu_expect_load_fail(ctx, path, NULL, "raw without options");

    /* .den: truncated, huge, bad version */
    unsigned char den[62 + 100];
    memset(den, 0, sizeof den);
    den[0] = 1;
    den[50] = 10;
    den[52] = 10;
    den[54] = 10;
    den[58] = 1000 & 255;
    den[59] = 1000 >> 8;
    path_of(path, sizeof path, "truncated.den");
    tu_write_file(path, den, sizeof den);
    tu_expect_load_fail(ctx, path, NULL, "den truncated");
    CHECK(strstr(vs_last_error(ctx), "truncated") != NULL, "den: %s", vs_last_error(ctx));
    den[50] = den[52] = den[54] = 60000 & 255;
    den[51] = den[53] = den[55] = 60000 >> 8;
    path_of(path, sizeof path, "huge.den");
    tu_write_file(path, den, sizeof den);
    tu_expect_load_fail(ctx, path, NULL, "den claiming 60000^3");
    path_of(path, sizeof path, "short_header.den");
    tu_write_file(path, den, 30);
    tu_expect_load_fail(ctx, path, NULL, "den short header");

    /* truncated .nii.gz */
    {
        enum { M = 40 * 40 * 40 };
        float *p = malloc(M * sizeof(float));
        for (int i = 0; i < M; i++) p[i] = (float)sin(i * 0.37) * 1000.0f;
        const int d[4] = {40, 40, 40, 1};
        const float unit[3] = {1, 1, 1};
        path_of(path, sizeof path, "full.nii.gz");
        write_nifti(path, 3, d, DT_F32, 32, unit, 0.0f, 0.0f, p, M * sizeof(float));
        free(p);
        size_t n;
        unsigned char *b = tu_read_file(path, &n);
        CHECK(b && n > 1000, "nii.gz written");
        path_of(path, sizeof path, "truncated.nii.gz");
        tu_write_file(path, b, n / 2);
        tu_expect_load_fail(ctx, path, NULL, "nii.gz truncated");
        path_of(path, sizeof path, "header_only.nii.gz");
        tu_write_file(path, b, 200);
        tu_expect_load_fail(ctx, path, NULL, "nii.gz cut in header");
        free(b);
        /* a header claiming 30000x30000x30000 over a tiny file */
        const int huge[4] = {30000, 30000, 30000, 1};
        path_of(path, sizeof path, "huge.nii");
        write_nifti(path, 3, huge, DT_U8, 8, unit, 0.0f, 0.0f, buf, 64);
        tu_expect_load_fail(ctx, path, NULL, "nii claiming 30000^3");
        const int big[4] = {1000, 1000, 1000, 1};
        path_of(path, sizeof path, "big.nii");
        write_nifti(path, 3, big, DT_U8, 8, unit, 0.0f, 0.0f, buf, 64);
        tu_expect_load_fail(ctx, path, NULL, "nii claiming 1000^3");
    }
    /* NRRD headers claiming more than the file holds */
    const char *nrrd_huge = "NRRD0004\ntype: uchar\ndimension: 3\nsizes: 60000 60000 60000\nencoding: raw\n\nxyz";
    path_of(path, sizeof path, "huge.nrrd");
    tu_write_file(path, nrrd_huge, strlen(nrrd_huge));
    tu_expect_load_fail(ctx, path, NULL, "nrrd claiming 60000^3");
    const char *nrrd_short = "NRRD0004\ntype: short\ndimension: 3\nsizes: 100 100 100\nendian: little\nencoding: raw\n\nxyz";
    path_of(path, sizeof path, "short.nrrd");
    tu_write_file(path, nrrd_short, strlen(nrrd_short));
    tu_expect_load_fail(ctx, path, NULL, "nrrd truncated");
    const char *nrrd_gz = "NRRD0004\ntype: float\ndimension: 3\nsizes: 100 100 100\nendian: little\nencoding: gzip\n\nxyz";
    path_of(path, sizeof path, "badgz.nrrd");
    tu_write_file(path, nrrd_gz, strlen(nrrd_gz));
    tu_expect_load_fail(ctx, path, NULL, "nrrd bad gzip");

    /* garbage with every extension, empty files, missing files */
    static const char *const exts[] = {".nii", ".nii.gz", ".nrrd", ".nhdr", ".tif", ".png", ".tar", ".den"};
    for (size_t i = 0; i < sizeof exts / sizeof exts[0]; i++) {
        char name[64];
        snprintf(name, sizeof name, "garbage%s", exts[i]);
        path_of(path, sizeof path, name);
        tu_write_file(path, buf, sizeof buf);
        tu_expect_load_fail(ctx, path, NULL, name);
        snprintf(name, sizeof name, "empty%s", exts[i]);
        path_of(path, sizeof path, name);
        tu_write_file(path, buf, 0);
        tu_expect_load_fail(ctx, path, NULL, name);
        snprintf(name, sizeof name, "missing%s", exts[i]);
        path_of(path, sizeof path, name);
        tu_expect_load_fail(ctx, path, NULL, name);
    }
    vs_load_options_init(&o);
    o.raw = 1;
    o.dims[0] = o.dims[1] = o.dims[2] = 4;
    path_of(path, sizeof path, "empty.raw");
    tu_write_file(path, buf, 0);
    tu_expect_load_fail(ctx, path, &o, "empty raw");
    path_of(path, sizeof path, "missing.raw");
    tu_expect_load_fail(ctx, path, &o, "missing raw");
    path_of(path, sizeof path, "unknown.xyz");
    tu_write_file(path, buf, 100);
    tu_expect_load_fail(ctx, path, NULL, "unknown extension");
    path_of(path, sizeof path, "emptyfolder");
    mkdir(path, 0755);
    tu_expect_load_fail(ctx, path, NULL, "empty folder");
    /* a FIFO must not hang the loader */
    path_of(path, sizeof path, "fifo.raw");
    if (mkfifo(path, 0600) == 0) tu_expect_load_fail(ctx, path, &o, "fifo");
    /* bad spacing override */
    vs_load_options_init(&o);
    o.has_spacing = 1;
    o.spacing[1] = 0.0;
    path_of(path, sizeof path, "t.den");
    tu_expect_load_fail(ctx, path, &o, "zero spacing override");
}

/* Does this process have OpenImageIO mapped? */
static int oiio_mapped(void)
{
    FILE *f = fopen("/proc/self/maps", "r");
    if (!f) return -1;
    char line[4096];
    int found = 0;
    while (!found && fgets(line, sizeof line, f)) found = strstr(line, "libOpenImageIO") != NULL;
    fclose(f);
    return found;
}

/* Image I/O is a module loaded on first use (src/io/oiio_adapter.h): loading a
 * NIfTI volume and rendering it must not map OpenImageIO (its 260 libraries
 * cost 130 MB and 0.15 s a start); the first image write loads it. */
static void test_io_module_lazy(vs_context *ctx)
{
    if (oiio_mapped() < 0) {
        printf("SKIP lazy image module: no /proc/self/maps\n");
        return;
    }
    CHECK(oiio_mapped() == 0, "OpenImageIO mapped at start: the library links it again");
    enum { N = 12 };
    uint8_t vox[N * N * N];
    for (int i = 0; i < N * N * N; i++) vox[i] = (uint8_t)(i % 7 == 0 ? 200 : 10);
    char path[1100];
    path_of(path, sizeof path, "lazy.nii");
    const int dims[4] = {N, N, N, 1};
    const float unit[3] = {1, 1, 1};
    write_nifti(path, 3, dims, DT_U8, 8, unit, 0.0f, 0.0f, vox, sizeof vox);
    vs_volume *v = load(ctx, path, NULL);
    vs_settings s;
    vs_settings_init(&s);
    s.width = s.height = 32;
    vs_image img = {0, 0, NULL};
    CHECK(v && vs_render(ctx, v, &s, &img, NULL) == VS_OK, "render: %s", vs_last_error(ctx));
    CHECK(oiio_mapped() == 0, "loading a NIfTI volume and rendering it mapped OpenImageIO");
    path_of(path, sizeof path, "lazy.png");
    CHECK(vs_image_write(ctx, path, &img, 8) == VS_OK, "write: %s", vs_last_error(ctx));
    CHECK(oiio_mapped() == 1, "an image was written without mapping OpenImageIO?");
    vs_image_free(&img);
    vs_volume_release(v);
}

int main(void)
{
    vs_context *ctx;
    if (vs_context_create(&ctx) != VS_OK) return 1;
    if (!tu_make_tmpdir(tmp, sizeof tmp, "test_load")) return 1;
    printf("temporary files in %s\n", tmp);
    test_io_module_lazy(ctx);
    test_real(ctx);
    test_nifti(ctx);
    test_nrrd(ctx);
    test_nrrd_data_files(ctx);
    test_raw_den(ctx);
    test_box(ctx);
    test_stacks(ctx);
    test_hostile(ctx);
    tu_remove_tmpdir(tmp);
    vs_context_release(ctx);
    TEST_DONE();
}
