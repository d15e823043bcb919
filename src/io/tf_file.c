/* Transfer-function files -> piecewise-linear vs_tf_point arrays.
 *
 * Three formats (chosen by the extension, else by the first bytes):
 *
 *  .json  ParaView colour-map preset (parsed with cJSON): an array of presets
 *         (the first one is used) or one preset object.  "RGBPoints"
 *         [x,r,g,b, ...] is the colour, interpolated linearly in RGB whatever
 *         "ColorSpace" says.  "Points" [x,opacity,midpoint,sharpness, ...] is
 *         the opacity, evaluated like vtkPiecewiseFunction (midpoint and
 *         sharpness shape each segment; shaped segments are sampled at
 *         TF_SEGMENT_SAMPLES points).  Without "Points", opacity rises
 *         linearly from 0 at the first RGB point to 1 at the last (ParaView's
 *         default ramp).  x is in data units, as stored (presets are not
 *         rescaled to the volume).  ParaView's opacity is per sample at its
 *         "scalar opacity unit distance"; vsplat takes it as opacity per unit
 *         length of one voxel directly.  Outside the points both functions
 *         keep their end values (VTK's clamping).
 *
 *  .1dt   ImageVis3D 1-D transfer function: the entry count N, then N
 *         entries "r g b a" in [0,1].  The file has no value axis: entry i is
 *         placed at vmin + i (vmax - vmin) / (N - 1) of the volume's value
 *         range (N = 1: a constant), so it needs a volume.
 *
 *  .vtf   vsplat's own text format, '#' comments, one entry per line:
 *           iso LO HI R G B A RAMP   an iso-range: opacity A and colour RGB
 *                                    inside [LO,HI] with the --iso/--ramp
 *                                    rule (0 at LO-RAMP, A at LO+RAMP, A at
 *                                    HI-RAMP, 0 at HI+RAMP; HI may be inf)
 *           point V R G B A          a raw control point (values ascending)
 *         iso ranges (any order; sorted here) must not overlap including
 *         their ramps; iso and point lines are not mixed in one file.
 *
 * Everything malformed is VS_ERR_FORMAT with a message naming the file and
 * the line (text formats), line and column (JSON syntax) or JSON element.
 * Files are capped at TF_MAX_FILE bytes and results at TF_MAX_POINTS points,
 * checked before anything is allocated for them. */
#include "context.h"
#include "volume.h"

#include <cJSON.h>
#include <ctype.h>
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>

#define TF_MAX_FILE (16u << 20)   /* bytes                                  */
#define TF_MAX_POINTS 65536       /* control points in and out              */
#define TF_SEGMENT_SAMPLES 64     /* per midpoint/sharpness-shaped segment  */

/* ---- growing point list ---- */

typedef struct tf_list {
    vs_tf_point *p;
    int n, cap;
} tf_list;

/* 0 ok, 1 too many points, 2 out of memory */
static int tf_push(tf_list *l, double v, double r, double g, double b, double a)
{
    if (l->n >= TF_MAX_POINTS) return 1;
    if (l->n == l->cap) {
        int cap = l->cap ? 2 * l->cap : 64;
        if (cap > TF_MAX_POINTS) cap = TF_MAX_POINTS;
        vs_tf_point *q = realloc(l->p, sizeof *q * (size_t)cap);
        if (!q) return 2;
        l->p = q;
        l->cap = cap;
    }
    vs_tf_point *p = &l->p[l->n++];
    p->value = v;
    p->r = (float)r;
    p->g = (float)g;
    p->b = (float)b;
    p->a = (float)a;
    return 0;
}

static vs_status push_error(vs_context *ctx, const char *path, int code)
{
    if (code == 2) return vs_set_error(ctx, VS_ERR_OUT_OF_MEMORY, "%s: out of memory", path);
    return vs_set_error(ctx, VS_ERR_TOO_LARGE, "%s: more than %d transfer-function points", path,
                        TF_MAX_POINTS);
}

/* Drop interior points that lie on the line between their neighbours (all
 * of r,g,b,a within 1e-6); discontinuities (equal values) are kept. */
static void tf_simplify(tf_list *l)
{
    if (l->n < 3) return;
    vs_tf_point *p = l->p;
    int out = 1; /* p[0] kept; p[out-1] is the anchor */
    for (int i = 1; i < l->n - 1; i++) {
        const vs_tf_point *a = &p[out - 1], *m = &p[i], *b = &p[i + 1];
        int drop = a->value < m->value && m->value < b->value;
        if (drop) {
            double t = (m->value - a->value) / (b->value - a->value);
            drop = fabs(a->r + t * (b->r - a->r) - m->r) < 1e-6 && fabs(a->g + t * (b->g - a->g) - m->g) < 1e-6 &&
                   fabs(a->b + t * (b->b - a->b) - m->b) < 1e-6 && fabs(a->a + t * (b->a - a->a) - m->a) < 1e-6;
        }
        if (!drop) p[out++] = *m;
    }
    p[out++] = p[l->n - 1];
    l->n = out;
}

static float clamp01(double x)
{
    return (float)(x < 0.0 ? 0.0 : x > 1.0 ? 1.0 : x);
}

/* ---- reading the file ---- */

static vs_status read_file(vs_context *ctx, const char *path, char **out, size_t *len)
{
    *out = NULL;
    *len = 0;
    FILE *f = fopen(path, "rb");
    if (!f) return vs_set_error(ctx, VS_ERR_IO, "%s: cannot open: %s", path, strerror(errno));
    size_t cap = 4096, n = 0;
    char *buf = malloc(cap + 1);
    if (!buf) {
        fclose(f);
        return vs_set_error(ctx, VS_ERR_OUT_OF_MEMORY, "%s: out of memory", path);
    }
    for (;;) {
        if (n == cap) {
            if (cap >= TF_MAX_FILE) {
                free(buf);
                fclose(f);
                return vs_set_error(ctx, VS_ERR_TOO_LARGE, "%s: larger than %u bytes: not a transfer function",
                                    path, TF_MAX_FILE);
            }
            cap *= 2;
            char *nb = realloc(buf, cap + 1);
            if (!nb) {
                free(buf);
                fclose(f);
                return vs_set_error(ctx, VS_ERR_OUT_OF_MEMORY, "%s: out of memory", path);
            }
            buf = nb;
        }
        size_t got = fread(buf + n, 1, cap - n, f);
        n += got;
        if (got == 0) break;
    }
    int bad = ferror(f);
    fclose(f);
    if (bad) {
        free(buf);
        return vs_set_error(ctx, VS_ERR_IO, "%s: read error", path);
    }
    buf[n] = '\0';
    const char *nul = memchr(buf, '\0', n);
    if (nul) {
        size_t off = (size_t)(nul - buf);
        free(buf);
        return vs_set_error(ctx, VS_ERR_FORMAT, "%s: NUL byte at offset %zu: not a text file", path, off);
    }
    *out = buf;
    *len = n;
    return VS_OK;
}

static void line_col(const char *buf, size_t off, int *line, int *col)
{
    int l = 1, c = 1;
    for (size_t i = 0; i < off && buf[i]; i++) {
        if (buf[i] == '\n') {
            l++;
            c = 1;
        } else {
            c++;
        }
    }
    *line = l;
    *col = c;
}

/* A whole token as a double; allow_inf also accepts inf / +inf. */
static int token_double(const char *tok, size_t len, int allow_inf, double *out)
{
    char tmp[80];
    if (len == 0 || len >= sizeof tmp) return 0;
    memcpy(tmp, tok, len);
    tmp[len] = '\0';
    if (allow_inf && (!strcasecmp(tmp, "inf") || !strcasecmp(tmp, "+inf") || !strcasecmp(tmp, "infinity"))) {
        *out = INFINITY;
        return 1;
    }
    char *end = NULL;
    errno = 0;
    double v = strtod(tmp, &end);
    if (end != tmp + len || !isfinite(v) || errno == ERANGE) return 0;
    *out = v;
    return 1;
}

/* ---- ParaView JSON ---- */

typedef struct pv_ctx {
    vs_context *ctx;
    const char *path;
    const char *where; /* "preset 'Name'" or "preset" */
} pv_ctx;

/* The numbers of an array key: *vals (malloc'ed), *n; stride 4 checked. */
static vs_status pv_numbers(const pv_ctx *pv, const cJSON *arr, const char *key, double **vals, int *n)
{
    *vals = NULL;
    *n = 0;
    if (!cJSON_IsArray(arr))
        return vs_set_error(pv->ctx, VS_ERR_FORMAT, "%s: %s: \"%s\" must be an array of numbers", pv->path,
                            pv->where, key);
    int count = cJSON_GetArraySize(arr);
    if (count == 0)
        return vs_set_error(pv->ctx, VS_ERR_FORMAT, "%s: %s: \"%s\" is empty", pv->path, pv->where, key);
    if (count % 4 != 0)
        return vs_set_error(pv->ctx, VS_ERR_FORMAT, "%s: %s: \"%s\" has %d numbers, not a multiple of 4 (%s)",
                            pv->path, pv->where, key, count,
                            !strcmp(key, "Points") ? "x,opacity,midpoint,sharpness" : "x,r,g,b");
    if (count / 4 > TF_MAX_POINTS)
        return vs_set_error(pv->ctx, VS_ERR_TOO_LARGE, "%s: %s: \"%s\" has more than %d points", pv->path,
                            pv->where, key, TF_MAX_POINTS);
    double *v = malloc(sizeof *v * (size_t)count);
    if (!v) return vs_set_error(pv->ctx, VS_ERR_OUT_OF_MEMORY, "%s: out of memory", pv->path);
    int i = 0;
    const cJSON *e;
    cJSON_ArrayForEach(e, arr)
    {
        if (!cJSON_IsNumber(e)) {
            free(v);
            return vs_set_error(pv->ctx, VS_ERR_FORMAT, "%s: %s: \"%s\"[%d] is not a number", pv->path, pv->where,
                                key, i);
        }
        if (!isfinite(e->valuedouble)) {
            free(v);
            return vs_set_error(pv->ctx, VS_ERR_FORMAT, "%s: %s: \"%s\"[%d] is not a finite number", pv->path,
                                pv->where, key, i);
        }
        v[i++] = e->valuedouble;
    }
    /* x must not decrease; the other three lie in [0,1] */
    for (int k = 0; k < count; k++) {
        if (k % 4 == 0) {
            if (k > 0 && v[k] < v[k - 4]) {
                double x = v[k], prev = v[k - 4];
                free(v);
                return vs_set_error(pv->ctx, VS_ERR_FORMAT,
                                    "%s: %s: \"%s\"[%d]: x = %g after %g: x values must not decrease", pv->path,
                                    pv->where, key, k, x, prev);
            }
        } else if (!(v[k] >= 0.0 && v[k] <= 1.0)) {
            static const char *const rgb[3] = {"red", "green", "blue"};
            static const char *const pts[3] = {"opacity", "midpoint", "sharpness"};
            double bad = v[k];
            free(v);
            return vs_set_error(pv->ctx, VS_ERR_FORMAT, "%s: %s: \"%s\"[%d]: %s %g is outside [0,1]", pv->path,
                                pv->where, key, k, !strcmp(key, "Points") ? pts[k % 4 - 1] : rgb[k % 4 - 1], bad);
        }
    }
    *vals = v;
    *n = count / 4;
    return VS_OK;
}

/* Colour at x: piecewise linear over rgb[] (n points), clamped. For equal
 * x values the later point wins (as vtkColorTransferFunction keeps it). */
static void pv_color(const double *c, int n, double x, double out[3])
{
    int hi = 0;
    while (hi < n && c[4 * hi] <= x) hi++;
    if (hi == 0) {
        memcpy(out, &c[1], sizeof(double) * 3);
        return;
    }
    if (hi == n) {
        memcpy(out, &c[4 * (n - 1) + 1], sizeof(double) * 3);
        return;
    }
    const double *a = &c[4 * (hi - 1)], *b = &c[4 * hi];
    double t = (x - a[0]) / (b[0] - a[0]);
    for (int k = 0; k < 3; k++) out[k] = a[1 + k] + t * (b[1 + k] - a[1 + k]);
}

/* A "Points" segment starting at point pt (x, opacity, midpoint, sharpness):
 * 0 linear, 1 a step at the midpoint (sharpness > 0.99), 2 a curve. */
static int pv_shape(const double *pt)
{
    if (pt[3] > 0.99) return 1;
    if (pt[3] >= 0.01 || fabs(pt[2] - 0.5) > 1e-9) return 2;
    return 0;
}

static double pv_mid(const double *pt)
{
    return pt[2] < 1e-5 ? 1e-5 : pt[2] > 1.0 - 1e-5 ? 1.0 - 1e-5 : pt[2];
}

/* Where the step of a shape-1 segment a -> b sits. */
static double pv_step_x(const double *a, const double *b)
{
    return a[0] + pv_mid(a) * (b[0] - a[0]);
}

/* vtkPiecewiseFunction::GetTable within one segment a -> b, s in (0,1),
 * for shapes 0 and 2. */
static double pv_segment(const double *a, const double *b, double s)
{
    double y1 = a[1], y2 = b[1], mid = pv_mid(a), sharp = a[3];
    s = s < mid ? 0.5 * s / mid : 0.5 + 0.5 * (s - mid) / (1.0 - mid);
    if (sharp < 0.01) return (1.0 - s) * y1 + s * y2;
    if (s < 0.5)
        s = 0.5 * pow(s * 2.0, 1.0 + 10.0 * sharp);
    else if (s > 0.5)
        s = 1.0 - 0.5 * pow((1.0 - s) * 2.0, 1.0 + 10.0 * sharp);
    double ss = s * s, sss = ss * s;
    double h1 = 2.0 * sss - 3.0 * ss + 1.0, h2 = -2.0 * sss + 3.0 * ss, h3 = sss - 2.0 * ss + s, h4 = sss - ss;
    double t = (1.0 - sharp) * (y2 - y1);
    double v = h1 * y1 + h2 * y2 + h3 * t + h4 * t;
    double lo = y1 < y2 ? y1 : y2, hi = y1 > y2 ? y1 : y2;
    return v < lo ? lo : v > hi ? hi : v;
}

/* Opacity at x; at a step, right selects the limit from the right.  The
 * function is continuous at the points themselves. x values strictly rise. */
static double pv_opacity(const double *o, int n, double x, int right)
{
    if (x <= o[0]) return o[1];
    if (x >= o[4 * (n - 1)]) return o[4 * (n - 1) + 1];
    int i = 0;
    while (o[4 * (i + 1)] <= x) i++;
    const double *a = &o[4 * i], *b = &o[4 * i + 4];
    if (x == a[0]) return a[1];
    if (pv_shape(a) == 1) {
        double xm = pv_step_x(a, b);
        return x < xm || (x == xm && !right) ? a[1] : b[1];
    }
    return pv_segment(a, b, (x - a[0]) / (b[0] - a[0]));
}

/* Equal x values: the later point replaces the earlier (VTK's AddPoint). */
static int pv_dedupe(double *v, int n)
{
    int m = 0;
    for (int i = 0; i < n; i++) {
        if (m > 0 && v[4 * (m - 1)] == v[4 * i]) m--;
        memmove(&v[4 * m], &v[4 * i], sizeof(double) * 4);
        m++;
    }
    return m;
}

static int cmp_double(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return x < y ? -1 : x > y;
}

static vs_status pv_convert(const pv_ctx *pv, const cJSON *preset, tf_list *out)
{
    const char *path = pv->path;
    const cJSON *rgbp = cJSON_GetObjectItemCaseSensitive(preset, "RGBPoints");
    const cJSON *ptsj = cJSON_GetObjectItemCaseSensitive(preset, "Points");
    if (!rgbp) {
        if (cJSON_GetObjectItemCaseSensitive(preset, "IndexedColors"))
            return vs_set_error(pv->ctx, VS_ERR_UNSUPPORTED,
                                "%s: %s: categorical presets (\"IndexedColors\") are not supported", path, pv->where);
        return vs_set_error(pv->ctx, VS_ERR_FORMAT, "%s: %s: no \"RGBPoints\" array", path, pv->where);
    }
    double *c = NULL, *o = NULL;
    int nc = 0, no = 0;
    vs_status st = pv_numbers(pv, rgbp, "RGBPoints", &c, &nc);
    if (st != VS_OK) return st;
    if (ptsj && !cJSON_IsNull(ptsj)) {
        st = pv_numbers(pv, ptsj, "Points", &o, &no);
        if (st != VS_OK) {
            free(c);
            return st;
        }
    } else {
        /* ParaView's default: a linear ramp 0 -> 1 across the colour map */
        o = malloc(sizeof *o * 8);
        if (!o) {
            free(c);
            return vs_set_error(pv->ctx, VS_ERR_OUT_OF_MEMORY, "%s: out of memory", path);
        }
        double x0 = c[0], x1 = c[4 * (nc - 1)];
        double init[8] = {x0, x1 > x0 ? 0.0 : 1.0, 0.5, 0.0, x1, 1.0, 0.5, 0.0};
        memcpy(o, init, sizeof init);
        no = 2;
    }
    nc = pv_dedupe(c, nc);
    no = pv_dedupe(o, no);
    /* Sample positions: every colour and opacity point, the step of a step
     * segment, and interior samples of curved segments. */
    size_t nx = (size_t)nc + (size_t)no;
    for (int i = 0; i + 1 < no; i++) nx += pv_shape(&o[4 * i]) == 2 ? TF_SEGMENT_SAMPLES : 1;
    if (nx > 4 * (size_t)TF_MAX_POINTS) {
        free(c);
        free(o);
        return vs_set_error(pv->ctx, VS_ERR_TOO_LARGE, "%s: %s: too many points", path, pv->where);
    }
    double *xs = malloc(sizeof *xs * nx);
    if (!xs) {
        free(c);
        free(o);
        return vs_set_error(pv->ctx, VS_ERR_OUT_OF_MEMORY, "%s: out of memory", path);
    }
    size_t k = 0;
    for (int i = 0; i < nc; i++) xs[k++] = c[4 * i];
    for (int i = 0; i < no; i++) xs[k++] = o[4 * i];
    for (int i = 0; i + 1 < no; i++) {
        const double *a = &o[4 * i], *b = &o[4 * i + 4];
        int shape = pv_shape(a);
        if (shape == 1) xs[k++] = pv_step_x(a, b);
        if (shape == 2)
            for (int j = 1; j <= TF_SEGMENT_SAMPLES; j++)
                xs[k++] = a[0] + (b[0] - a[0]) * (double)j / (TF_SEGMENT_SAMPLES + 1);
    }
    qsort(xs, k, sizeof *xs, cmp_double);
    int code = 0;
    for (size_t i = 0; i < k && !code; i++) {
        if (i > 0 && xs[i] == xs[i - 1]) continue;
        double rgb[3];
        pv_color(c, nc, xs[i], rgb);
        double al = pv_opacity(o, no, xs[i], 0), ar = pv_opacity(o, no, xs[i], 1);
        code = tf_push(out, xs[i], clamp01(rgb[0]), clamp01(rgb[1]), clamp01(rgb[2]), clamp01(al));
        if (!code && ar != al) code = tf_push(out, xs[i], clamp01(rgb[0]), clamp01(rgb[1]), clamp01(rgb[2]), clamp01(ar));
    }
    free(xs);
    free(c);
    free(o);
    if (code) return push_error(pv->ctx, path, code);
    return VS_OK;
}

static vs_status load_json(vs_context *ctx, const char *path, const char *buf, size_t len, tf_list *out)
{
    const char *end = NULL;
    /* len + 1: the terminating NUL is part of the buffer, so cJSON can
     * demand that nothing but white space follows the value. */
    cJSON *root = cJSON_ParseWithLengthOpts(buf, len + 1, &end, 1);
    if (!root) {
        size_t off = end && end >= buf && end <= buf + len ? (size_t)(end - buf) : 0;
        int line, col;
        line_col(buf, off, &line, &col);
        if (off >= len)
            return vs_set_error(ctx, VS_ERR_FORMAT, "%s: line %d, column %d: malformed JSON (truncated?)", path,
                                line, col);
        char near[24];
        size_t m = 0;
        for (size_t i = off; i < len && m < 16 && buf[i] != '\n' && buf[i] != '\r'; i++)
            near[m++] = isprint((unsigned char)buf[i]) ? buf[i] : '?';
        near[m] = '\0';
        return vs_set_error(ctx, VS_ERR_FORMAT, "%s: line %d, column %d: malformed JSON near '%s'", path, line,
                            col, near);
    }
    const cJSON *preset = root;
    if (cJSON_IsArray(root)) {
        if (cJSON_GetArraySize(root) == 0) {
            cJSON_Delete(root);
            return vs_set_error(ctx, VS_ERR_FORMAT, "%s: empty array: no colour-map preset", path);
        }
        preset = cJSON_GetArrayItem(root, 0);
    }
    if (!cJSON_IsObject(preset)) {
        cJSON_Delete(root);
        return vs_set_error(ctx, VS_ERR_FORMAT, "%s: expected a ParaView preset object (or an array of them)", path);
    }
    char where[160];
    const cJSON *name = cJSON_GetObjectItemCaseSensitive(preset, "Name");
    if (name && !cJSON_IsString(name)) {
        cJSON_Delete(root);
        return vs_set_error(ctx, VS_ERR_FORMAT, "%s: preset \"Name\" must be a string", path);
    }
    if (name)
        snprintf(where, sizeof where, "preset '%.100s'", name->valuestring);
    else
        snprintf(where, sizeof where, "preset");
    pv_ctx pv = {ctx, path, where};
    vs_status st = pv_convert(&pv, preset, out);
    cJSON_Delete(root);
    return st;
}

/* ---- ImageVis3D .1dt ---- */

/* Next white-space separated token at *pos; NULL at the end. *line tracks
 * the line of the token. */
static const char *next_token(const char *buf, size_t len, size_t *pos, int *line, size_t *toklen)
{
    size_t i = *pos;
    while (i < len && isspace((unsigned char)buf[i])) {
        if (buf[i] == '\n') (*line)++;
        i++;
    }
    if (i >= len) {
        *pos = i;
        return NULL;
    }
    size_t s = i;
    while (i < len && !isspace((unsigned char)buf[i])) i++;
    *pos = i;
    *toklen = i - s;
    return buf + s;
}

static vs_status load_1dt(vs_context *ctx, const char *path, const char *buf, size_t len,
                          const struct vs_volume *vol, tf_list *out)
{
    if (!vol)
        return vs_set_error(ctx, VS_ERR_INVALID_ARGUMENT,
                            "%s: an ImageVis3D .1dt file has no value axis; it needs the volume "
                            "(vs_tf_load_for_volume)",
                            path);
    size_t pos = 0, tl = 0;
    int line = 1;
    const char *t = next_token(buf, len, &pos, &line, &tl);
    if (!t) return vs_set_error(ctx, VS_ERR_FORMAT, "%s: empty file (expected the entry count)", path);
    double nd;
    if (!token_double(t, tl, 0, &nd) || nd != floor(nd))
        return vs_set_error(ctx, VS_ERR_FORMAT, "%s: line %d: '%.*s' is not an entry count", path, line,
                            (int)(tl > 40 ? 40 : tl), t);
    if (nd < 1)
        return vs_set_error(ctx, VS_ERR_FORMAT, "%s: line %d: entry count %g: need at least one entry", path, line,
                            nd);
    if (nd > TF_MAX_POINTS)
        return vs_set_error(ctx, VS_ERR_TOO_LARGE, "%s: line %d: entry count %g exceeds the limit %d", path, line,
                            nd, TF_MAX_POINTS);
    int n = (int)nd;
    double lo = vol->vmin, hi = vol->vmax;
    for (int i = 0; i < n; i++) {
        double c[4];
        for (int k = 0; k < 4; k++) {
            t = next_token(buf, len, &pos, &line, &tl);
            if (!t)
                return vs_set_error(ctx, VS_ERR_FORMAT,
                                    "%s: line %d: file ends inside entry %d; the header promises %d entries", path,
                                    line, i + 1, n);
            if (!token_double(t, tl, 0, &c[k]))
                return vs_set_error(ctx, VS_ERR_FORMAT, "%s: line %d: '%.*s' is not a finite number", path, line,
                                    (int)(tl > 40 ? 40 : tl), t);
            if (c[k] < 0.0 || c[k] > 1.0)
                return vs_set_error(ctx, VS_ERR_FORMAT, "%s: line %d: %s %g is outside [0,1]", path, line,
                                    k == 3 ? "opacity" : "colour component", c[k]);
        }
        double v = n == 1 ? lo : lo + (hi - lo) * (double)i / (double)(n - 1);
        int code = tf_push(out, v, c[0], c[1], c[2], c[3]);
        if (code) return push_error(ctx, path, code);
    }
    t = next_token(buf, len, &pos, &line, &tl);
    if (t)
        return vs_set_error(ctx, VS_ERR_FORMAT, "%s: line %d: more data after the %d entries the header promises",
                            path, line, n);
    return VS_OK;
}

/* ---- vsplat .vtf ---- */

typedef struct vtf_iso {
    double lo, hi, r, g, b, a, ramp;
    int line;
} vtf_iso;

static int cmp_iso(const void *x, const void *y)
{
    const vtf_iso *a = x, *b = y;
    return a->lo < b->lo ? -1 : a->lo > b->lo ? 1 : a->line - b->line;
}

static vs_status vtf_emit_iso(vs_context *ctx, const char *path, const vtf_iso *s, tf_list *out)
{
    int code = 0;
    double w = s->ramp;
#define P(v, al) (code ? code : (code = tf_push(out, (v), s->r, s->g, s->b, (al))))
    if (!isfinite(s->hi)) {
        P(s->lo - w, 0.0);
        P(s->lo + w, s->a);
    } else if (w == 0.0) {
        P(s->lo, 0.0);
        P(s->lo, s->a);
        P(s->hi, s->a);
        P(s->hi, 0.0);
    } else if (s->hi - s->lo >= 2.0 * w) {
        P(s->lo - w, 0.0);
        P(s->lo + w, s->a);
        if (s->hi - w > s->lo + w) P(s->hi - w, s->a);
        P(s->hi + w, 0.0);
    } else { /* narrower than the two ramps: a triangle, as the iso rule gives */
        double mid = 0.5 * (s->lo + s->hi);
        P(s->lo - w, 0.0);
        P(mid, s->a * (s->hi - s->lo + 2.0 * w) / (4.0 * w));
        P(s->hi + w, 0.0);
    }
#undef P
    return code ? push_error(ctx, path, code) : VS_OK;
}

static vs_status load_vtf(vs_context *ctx, const char *path, const char *buf, size_t len, tf_list *out)
{
    enum { MAXTOK = 9 };
    vtf_iso *isos = NULL;
    int niso = 0, capiso = 0, npoint = 0, line = 0;
    vs_status st = VS_OK;
    size_t pos = 0;
    while (pos < len && st == VS_OK) {
        line++;
        size_t eol = pos;
        while (eol < len && buf[eol] != '\n') eol++;
        size_t end = eol;
        const char *hash = memchr(buf + pos, '#', eol - pos);
        if (hash) end = (size_t)(hash - buf);
        /* tokens of this line */
        const char *tok[MAXTOK + 1];
        size_t tlen[MAXTOK + 1];
        int nt = 0;
        size_t i = pos;
        while (i < end) {
            while (i < end && isspace((unsigned char)buf[i])) i++;
            if (i >= end) break;
            size_t s = i;
            while (i < end && !isspace((unsigned char)buf[i])) i++;
            if (nt == MAXTOK + 1) {
                nt++;
                break;
            }
            tok[nt] = buf + s;
            tlen[nt] = i - s;
            nt++;
        }
        pos = eol < len ? eol + 1 : eol;
        if (nt == 0) continue;
        int is_iso = tlen[0] == 3 && !strncmp(tok[0], "iso", 3);
        int is_point = tlen[0] == 5 && !strncmp(tok[0], "point", 5);
        if (!is_iso && !is_point) {
            st = vs_set_error(ctx, VS_ERR_FORMAT, "%s: line %d: unknown entry '%.*s' (expected 'iso' or 'point')",
                              path, line, (int)(tlen[0] > 40 ? 40 : tlen[0]), tok[0]);
            break;
        }
        int want = is_iso ? 8 : 6;
        if (nt != want) {
            st = vs_set_error(ctx, VS_ERR_FORMAT, "%s: line %d: expected '%s' with %d numbers, found %s%d", path, line,
                              is_iso ? "iso LO HI R G B A RAMP" : "point V R G B A", want - 1,
                              nt > MAXTOK ? "more than " : "", (nt > MAXTOK ? MAXTOK : nt) - 1);
            break;
        }
        if ((is_iso && npoint) || (is_point && niso)) {
            st = vs_set_error(ctx, VS_ERR_FORMAT, "%s: line %d: 'iso' and 'point' entries cannot be mixed", path,
                              line);
            break;
        }
        double v[8];
        for (int k = 1; k < want && st == VS_OK; k++) {
            if (!token_double(tok[k], tlen[k], is_iso && k == 2, &v[k - 1]))
                st = vs_set_error(ctx, VS_ERR_FORMAT, "%s: line %d: field %d '%.*s' is not a finite number", path,
                                  line, k + 1, (int)(tlen[k] > 40 ? 40 : tlen[k]), tok[k]);
        }
        if (st != VS_OK) break;
        const double *rgba = is_iso ? &v[2] : &v[1];
        for (int k = 0; k < 4; k++)
            if (rgba[k] < 0.0 || rgba[k] > 1.0) {
                st = vs_set_error(ctx, VS_ERR_FORMAT, "%s: line %d: %s %g is outside [0,1]", path, line,
                                  k == 3 ? "opacity" : "colour component", rgba[k]);
                break;
            }
        if (st != VS_OK) break;
        if (is_point) {
            if (out->n > 0 && v[0] < out->p[out->n - 1].value) {
                st = vs_set_error(ctx, VS_ERR_FORMAT, "%s: line %d: point value %g is below the previous %g "
                                  "(values must not decrease)", path, line, v[0], out->p[out->n - 1].value);
                break;
            }
            int code = tf_push(out, v[0], v[1], v[2], v[3], v[4]);
            if (code) st = push_error(ctx, path, code);
            npoint++;
            continue;
        }
        if (v[1] < v[0]) {
            st = vs_set_error(ctx, VS_ERR_FORMAT, "%s: line %d: iso-range %g..%g is empty (HI < LO)", path, line, v[0],
                              v[1]);
            break;
        }
        if (v[6] < 0.0) {
            st = vs_set_error(ctx, VS_ERR_FORMAT, "%s: line %d: ramp %g must not be negative", path, line, v[6]);
            break;
        }
        if (niso >= TF_MAX_POINTS / 4) {
            st = vs_set_error(ctx, VS_ERR_TOO_LARGE, "%s: line %d: more than %d iso-ranges", path, line,
                              TF_MAX_POINTS / 4);
            break;
        }
        if (niso == capiso) {
            int cap = capiso ? 2 * capiso : 8;
            vtf_iso *q = realloc(isos, sizeof *q * (size_t)cap);
            if (!q) {
                st = vs_set_error(ctx, VS_ERR_OUT_OF_MEMORY, "%s: out of memory", path);
                break;
            }
            isos = q;
            capiso = cap;
        }
        vtf_iso *s = &isos[niso++];
        s->lo = v[0];
        s->hi = v[1];
        s->r = v[2];
        s->g = v[3];
        s->b = v[4];
        s->a = v[5];
        s->ramp = v[6];
        s->line = line;
    }
    if (st == VS_OK && niso == 0 && npoint == 0)
        st = vs_set_error(ctx, VS_ERR_FORMAT, "%s: no 'iso' or 'point' entries", path);
    if (st == VS_OK && niso > 0) {
        qsort(isos, (size_t)niso, sizeof *isos, cmp_iso);
        for (int i = 1; i < niso && st == VS_OK; i++) {
            const vtf_iso *a = &isos[i - 1], *b = &isos[i];
            if (!(a->hi + a->ramp <= b->lo - b->ramp))
                st = vs_set_error(ctx, VS_ERR_FORMAT,
                                  "%s: line %d: iso-range %g..%g (ramp %g) overlaps the one on line %d", path,
                                  b->line, b->lo, b->hi, b->ramp, a->line);
        }
        for (int i = 0; i < niso && st == VS_OK; i++) st = vtf_emit_iso(ctx, path, &isos[i], out);
    }
    free(isos);
    return st;
}

/* ---- entry points ---- */

typedef enum tf_format { TF_UNKNOWN, TF_JSON, TF_1DT, TF_VTF } tf_format;

static tf_format format_of(const char *path, const char *buf, size_t len)
{
    const char *slash = strrchr(path, '/');
    const char *dot = strrchr(slash ? slash + 1 : path, '.');
    if (dot) {
        if (!strcasecmp(dot, ".json")) return TF_JSON;
        if (!strcasecmp(dot, ".1dt")) return TF_1DT;
        if (!strcasecmp(dot, ".vtf")) return TF_VTF;
    }
    size_t i = 0;
    if (len >= 3 && (unsigned char)buf[0] == 0xEF && (unsigned char)buf[1] == 0xBB && (unsigned char)buf[2] == 0xBF)
        i = 3;
    while (i < len && isspace((unsigned char)buf[i])) i++;
    if (i >= len) return TF_UNKNOWN;
    if (buf[i] == '[' || buf[i] == '{') return TF_JSON;
    if (buf[i] == '#' || !strncmp(buf + i, "iso", 3) || !strncmp(buf + i, "point", 5)) return TF_VTF;
    if (isdigit((unsigned char)buf[i])) return TF_1DT;
    return TF_UNKNOWN;
}

vs_status vs_tf_load_for_volume(vs_context *ctx, const char *path, const vs_volume *vol, vs_tf_point **points,
                                int *count)
{
    if (points) *points = NULL;
    if (count) *count = 0;
    if (!path || !*path || !points || !count)
        return vs_set_error(ctx, VS_ERR_INVALID_ARGUMENT, "transfer-function file: NULL argument");
    char *buf = NULL;
    size_t len = 0;
    vs_status st = read_file(ctx, path, &buf, &len);
    if (st != VS_OK) return st;
    tf_list l = {NULL, 0, 0};
    switch (format_of(path, buf, len)) {
    case TF_JSON: st = load_json(ctx, path, buf, len, &l); break;
    case TF_1DT: st = load_1dt(ctx, path, buf, len, vol, &l); break;
    case TF_VTF: st = load_vtf(ctx, path, buf, len, &l); break;
    default:
        st = vs_set_error(ctx, VS_ERR_FORMAT,
                          "%s: unknown transfer-function format (use .json ParaView preset, .1dt or .vtf)", path);
    }
    free(buf);
    if (st == VS_OK && l.n == 0) st = vs_set_error(ctx, VS_ERR_FORMAT, "%s: no transfer-function points", path);
    if (st != VS_OK) {
        free(l.p);
        return st;
    }
    tf_simplify(&l);
    *points = l.p;
    *count = l.n;
    return VS_OK;
}

vs_status vs_tf_load(vs_context *ctx, const char *path, vs_tf_point **points, int *count)
{
    return vs_tf_load_for_volume(ctx, path, NULL, points, count);
}

void vs_tf_free(vs_tf_point *points)
{
    free(points);
}
