/* Image stacks, decoded through the OpenImageIO adapter: a multi-page file
 * (TIFF; one page per z slice), a folder of PNG/TIFF slices in natural
 * numeric order (2.png before 10.png), or an uncompressed ustar archive of
 * slices in member order (headers parsed here; members decoded from memory).
 *
 * Policy: every slice must have the first slice's size and sample type.
 * 8-bit -> u8, 16-bit -> u16 (i16 if signed), half/float/double -> f32;
 * other sample types are rejected.  Gray+alpha keeps the gray channel; RGB(A)
 * becomes Rec. 709 luminance 0.2126 R + 0.7152 G + 0.0722 B (alpha ignored),
 * rounded to the sample type.
 * Spacing (TIFF only; PNG pHYs is ignored): x, y = 1/XResolution,
 * 1/YResolution; z = ImageJ "spacing=" from ImageDescription; without it, 1
 * for ImageJ files (ImageJ's default depth) and the mean x/y spacing for other
 * TIFFs (their z unit is unknown, so assume cubic voxels).  Without a
 * resolution: 1,1,1. */
#include "context.h"
#include "load.h"
#include "load_common.h"
#include "tiff_check.h"
#include "oiio_adapter.h"

#include <ctype.h>
#include <dirent.h>
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

/* Image data can be compressed far more than deflate's 1032:1 (LZW runs);
 * 4096:1 still stops absurd headers without refusing real files. */
static uint64_t image_bound(uint64_t encoded) { return encoded * 4096u + 65536u; }

static int is_slice_name(const char *name)
{
    const char *base = strrchr(name, '/');
    base = base ? base + 1 : name;
    if (base[0] == '.') return 0; /* hidden files, macOS "._x.png" */
    return vs_load_ends_with(base, ".png") || vs_load_ends_with(base, ".tif") ||
           vs_load_ends_with(base, ".tiff");
}

static int is_tiff_name(const char *name)
{
    return vs_load_ends_with(name, ".tif") || vs_load_ends_with(name, ".tiff");
}

/* Value of "key=" at the start of a line of an ImageJ description. */
static int imagej_value(const char *desc, const char *key, double *out)
{
    size_t k = strlen(key);
    for (const char *p = desc; p && *p;) {
        if (strncmp(p, key, k) == 0 && p[k] == '=') {
            char *end;
            double x = strtod(p + k + 1, &end);
            if (end == p + k + 1) return 0;
            *out = x;
            return 1;
        }
        p = strchr(p, '\n');
        if (p) p++;
    }
    return 0;
}

typedef struct stack {
    vs_context *ctx;
    const vs_oiio_api *io;
    const char *path;   /* the stack, for messages */
    int nz;
    uint64_t encoded;   /* bytes of encoded input, for the size bound */
    int tiff;           /* spacing from TIFF tags of the first slice */
    vs_volume *v;       /* allocated at the first slice */
    vs_pixel_type pix;
    size_t elem;
    int width, height;
    void *scratch;      /* multi-channel staging */
    size_t scratch_bytes;
} stack;

static vs_status stack_alloc(stack *s, const vs_oiio_info *info, const char *slice)
{
    vs_type type;
    switch (info->native) {
    case VS_PIX_U8: type = VS_U8; break;
    case VS_PIX_I16: type = VS_I16; break;
    case VS_PIX_U16: type = VS_U16; break;
    case VS_PIX_F32: type = VS_F32; break;
    default:
        return vs_set_error(s->ctx, VS_ERR_UNSUPPORTED,
                            "%s: %s: unsupported sample type (expected 8/16-bit or float)", s->path,
                            slice);
    }
    int64_t d[3] = {info->width, info->height, s->nz};
    uint64_t need;
    vs_status st = vs_load_check_dims(s->ctx, s->path, d, vs_type_size(type), &need);
    if (st != VS_OK) return st;
    if (need > image_bound(s->encoded))
        return vs_set_error(s->ctx, VS_ERR_FORMAT,
                            "%s: %dx%dx%d voxels cannot come from %llu bytes of images", s->path,
                            info->width, info->height, s->nz, (unsigned long long)s->encoded);
    double sp[3] = {1.0, 1.0, 1.0};
    if (s->tiff && info->has_resolution) {
        double z;
        sp[0] = 1.0 / info->xres;
        sp[1] = 1.0 / info->yres;
        int imagej = strncmp(info->description, "ImageJ=", 7) == 0;
        if (imagej_value(info->description, "spacing", &z) && fabs(z) > 0.0 && isfinite(z))
            sp[2] = fabs(z);
        else
            sp[2] = imagej ? 1.0 : 0.5 * (sp[0] + sp[1]);
    }
    int dims[3] = {info->width, info->height, s->nz};
    st = vs_load_alloc(s->ctx, s->path, type, dims, sp, &s->v);
    if (st != VS_OK) return st;
    s->pix = info->native;
    s->elem = vs_type_size(type);
    s->width = info->width;
    s->height = info->height;
    return VS_OK;
}

/* Collapses interleaved channels to one (see the policy at the top). */
static void to_gray(const stack *s, const void *src, int ch, void *dst)
{
    size_t n = (size_t)s->width * s->height;
    for (size_t i = 0; i < n; i++) {
        double g;
        size_t k = i * (size_t)ch;
        double c[3] = {0.0, 0.0, 0.0};
        for (int j = 0; j < 3 && j < ch; j++) {
            switch (s->pix) {
            case VS_PIX_U8: c[j] = ((const uint8_t *)src)[k + j]; break;
            case VS_PIX_I16: c[j] = ((const int16_t *)src)[k + j]; break;
            case VS_PIX_U16: c[j] = ((const uint16_t *)src)[k + j]; break;
            default: c[j] = ((const float *)src)[k + j]; break;
            }
        }
        g = ch >= 3 ? 0.2126 * c[0] + 0.7152 * c[1] + 0.0722 * c[2] : c[0];
        switch (s->pix) {
        case VS_PIX_U8: ((uint8_t *)dst)[i] = (uint8_t)fmin(255.0, fmax(0.0, floor(g + 0.5))); break;
        case VS_PIX_I16:
            ((int16_t *)dst)[i] = (int16_t)fmin(32767.0, fmax(-32768.0, floor(g + 0.5)));
            break;
        case VS_PIX_U16:
            ((uint16_t *)dst)[i] = (uint16_t)fmin(65535.0, fmax(0.0, floor(g + 0.5)));
            break;
        default: ((float *)dst)[i] = (float)g; break;
        }
    }
}

static const char *pix_name(vs_pixel_type p)
{
    switch (p) {
    case VS_PIX_U8: return "8-bit";
    case VS_PIX_I16: return "16-bit signed";
    case VS_PIX_U16: return "16-bit";
    case VS_PIX_F32: return "floating-point";
    default: return "of another sample type";
    }
}

/* Reads page `page` of reader `r` into slice z. */
static vs_status stack_add(stack *s, vs_oiio_reader *r, int page, int z, const char *slice)
{
    char err[400];
    vs_oiio_info *info = malloc(sizeof *info);
    if (!info) return vs_set_error(s->ctx, VS_ERR_OUT_OF_MEMORY, "%s: out of memory", s->path);
    vs_status st = s->io->page_info(r, page, info, err, sizeof err);
    if (st != VS_OK) {
        free(info);
        return vs_set_error(s->ctx, st, "%s: %s", s->path, err);
    }
    if (!s->v) {
        st = stack_alloc(s, info, slice);
        if (st != VS_OK) {
            free(info);
            return st;
        }
    }
    int ch = info->channels;
    if (info->width != s->width || info->height != s->height || info->native != s->pix) {
        st = vs_set_error(s->ctx, VS_ERR_FORMAT,
                          "%s: not one slice series: slice %d (%s) is %dx%d %s, but the first slice is %dx%d %s",
                          s->path, z + 1, slice, info->width, info->height, pix_name(info->native), s->width,
                          s->height, pix_name(s->pix));
        free(info);
        return st;
    }
    free(info);
    size_t slice_bytes = (size_t)s->width * s->height * s->elem;
    unsigned char *dst = (unsigned char *)s->v->data + (size_t)z * slice_bytes;
    if (ch == 1) {
        st = s->io->read_page(r, page, s->pix, dst, slice_bytes, err, sizeof err);
    } else {
        size_t need = slice_bytes * (size_t)ch;
        if (need > s->scratch_bytes) {
            void *p = realloc(s->scratch, need);
            if (!p) return vs_set_error(s->ctx, VS_ERR_OUT_OF_MEMORY, "%s: out of memory", s->path);
            s->scratch = p;
            s->scratch_bytes = need;
        }
        st = s->io->read_page(r, page, s->pix, s->scratch, need, err, sizeof err);
        if (st == VS_OK) to_gray(s, s->scratch, ch, dst);
    }
    if (st != VS_OK) return vs_set_error(s->ctx, st, "%s: %s", s->path, err);
    return VS_OK;
}

static vs_status stack_finish(stack *s, vs_status st, vs_volume **out)
{
    free(s->scratch);
    if (st != VS_OK) {
        vs_volume_release(s->v);
        return st;
    }
    *out = s->v;
    return VS_OK;
}

/* ---- one file, pages as slices ---- */

vs_status vs_load_image_pages(vs_context *ctx, const char *path, vs_volume **out)
{
    uint64_t fsize;
    vs_status st = vs_load_file_size(ctx, path, &fsize);
    if (st != VS_OK) return st;
    if (fsize == 0) return vs_set_error(ctx, VS_ERR_FORMAT, "%s: empty file", path);
    const vs_oiio_api *io = vs_oiio(ctx);
    if (!io) return VS_ERR_IO;
    char err[400];
    vs_oiio_reader *r;
    st = vs_tiff_check(ctx, path, NULL, 0); /* OIIO inflates a cut strip from garbage */
    if (st != VS_OK) return st;
    st = io->open(path, NULL, 0, &r, err, sizeof err);
    if (st != VS_OK) return vs_set_error(ctx, st, "%s", err);
    int pages = 0;
    st = io->count_pages(r, VS_MAX_DIM + 1, &pages, err, sizeof err);
    if (st != VS_OK) {
        io->close(r);
        return vs_set_error(ctx, st, "%s", err);
    }
    if (pages > VS_MAX_DIM) {
        io->close(r);
        return vs_set_error(ctx, VS_ERR_TOO_LARGE, "%s: more than %d pages", path, VS_MAX_DIM);
    }
    stack s = {.ctx = ctx, .io = io, .path = path, .nz = pages, .encoded = fsize, .tiff = is_tiff_name(path)};
    /* ImageJ hyperstacks interleave channels/frames with slices. */
    vs_oiio_info *info = malloc(sizeof *info);
    if (!info) st = vs_set_error(ctx, VS_ERR_OUT_OF_MEMORY, "%s: out of memory", path);
    else if ((st = io->page_info(r, 0, info, err, sizeof err)) != VS_OK)
        vs_set_error(ctx, st, "%s", err);
    else if (strncmp(info->description, "ImageJ=", 7) == 0) {
        double c = 1, f = 1;
        imagej_value(info->description, "channels", &c);
        imagej_value(info->description, "frames", &f);
        if (c > 1 || f > 1)
            st = vs_set_error(ctx, VS_ERR_UNSUPPORTED,
                              "%s: ImageJ hyperstack with %g channels and %g frames: only "
                              "single-channel z stacks are supported",
                              path, c, f);
    }
    free(info);
    for (int z = 0; st == VS_OK && z < pages; z++) {
        char name[64];
        snprintf(name, sizeof name, "page %d", z);
        st = stack_add(&s, r, z, z, name);
    }
    io->close(r);
    return stack_finish(&s, st, out);
}

/* ---- folder of slices ---- */

/* Natural order: digit runs compare as numbers ("2" < "10"), the rest bytewise. */
static int natural_cmp(const char *a, const char *b)
{
    while (*a && *b) {
        if (isdigit((unsigned char)*a) && isdigit((unsigned char)*b)) {
            while (*a == '0') a++;
            while (*b == '0') b++;
            size_t na = 0, nb = 0;
            while (isdigit((unsigned char)a[na])) na++;
            while (isdigit((unsigned char)b[nb])) nb++;
            if (na != nb) return na < nb ? -1 : 1;
            int c = strncmp(a, b, na);
            if (c) return c;
            a += na;
            b += nb;
        } else {
            if (*a != *b) return (unsigned char)*a < (unsigned char)*b ? -1 : 1;
            a++;
            b++;
        }
    }
    if (*a || *b) return *a ? 1 : -1;
    return 0;
}

static int natural_qsort(const void *x, const void *y)
{
    const char *a = *(const char *const *)x, *b = *(const char *const *)y;
    int c = natural_cmp(a, b);
    return c ? c : strcmp(a, b); /* "01" vs "1": still a total order */
}

vs_status vs_load_folder(vs_context *ctx, const char *path, vs_volume **out)
{
    const vs_oiio_api *io = vs_oiio(ctx);
    if (!io) return VS_ERR_IO;
    DIR *dir = opendir(path);
    if (!dir) return vs_set_error(ctx, VS_ERR_IO, "%s: cannot open folder: %s", path, strerror(errno));
    char **names = NULL;
    size_t n = 0, cap = 0;
    uint64_t total = 0;
    vs_status st = VS_OK;
    struct dirent *e;
    char full[4096];
    while (st == VS_OK && (e = readdir(dir)) != NULL) {
        if (!is_slice_name(e->d_name)) continue;
        struct stat sb;
        snprintf(full, sizeof full, "%s/%s", path, e->d_name);
        if (stat(full, &sb) != 0 || !S_ISREG(sb.st_mode)) continue;
        if (n >= (size_t)VS_MAX_DIM) {
            st = vs_set_error(ctx, VS_ERR_TOO_LARGE, "%s: more than %d slices", path, VS_MAX_DIM);
            break;
        }
        if (n == cap) {
            size_t nc = cap ? 2 * cap : 64;
            char **p = realloc(names, nc * sizeof *p);
            if (!p) {
                st = vs_set_error(ctx, VS_ERR_OUT_OF_MEMORY, "%s: out of memory", path);
                break;
            }
            names = p;
            cap = nc;
        }
        names[n] = strdup(e->d_name);
        if (!names[n]) {
            st = vs_set_error(ctx, VS_ERR_OUT_OF_MEMORY, "%s: out of memory", path);
            break;
        }
        n++;
        total += (uint64_t)sb.st_size;
    }
    closedir(dir);
    if (st == VS_OK && n == 0)
        st = vs_set_error(ctx, VS_ERR_FORMAT, "%s: no .png, .tif or .tiff slices in the folder", path);
    stack s = {.ctx = ctx, .io = io, .path = path, .nz = (int)n, .encoded = total};
    if (st == VS_OK) {
        qsort(names, n, sizeof *names, natural_qsort);
        s.tiff = is_tiff_name(names[0]);
    }
    for (size_t z = 0; st == VS_OK && z < n; z++) {
        char err[400];
        vs_oiio_reader *r;
        snprintf(full, sizeof full, "%s/%s", path, names[z]);
        if ((st = vs_tiff_check(ctx, full, NULL, 0)) != VS_OK) break;
        st = io->open(full, NULL, 0, &r, err, sizeof err);
        if (st != VS_OK) {
            vs_set_error(ctx, st, "%s: %s", path, err);
            break;
        }
        /* one page per file: a multi-page TIFF among the slices would
         * otherwise give only its first page */
        int pages = 1;
        st = io->count_pages(r, 2, &pages, err, sizeof err);
        if (st != VS_OK) vs_set_error(ctx, st, "%s: %s", path, err);
        else if (pages > 1)
            st = vs_set_error(ctx, VS_ERR_FORMAT,
                              "%s: not one slice series: %s has several pages (a multi-page stack: give that "
                              "file itself, not the folder)",
                              path, names[z]);
        if (st == VS_OK) st = stack_add(&s, r, 0, (int)z, names[z]);
        io->close(r);
    }
    for (size_t i = 0; i < n; i++) free(names[i]);
    free(names);
    return stack_finish(&s, st, out);
}

/* ---- ustar archive of slices ---- */

typedef struct tar_member {
    uint64_t offset, size;
    char name[272];
} tar_member;

/* Octal numeric field (NUL/space padded).  Base-256 sizes (>8 GB members)
 * are refused: no slice is that large. */
static int tar_octal(const unsigned char *f, size_t len, uint64_t *out)
{
    size_t i = 0;
    uint64_t v = 0;
    while (i < len && f[i] == ' ') i++;
    int digits = 0;
    for (; i < len && f[i] >= '0' && f[i] <= '7'; i++, digits++) {
        if (v >> 60) return 0;
        v = v * 8 + (uint64_t)(f[i] - '0');
    }
    for (; i < len; i++)
        if (f[i] != ' ' && f[i] != '\0') return 0;
    if (!digits) return 0;
    *out = v;
    return 1;
}

static int tar_checksum_ok(const unsigned char *h)
{
    uint64_t stored;
    if (!tar_octal(h + 148, 8, &stored)) return 0;
    uint64_t u = 0;
    int64_t s = 0;
    for (int i = 0; i < 512; i++) {
        unsigned char c = (i >= 148 && i < 156) ? ' ' : h[i];
        u += c;
        s += (signed char)c; /* some old tars summed signed bytes */
    }
    return stored == u || (int64_t)stored == s;
}

/* Lists the slice members; the message names the archive and the offset. */
static vs_status tar_list(vs_context *ctx, const char *path, FILE *f, uint64_t fsize,
                          tar_member **out, size_t *count)
{
    tar_member *m = NULL;
    size_t n = 0, cap = 0;
    uint64_t off = 0;
    char longname[256] = "";
    unsigned char h[512];
    vs_status st = VS_OK;
    for (;;) {
        if (off == fsize) break; /* no end blocks: tolerate, as GNU tar does */
        if (off + 512 > fsize) {
            st = vs_set_error(ctx, VS_ERR_FORMAT, "%s: truncated tar header at offset %llu", path,
                              (unsigned long long)off);
            break;
        }
        if (fseeko(f, (off_t)off, SEEK_SET) != 0 || fread(h, 1, 512, f) != 512) {
            st = vs_set_error(ctx, VS_ERR_IO, "%s: cannot read at offset %llu", path,
                              (unsigned long long)off);
            break;
        }
        int zero = 1;
        for (int i = 0; i < 512 && zero; i++) zero = h[i] == 0;
        if (zero) break; /* end of archive */
        uint64_t size;
        if (!tar_checksum_ok(h) || !tar_octal(h + 124, 12, &size)) {
            st = vs_set_error(ctx, VS_ERR_FORMAT,
                              "%s: corrupt tar header at offset %llu (bad checksum or size field)",
                              path, (unsigned long long)off);
            break;
        }
        uint64_t data = off + 512;
        if (size > fsize - data) {
            st = vs_set_error(ctx, VS_ERR_FORMAT,
                              "%s: truncated: tar member at offset %llu claims %llu bytes, only "
                              "%llu remain",
                              path, (unsigned long long)off, (unsigned long long)size,
                              (unsigned long long)(fsize - data));
            break;
        }
        char type = (char)h[156];
        char name[272]; /* prefix (155) + '/' + name (100) */
        if (longname[0]) {
            snprintf(name, sizeof name, "%s", longname);
            longname[0] = '\0';
        } else {
            char nm[101], prefix[156];
            memcpy(nm, h, 100);
            nm[100] = '\0';
            memcpy(prefix, h + 345, 155);
            prefix[155] = '\0';
            if (memcmp(h + 257, "ustar", 5) == 0 && prefix[0] && memcmp(h + 257, "ustar ", 6) != 0)
                snprintf(name, sizeof name, "%.155s/%.100s", prefix, nm);
            else
                snprintf(name, sizeof name, "%s", nm);
        }
        if (type == 'L') { /* GNU long name: the data is the next member's name */
            size_t k = size < sizeof longname - 1 ? (size_t)size : sizeof longname - 1;
            if (fread(longname, 1, k, f) != k) {
                st = vs_set_error(ctx, VS_ERR_IO, "%s: cannot read at offset %llu", path,
                                  (unsigned long long)data);
                break;
            }
            longname[k] = '\0';
        } else if ((type == '0' || type == '\0' || type == '7') && is_slice_name(name)) {
            if (n >= (size_t)VS_MAX_DIM) {
                st = vs_set_error(ctx, VS_ERR_TOO_LARGE, "%s: more than %d slices", path, VS_MAX_DIM);
                break;
            }
            if (n == cap) {
                size_t nc = cap ? 2 * cap : 64;
                tar_member *p = realloc(m, nc * sizeof *p);
                if (!p) {
                    st = vs_set_error(ctx, VS_ERR_OUT_OF_MEMORY, "%s: out of memory", path);
                    break;
                }
                m = p;
                cap = nc;
            }
            m[n].offset = data;
            m[n].size = size;
            snprintf(m[n].name, sizeof m[n].name, "%s", name);
            n++;
        }
        /* directories, pax headers, links and other files are skipped */
        off = data + (size + 511) / 512 * 512;
        if (off > fsize) {
            st = vs_set_error(ctx, VS_ERR_FORMAT,
                              "%s: truncated: the archive ends inside the member at offset %llu",
                              path, (unsigned long long)(data - 512));
            break;
        }
    }
    if (st == VS_OK && n == 0)
        st = vs_set_error(ctx, VS_ERR_FORMAT, "%s: no .png, .tif or .tiff members in the archive",
                          path);
    if (st != VS_OK) {
        free(m);
        return st;
    }
    *out = m;
    *count = n;
    return VS_OK;
}

vs_status vs_load_tar(vs_context *ctx, const char *path, vs_volume **out)
{
    uint64_t fsize;
    vs_status st = vs_load_file_size(ctx, path, &fsize);
    if (st != VS_OK) return st;
    if (fsize == 0) return vs_set_error(ctx, VS_ERR_FORMAT, "%s: empty file", path);
    const vs_oiio_api *io = vs_oiio(ctx);
    if (!io) return VS_ERR_IO;
    FILE *f = fopen(path, "rb");
    if (!f) return vs_set_error(ctx, VS_ERR_IO, "%s: cannot open: %s", path, strerror(errno));
    tar_member *m = NULL;
    size_t n = 0;
    st = tar_list(ctx, path, f, fsize, &m, &n);
    if (st != VS_OK) {
        fclose(f);
        return st;
    }
    uint64_t total = 0;
    for (size_t i = 0; i < n; i++) total += m[i].size;
    stack s = {.ctx = ctx, .io = io, .path = path, .nz = (int)n, .encoded = total, .tiff = is_tiff_name(m[0].name)};
    unsigned char *buf = NULL;
    for (size_t z = 0; st == VS_OK && z < n; z++) {
        if (m[z].size == 0) {
            st = vs_set_error(ctx, VS_ERR_FORMAT, "%s: member %s is empty", path, m[z].name);
            break;
        }
        /* Bounded by the archive size, checked while listing. */
        unsigned char *p = realloc(buf, (size_t)m[z].size);
        if (!p) {
            st = vs_set_error(ctx, VS_ERR_OUT_OF_MEMORY, "%s: out of memory", path);
            break;
        }
        buf = p;
        if (fseeko(f, (off_t)m[z].offset, SEEK_SET) != 0 ||
            fread(buf, 1, (size_t)m[z].size, f) != m[z].size) {
            st = vs_set_error(ctx, VS_ERR_IO, "%s: cannot read member %s", path, m[z].name);
            break;
        }
        char err[400];
        vs_oiio_reader *r;
        snprintf(err, sizeof err, "%s: %s", path, m[z].name);
        if ((st = vs_tiff_check(ctx, err, buf, (size_t)m[z].size)) != VS_OK) break;
        st = io->open(m[z].name, buf, (size_t)m[z].size, &r, err, sizeof err);
        if (st != VS_OK) {
            vs_set_error(ctx, st, "%s: %s", path, err);
            break;
        }
        int pages = 1;
        st = io->count_pages(r, 2, &pages, err, sizeof err);
        if (st != VS_OK) vs_set_error(ctx, st, "%s: %s", path, err);
        else if (pages > 1)
            st = vs_set_error(ctx, VS_ERR_FORMAT,
                              "%s: not one slice series: member %s has several pages (a multi-page stack)", path,
                              m[z].name);
        if (st == VS_OK) st = stack_add(&s, r, 0, (int)z, m[z].name);
        io->close(r);
    }
    free(buf);
    free(m);
    fclose(f);
    return stack_finish(&s, st, out);
}
