/* Render statistics as JSON.
 *
 * vs_stats_to_json() behaves like snprintf: it returns the number of bytes the
 * full document needs (excluding the terminating NUL) and writes at most cap
 * bytes, always NUL-terminated when cap > 0.  Non-finite numbers become null,
 * so the output is always valid JSON.  Only the fields the caller's layout
 * (st->struct_size, src/abi.c) holds are read and written.  No global state. */
#include "abi.h"

#include <inttypes.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

typedef struct json_out {
    char *buf;
    size_t cap;
    size_t len; /* bytes needed so far (may exceed cap) */
} json_out;

static void put_raw(json_out *o, const char *s, size_t n)
{
    if (o->len < o->cap) {
        size_t room = o->cap - o->len;
        memcpy(o->buf + o->len, s, n < room ? n : room);
    }
    o->len += n;
}

static void put_str(json_out *o, const char *s) { put_raw(o, s, strlen(s)); }

#if defined(__GNUC__)
__attribute__((format(printf, 2, 3)))
#endif
static void put_fmt(json_out *o, const char *fmt, ...)
{
    char tmp[64];
    va_list ap;
    va_start(ap, fmt);
    int n = vsnprintf(tmp, sizeof tmp, fmt, ap);
    va_end(ap);
    if (n < 0) n = 0;
    if ((size_t)n >= sizeof tmp) n = (int)sizeof tmp - 1; /* numbers never get this long */
    put_raw(o, tmp, (size_t)n);
}

/* A JSON string: quotes, backslash and control characters escaped. */
static void put_json_string(json_out *o, const char *s)
{
    if (!s) {
        put_str(o, "null");
        return;
    }
    put_raw(o, "\"", 1);
    for (const unsigned char *p = (const unsigned char *)s; *p; p++) {
        if (*p == '"' || *p == '\\') {
            char e[2] = {'\\', (char)*p};
            put_raw(o, e, 2);
        } else if (*p < 0x20) {
            put_fmt(o, "\\u%04x", (unsigned)*p);
        } else {
            put_raw(o, (const char *)p, 1);
        }
    }
    put_raw(o, "\"", 1);
}

static void put_double(json_out *o, double v)
{
    if (!isfinite(v)) {
        put_str(o, "null");
        return;
    }
    if (v == 0.0) v = 0.0; /* no "-0" */
    /* shortest of %.15g / %.17g that reads back exactly */
    char tmp[40];
    snprintf(tmp, sizeof tmp, "%.15g", v);
    if (strtod(tmp, NULL) != v) snprintf(tmp, sizeof tmp, "%.17g", v);
    put_str(o, tmp);
}

static void key(json_out *o, const char *indent, const char *k)
{
    put_str(o, indent);
    put_json_string(o, k);
    put_str(o, ": ");
}

static void kv_str(json_out *o, const char *k, const char *v)
{
    key(o, "  ", k);
    put_json_string(o, v);
    put_str(o, ",\n");
}

static void kv_u64(json_out *o, const char *k, uint64_t v)
{
    key(o, "  ", k);
    put_fmt(o, "%" PRIu64, v);
    put_str(o, ",\n");
}

static void kv_int(json_out *o, const char *k, int v)
{
    key(o, "  ", k);
    put_fmt(o, "%d", v);
    put_str(o, ",\n");
}

static void kv_dbl(json_out *o, const char *k, double v)
{
    key(o, "  ", k);
    put_double(o, v);
    put_str(o, ",\n");
}

size_t vs_stats_to_json(const vs_stats *st, char *buf, size_t cap)
{
    json_out o = {buf, buf ? cap : 0, 0};
    vs_stats zero;
    if (!st) {
        memset(&zero, 0, sizeof zero);
        zero.struct_size = sizeof zero;
        st = &zero;
    }
    if (!vs_stats_layout_known(st->struct_size)) {
        if (o.cap > 0) o.buf[0] = '\0';
        return 0;
    }
    const size_t size = st->struct_size;
#define HAS(m) (VS_FIELD_END(vs_stats, m) <= size)
    put_str(&o, "{\n");
    if (HAS(pipeline)) kv_str(&o, "pipeline", st->pipeline);
    if (HAS(isa)) kv_str(&o, "isa", st->isa);
    if (HAS(threads)) kv_int(&o, "threads", st->threads);
    if (HAS(width)) kv_int(&o, "width", st->width);
    if (HAS(height)) kv_int(&o, "height", st->height);
    if (HAS(voxels_total)) kv_u64(&o, "voxels_total", st->voxels_total);
    if (HAS(voxels_relevant)) kv_u64(&o, "voxels_relevant", st->voxels_relevant);
    if (HAS(voxels_splatted)) kv_u64(&o, "voxels_splatted", st->voxels_splatted);
    if (HAS(voxels_culled)) kv_u64(&o, "voxels_culled", st->voxels_culled);
    if (HAS(sheets)) kv_u64(&o, "sheets", st->sheets);
    if (HAS(tiles_total)) kv_u64(&o, "tiles_total", st->tiles_total);
    if (HAS(tiles_shaded)) kv_u64(&o, "tiles_shaded", st->tiles_shaded);
    if (HAS(ms_total)) kv_dbl(&o, "ms_total", st->ms_total);
    if (HAS(ms_stage)) {
        key(&o, "  ", "ms_stage");
    put_str(&o, "{\n");
        const struct {
            const char *name;
            double v;
        } stage[5] = {{"setup", st->ms_stage.setup},
                      {"rasterize", st->ms_stage.rasterize},
                      {"gradient", st->ms_stage.gradient},
                      {"shade", st->ms_stage.shade},
                      {"composite", st->ms_stage.composite}};
        for (int i = 0; i < 5; i++) {
            key(&o, "    ", stage[i].name);
            put_double(&o, stage[i].v);
            put_str(&o, i < 4 ? ",\n" : "\n");
        }
        put_str(&o, "  },\n");
    }
    if (HAS(ms_relevant)) kv_dbl(&o, "ms_relevant", st->ms_relevant);
    if (HAS(iso_lo)) kv_dbl(&o, "iso_lo", st->iso_lo);
    if (HAS(iso_hi)) kv_dbl(&o, "iso_hi", st->iso_hi);
    if (HAS(ramp)) kv_dbl(&o, "ramp", st->ramp);
    if (HAS(pin_warning)) kv_int(&o, "pin_warning", st->pin_warning);
    if (HAS(bricks_culled)) kv_u64(&o, "bricks_culled", st->bricks_culled);
    if (HAS(voxels_projected)) kv_u64(&o, "voxels_projected", st->voxels_projected);
    if (HAS(voxels_tested)) kv_u64(&o, "voxels_tested", st->voxels_tested);
    if (HAS(footprint_floats)) kv_u64(&o, "footprint_floats", st->footprint_floats);
    if (HAS(pixels_classified)) kv_u64(&o, "pixels_classified", st->pixels_classified);
    if (HAS(pixels_shaded)) kv_u64(&o, "pixels_shaded", st->pixels_shaded);
    for (int rw = 0; rw < 2; rw++) {
        const vs_stage_bytes *b = rw ? &st->bytes_written : &st->bytes_read;
        if (!(rw ? HAS(bytes_written) : HAS(bytes_read))) continue;
        key(&o, "  ", rw ? "bytes_written" : "bytes_read");
        put_str(&o, "{\n");
        const struct {
            const char *name;
            uint64_t v;
        } stage[4] = {{"rasterize", b->rasterize}, {"gradient", b->gradient}, {"shade", b->shade},
                      {"composite", b->composite}};
        for (int i = 0; i < 4; i++) {
            key(&o, "    ", stage[i].name);
            put_fmt(&o, "%" PRIu64, stage[i].v);
            put_str(&o, i < 3 ? ",\n" : "\n");
        }
        put_str(&o, "  },\n");
    }
    if (HAS(ms_lod)) kv_dbl(&o, "ms_lod", st->ms_lod);
    if (HAS(lod_level)) kv_int(&o, "lod_level", st->lod_level);
    if (HAS(ms_resample)) kv_dbl(&o, "ms_resample", st->ms_resample);
    if (HAS(resampled)) kv_int(&o, "resampled", st->resampled);
#undef HAS
    key(&o, "  ", "version");
    put_json_string(&o, VS_VERSION_STRING);
    put_str(&o, "\n}\n");

    if (o.cap > 0) o.buf[o.len < o.cap ? o.len : o.cap - 1] = '\0';
    return o.len;
}
