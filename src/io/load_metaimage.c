/* ITK MetaImage: a text header of "Key = Value" lines, then the voxels in
 * the same file (.mha, ElementDataFile = LOCAL) or in the file the last key
 * names (.mhd).  A header this small is read here rather than through ITK.
 * TransformMatrix lists the world direction of index axis 0, then 1, then
 * 2, in ITK's LPS world; Offset is voxel 0's position. */
#include "context.h"
#include "load.h"
#include "load_common.h"

#include <ctype.h>
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <zlib.h>

enum { HEADER_MAX = 1 << 16 };

typedef struct meta {
    int ndims;
    int64_t dims[3];
    double spacing[3];
    int has_transform, has_offset;
    double transform[9], offset[3];
    const char *type_name;
    vs_type out;          /* the volume's type                         */
    size_t elem;          /* bytes per stored element                  */
    int kind;             /* 0 unsigned, 1 signed, 2 float             */
    int msb;              /* big-endian data                           */
    int compressed;
    int64_t compressed_size; /* -1: to the end of the file             */
    int64_t header_size;     /* bytes to skip in the data file; -1: the
                                data is the file's last bytes          */
    char data_file[1024];    /* "" for LOCAL                           */
    uint64_t data_offset;    /* LOCAL: where the header ends           */
} meta;

static const struct {
    const char *name;
    vs_type out;
    size_t elem;
    int kind;
} types[] = {
    {"MET_UCHAR", VS_U8, 1, 0},  {"MET_CHAR", VS_I16, 1, 1},   {"MET_SHORT", VS_I16, 2, 1},
    {"MET_USHORT", VS_U16, 2, 0}, {"MET_INT", VS_F32, 4, 1},    {"MET_UINT", VS_F32, 4, 0},
    {"MET_FLOAT", VS_F32, 4, 2}, {"MET_DOUBLE", VS_F32, 8, 2},
};

/* Up to n numbers separated by blanks; returns how many. */
static int numbers(const char *s, double *out, int n)
{
    int k = 0;
    while (k < n) {
        char *end;
        errno = 0;
        double v = strtod(s, &end);
        if (end == s || errno || !isfinite(v)) break;
        out[k++] = v;
        s = end;
    }
    while (isspace((unsigned char)*s)) s++;
    return *s ? -1 : k; /* trailing junk or too many values */
}

static int truth(const char *v)
{
    return !strcasecmp(v, "true") || !strcasecmp(v, "1") || !strcasecmp(v, "yes");
}

/* One "Key = Value" line into m; 1 when it was ElementDataFile (the last). */
static vs_status parse_line(vs_context *ctx, const char *path, char *key, char *val, meta *m, int *last)
{
    double v[9];
    int n;
#define IS(k) (strcasecmp(key, k) == 0)
#define BAD(what) vs_set_error(ctx, VS_ERR_FORMAT, "%s: MetaImage %s = \"%s\": " what, path, key, val)
    if (IS("ObjectType")) {
        if (strcasecmp(val, "Image")) return BAD("not an image");
    } else if (IS("NDims")) {
        if (numbers(val, v, 1) != 1 || (v[0] != 2 && v[0] != 3))
            return BAD("only 2 or 3 dimensions are volumes");
        m->ndims = (int)v[0];
    } else if (IS("DimSize")) {
        n = numbers(val, v, 3);
        if (n < 2) return BAD("expected 2 or 3 sizes");
        for (int a = 0; a < 3; a++) {
            double d = a < n ? v[a] : 1;
            /* the limits are vs_load_check_dims's, with their own message */
            if (d != floor(d) || d < 1 || d > 1e9) return BAD("sizes must be whole numbers >= 1");
            m->dims[a] = (int64_t)d;
        }
    } else if (IS("ElementSpacing") || (IS("ElementSize") && m->spacing[0] == 0)) {
        n = numbers(val, v, 3);
        if (n < 2) return BAD("expected 2 or 3 spacings");
        for (int a = 0; a < 3; a++) {
            double d = a < n ? v[a] : 1;
            if (!(d > 0) || d > 1e12) return BAD("spacings must be > 0");
            m->spacing[a] = d;
        }
    } else if (IS("TransformMatrix") || IS("Rotation") || IS("Orientation")) {
        if (numbers(val, v, 9) != 9) return BAD("expected 9 numbers");
        memcpy(m->transform, v, sizeof m->transform);
        m->has_transform = 1;
    } else if (IS("Offset") || IS("Position") || IS("Origin")) {
        if (numbers(val, v, 3) != 3) return BAD("expected 3 numbers");
        memcpy(m->offset, v, sizeof m->offset);
        m->has_offset = 1;
    } else if (IS("ElementType")) {
        size_t k = 0;
        while (k < sizeof types / sizeof *types && strcasecmp(val, types[k].name)) k++;
        if (k == sizeof types / sizeof *types)
            return BAD("not supported (MET_UCHAR, MET_CHAR, MET_SHORT, MET_USHORT, MET_INT, MET_UINT, "
                       "MET_FLOAT or MET_DOUBLE)");
        m->type_name = types[k].name;
        m->out = types[k].out;
        m->elem = types[k].elem;
        m->kind = types[k].kind;
    } else if (IS("ElementNumberOfChannels")) {
        if (numbers(val, v, 1) != 1 || v[0] != 1) return BAD("only one channel is a volume");
    } else if (IS("BinaryData")) {
        if (!truth(val)) return BAD("text (ASCII) voxels are not supported");
    } else if (IS("BinaryDataByteOrderMSB") || IS("ElementByteOrderMSB")) {
        m->msb = truth(val);
    } else if (IS("CompressedData")) {
        m->compressed = truth(val);
    } else if (IS("CompressedDataSize")) {
        if (numbers(val, v, 1) != 1 || v[0] < 1 || v[0] > 1e15 || v[0] != floor(v[0]))
            return BAD("expected a byte count");
        m->compressed_size = (int64_t)v[0];
    } else if (IS("HeaderSize")) {
        if (numbers(val, v, 1) != 1 || v[0] < -1 || v[0] > 1e15 || v[0] != floor(v[0]))
            return BAD("expected a byte count or -1");
        m->header_size = (int64_t)v[0];
    } else if (IS("ElementDataFile")) {
        if (!strcasecmp(val, "LOCAL")) m->data_file[0] = '\0';
        else if (!strncasecmp(val, "LIST", 4) || strchr(val, '%') || strchr(val, ' '))
            return BAD("data split over several files is not supported");
        else if (!*val || strlen(val) >= sizeof m->data_file) return BAD("not a usable file name");
        else snprintf(m->data_file, sizeof m->data_file, "%s", val);
        *last = 1;
    }
    /* other keys (Comment, AnatomicalOrientation, CenterOfRotation,
     * ElementMin/Max, Modality, ...) change nothing here */
#undef IS
#undef BAD
    return VS_OK;
}

static vs_status parse_header(vs_context *ctx, const char *path, FILE *f, meta *m)
{
    memset(m, 0, sizeof *m);
    m->compressed_size = -1;
    m->header_size = 0;
    char line[4096];
    uint64_t pos = 0;
    int last = 0, lines = 0;
    while (!last) {
        if (!fgets(line, sizeof line, f))
            return vs_set_error(ctx, VS_ERR_FORMAT, "%s: MetaImage header ends without ElementDataFile", path);
        size_t len = strlen(line);
        pos += len;
        if (pos > HEADER_MAX || (len == sizeof line - 1 && line[len - 1] != '\n'))
            return vs_set_error(ctx, VS_ERR_FORMAT, "%s: not a MetaImage header (line %d too long)", path,
                                lines + 1);
        if (memchr(line, '\0', len))
            return vs_set_error(ctx, VS_ERR_FORMAT, "%s: not a MetaImage header (binary bytes in line %d)",
                                path, lines + 1);
        lines++;
        while (len && isspace((unsigned char)line[len - 1])) line[--len] = '\0';
        char *k = line;
        while (isspace((unsigned char)*k)) k++;
        if (!*k) continue;
        char *eq = strchr(k, '=');
        if (!eq) return vs_set_error(ctx, VS_ERR_FORMAT, "%s: MetaImage header line %d has no '='", path, lines);
        char *ke = eq;
        while (ke > k && isspace((unsigned char)ke[-1])) ke--;
        *ke = '\0';
        char *val = eq + 1;
        while (isspace((unsigned char)*val)) val++;
        vs_status st = parse_line(ctx, path, k, val, m, &last);
        if (st != VS_OK) return st;
    }
    m->data_offset = pos;
    if (!m->ndims) return vs_set_error(ctx, VS_ERR_FORMAT, "%s: MetaImage header has no NDims", path);
    if (!m->dims[0]) return vs_set_error(ctx, VS_ERR_FORMAT, "%s: MetaImage header has no DimSize", path);
    if (m->ndims == 2 && m->dims[2] != 1)
        return vs_set_error(ctx, VS_ERR_FORMAT, "%s: NDims = 2 but DimSize has 3 sizes", path);
    if (!m->type_name) return vs_set_error(ctx, VS_ERR_FORMAT, "%s: MetaImage header has no ElementType", path);
    if (m->compressed && m->header_size == -1)
        return vs_set_error(ctx, VS_ERR_FORMAT, "%s: HeaderSize = -1 cannot be used with CompressedData", path);
    for (int a = 0; a < 3; a++)
        if (m->spacing[a] == 0) m->spacing[a] = 1.0;
    return VS_OK;
}

/* Inflate exactly `need` bytes (zlib or gzip stream) from f. */
static vs_status inflate_data(vs_context *ctx, const char *path, FILE *f, uint64_t avail, uint64_t need,
                              unsigned char *dst)
{
    if (need > vs_load_inflate_bound(avail))
        return vs_set_error(ctx, VS_ERR_FORMAT, "%s: %llu compressed bytes cannot hold %llu bytes of voxels",
                            path, (unsigned long long)avail, (unsigned long long)need);
    z_stream z;
    memset(&z, 0, sizeof z);
    if (inflateInit2(&z, 15 + 32) != Z_OK) return vs_set_error(ctx, VS_ERR_OUT_OF_MEMORY, "%s: zlib", path);
    unsigned char in[1 << 16];
    uint64_t done = 0;
    int r = Z_OK;
    while (done < need && r != Z_STREAM_END) {
        if (z.avail_in == 0) {
            if (avail == 0) break;
            size_t want = avail < sizeof in ? (size_t)avail : sizeof in;
            size_t got = fread(in, 1, want, f);
            if (got == 0) break;
            avail -= got;
            z.next_in = in;
            z.avail_in = (unsigned)got;
        }
        uint64_t left = need - done;
        z.next_out = dst + done;
        z.avail_out = left > (1u << 30) ? (1u << 30) : (unsigned)left;
        unsigned before = z.avail_out;
        r = inflate(&z, Z_NO_FLUSH);
        done += before - z.avail_out;
        if (r != Z_OK && r != Z_STREAM_END && r != Z_BUF_ERROR) break;
        if (r == Z_BUF_ERROR && z.avail_in == 0 && avail == 0) break;
    }
    inflateEnd(&z);
    if (r != Z_OK && r != Z_STREAM_END && r != Z_BUF_ERROR)
        return vs_set_error(ctx, VS_ERR_FORMAT, "%s: compressed voxels are damaged (zlib: %s)", path,
                            z.msg ? z.msg : "error");
    if (done < need)
        return vs_set_error(ctx, VS_ERR_FORMAT, "%s: truncated: expected %llu bytes of voxels, decompressed %llu",
                            path, (unsigned long long)need, (unsigned long long)done);
    return VS_OK;
}

/* Stored elements (byte order fixed) into the volume's type. */
static void convert(const meta *m, const unsigned char *src, vs_volume *v, size_t n)
{
    for (size_t i = 0; i < n; i++) {
        unsigned char b[8];
        for (size_t k = 0; k < m->elem; k++) b[k] = src[i * m->elem + (m->msb ? m->elem - 1 - k : k)];
        uint64_t u = 0;
        for (size_t k = 0; k < m->elem; k++) u |= (uint64_t)b[k] << (8 * k);
        double x;
        if (m->kind == 2) {
            if (m->elem == 4) {
                uint32_t w = (uint32_t)u;
                float fl;
                memcpy(&fl, &w, 4);
                x = fl;
            } else memcpy(&x, &u, 8);
        } else if (m->kind == 1) {
            int bits = (int)m->elem * 8;
            x = (double)(int64_t)(u << (64 - bits)) / (double)((uint64_t)1 << (64 - bits));
        } else x = (double)u;
        switch (v->type) {
        case VS_U8: ((uint8_t *)v->data)[i] = (uint8_t)x; break;
        case VS_I16: ((int16_t *)v->data)[i] = (int16_t)x; break;
        case VS_U16: ((uint16_t *)v->data)[i] = (uint16_t)x; break;
        default: ((float *)v->data)[i] = (float)x; break;
        }
    }
}

static vs_status read_voxels(vs_context *ctx, const char *path, const meta *m, vs_volume *v)
{
    /* the data file is beside the header */
    char dpath[4096];
    const char *data_path = path;
    if (m->data_file[0]) {
        const char *slash = strrchr(path, '/');
        if (m->data_file[0] == '/' || !slash) snprintf(dpath, sizeof dpath, "%s", m->data_file);
        else snprintf(dpath, sizeof dpath, "%.*s/%s", (int)(slash - path), path, m->data_file);
        data_path = dpath;
    }
    uint64_t fsize;
    vs_status st = vs_load_file_size(ctx, data_path, &fsize);
    if (st != VS_OK) return st;
    const size_t n = (size_t)(m->dims[0] * m->dims[1] * m->dims[2]);
    const uint64_t need = (uint64_t)n * m->elem;
    uint64_t start = m->data_file[0] ? 0 : m->data_offset;
    if (m->header_size > 0) start += (uint64_t)m->header_size;
    if (m->header_size == -1) {
        if (fsize < need)
            return vs_set_error(ctx, VS_ERR_FORMAT, "%s: truncated: %llu bytes of voxels expected, file has %llu",
                                data_path, (unsigned long long)need, (unsigned long long)fsize);
        start = fsize - need;
    }
    if (start > fsize)
        return vs_set_error(ctx, VS_ERR_FORMAT, "%s: HeaderSize %lld is past the end of the file (%llu bytes)",
                            data_path, (long long)m->header_size, (unsigned long long)fsize);
    uint64_t avail = fsize - start;
    if (m->compressed && m->compressed_size > 0) {
        if ((uint64_t)m->compressed_size > avail)
            return vs_set_error(ctx, VS_ERR_FORMAT,
                                "%s: truncated: CompressedDataSize %lld but %llu bytes in the file", data_path,
                                (long long)m->compressed_size, (unsigned long long)avail);
        avail = (uint64_t)m->compressed_size;
    }
    if (!m->compressed && avail < need)
        return vs_set_error(ctx, VS_ERR_FORMAT, "%s: truncated: expected %llu bytes of voxels, file has %llu",
                            data_path, (unsigned long long)need, (unsigned long long)avail);
    FILE *f = fopen(data_path, "rb");
    if (!f) return vs_set_error(ctx, VS_ERR_IO, "%s: cannot open: %s", data_path, strerror(errno));
    /* Elements of the volume's own type are read into it (no second copy
     * of the data), others through a buffer and converted. */
    const int own = m->elem == vs_type_size(v->type) &&
                    (v->type == VS_F32 ? m->kind == 2 : m->kind == (v->type == VS_I16 ? 1 : 0));
    unsigned char *buf = own ? v->data : malloc(need ? (size_t)need : 1);
    if (!buf) {
        fclose(f);
        return vs_set_error(ctx, VS_ERR_OUT_OF_MEMORY, "%s: out of memory for %llu bytes", data_path,
                            (unsigned long long)need);
    }
    if (fseeko(f, (off_t)start, SEEK_SET) != 0) st = vs_set_error(ctx, VS_ERR_IO, "%s: cannot seek", data_path);
    else if (m->compressed) st = inflate_data(ctx, data_path, f, avail, need, buf);
    else if (fread(buf, 1, (size_t)need, f) != need)
        st = vs_set_error(ctx, VS_ERR_IO, "%s: cannot read %llu bytes", data_path, (unsigned long long)need);
    fclose(f);
    const uint16_t one = 1;
    const int host_msb = *(const unsigned char *)&one == 0;
    if (st == VS_OK && own && m->elem > 1 && m->msb != host_msb) vs_load_swap_bytes(buf, n, m->elem);
    if (st == VS_OK && !own) convert(m, buf, v, n);
    if (!own) free(buf);
    return st;
}

vs_status vs_load_metaimage(vs_context *ctx, const char *path, vs_volume **out)
{
    uint64_t fsize;
    vs_status st = vs_load_file_size(ctx, path, &fsize);
    if (st != VS_OK) return st;
    FILE *f = fopen(path, "rb");
    if (!f) return vs_set_error(ctx, VS_ERR_IO, "%s: cannot open: %s", path, strerror(errno));
    meta m;
    st = parse_header(ctx, path, f, &m);
    fclose(f);
    if (st != VS_OK) return st;
    st = vs_load_check_dims(ctx, path, m.dims, m.elem, NULL);
    if (st != VS_OK) return st;
    const int dims[3] = {(int)m.dims[0], (int)m.dims[1], (int)m.dims[2]};
    vs_volume *v = NULL;
    st = vs_load_alloc(ctx, path, m.out, dims, m.spacing, &v);
    if (st == VS_OK) st = read_voxels(ctx, path, &m, v);
    if (st == VS_OK && (m.has_transform || m.has_offset)) {
        static const double id[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1};
        const double *d = m.has_transform ? m.transform : id;
        double a[3][4];
        for (int r = 0; r < 3; r++) {
            for (int c = 0; c < 3; c++) a[r][c] = d[3 * c + r] * m.spacing[c];
            a[r][3] = m.has_offset ? m.offset[r] : 0.0;
        }
        /* ITK's world is LPS: x and y change sign for RAS */
        for (int r = 0; r < 2; r++)
            for (int c = 0; c < 4; c++) a[r][c] = -a[r][c];
        st = vs_volume_set_affine(ctx, v, a);
        if (st != VS_OK) vs_set_error(ctx, st, "%s: TransformMatrix is singular", path);
    }
    if (st != VS_OK) {
        vs_volume_release(v);
        return st;
    }
    *out = v;
    return VS_OK;
}
