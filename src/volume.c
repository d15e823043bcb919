/* Dense typed volumes: allocation with checked sizes, accessors, value range,
 * and the histogram-based default iso-value (Otsu). */
#include "volume.h"
#include "context.h"

#include <float.h>
#include <stdatomic.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>

static atomic_uint_fast64_t volume_serial;

size_t vs_type_size(vs_type t)
{
    switch (t) {
    case VS_U8: return 1;
    case VS_I16:
    case VS_U16: return 2;
    case VS_F32: return 4;
    }
    return 0;
}

const char *vs_type_name(vs_type t)
{
    switch (t) {
    case VS_U8: return "u8";
    case VS_I16: return "i16";
    case VS_U16: return "u16";
    case VS_F32: return "f32";
    }
    return "unknown";
}

vs_status vs_volume_alloc_shell(vs_context *ctx, vs_type type, const int dims[3],
                                const double spacing[3], struct vs_volume **out)
{
    if (!dims || !out) return vs_set_error(ctx, VS_ERR_INVALID_ARGUMENT, "volume: NULL argument");
    *out = NULL;
    if (vs_type_size(type) == 0)
        return vs_set_error(ctx, VS_ERR_INVALID_ARGUMENT, "volume: unknown voxel type %d", (int)type);
    uint64_t n = 1;
    for (int a = 0; a < 3; a++) {
        if (dims[a] < 1 || dims[a] > VS_MAX_DIM)
            return vs_set_error(ctx, VS_ERR_TOO_LARGE,
                                "volume: dimension %d is %d (must be 1..%d)", a, dims[a], VS_MAX_DIM);
        n *= (uint64_t)dims[a];
        double sp = spacing ? spacing[a] : 1.0;
        if (!(sp > 0.0) || !isfinite(sp) || sp > 1e12 || sp < 1e-12)
            return vs_set_error(ctx, VS_ERR_INVALID_ARGUMENT,
                                "volume: spacing %d is %g (must be finite and > 0)", a, sp);
    }
    if (n > VS_MAX_VOXELS)
        return vs_set_error(ctx, VS_ERR_TOO_LARGE, "volume: %llu voxels exceed the limit of %llu",
                            (unsigned long long)n, (unsigned long long)VS_MAX_VOXELS);
    struct vs_volume *v = calloc(1, sizeof *v);
    if (!v) return vs_set_error(ctx, VS_ERR_OUT_OF_MEMORY, "volume: out of memory");
    v->type = type;
    for (int a = 0; a < 3; a++) {
        v->dims[a] = dims[a];
        v->spacing[a] = spacing ? spacing[a] : 1.0;
        v->affine[a][a] = v->spacing[a];
    }
    v->default_iso = NAN;
    v->default_ramp = NAN;
    v->serial = v->data_serial = atomic_fetch_add(&volume_serial, 1) + 1;
    *out = v;
    return VS_OK;
}

/* The memory this process can still take: the kernel's estimate of what
 * can be allocated without swapping (MemAvailable), capped by the
 * address-space and data limits (ulimit -v, -d, which cluster schedulers
 * set).  *what names the bound; 0 when none can be read. */
static uint64_t memory_available(const char **what)
{
    uint64_t avail = 0;
    *what = "";
    FILE *f = fopen("/proc/meminfo", "r");
    if (f) {
        char line[256];
        unsigned long long kb;
        while (fgets(line, sizeof line, f))
            if (sscanf(line, "MemAvailable: %llu kB", &kb) == 1) {
                avail = (uint64_t)kb * 1024u;
                *what = "memory available";
                break;
            }
        fclose(f);
    }
    static const struct { int res; const char *name; } limits[] = {{RLIMIT_AS, "address-space limit"},
                                                                   {RLIMIT_DATA, "data-size limit"}};
    for (size_t i = 0; i < sizeof limits / sizeof limits[0]; i++) {
        struct rlimit rl;
        if (getrlimit(limits[i].res, &rl) == 0 && rl.rlim_cur != RLIM_INFINITY &&
            (avail == 0 || (uint64_t)rl.rlim_cur < avail)) {
            avail = (uint64_t)rl.rlim_cur;
            *what = limits[i].name;
        }
    }
    return avail;
}

vs_status vs_volume_alloc(vs_context *ctx, vs_type type, const int dims[3],
                          const double spacing[3], struct vs_volume **out)
{
    vs_status st = vs_volume_alloc_shell(ctx, type, dims, spacing, out);
    if (st != VS_OK) return st;
    struct vs_volume *v = *out;
    const size_t n = (size_t)dims[0] * (size_t)dims[1] * (size_t)dims[2];
    /* Refused up front, with what it needs: Linux overcommits, so a volume
     * larger than memory would be allocated and the process killed while
     * the file is read into it.  Asked only for large volumes: small ones
     * (levels, test volumes, fuzzed inputs) skip reading /proc each time. */
    const char *bound = "";
    const uint64_t need = (uint64_t)n * vs_type_size(type);
    const uint64_t avail = need >= ((uint64_t)64 << 20) ? memory_available(&bound) : 0;
    if (avail && need > avail) {
        free(v);
        *out = NULL;
        return vs_set_error(ctx, VS_ERR_TOO_LARGE,
                            "volume of %dx%dx%d %s voxels needs %.2f GB, more than the %.2f GB of the %s",
                            dims[0], dims[1], dims[2], vs_type_name(type), need / 1e9, avail / 1e9, bound);
    }
    v->data = calloc(n, vs_type_size(type));
    if (!v->data) {
        free(v);
        *out = NULL;
        return vs_set_error(ctx, VS_ERR_OUT_OF_MEMORY, "volume: cannot allocate %llu bytes",
                            (unsigned long long)n * vs_type_size(type));
    }
    return VS_OK;
}

vs_status vs_volume_create(vs_context *ctx, vs_type type, const int dims[3],
                           const double spacing[3], vs_volume **out)
{
    return vs_volume_alloc(ctx, type, dims, spacing, out);
}

void vs_volume_release(vs_volume *v)
{
    if (!v) return;
    if (!v->wrapped)
        free(v->data);
    else if (v->release)
        v->release(v->release_user, v->data);
    free(v);
}

void *vs_volume_data(vs_volume *v) { return v ? v->data : NULL; }
void vs_volume_dims(const vs_volume *v, int dims[3])
{
    if (!dims) return;
    for (int a = 0; a < 3; a++) dims[a] = v ? v->dims[a] : 0;
}
void vs_volume_spacing(const vs_volume *v, double spacing[3])
{
    if (!spacing) return;
    for (int a = 0; a < 3; a++) spacing[a] = v ? v->spacing[a] : 0.0;
}
vs_status vs_volume_set_affine(vs_context *ctx, struct vs_volume *v, const double m[3][4])
{
    double sp[3];
    for (int c = 0; c < 3; c++) {
        sp[c] = sqrt(m[0][c] * m[0][c] + m[1][c] * m[1][c] + m[2][c] * m[2][c]);
        if (!isfinite(sp[c]) || !(sp[c] > 1e-12) || sp[c] > 1e12 || !isfinite(m[c][3]))
            return vs_set_error(ctx, VS_ERR_INVALID_ARGUMENT,
                                "volume: orientation matrix column %d has length %g (must be finite and > 0)", c,
                                sp[c]);
    }
    double det = m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1]) -
                 m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0]) +
                 m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0]);
    if (!(fabs(det) > 1e-6 * sp[0] * sp[1] * sp[2]))
        return vs_set_error(ctx, VS_ERR_INVALID_ARGUMENT, "volume: orientation matrix is singular");
    for (int r = 0; r < 3; r++)
        for (int c = 0; c < 4; c++) v->affine[r][c] = m[r][c];
    for (int a = 0; a < 3; a++) v->spacing[a] = sp[a];
    v->has_orientation = 1;
    return VS_OK;
}
vs_status vs_volume_set_transform(vs_context *ctx, vs_volume *v, const double m[12])
{
    if (!v || !m) return vs_set_error(ctx, VS_ERR_INVALID_ARGUMENT, "volume transform: NULL argument");
    const double a[3][4] = {{m[0], m[1], m[2], m[3]}, {m[4], m[5], m[6], m[7]}, {m[8], m[9], m[10], m[11]}};
    return vs_volume_set_affine(ctx, v, a);
}
int vs_volume_affine(const vs_volume *v, double m[12])
{
    if (!m) return 0;
    for (int r = 0; r < 3; r++)
        for (int c = 0; c < 4; c++) m[4 * r + c] = v ? v->affine[r][c] : 0.0;
    return v ? v->has_orientation : 0;
}
vs_type vs_volume_type(const vs_volume *v) { return v ? v->type : VS_U8; }
int vs_volume_has_analytic(const vs_volume *v) { return v && v->has_analytic; }

void vs_volume_range(const vs_volume *v, double *lo, double *hi)
{
    if (lo) *lo = v ? v->vmin : 0.0;
    if (hi) *hi = v ? v->vmax : 0.0;
}

/* The least and greatest of n integers of type T (a loop the compiler
 * vectorises). */
#define INT_RANGE(T)                                                                                               \
    do {                                                                                                           \
        const T *p = v->data;                                                                                      \
        T a = p[0], b = p[0];                                                                                      \
        for (size_t i = 1; i < n; i++) {                                                                           \
            a = p[i] < a ? p[i] : a;                                                                               \
            b = p[i] > b ? p[i] : b;                                                                               \
        }                                                                                                          \
        lo = a;                                                                                                    \
        hi = b;                                                                                                    \
    } while (0)

void vs_volume_update_range(vs_volume *v)
{
    if (!v) return;
    size_t n = (size_t)v->dims[0] * v->dims[1] * v->dims[2];
    double lo = DBL_MAX, hi = -DBL_MAX;
    switch (v->type) {
    case VS_U8: INT_RANGE(uint8_t); break;
    case VS_I16: INT_RANGE(int16_t); break;
    case VS_U16: INT_RANGE(uint16_t); break;
    default: {
        const float *p = v->data;
        float a = FLT_MAX, b = -FLT_MAX;
        for (size_t i = 0; i < n; i++) {
            if (!isfinite(p[i])) continue;
            a = p[i] < a ? p[i] : a;
            b = p[i] > b ? p[i] : b;
        }
        if (a <= b) {
            lo = a;
            hi = b;
        }
    } break;
    }
    if (lo > hi) lo = hi = 0.0; /* no finite value at all */
    v->vmin = lo;
    v->vmax = hi;
    v->serial = v->data_serial = atomic_fetch_add(&volume_serial, 1) + 1; /* the data may have changed */
}

/* A fresh serial: the caches keyed on the old one are rebuilt. */
static void new_serial(struct vs_volume *v) { v->serial = atomic_fetch_add(&volume_serial, 1) + 1; }

vs_status vs_volume_set_range(vs_volume *v, double lo, double hi)
{
    if (!v || !isfinite(lo) || !isfinite(hi) || lo > hi) return VS_ERR_INVALID_ARGUMENT;
    v->vmin = lo;
    v->vmax = hi;
    new_serial(v); /* tables keyed on the range; the voxels are the same */
    return VS_OK;
}

double vs_volume_base(const struct vs_volume *v)
{
    if (!(v->vmin < 0.0) || !(v->vmin < v->vmax) || !(v->vmax - v->vmin <= 0.25 * FLT_MAX)) return 0.0;
    return v->vmin;
}

void vs_volume_histogram(const vs_volume *v, double hist[VS_HISTOGRAM_BINS])
{
    if (!v || !hist) return;
    const double lo = v->vmin, hi = v->vmax;
    const size_t n = (size_t)v->dims[0] * v->dims[1] * v->dims[2];
    const double scale = hi > lo ? (VS_HISTOGRAM_BINS - 1) / (hi - lo) : 0.0;
    for (size_t i = 0; i < n; i++) {
        double x = vs_volume_at(v, i);
        if (!isfinite(x)) continue;
        /* clamped: a declared range may be narrower than the data */
        double b = (x - lo) * scale;
        hist[b < 0.0 ? 0 : b > VS_HISTOGRAM_BINS - 1 ? VS_HISTOGRAM_BINS - 1 : (int)b] += 1.0;
    }
}

double vs_histogram_iso(const double hist[VS_HISTOGRAM_BINS], double lo, double hi)
{
    enum { BINS = VS_HISTOGRAM_BINS };
    if (!hist || !(hi > lo)) return lo;
    const double scale = (BINS - 1) / (hi - lo);
    /* Otsu: maximise between-class variance. */
    double total = 0, sum = 0;
    for (int i = 0; i < BINS; i++) {
        total += hist[i];
        sum += i * hist[i];
    }
    double w0 = 0, s0 = 0, best = -1;
    int best_t = BINS / 2;
    for (int t = 0; t < BINS - 1; t++) {
        w0 += hist[t];
        s0 += t * hist[t];
        double w1 = total - w0;
        if (w0 <= 0 || w1 <= 0) continue;
        double m0 = s0 / w0, m1 = (sum - s0) / w1;
        double between = w0 * w1 * (m0 - m1) * (m0 - m1);
        if (between > best) {
            best = between;
            best_t = t;
        }
    }
    return lo + (best_t + 0.5) / scale;
}

double vs_volume_default_iso(const vs_volume *v)
{
    if (!v) return 0.0;
    if (isfinite(v->default_iso)) return v->default_iso;
    if (!(v->vmax > v->vmin)) return v->vmin;
    double hist[VS_HISTOGRAM_BINS] = {0};
    vs_volume_histogram(v, hist);
    return vs_histogram_iso(hist, v->vmin, v->vmax);
}

/* rounded to nearest (half away from zero) and saturated to the type */
static inline float round_clamp(float x, float lo, float hi)
{
    x = x < lo ? lo : x > hi ? hi : x;
    return x >= 0.0f ? x + 0.5f : x - 0.5f; /* truncated by the cast */
}

void vs_volume_store_floats(struct vs_volume *v, size_t at, const float *x, int n)
{
    switch (v->type) {
    case VS_U8:
        for (int i = 0; i < n; i++) ((uint8_t *)v->data)[at + i] = (uint8_t)round_clamp(x[i], 0.0f, 255.0f);
        break;
    case VS_I16:
        for (int i = 0; i < n; i++)
            ((int16_t *)v->data)[at + i] = (int16_t)round_clamp(x[i], -32768.0f, 32767.0f);
        break;
    case VS_U16:
        for (int i = 0; i < n; i++) ((uint16_t *)v->data)[at + i] = (uint16_t)round_clamp(x[i], 0.0f, 65535.0f);
        break;
    default: memcpy((float *)v->data + at, x, (size_t)n * sizeof *x);
    }
}

double vs_volume_index_in(const struct vs_volume *from, const struct vs_volume *to, int a, double c)
{
    /* along the axis's unit direction u: to's index of the world point
     * from's transform puts at c */
    double shift = 0.0;
    for (int r = 0; r < 3; r++) shift += from->affine[r][a] / from->spacing[a] * (from->affine[r][3] - to->affine[r][3]);
    return (c * from->spacing[a] + shift) / to->spacing[a];
}

#define AXPY(T, CONV)                                                                                              \
    do {                                                                                                           \
        const T *x = (const T *)v->data + at;                                                                      \
        if (first)                                                                                                 \
            for (size_t i = 0; i < n; i++) out[i] = w * CONV(x[i]);                                                \
        else                                                                                                       \
            for (size_t i = 0; i < n; i++) out[i] += w * CONV(x[i]);                                               \
    } while (0)
#define AS_FLOAT(x) ((float)(x))
#define AS_FINITE(x) (isfinite(x) ? (x) : base)

void vs_volume_axpy_floats(const struct vs_volume *v, size_t at, size_t n, float w, float base, int first, float *out)
{
    switch (v->type) {
    case VS_U8: AXPY(uint8_t, AS_FLOAT); break;
    case VS_I16: AXPY(int16_t, AS_FLOAT); break;
    case VS_U16: AXPY(uint16_t, AS_FLOAT); break;
    default: AXPY(float, AS_FINITE); break;
    }
}

void vs_volume_share_classification(struct vs_volume *copy, const struct vs_volume *v)
{
    copy->vmin = v->vmin;
    copy->vmax = v->vmax;
    copy->default_iso = v->default_iso;
    copy->default_ramp = v->default_ramp;
}

void vs_volume_stamp_take(vs_volume_stamp *st, const struct vs_volume *v)
{
    st->vol = v;
    st->serial = v->serial;
    st->data_serial = v->data_serial;
    memcpy(st->spacing, v->spacing, sizeof st->spacing);
    memcpy(st->affine, v->affine, sizeof st->affine);
    st->has_orientation = v->has_orientation;
    st->base = vs_volume_base(v);
}

int vs_volume_stamp_same_field(const vs_volume_stamp *st, const struct vs_volume *v)
{
    return st->vol == v && st->data_serial == v->data_serial && !memcmp(st->spacing, v->spacing, sizeof st->spacing) &&
           st->base == vs_volume_base(v);
}

int vs_volume_stamp_same_place(const vs_volume_stamp *st, const struct vs_volume *v)
{
    return !memcmp(st->affine, v->affine, sizeof st->affine) && st->has_orientation == v->has_orientation;
}
