/* Truncated TIFFs, refused before OpenImageIO reads them.  OIIO 2.4 reads
 * the strips of a deflate-compressed multi-strip TIFF without checking how
 * many bytes it got: a strip cut short by the end of the file is inflated
 * from uninitialised memory (valgrind, issue 24) and the slice loads as
 * garbage.  So every StripOffsets/TileOffsets entry plus its byte count
 * must lie inside the file.  A small reader of the IFD chain, classic and
 * BigTIFF, either byte order; only what locates the image data is read.
 * Also refused, both found by fuzz_stack under valgrind (OIIO returns the
 * page as read, its undecoded part uninitialised): a Predictor other than
 * 1..3, a compression scheme libtiff does not know, and a deflate strip
 * that inflates to fewer bytes than its rows need.
 * A directory that cannot be read in full ends the walk: libtiff then sees
 * fewer pages, or refuses the file itself. */
#include "tiff_check.h"

#include <stdint.h>
#include <stdio.h>
#include <string.h>
#include <sys/stat.h>
#include <zlib.h>

typedef struct src {
    FILE *f;
    const uint8_t *mem;
    uint64_t size;
    int be, big; /* big-endian; BigTIFF (8-byte offsets and counts) */
} src;

static int read_at(const src *s, uint64_t off, void *buf, size_t n)
{
    if (off > s->size || n > s->size - off) return 0;
    if (s->mem) {
        memcpy(buf, s->mem + off, n);
        return 1;
    }
    return fseeko(s->f, (off_t)off, SEEK_SET) == 0 && fread(buf, 1, n, s->f) == n;
}

static uint64_t get(const src *s, const uint8_t *p, int bytes)
{
    uint64_t v = 0;
    for (int i = 0; i < bytes; i++) v |= (uint64_t)p[s->be ? bytes - 1 - i : i] << (8 * i);
    return v;
}

/* One array-valued tag: where its values are, their width and count. */
typedef struct tag_ref {
    uint64_t count, at; /* at: file offset of the values */
    int width;          /* 2 (SHORT), 4 (LONG) or 8 (LONG8); 0 absent */
    unsigned tag;
} tag_ref;

/* Bytes a zlib stream at off (c bytes) inflates to, stopping at `need`. */
static uint64_t inflated(const src *s, uint64_t off, uint64_t c, uint64_t need)
{
    z_stream z;
    memset(&z, 0, sizeof z);
    if (inflateInit(&z) != Z_OK) return need; /* cannot tell: let it pass */
    static const size_t chunk = 16384;
    uint8_t in[16384], out[16384];
    uint64_t total = 0;
    int rc = Z_OK;
    while (rc == Z_OK && total < need) {
        if (z.avail_in == 0) {
            size_t n = c > chunk ? chunk : (size_t)c;
            if (n == 0 || !read_at(s, off, in, n)) break;
            off += n;
            c -= n;
            z.next_in = in;
            z.avail_in = (uInt)n;
        }
        z.next_out = out;
        z.avail_out = (uInt)chunk;
        rc = inflate(&z, Z_NO_FLUSH);
        total += chunk - z.avail_out;
        if (rc == Z_BUF_ERROR && z.avail_in == 0 && c > 0) rc = Z_OK; /* more input */
    }
    inflateEnd(&z);
    return total;
}

/* The compression schemes libtiff 4 knows; OIIO "reads" others as
 * nothing (fuzz_stack: scheme 520). */
static int known_compression(uint64_t c)
{
    static const unsigned k[] = {1,     2,     3,     4,     5,     6,     7,     8,     32766, 32771, 32773,
                                 32809, 32909, 32946, 34661, 34676, 34677, 34925, 50000, 50001};
    for (size_t i = 0; i < sizeof k / sizeof k[0]; i++)
        if (c == k[i]) return 1;
    return 0;
}

/* The first value of a SHORT/LONG tag entry b (0 for other types). */
static uint64_t first_value(const src *s, const uint8_t *b, unsigned type, int ow)
{
    int w = type == 3 ? 2 : type == 4 ? 4 : type == 16 ? 8 : 0;
    if (!w) return 0;
    uint64_t count = get(s, b + 4, ow);
    if (count * (uint64_t)w <= (uint64_t)ow) return get(s, b + 4 + ow, w);
    uint8_t v[8];
    return read_at(s, get(s, b + 4 + ow, ow), v, (size_t)w) ? get(s, v, w) : 0;
}

static int value(const src *s, const tag_ref *t, uint64_t i, uint64_t *out)
{
    uint8_t b[8];
    if (!read_at(s, t->at + i * (uint64_t)t->width, b, (size_t)t->width)) return 0;
    *out = get(s, b, t->width);
    return 1;
}

vs_status vs_tiff_check(vs_context *ctx, const char *path, const void *mem, size_t size)
{
    src s = {.mem = mem, .size = size};
    if (!mem) {
        s.f = fopen(path, "rb");
        if (!s.f) return VS_OK; /* the reader reports it */
        struct stat st;
        if (fstat(fileno(s.f), &st) != 0) {
            fclose(s.f);
            return VS_OK;
        }
        s.size = (uint64_t)st.st_size;
    }
    vs_status status = VS_OK;
    uint8_t h[16];
    if (!read_at(&s, 0, h, 8) || !((h[0] == 'I' && h[1] == 'I') || (h[0] == 'M' && h[1] == 'M'))) goto done;
    s.be = h[0] == 'M';
    uint64_t version = get(&s, h + 2, 2);
    if (version == 43) {
        if (!read_at(&s, 0, h, 16) || get(&s, h + 4, 2) != 8) goto done;
        s.big = 1;
    } else if (version != 42) {
        goto done;
    }
    const int ow = s.big ? 8 : 4; /* offset width */
    uint64_t ifd = get(&s, h + (s.big ? 8 : 4), ow);
    /* A loop of directories ends on this budget (libtiff refuses loops). */
    uint64_t budget = 4 * s.size + 4096;
    for (int page = 0; ifd != 0 && page <= 65536 && budget > 0; page++) {
        uint8_t nb[8];
        if (!read_at(&s, ifd, nb, (size_t)(s.big ? 8 : 2))) break;
        uint64_t n = get(&s, nb, s.big ? 8 : 2);
        const uint64_t esz = s.big ? 20 : 12;
        uint64_t first = ifd + (s.big ? 8 : 2);
        if (n > 65535 || n * esz > s.size) break;
        tag_ref offs = {0, 0, 0, 0}, cnts = {0, 0, 0, 0};
        uint64_t width = 0, height = 0, bps = 1, comp = 1, photo = 0, spp = 1, rps = UINT32_MAX, planar = 1;
        for (uint64_t e = 0; e < n; e++) {
            uint8_t b[20];
            if (!read_at(&s, first + e * esz, b, (size_t)esz)) goto done;
            unsigned tag = (unsigned)get(&s, b, 2), type = (unsigned)get(&s, b + 2, 2);
            if (tag == 317) { /* Predictor: OIIO loads an unknown one without data */
                uint64_t pv = get(&s, b + 4 + ow, type == 3 ? 2 : 4);
                if (get(&s, b + 4, ow) == 1 && (type == 3 || type == 4) && (pv < 1 || pv > 3)) {
                    status = vs_set_error(ctx, VS_ERR_FORMAT, "%s: TIFF page %d has unknown predictor %llu", path,
                                          page, (unsigned long long)pv);
                    goto done;
                }
                continue;
            }
            uint64_t fv = first_value(&s, b, type, ow);
            switch (tag) {
            case 256: width = fv; break;
            case 257: height = fv; break;
            case 258: bps = fv; break;
            case 259: comp = fv; break;
            case 262: photo = fv; break;
            case 277: spp = fv; break;
            case 278: rps = fv ? fv : UINT32_MAX; break;
            case 284: planar = fv; break;
            default: break;
            }
            if (tag != 273 && tag != 279 && tag != 324 && tag != 325) continue;
            int w = type == 3 ? 2 : type == 4 ? 4 : type == 16 ? 8 : 0;
            if (!w) continue; /* not a type libtiff takes for these: its error */
            tag_ref t = {get(&s, b + 4, ow), 0, w, tag};
            uint64_t inline_at = first + e * esz + 4 + (uint64_t)ow;
            t.at = t.count * (uint64_t)w <= (uint64_t)ow ? inline_at : get(&s, b + 4 + ow, ow);
            if (tag == 273 || tag == 324) offs = t;
            else cnts = t;
        }
        budget = budget > n ? budget - n : 0;
        if (!known_compression(comp)) {
            status = vs_set_error(ctx, VS_ERR_FORMAT, "%s: TIFF page %d has unknown compression %llu", path, page,
                                  (unsigned long long)comp);
            goto done;
        }
        /* deflate strips of whole bytes, one plane, no subsampling: the
         * bytes each strip's rows need (0: not checked) */
        uint64_t rowbytes = 0;
        if ((comp == 8 || comp == 32946) && planar == 1 && photo != 6 && (bps == 8 || bps == 16 || bps == 32) &&
            width > 0 && width <= 65536 && spp >= 1 && spp <= 1024 && height > 0 && offs.tag == 273)
            rowbytes = width * spp * bps / 8;
        if (offs.width && cnts.width && offs.count == cnts.count) {
            for (uint64_t i = 0; i < offs.count && budget > 0; i++, budget--) {
                uint64_t o, c;
                if (!value(&s, &offs, i, &o) || !value(&s, &cnts, i, &c)) break; /* libtiff's error */
                if (o > s.size || c > s.size - o) {
                    status = vs_set_error(ctx, VS_ERR_FORMAT,
                                          "%s: truncated TIFF: page %d strip %llu needs bytes %llu..%llu, the file "
                                          "has %llu",
                                          path, page, (unsigned long long)i, (unsigned long long)o,
                                          (unsigned long long)(o + c), (unsigned long long)s.size);
                    goto done;
                }
                uint64_t row0 = i * rps;
                if (rowbytes && row0 < height) {
                    uint64_t need = rowbytes * (height - row0 < rps ? height - row0 : rps);
                    uint64_t got = need <= ((uint64_t)1 << 32) ? inflated(&s, o, c, need) : need;
                    if (got < need) {
                        status = vs_set_error(ctx, VS_ERR_FORMAT,
                                              "%s: TIFF page %d strip %llu inflates to %llu of the %llu bytes its "
                                              "rows need",
                                              path, page, (unsigned long long)i, (unsigned long long)got,
                                              (unsigned long long)need);
                        goto done;
                    }
                }
            }
        }
        uint8_t nx[8];
        if (!read_at(&s, first + n * esz, nx, (size_t)ow)) break;
        ifd = get(&s, nx, ow);
    }
done:
    if (s.f) fclose(s.f);
    return status;
}
