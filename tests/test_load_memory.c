/* Loaders read into the volume's own buffer: loading a file may raise the
 * process's peak resident memory by the volume and a little more (a
 * decoder's state, a header), never by a second copy of the data.  Each
 * file of a 25.6 MB u8 volume is loaded in a child process, and the
 * child's peak (wait4's ru_maxrss) is compared with a child that loads
 * nothing.  NRRD (raw through Teem, gzip and bzip2 through
 * nrrd_compressed.c), MetaImage, named raw files and NIfTI (plain, gzip).  Sanitizer builds
 * (VSPLAT_SANITIZED=1) print the figures without the bound: ASan's
 * allocator and quarantine change what is resident. */
#include "internal.h"
#include "testutil.h"

#include <bzlib.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>
#include <zlib.h>

enum { NX = 320, NY = 320, NZ = 250, N = NX * NY * NZ };
#define SLACK_MB 8.0 /* bzip2's decoder (3.6 MB), stdio buffers, a header */

static char tmp[1024];

/* The peak resident memory, in MB, of a child that loads path (NULL: loads
 * nothing); -1 if the load fails. */
static double child_peak_mb(const char *path)
{
    fflush(stdout);
    const pid_t pid = fork();
    if (pid == 0) {
        int ok = 1;
        if (path) {
            vs_context *c = NULL;
            vs_volume *v = NULL;
            ok = vs_context_create(&c) == VS_OK && vs_volume_load(c, path, NULL, &v) == VS_OK;
            if (!ok) fprintf(stderr, "%s: %s\n", path, c ? vs_last_error(c) : "no context");
            vs_volume_release(v);
            vs_context_release(c);
        }
        _exit(ok ? 0 : 1);
    }
    int status = 0;
    struct rusage ru;
    if (pid < 0 || wait4(pid, &status, 0, &ru) != pid || !WIFEXITED(status) || WEXITSTATUS(status) != 0)
        return -1;
    return ru.ru_maxrss / 1024.0;
}

static void write_all(const char *path, const char *header, const void *data, size_t n)
{
    FILE *f = fopen(path, "wb");
    if (!f || fputs(header, f) < 0 || fwrite(data, 1, n, f) != n) exit(2);
    fclose(f);
}

int main(void)
{
    const char *san = getenv("VSPLAT_SANITIZED");
    const int sanitized = san && *san && strcmp(san, "0") != 0;
    if (!tu_make_tmpdir(tmp, sizeof tmp, "load_memory")) return 1;
    unsigned char *vol = malloc(N);
    unsigned zcap = N + N / 100 + 1000;
    char *z = malloc(zcap);
    if (!vol || !z) return 2;
    for (int i = 0; i < N; i++) {
        const int x = i % NX, y = i / NX % NY, k = i / (NX * NY);
        vol[i] = (unsigned char)((x * 7 + y * 3 + k) & 255);
    }
    char path[1200], hdr[512];
    struct {
        const char *name, *encoding;
    } nrrds[] = {{"v.nrrd", "raw"}, {"v_gz.nrrd", "gzip"}, {"v_bz2.nrrd", "bzip2"}};
    for (int k = 0; k < 3; k++) {
        snprintf(path, sizeof path, "%s/%s", tmp, nrrds[k].name);
        snprintf(hdr, sizeof hdr, "NRRD0004\ntype: uchar\ndimension: 3\nsizes: %d %d %d\nencoding: %s\n\n", NX, NY,
                 NZ, nrrds[k].encoding);
        if (k == 0) {
            write_all(path, hdr, vol, N);
        } else if (k == 1) {
            uLongf zn = zcap;
            z_stream zs;
            memset(&zs, 0, sizeof zs);
            if (deflateInit2(&zs, 1, Z_DEFLATED, 15 + 16, 8, Z_DEFAULT_STRATEGY) != Z_OK) return 2;
            zs.next_in = vol;
            zs.avail_in = N;
            zs.next_out = (Bytef *)z;
            zs.avail_out = (uInt)zn;
            if (deflate(&zs, Z_FINISH) != Z_STREAM_END) return 2;
            write_all(path, hdr, z, zs.total_out);
            deflateEnd(&zs);
        } else {
            unsigned zn = zcap;
            if (BZ2_bzBuffToBuffCompress(z, &zn, (char *)vol, N, 1, 0, 0) != BZ_OK) return 2;
            write_all(path, hdr, z, zn);
        }
    }
    snprintf(path, sizeof path, "%s/v.mha", tmp);
    snprintf(hdr, sizeof hdr,
             "ObjectType = Image\nNDims = 3\nDimSize = %d %d %d\nElementType = MET_UCHAR\nElementDataFile = LOCAL\n",
             NX, NY, NZ);
    write_all(path, hdr, vol, N);
    snprintf(path, sizeof path, "%s/v_%dx%dx%d_u8.raw", tmp, NX, NY, NZ);
    write_all(path, "", vol, N);
    /* NIfTI-1, u8, little-endian (every host the tests run on), plain and gzip */
    unsigned char nh[352] = {0};
    const int32_t sizeof_hdr = 348;
    const int16_t dim[8] = {3, NX, NY, NZ, 1, 1, 1, 1}, datatype = 2 /* DT_UINT8 */, bitpix = 8;
    const float pixdim[8] = {1, 1, 1, 1, 1, 1, 1, 1}, vox_offset = 352;
    memcpy(nh, &sizeof_hdr, 4);
    memcpy(nh + 40, dim, sizeof dim);
    memcpy(nh + 70, &datatype, 2);
    memcpy(nh + 72, &bitpix, 2);
    memcpy(nh + 76, pixdim, sizeof pixdim);
    memcpy(nh + 108, &vox_offset, 4);
    memcpy(nh + 344, "n+1", 4);
    snprintf(path, sizeof path, "%s/v.nii", tmp);
    FILE *f = fopen(path, "wb");
    if (!f || fwrite(nh, 1, sizeof nh, f) != sizeof nh || fwrite(vol, 1, N, f) != N) return 2;
    fclose(f);
    snprintf(path, sizeof path, "%s/v.nii.gz", tmp);
    gzFile g = gzopen(path, "wb1");
    if (!g || gzwrite(g, nh, sizeof nh) != (int)sizeof nh || gzwrite(g, vol, N) != N) return 2;
    gzclose(g);
    free(vol);
    free(z);

    char raw_name[64];
    snprintf(raw_name, sizeof raw_name, "v_%dx%dx%d_u8.raw", NX, NY, NZ);
    const char *files[] = {"v.nrrd", "v_gz.nrrd", "v_bz2.nrrd", "v.mha", raw_name, "v.nii", "v.nii.gz"};
    const int nfiles = (int)(sizeof files / sizeof files[0]);
    const double base = child_peak_mb(NULL), vol_mb = N / (1024.0 * 1024.0);
    CHECK(base > 0, "the empty child failed");
    printf("  volume %.1f MB; a child that loads nothing peaks at %.1f MB\n", vol_mb, base);
    for (int k = 0; k < nfiles; k++) {
        snprintf(path, sizeof path, "%s/%s", tmp, files[k]);
        const double peak = child_peak_mb(path);
        CHECK(peak > 0, "%s: the load failed", files[k]);
        const double extra = peak - base;
        printf("  %-24s peak %.1f MB: %.2f volumes more%s\n", files[k], peak, extra / vol_mb,
               sanitized ? " (sanitizer build: not bounded)" : "");
        if (!sanitized)
            CHECK(extra <= vol_mb + SLACK_MB, "%s: loading raised the peak by %.1f MB, more than the volume (%.1f MB) + %.0f",
                  files[k], extra, vol_mb, SLACK_MB);
    }
    tu_remove_tmpdir(tmp);
    TEST_DONE();
}
