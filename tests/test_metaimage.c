/* ITK MetaImage (.mha, .mhd + data file).  The same voxels written every
 * way the format allows (one file or two, LOCAL, HeaderSize, zlib,
 * big-endian, each element type) load as identical volumes; the transform
 * follows ITK's convention (TransformMatrix lists index axis 0's LPS
 * direction first, Offset is voxel 0) turned into RAS, checked against a
 * matrix worked out by hand; hostile headers fail with a message. */
#include "testutil.h"

#include <stdint.h>
#include <zlib.h>

#define NX 9
#define NY 7
#define NZ 5
#define NV (NX * NY * NZ)

static char dir[4096];

static double value(size_t i) { return (double)((i * 37) % 251) - 60.0; } /* fits i16, u8 after +60 */

static void write_file(const char *name, const void *a, size_t na, const void *b, size_t nb)
{
    char p[4200];
    snprintf(p, sizeof p, "%s/%s", dir, name);
    FILE *f = fopen(p, "wb");
    if (!f) { perror(p); exit(2); }
    if (na) fwrite(a, 1, na, f);
    if (nb) fwrite(b, 1, nb, f);
    fclose(f);
}

/* The voxels as `type` (plus `shift` so unsigned types hold them), each
 * element's bytes reversed when msb. */
static size_t encode(const char *type, double shift, int msb, unsigned char *out)
{
    size_t elem = 0;
    for (size_t i = 0; i < NV; i++) {
        double x = value(i) + shift;
        unsigned char b[8];
        if (!strcmp(type, "MET_UCHAR")) { b[0] = (uint8_t)x; elem = 1; }
        else if (!strcmp(type, "MET_CHAR")) { int8_t t = (int8_t)(x / 2); memcpy(b, &t, 1); elem = 1; }
        else if (!strcmp(type, "MET_SHORT")) { int16_t t = (int16_t)x; memcpy(b, &t, 2); elem = 2; }
        else if (!strcmp(type, "MET_USHORT")) { uint16_t t = (uint16_t)x; memcpy(b, &t, 2); elem = 2; }
        else if (!strcmp(type, "MET_INT")) { int32_t t = (int32_t)x; memcpy(b, &t, 4); elem = 4; }
        else if (!strcmp(type, "MET_FLOAT")) { float t = (float)x; memcpy(b, &t, 4); elem = 4; }
        else { memcpy(b, &x, 8); elem = 8; }
        for (size_t k = 0; k < elem; k++) out[i * elem + k] = b[msb ? elem - 1 - k : k];
    }
    return elem * NV;
}

static const char *geometry = "TransformMatrix = 0 1 0 -1 0 0 0 0 1\n"
                              "Offset = 10 20 30\n"
                              "ElementSpacing = 2 3 4\n"
                              "DimSize = 9 7 5\n";

/* The RAS affine the header above means, worked out by hand: axis 0 runs
 * along LPS +y (RAS -y), axis 1 along LPS -x (RAS +x); x and y of the
 * offset change sign. */
static const double expect_affine[12] = {0, 3, 0, -10, -2, 0, 0, -20, 0, 0, 4, 30};

static vs_volume *load(vs_context *ctx, const char *name)
{
    char p[4200];
    snprintf(p, sizeof p, "%s/%s", dir, name);
    vs_volume *v = NULL;
    vs_status st = vs_volume_load(ctx, p, NULL, &v);
    CHECK(st == VS_OK, "%s: %s", name, vs_last_error(ctx));
    return v;
}

/* Loaded as `type`, voxel i equal to scale * value(i) + shift. */
static void check(vs_context *ctx, const char *name, vs_type type, double scale, double shift)
{
    vs_volume *v = load(ctx, name);
    if (!v) return;
    int d[3];
    double m[12];
    vs_volume_dims(v, d);
    CHECK(d[0] == NX && d[1] == NY && d[2] == NZ, "%s: dims %dx%dx%d", name, d[0], d[1], d[2]);
    CHECK(vs_volume_type(v) == type, "%s: type %s, expected %s", name, vs_type_name(vs_volume_type(v)),
          vs_type_name(type));
    CHECK(vs_volume_affine(v, m) == 1, "%s: no orientation", name);
    for (int i = 0; i < 12; i++) CHECK(fabs(m[i] - expect_affine[i]) < 1e-12, "%s: affine[%d] %g, expected %g", name, i, m[i], expect_affine[i]);
    int bad = 0;
    for (size_t i = 0; i < NV && d[0] * d[1] * d[2] == NV; i++) {
        double got;
        switch (vs_volume_type(v)) {
        case VS_U8: got = ((uint8_t *)vs_volume_data(v))[i]; break;
        case VS_I16: got = ((int16_t *)vs_volume_data(v))[i]; break;
        case VS_U16: got = ((uint16_t *)vs_volume_data(v))[i]; break;
        default: got = ((float *)vs_volume_data(v))[i]; break;
        }
        double want = !strcmp(name, "char.mha") ? (double)(int8_t)((value(i) + shift) / 2) : scale * value(i) + shift;
        if (got != want) bad++;
    }
    CHECK(bad == 0, "%s: %d voxels differ", name, bad);
    vs_volume_release(v);
}

static void write_mha(const char *name, const char *type, double shift, int msb, const char *extra)
{
    unsigned char data[NV * 8];
    size_t n = encode(type, shift, msb, data);
    char h[2048];
    snprintf(h, sizeof h,
             "ObjectType = Image\nNDims = 3\nBinaryData = True\nBinaryDataByteOrderMSB = %s\n%s%s"
             "ElementType = %s\nElementDataFile = LOCAL\n",
             msb ? "True" : "False", geometry, extra ? extra : "", type);
    write_file(name, h, strlen(h), data, n);
}

static void expect_error(vs_context *ctx, const char *name, const char *header, const void *data, size_t n,
                         const char *want)
{
    write_file(name, header, strlen(header), data, n);
    char p[4200];
    snprintf(p, sizeof p, "%s/%s", dir, name);
    vs_volume *v = (vs_volume *)1;
    vs_status st = vs_volume_load(ctx, p, NULL, &v);
    CHECK(st != VS_OK && v == NULL, "%s loaded, expected an error with '%s'", name, want);
    CHECK(strstr(vs_last_error(ctx), want) != NULL, "%s: message '%s' lacks '%s'", name, vs_last_error(ctx), want);
}

int main(void)
{
    snprintf(dir, sizeof dir, "%s/metaimage", VSPLAT_TEST_BINARY_DIR);
    mkdir(dir, 0755);
    vs_context *ctx = NULL;
    if (vs_context_create(&ctx) != VS_OK) return 2;

    write_mha("short.mha", "MET_SHORT", 0, 0, NULL);
    write_mha("short_msb.mha", "MET_SHORT", 0, 1, NULL);
    write_mha("ushort.mha", "MET_USHORT", 100, 1, NULL);
    write_mha("uchar.mha", "MET_UCHAR", 60, 0, NULL);
    write_mha("char.mha", "MET_CHAR", 0, 0, NULL);
    write_mha("int.mha", "MET_INT", 0, 1, NULL);
    write_mha("float_msb.mha", "MET_FLOAT", 0, 1, NULL);
    write_mha("double.mha", "MET_DOUBLE", 0, 0, NULL);
    check(ctx, "short.mha", VS_I16, 1, 0);
    check(ctx, "short_msb.mha", VS_I16, 1, 0);
    check(ctx, "ushort.mha", VS_U16, 1, 100);
    check(ctx, "uchar.mha", VS_U8, 1, 60);
    check(ctx, "char.mha", VS_I16, 1, 0);
    check(ctx, "int.mha", VS_F32, 1, 0);
    check(ctx, "float_msb.mha", VS_F32, 1, 0);
    check(ctx, "double.mha", VS_F32, 1, 0);

    /* .mhd + raw, with HeaderSize bytes to skip, and HeaderSize -1 (the
     * data is the file's end) */
    unsigned char data[NV * 8], z[NV * 8 + 1024];
    size_t n = encode("MET_SHORT", 0, 0, data);
    char h[2048];
    snprintf(h, sizeof h, "ObjectType = Image\nNDims = 3\n%sElementType = MET_SHORT\nElementDataFile = short.raw\n",
             geometry);
    write_file("two.mhd", h, strlen(h), NULL, 0);
    write_file("short.raw", data, n, NULL, 0);
    check(ctx, "two.mhd", VS_I16, 1, 0);
    snprintf(h, sizeof h, "NDims = 3\n%sHeaderSize = 16\nElementType = MET_SHORT\nElementDataFile = skip.raw\n",
             geometry);
    write_file("skip.mhd", h, strlen(h), NULL, 0);
    write_file("skip.raw", "0123456789abcdef", 16, data, n);
    check(ctx, "skip.mhd", VS_I16, 1, 0);
    snprintf(h, sizeof h, "NDims = 3\n%sHeaderSize = -1\nElementType = MET_SHORT\nElementDataFile = end.raw\n",
             geometry);
    write_file("end.mhd", h, strlen(h), NULL, 0);
    write_file("end.raw", "some header of another program", 30, data, n);
    check(ctx, "end.mhd", VS_I16, 1, 0);

    /* zlib, as ITK writes it, with and without CompressedDataSize */
    uLongf zn = sizeof z;
    CHECK(compress2(z, &zn, data, n, 6) == Z_OK, "compress2");
    snprintf(h, sizeof h,
             "NDims = 3\n%sCompressedData = True\nCompressedDataSize = %lu\nElementType = MET_SHORT\n"
             "ElementDataFile = LOCAL\n",
             geometry, (unsigned long)zn);
    write_file("zlib.mha", h, strlen(h), z, zn);
    check(ctx, "zlib.mha", VS_I16, 1, 0);
    snprintf(h, sizeof h, "NDims = 3\n%sCompressedData = True\nElementType = MET_SHORT\nElementDataFile = z.zraw\n",
             geometry);
    write_file("zlib.mhd", h, strlen(h), NULL, 0);
    write_file("z.zraw", z, zn, NULL, 0);
    check(ctx, "zlib.mhd", VS_I16, 1, 0);

    /* hostile headers: a clear error each, no crash */
    char hb[4096];
#define HDR(...) (snprintf(hb, sizeof hb, __VA_ARGS__), hb)
    const char *ok = "NDims = 3\nDimSize = 9 7 5\nElementType = MET_SHORT\n";
    expect_error(ctx, "trunc.mha", HDR("%sElementDataFile = LOCAL\n", ok), data, n - 1, "truncated");
    expect_error(ctx, "notype.mha", "NDims = 3\nDimSize = 9 7 5\nElementDataFile = LOCAL\n", data, n,
                 "no ElementType");
    expect_error(ctx, "ndims4.mha", "NDims = 4\nDimSize = 9 7 5 1\nElementType = MET_SHORT\nElementDataFile = LOCAL\n",
                 data, n, "only 2 or 3 dimensions");
    expect_error(ctx, "negative.mha", "NDims = 3\nDimSize = 9 -7 5\nElementType = MET_SHORT\nElementDataFile = LOCAL\n",
                 data, n, "sizes must be whole numbers >= 1");
    expect_error(ctx, "huge.mha", "NDims = 3\nDimSize = 16000 16000 16000\nElementType = MET_SHORT\nElementDataFile = LOCAL\n",
                 data, n, "exceed the limit");
    expect_error(ctx, "long.mha", "NDims = 3\nDimSize = 9 7 5\nElementType = MET_LONG_LONG\nElementDataFile = LOCAL\n",
                 data, n, "not supported");
    expect_error(ctx, "rgb.mha", HDR("%sElementNumberOfChannels = 3\nElementDataFile = LOCAL\n", ok), data, n,
                 "only one channel");
    expect_error(ctx, "ascii.mha", HDR("%sBinaryData = False\nElementDataFile = LOCAL\n", ok), data, n,
                 "text (ASCII) voxels");
    expect_error(ctx, "noend.mha", ok, NULL, 0, "without ElementDataFile");
    expect_error(ctx, "noeq.mha", "NDims 3\n", NULL, 0, "has no '='");
    expect_error(ctx, "missing.mhd", HDR("%sElementDataFile = nowhere.raw\n", ok), NULL, 0, "nowhere.raw: cannot open");
    expect_error(ctx, "list.mhd", HDR("%sElementDataFile = LIST\n", ok), NULL, 0, "several files");
    expect_error(ctx, "pattern.mhd", HDR("%sElementDataFile = slice%%03d.raw 1 5 1\n", ok), NULL, 0, "several files");
    expect_error(ctx, "skip.mha", HDR("%sHeaderSize = 100000\nElementDataFile = LOCAL\n", ok), data, n,
                 "past the end of the file");
    expect_error(ctx, "zjunk.mha", HDR("%sCompressedData = True\nElementDataFile = LOCAL\n", ok), data, n,
                 "compressed voxels are damaged");
    expect_error(ctx, "zshort.mha", HDR("%sCompressedData = True\nElementDataFile = LOCAL\n", ok), z, zn / 2,
                 "truncated");
    expect_error(ctx, "zsize.mha", HDR("%sCompressedData = True\nCompressedDataSize = 99999\nElementDataFile = LOCAL\n", ok),
                 z, zn, "CompressedDataSize 99999");
    expect_error(ctx, "singular.mha", HDR("%sTransformMatrix = 1 0 0 1 0 0 0 0 1\nElementDataFile = LOCAL\n", ok),
                 data, n, "TransformMatrix is singular");
    expect_error(ctx, "binary.mha", "NDims = 3\n\x01\x02\x00junk", NULL, 0, "has no '='");
    vs_context_release(ctx);
    TEST_DONE();
}
