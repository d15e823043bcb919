/* Files that the third-party readers mishandle, refused before they see
 * them (issue 24):
 *  - TIFF: a deflate-compressed multi-strip TIFF whose last strips are cut
 *    off by the end of the file.  OpenImageIO 2.4 inflates such a strip
 *    from uninitialised memory and the slice loads as garbage; every cut
 *    must now be refused with "truncated", in either byte order and as
 *    BigTIFF, as one file and as a slice of a folder, and the whole file
 *    must load with exactly the voxels written;
 *  - NRRD: headers that Teem 1.12's parser leaks on (per-axis fields
 *    before "dimension", unterminated quoted strings, extra space units)
 *    are refused with our message, not Teem's (the leak itself is caught by
 *    LSan in the ASan suite and by valgrind in tests/cli_valgrind.sh), and
 *    the same fields in a valid order still load. */
#include "testutil.h"

#include <unistd.h>
#include <zlib.h>

enum { W = 16, H = 16, RPS = 2, NS = H / RPS };

static vs_context *ctx;
static char tmp[1024];

static uint8_t pixel(int x, int y) { return (uint8_t)(x * 7 + y * 13); }

typedef struct buf {
    uint8_t d[4096];
    size_t n;
    int be;
} buf;

static void put(buf *b, uint64_t v, int bytes)
{
    for (int i = 0; i < bytes; i++) b->d[b->n + i] = (uint8_t)(v >> (8 * (b->be ? bytes - 1 - i : i)));
    b->n += (size_t)bytes;
}

/* A W x H u8 TIFF, deflate, RPS rows a strip; header, directory, offset
 * and count arrays, then the strips, so that a cut of the end cuts strips. */
static size_t make_tiff(uint8_t *out, int be, int big)
{
    uint8_t strips[NS][256];
    uLongf slen[NS];
    for (int s = 0; s < NS; s++) {
        uint8_t raw[W * RPS];
        for (int y = 0; y < RPS; y++)
            for (int x = 0; x < W; x++) raw[y * W + x] = pixel(x, s * RPS + y);
        slen[s] = sizeof strips[s];
        if (compress(strips[s], &slen[s], raw, sizeof raw) != Z_OK) return 0;
    }
    const int ow = big ? 8 : 4, esz = big ? 20 : 12, ne = 9;
    buf b = {.n = 0, .be = be};
    b.d[0] = b.d[1] = be ? 'M' : 'I';
    b.n = 2;
    put(&b, big ? 43 : 42, 2);
    if (big) {
        put(&b, 8, 2);
        put(&b, 0, 2);
    }
    uint64_t ifd = (uint64_t)b.n + (uint64_t)ow;
    put(&b, ifd, ow);
    uint64_t arrays = ifd + (big ? 8 : 2) + (uint64_t)ne * esz + (uint64_t)ow;
    uint64_t offs_at = arrays, cnts_at = arrays + (uint64_t)NS * ow, data = cnts_at + (uint64_t)NS * ow;
    put(&b, ne, big ? 8 : 2);
    const unsigned tags[9] = {256, 257, 258, 259, 262, 273, 277, 278, 279};
    const uint64_t vals[9] = {W, H, 8, 8, 1, offs_at, 1, RPS, cnts_at};
    for (int e = 0; e < ne; e++) {
        int array = tags[e] == 273 || tags[e] == 279;
        put(&b, tags[e], 2);
        put(&b, array ? (big ? 16 : 4) : 3, 2); /* LONG8/LONG arrays, SHORT scalars */
        put(&b, array ? NS : 1, ow);
        if (array) {
            put(&b, vals[e], ow);
        } else {
            put(&b, vals[e], 2);
            put(&b, 0, ow - 2);
        }
    }
    put(&b, 0, ow); /* no next directory */
    uint64_t at = data;
    for (int s = 0; s < NS; s++) put(&b, at, ow), at += slen[s];
    for (int s = 0; s < NS; s++) put(&b, slen[s], ow);
    for (int s = 0; s < NS; s++) memcpy(b.d + b.n, strips[s], slen[s]), b.n += slen[s];
    memcpy(out, b.d, b.n);
    return b.n;
}

static void test_tiff(int be, int big)
{
    uint8_t t[4096];
    size_t n = make_tiff(t, be, big);
    const char *what = big ? (be ? "BigTIFF big-endian" : "BigTIFF") : (be ? "TIFF big-endian" : "TIFF");
    CHECK(n > 100, "%s: cannot build", what);
    char path[1200], dir[1200], slice[1300];
    snprintf(path, sizeof path, "%s/strips.tif", tmp);
    snprintf(dir, sizeof dir, "%s/slices", tmp);
    snprintf(slice, sizeof slice, "%s/s1.tif", dir);
    mkdir(dir, 0755);
    tu_write_file(path, t, n);
    vs_volume *v = NULL;
    CHECK(vs_volume_load(ctx, path, NULL, &v) == VS_OK, "%s whole: %s", what, vs_last_error(ctx));
    if (v) {
        int d[3];
        vs_volume_dims(v, d);
        const uint8_t *p = vs_volume_data(v);
        int bad = d[0] != W || d[1] != H || d[2] != 1 || vs_volume_type(v) != VS_U8;
        for (int i = 0; !bad && i < W * H; i++) bad = p[i] != pixel(i % W, i / W);
        CHECK(!bad, "%s whole: not the voxels written", what);
        vs_volume_release(v);
    }
    /* the strips are the last bytes: every cut is inside one */
    int refused = 0, cuts = 0;
    size_t data0 = n;
    for (size_t i = 0; i + 3 < n; i++) /* the first strip starts with zlib's 0x78 */
        if (t[i] == 0x78 && t[i + 1] == 0x9c) {
            data0 = i;
            break;
        }
    for (size_t cut = n - 1; cut > data0; cut -= cut > data0 + 7 ? 7 : 1) {
        tu_write_file(path, t, cut);
        tu_write_file(slice, t, cut);
        const char *paths[2] = {path, dir};
        for (int k = 0; k < 2; k++) {
            vs_volume *c = (vs_volume *)1;
            vs_status st = vs_volume_load(ctx, paths[k], NULL, &c);
            cuts++;
            if (st != VS_OK && !c && strstr(vs_last_error(ctx), "truncated")) {
                refused++;
            } else {
                CHECK(0, "%s cut at %zu of %zu (%s): status %d, %s", what, cut, n, k ? "folder" : "file", (int)st,
                      vs_last_error(ctx));
                if (st == VS_OK) vs_volume_release(c);
            }
        }
    }
    printf("  %-20s %zu bytes: whole loads exactly; %d of %d cuts into the strips refused\n", what, n, refused, cuts);
    unlink(path);
    unlink(slice);
    rmdir(dir);
}

/* Leaking headers: refused with our message (Teem's own names "dimension"
 * differently), and the same fields after "dimension" load. */
static void test_nrrd(void)
{
    static const char *const bad[][2] = {
        {"NRRD0005\ntype: float\ncenterings: cell\nsizes: 2 2 2\n", "before \"dimension\""},
        {"NRRD0004\nkinds: domain domain domain\ndimension: 3\n", "before \"dimension\""},
        {"NRRD0004\ntype: float\ndata file: LIST\n", "before \"dimension\""},
        {"NRRD0004\ndata file: f%03d.raw 1 3 1\n", "before \"dimension\""},
        {"NRRD0004\ntype: float\ndimension: 3\nlabels: \"x\n", "unterminated"},
        {"NRRD0004\ntype: float\ndimension: 3\nunits: \"mm\" \"mm\n", "unterminated"},
        {"NRRD0004\ntype: float\ndimension: 3\nspace dimension: 3\nspace units: \"mm\" \"mm\" \"mm\" \"mm\"\n",
         "\"space units\" has 4 strings for 3 space dimensions"},
        {"NRRD0004\ntype: float\ndimension: 3\nspace: RAST\nspace units: \"mm\" \"mm\" \"mm\" \"s\" \"x\"\n",
         "\"space units\" has 5 strings for 4 space dimensions"},
    };
    char path[1200];
    snprintf(path, sizeof path, "%s/h.nrrd", tmp);
    for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++) {
        tu_write_file(path, bad[i][0], strlen(bad[i][0]));
        vs_volume *v = (vs_volume *)1;
        vs_status st = vs_volume_load(ctx, path, NULL, &v);
        CHECK(st == VS_ERR_FORMAT && !v && strstr(vs_last_error(ctx), bad[i][1]), "nrrd header %zu: %d %s", i,
              (int)st, vs_last_error(ctx));
    }
    const char good[] = "NRRD0004\ntype: uchar\ndimension: 3\nspace: RAS\nsizes: 2 2 2\ncenterings: cell cell cell\n"
                        "kinds: domain domain domain\nlabels: \"x\" \"y \\\"z\\\"\" \"z\"\nunits: \"mm\" \"mm\" \"mm\"\n"
                        "space units: \"mm\" \"mm\" \"mm\"\n"
                        "encoding: raw\n\n01234567";
    tu_write_file(path, good, sizeof good - 1);
    vs_volume *v = NULL;
    CHECK(vs_volume_load(ctx, path, NULL, &v) == VS_OK, "valid header with every checked field: %s",
          vs_last_error(ctx));
    if (v) {
        CHECK(!memcmp(vs_volume_data(v), "01234567", 8), "valid header: wrong voxels");
        vs_volume_release(v);
    }
    unlink(path);
    printf("  nrrd: %zu leaking headers refused, the valid order loads\n", sizeof bad / sizeof bad[0]);
}

int main(void)
{
    snprintf(tmp, sizeof tmp, "%s/vsplat_truncated_%ld", tu_tmpdir(), (long)getpid());
    mkdir(tmp, 0755);
    CHECK(vs_context_create(&ctx) == VS_OK, "context");
    for (int big = 0; big < 2; big++)
        for (int be = 0; be < 2; be++) test_tiff(be, big);
    test_nrrd();
    vs_context_release(ctx);
    rmdir(tmp);
    TEST_DONE();
}
