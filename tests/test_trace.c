/* Profiling a stage: the timeline (vs_trace, --trace) and the work counts.
 * A frame rendered on two threads into a trace is written as Chrome Trace
 * Event JSON and read back with cJSON: the file has the format's structure,
 * every span lies inside its thread's tile or frame span, spans of a
 * thread never overlap but for nesting, and each stage's spans add up to
 * that stage's time in the stats.  The work counts obey what the stages do
 * by construction (culling only with occlusion, fewer floats when culling,
 * shaded pixels among the classified ones). */
#include "testutil.h"

#include <cjson/cJSON.h>

static vs_context *ctx;

typedef struct span {
    const char *name, *cat;
    double ts, dur; /* microseconds */
    int tid, tile;
} span;

static int by_tid_ts(const void *a, const void *b)
{
    const span *x = a, *y = b;
    if (x->tid != y->tid) return x->tid - y->tid;
    if (x->ts != y->ts) return x->ts < y->ts ? -1 : 1;
    return x->dur > y->dur ? -1 : x->dur < y->dur; /* the enclosing span first */
}

static int is_stage(const char *n)
{
    static const char *const stages[] = {"projection", "splatting", "classification", "shading", "compositing",
                                         "occlusion map"};
    for (int i = 0; i < 6; i++)
        if (!strcmp(n, stages[i])) return 1;
    return 0;
}

/* Sum of the durations (ms) of spans named a or b. */
static double sum_ms(const span *s, int n, const char *a, const char *b)
{
    double t = 0;
    for (int i = 0; i < n; i++)
        if (!strcmp(s[i].name, a) || (b && !strcmp(s[i].name, b))) t += s[i].dur * 1e-3;
    return t;
}

static void check_trace(const char *path, const vs_stats *st, int threads)
{
    size_t len = 0;
    char *text = (char *)tu_read_file(path, &len);
    CHECK(text != NULL, "%s not written", path);
    if (!text) return;
    cJSON *root = cJSON_ParseWithLength(text, len);
    CHECK(root != NULL, "%s is not JSON", path);
    const cJSON *ev = cJSON_GetObjectItemCaseSensitive(root, "traceEvents");
    CHECK(cJSON_IsArray(ev), "no traceEvents array");
    const int nev = cJSON_GetArraySize(ev);
    span *s = calloc((size_t)(nev > 0 ? nev : 1), sizeof *s);
    int n = 0, named[64] = {0};
    const cJSON *e;
    cJSON_ArrayForEach(e, ev)
    {
        const cJSON *name = cJSON_GetObjectItemCaseSensitive(e, "name"), *ph = cJSON_GetObjectItemCaseSensitive(e, "ph"),
                    *pid = cJSON_GetObjectItemCaseSensitive(e, "pid"), *tid = cJSON_GetObjectItemCaseSensitive(e, "tid");
        CHECK(cJSON_IsString(name) && cJSON_IsString(ph) && cJSON_IsNumber(pid) && cJSON_IsNumber(tid),
              "an event without name, ph, pid or tid");
        if (!cJSON_IsString(ph) || !cJSON_IsNumber(tid)) continue;
        if (!strcmp(ph->valuestring, "M")) {
            if (!strcmp(name->valuestring, "thread_name") && tid->valueint >= 0 && tid->valueint < 64)
                named[tid->valueint] = 1;
            continue;
        }
        CHECK(!strcmp(ph->valuestring, "X"), "event phase %s (only complete events expected)", ph->valuestring);
        const cJSON *ts = cJSON_GetObjectItemCaseSensitive(e, "ts"), *dur = cJSON_GetObjectItemCaseSensitive(e, "dur"),
                    *cat = cJSON_GetObjectItemCaseSensitive(e, "cat"), *args = cJSON_GetObjectItemCaseSensitive(e, "args");
        CHECK(cJSON_IsNumber(ts) && cJSON_IsNumber(dur) && cJSON_IsString(cat), "span %s without ts, dur or cat",
              name->valuestring);
        if (!cJSON_IsNumber(ts) || !cJSON_IsNumber(dur) || !cJSON_IsString(cat)) continue;
        CHECK(ts->valuedouble >= 0 && dur->valuedouble >= 0, "span %s at %g for %g us", name->valuestring,
              ts->valuedouble, dur->valuedouble);
        const cJSON *tile = args ? cJSON_GetObjectItemCaseSensitive(args, "tile") : NULL;
        s[n++] = (span){name->valuestring, cat->valuestring, ts->valuedouble, dur->valuedouble, tid->valueint,
                        cJSON_IsNumber(tile) ? tile->valueint : -1};
    }
    qsort(s, (size_t)n, sizeof *s, by_tid_ts);

    /* every thread that has spans is named, and with two threads both have tiles */
    int tiles_of[64] = {0}, stages = 0;
    for (int i = 0; i < n; i++) {
        CHECK(s[i].tid >= 0 && s[i].tid < threads, "span on thread %d of %d", s[i].tid, threads);
        if (s[i].tid < 0 || s[i].tid >= 64) continue;
        CHECK(named[s[i].tid], "thread %d has spans but no thread_name", s[i].tid);
        if (!strcmp(s[i].name, "tile")) tiles_of[s[i].tid]++;
        stages += is_stage(s[i].name);
    }
    for (int w = 0; w < threads; w++) CHECK(tiles_of[w] > 0, "thread %d has no tile span", w);
    CHECK(stages > 0, "no stage spans");

    /* nesting, per thread: a stage span inside its tile's span (same tile),
     * a tile inside the frame's "tiles" span on thread 0, stage spans of a
     * tile in sequence */
    const double eps = 0.002; /* us: ts and dur are printed to 1 ns */
    for (int i = 0; i < n; i++) {
        if (is_stage(s[i].name)) {
            int inside = 0;
            for (int j = i - 1; j >= 0 && s[j].tid == s[i].tid; j--)
                if (!strcmp(s[j].name, "tile")) {
                    inside = s[j].tile == s[i].tile && s[i].ts >= s[j].ts - eps &&
                             s[i].ts + s[i].dur <= s[j].ts + s[j].dur + eps;
                    break;
                }
            CHECK(inside, "%s span of tile %d at %.3f us (thread %d) is not inside its tile's span", s[i].name,
                  s[i].tile, s[i].ts, s[i].tid);
            if (i + 1 < n && s[i + 1].tid == s[i].tid && is_stage(s[i + 1].name))
                CHECK(s[i + 1].ts >= s[i].ts + s[i].dur - eps, "%s and %s spans overlap on thread %d", s[i].name,
                      s[i + 1].name, s[i].tid);
        } else if (!strcmp(s[i].name, "tile")) {
            for (int j = i + 1; j < n && s[j].tid == s[i].tid; j++)
                if (!strcmp(s[j].name, "tile")) {
                    CHECK(s[j].ts >= s[i].ts + s[i].dur - eps, "tiles %d and %d overlap on thread %d", s[i].tile,
                          s[j].tile, s[i].tid);
                    break;
                }
            if (s[i].tid == 0) {
                int inside = 0;
                for (int j = 0; j < n && s[j].tid == 0; j++)
                    if (!strcmp(s[j].name, "tiles"))
                        inside |= s[i].ts >= s[j].ts - eps && s[i].ts + s[i].dur <= s[j].ts + s[j].dur + eps;
                CHECK(inside, "tile %d on thread 0 outside the frame's tiles span", s[i].tile);
            }
        } else {
            CHECK(s[i].tid == 0, "frame span %s on thread %d", s[i].name, s[i].tid);
            if (strcmp(s[i].name, "frame")) {
                int inside = 0;
                for (int j = 0; j < n && s[j].tid == 0; j++)
                    if (!strcmp(s[j].name, "frame"))
                        inside |= s[i].ts >= s[j].ts - eps && s[i].ts + s[i].dur <= s[j].ts + s[j].dur + eps;
                CHECK(inside, "%s span outside the frame span", s[i].name);
            }
        }
    }

    /* the stage spans add up to the stage times of the stats */
    const struct {
        const char *a, *b;
        double ms;
    } sums[4] = {{"projection", "splatting", st->ms_stage.rasterize},
                 {"classification", NULL, st->ms_stage.gradient},
                 {"shading", NULL, st->ms_stage.shade},
                 {"compositing", "occlusion map", st->ms_stage.composite}};
    for (int k = 0; k < 4; k++) {
        const double got = sum_ms(s, n, sums[k].a, sums[k].b);
        CHECK(fabs(got - sums[k].ms) <= 1e-6 * n + 1e-9 * sums[k].ms, "%s%s%s spans add up to %.6f ms, stats say %.6f",
              sums[k].a, sums[k].b ? " + " : "", sums[k].b ? sums[k].b : "", got, sums[k].ms);
        printf("  %-28s %9.3f ms in spans, %9.3f ms in the stats\n", sums[k].a, got, sums[k].ms);
    }
    printf("%s: %d spans on %d threads (%d and %d tiles), nested, adding up to the stage times\n", path, n, threads,
           tiles_of[0], threads > 1 ? tiles_of[1] : 0);
    free(s);
    cJSON_Delete(root);
    free(text);
}

int main(void)
{
    if (vs_context_create(&ctx) != VS_OK) return 2;
    char dir[512];
    if (!tu_make_tmpdir(dir, sizeof dir, "trace")) return 2;
    vs_volume *v = tu_scene(ctx, "sphere:96");
    if (!v) TEST_DONE();
    vs_settings s;
    vs_settings_init(&s);
    s.width = s.height = 256;
    s.tile_size = 16; /* many tiles: both workers get some */
    s.threads = 2;
    s.azimuth = 30;
    s.elevation = 20;

    for (int p = VS_PIPELINE_PRE; p <= VS_PIPELINE_POST_ALPHA; p++) {
        vs_trace *tr = NULL;
        CHECK(vs_trace_create(&tr) == VS_OK, "vs_trace_create");
        s.pipeline = (vs_pipeline)p;
        s.trace = tr;
        vs_image img;
        vs_stats st;
        CHECK(vs_render(ctx, v, &s, &img, &st) == VS_OK, "render: %s", vs_last_error(ctx));
        CHECK(vs_trace_spans(tr) > 0, "%s: no spans recorded", vs_pipeline_name(s.pipeline));
        char path[600];
        snprintf(path, sizeof path, "%s/%s.json", dir, vs_pipeline_name(s.pipeline));
        CHECK(vs_trace_write(ctx, tr, path) == VS_OK, "write: %s", vs_last_error(ctx));
        check_trace(path, &st, st.threads);
        CHECK(st.threads == 2, "rendered on %d threads", st.threads);

        /* a second frame appends to the same trace */
        const size_t n1 = vs_trace_spans(tr);
        vs_image img2;
        CHECK(vs_render(ctx, v, &s, &img2, NULL) == VS_OK, "second render");
        CHECK(vs_trace_spans(tr) > n1, "the second frame added no spans");
        CHECK(tu_max_diff(&img, &img2) == 0.0, "tracing changed the image");
        vs_image_free(&img2);

        /* without a trace: the same image, and the trace is left alone */
        const size_t n2 = vs_trace_spans(tr);
        s.trace = NULL;
        CHECK(vs_render(ctx, v, &s, &img2, NULL) == VS_OK, "untraced render");
        CHECK(vs_trace_spans(tr) == n2, "a render without the trace recorded into it");
        CHECK(tu_max_diff(&img, &img2) == 0.0, "the traced image differs from the untraced one");
        vs_image_free(&img2);

        /* work counts by construction */
        CHECK(st.voxels_projected > 0 && st.footprint_floats > 0 && st.pixels_classified > 0 && st.pixels_shaded > 0,
              "%s: a count is zero", vs_pipeline_name(s.pipeline));
        CHECK(st.pixels_shaded <= st.pixels_classified, "more pixels shaded than classified");
        CHECK(st.bytes_read.rasterize == 4 * st.footprint_floats, "rasterize bytes read");
        CHECK(st.voxels_tested > 0 && st.voxels_culled > 0, "%s: occlusion tested nothing",
              vs_pipeline_name(s.pipeline));
        s.occlusion = 0;
        vs_stats all;
        CHECK(vs_render(ctx, v, &s, &img2, &all) == VS_OK, "render without occlusion");
        CHECK(all.voxels_tested == 0 && all.voxels_culled == 0 && all.bricks_culled == 0,
              "tests or culls without occlusion: %llu %llu %llu", (unsigned long long)all.voxels_tested,
              (unsigned long long)all.voxels_culled, (unsigned long long)all.bricks_culled);
        CHECK(all.footprint_floats > st.footprint_floats && all.voxels_splatted > st.voxels_splatted,
              "culling saved no footprint floats (%llu vs %llu)", (unsigned long long)st.footprint_floats,
              (unsigned long long)all.footprint_floats);
        s.occlusion = 1;
        vs_image_free(&img2);
        printf("  %s: %llu voxels projected, %llu tested, %llu floats added (%llu without culling), %llu of %llu "
               "pixels shaded\n",
               vs_pipeline_name(s.pipeline), (unsigned long long)st.voxels_projected,
               (unsigned long long)st.voxels_tested, (unsigned long long)st.footprint_floats,
               (unsigned long long)all.footprint_floats, (unsigned long long)st.pixels_shaded,
               (unsigned long long)st.pixels_classified);
        vs_image_free(&img);
        vs_trace_release(tr);
    }

    /* levels of detail: the frame that builds a level shows the build as a
     * span inside its frame span, as long as the stats say; the next frame,
     * which reuses it, shows none */
    {
        vs_trace *tr = NULL;
        CHECK(vs_trace_create(&tr) == VS_OK, "vs_trace_create");
        vs_settings l = s;
        l.pipeline = VS_PIPELINE_POST_CD;
        l.width = l.height = 40;
        l.tile_size = 8;
        l.trace = tr;
        vs_context *c2 = NULL;
        CHECK(vs_context_create(&c2) == VS_OK, "context");
        vs_image img;
        vs_stats st, st2;
        CHECK(vs_render(c2, v, &l, &img, &st) == VS_OK, "render: %s", vs_last_error(c2));
        CHECK(st.lod_level > 0 && st.ms_lod > 0, "a 96^3 sphere at 40x40 used level %d (%.3f ms building it)",
              st.lod_level, st.ms_lod);
        vs_image_free(&img);
        char path[600];
        snprintf(path, sizeof path, "%s/lod.json", dir);
        CHECK(vs_trace_write(c2, tr, path) == VS_OK, "write: %s", vs_last_error(c2));
        check_trace(path, &st, st.threads);
        size_t len = 0;
        char *text = (char *)tu_read_file(path, &len);
        cJSON *root = text ? cJSON_ParseWithLength(text, len) : NULL;
        int spans = 0;
        double ms = 0;
        const cJSON *e;
        cJSON_ArrayForEach(e, cJSON_GetObjectItemCaseSensitive(root, "traceEvents"))
        {
            const cJSON *name = cJSON_GetObjectItemCaseSensitive(e, "name");
            if (cJSON_IsString(name) && !strcmp(name->valuestring, "levels of detail")) {
                spans++;
                ms = cJSON_GetNumberValue(cJSON_GetObjectItemCaseSensitive(e, "dur")) * 1e-3;
            }
        }
        CHECK(spans == 1, "%d levels-of-detail spans in the first frame", spans);
        CHECK(ms >= st.ms_lod - 1e-3, "the levels-of-detail span lasts %.4f ms, the stats say %.4f", ms, st.ms_lod);
        printf("levels of detail: level %d built in %.3f ms, one span of %.3f ms\n", st.lod_level, st.ms_lod, ms);
        cJSON_Delete(root);
        free(text);
        const size_t n1 = vs_trace_spans(tr);
        CHECK(vs_render(c2, v, &l, &img, &st2) == VS_OK, "second render");
        CHECK(st2.lod_level == st.lod_level && st2.ms_lod == 0.0, "the second frame rebuilt the level");
        CHECK(vs_trace_spans(tr) > n1, "the second frame added no spans");
        vs_image_free(&img);
        CHECK(vs_trace_write(c2, tr, path) == VS_OK, "write: %s", vs_last_error(c2));
        text = (char *)tu_read_file(path, &len);
        int again = 0;
        for (const char *q = text; q && (q = strstr(q, "\"levels of detail\"")); q++) again++;
        CHECK(again == 1, "%d levels-of-detail spans after a frame that reused the level", again);
        free(text);
        vs_context_release(c2);
        vs_trace_release(tr);
    }

    /* the ray caster: one frame span, one ray-casting span */
    {
        vs_trace *tr = NULL;
        vs_trace_create(&tr);
        s.pipeline = VS_PIPELINE_RAYCAST;
        s.width = s.height = 32;
        s.trace = tr;
        vs_image img;
        CHECK(vs_render(ctx, v, &s, &img, NULL) == VS_OK, "raycast: %s", vs_last_error(ctx));
        CHECK(vs_trace_spans(tr) == 2, "raycast recorded %zu spans", vs_trace_spans(tr));
        vs_image_free(&img);
        /* a folder is not a file */
        CHECK(vs_trace_write(ctx, tr, dir) == VS_ERR_IO, "writing the trace over a folder did not fail");
        CHECK(strstr(vs_last_error(ctx), dir) != NULL, "the message does not name the path: %s", vs_last_error(ctx));
        vs_trace_release(tr);
    }
    CHECK(vs_trace_write(ctx, NULL, "x.json") == VS_ERR_INVALID_ARGUMENT, "NULL trace accepted");
    CHECK(vs_trace_create(NULL) == VS_ERR_INVALID_ARGUMENT, "NULL out accepted");
    vs_trace_release(NULL);
    vs_volume_release(v);
    vs_context_release(ctx);
    tu_remove_tmpdir(dir);
    TEST_DONE();
}
