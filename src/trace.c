/* Timelines of frames as Chrome Trace Event JSON (trace.h), which Perfetto
 * and chrome://tracing open: one "complete" event per span, a thread per
 * worker (thread 0 is the one that called vs_render), times in
 * microseconds from the first span. */
#include "context.h"
#include "trace.h"

#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

struct vs_trace {
    vs_span *s;
    size_t n, cap;
    int frames;
    int failed;
};

static const char *const span_names[VS_SPAN_COUNT] = {
    "frame", "setup", "relevant voxels", "levels of detail", "binning", "tiles", "ray casting", "tile",
    "projection", "splatting", "classification", "shading", "compositing", "occlusion map"};

int vs_span_grow(vs_span_buf *b)
{
    const size_t cap = b->cap ? 2 * b->cap : 4096;
    vs_span *s = realloc(b->s, cap * sizeof *s);
    if (!s) {
        b->failed = 1;
        return 0;
    }
    b->s = s;
    b->cap = cap;
    return 1;
}

vs_status vs_trace_create(vs_trace **out)
{
    if (!out) return VS_ERR_INVALID_ARGUMENT;
    *out = calloc(1, sizeof **out);
    return *out ? VS_OK : VS_ERR_OUT_OF_MEMORY;
}

void vs_trace_release(vs_trace *t)
{
    if (!t) return;
    free(t->s);
    free(t);
}

size_t vs_trace_spans(const vs_trace *t) { return t ? t->n : 0; }

int vs_trace_append(vs_trace *t, const vs_span_buf *b)
{
    if (b->failed) t->failed = 1;
    if (t->n + b->n > t->cap) {
        size_t cap = t->cap ? t->cap : 4096;
        while (cap < t->n + b->n) cap *= 2;
        vs_span *s = realloc(t->s, cap * sizeof *s);
        if (!s) {
            t->failed = 1;
            return 0;
        }
        t->s = s;
        t->cap = cap;
    }
    if (b->n) memcpy(t->s + t->n, b->s, b->n * sizeof *b->s);
    t->n += b->n;
    return 1;
}

void vs_trace_frame_done(vs_trace *t) { t->frames++; }

vs_status vs_trace_write(vs_context *ctx, const vs_trace *t, const char *path)
{
    if (!t || !path) return vs_set_error(ctx, VS_ERR_INVALID_ARGUMENT, "vs_trace_write: no trace or no path");
    if (t->failed)
        return vs_set_error(ctx, VS_ERR_OUT_OF_MEMORY, "%s: out of memory while recording the trace", path);
    FILE *f = fopen(path, "w");
    if (!f) return vs_set_error(ctx, VS_ERR_IO, "%s: cannot write: %s", path, strerror(errno));
    double epoch = 0.0;
    int workers = 0;
    for (size_t i = 0; i < t->n; i++) {
        if (i == 0 || t->s[i].t0 < epoch) epoch = t->s[i].t0;
        if (t->s[i].worker + 1 > workers) workers = t->s[i].worker + 1;
    }
    fprintf(f, "{\"displayTimeUnit\": \"ms\", \"otherData\": {\"generator\": \"vsplat %s\", \"frames\": %d},\n"
               "\"traceEvents\": [\n",
            VS_VERSION_STRING, t->frames);
    fprintf(f, "{\"name\": \"process_name\", \"ph\": \"M\", \"pid\": 1, \"tid\": 0, \"args\": {\"name\": \"vsplat\"}}");
    for (int w = 0; w < workers; w++)
        fprintf(f,
                ",\n{\"name\": \"thread_name\", \"ph\": \"M\", \"pid\": 1, \"tid\": %d, \"args\": {\"name\": \"%s %d\"}}",
                w, w ? "worker" : "caller, worker", w);
    for (size_t i = 0; i < t->n; i++) {
        const vs_span *s = &t->s[i];
        fprintf(f, ",\n{\"name\": \"%s\", \"cat\": \"%s\", \"ph\": \"X\", \"ts\": %.3f, \"dur\": %.3f, \"pid\": 1, \"tid\": %d",
                span_names[s->name], s->name >= VS_SPAN_PROJECT ? "stage" : (s->name == VS_SPAN_TILE ? "tile" : "frame"),
                (s->t0 - epoch) * 1e3, (s->t1 - s->t0) * 1e3, s->worker);
        if (s->tile >= 0) fprintf(f, ", \"args\": {\"tile\": %d}", s->tile);
        fputc('}', f);
    }
    fputs("\n]}\n", f);
    const int bad = ferror(f);
    if (fclose(f) != 0 || bad) return vs_set_error(ctx, VS_ERR_IO, "%s: write failed", path);
    return VS_OK;
}
