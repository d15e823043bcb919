/* What vsplat.h promises about threads, checked (and run under TSan by
 * tools/sanitize.sh):
 *  - four contexts in four threads render one shared volume at the same
 *    time (each on its own pool, two frames each: cold and cached) and get
 *    the images one context gets rendering the same settings one after the
 *    other, bit for bit;
 *  - a flag set by another thread and returned by the progress callback
 *    cancels the frame (VS_ERR_CANCELLED, no image), and the same context
 *    then renders the reference image again;
 *  - a second thread's vs_render on a context that is rendering returns
 *    VS_ERR_BUSY at once and leaves the first frame intact.
 * The moments that matter are forced with a condition variable (the
 * callback waits until the other thread has acted), not left to timing. */
#include "testutil.h"

#include <pthread.h>

#define NCTX 4

static vs_volume *vol;
static int size = 160;

static void settings_for(int i, vs_settings *s)
{
    vs_settings_init(s);
    s->width = s->height = size;
    s->pipeline = (vs_pipeline)(i % 4); /* pre, post-cd, post-gs, post-alpha */
    s->azimuth = 25.0 + 40.0 * i;
    s->elevation = 10.0 * i - 15.0;
    s->threads = 2;
    s->pin = 0; /* four pools on the same cores */
    s->tile_size = 32;
}

static int same_image(const vs_image *a, const vs_image *b)
{
    return a->rgba && b->rgba && a->width == b->width && a->height == b->height &&
           !memcmp(a->rgba, b->rgba, (size_t)a->width * a->height * 4 * sizeof(float));
}

/* ---- four contexts at once ---- */
typedef struct job {
    int i;
    pthread_barrier_t *start;
    vs_image img[2];
    vs_status st[2];
    char msg[256];
} job;

static void *render_job(void *arg)
{
    job *j = arg;
    vs_context *c;
    if (vs_context_create(&c) != VS_OK) {
        j->st[0] = VS_ERR_OUT_OF_MEMORY;
        return NULL;
    }
    vs_settings s;
    settings_for(j->i, &s);
    pthread_barrier_wait(j->start); /* all four start together */
    for (int f = 0; f < 2; f++) {
        j->st[f] = vs_render(c, vol, &s, &j->img[f], NULL);
        if (j->st[f] != VS_OK) snprintf(j->msg, sizeof j->msg, "%s", vs_last_error(c));
    }
    vs_context_release(c);
    return NULL;
}

static void check_parallel(const vs_image *ref)
{
    pthread_barrier_t start;
    pthread_barrier_init(&start, NULL, NCTX);
    job jobs[NCTX];
    pthread_t th[NCTX];
    for (int i = 0; i < NCTX; i++) {
        memset(&jobs[i], 0, sizeof jobs[i]);
        jobs[i].i = i;
        jobs[i].start = &start;
        pthread_create(&th[i], NULL, render_job, &jobs[i]);
    }
    for (int i = 0; i < NCTX; i++) pthread_join(th[i], NULL);
    pthread_barrier_destroy(&start);
    for (int i = 0; i < NCTX; i++)
        for (int f = 0; f < 2; f++) {
            CHECK(jobs[i].st[f] == VS_OK, "thread %d frame %d: %s", i, f, jobs[i].msg);
            CHECK(same_image(&jobs[i].img[f], &ref[i]), "thread %d frame %d (%s) differs from the sequential image",
                  i, f, vs_pipeline_name((vs_pipeline)(i % 4)));
            vs_image_free(&jobs[i].img[f]);
        }
    printf("4 contexts in 4 threads, one shared volume, 2 frames each: identical to one after the other\n");
}

/* ---- a callback that holds the frame until another thread has acted ---- */
typedef struct gate {
    pthread_mutex_t mu;
    pthread_cond_t cv;
    int inside; /* the render reached its first callback */
    int acted;  /* the other thread did its part */
    int done;   /* the render returned (without a callback, worker 0 got no tile) */
    int cancel; /* set by the other thread (under mu, as the callback reads it) */
    int calls;
} gate;

static int gated_progress(void *user, double fraction)
{
    gate *g = user;
    /* the closing call (1.0) comes after the tiles; a cancel there is too
     * late to count, so only a call during the tiles opens the gate */
    if (fraction >= 1.0) return 0;
    pthread_mutex_lock(&g->mu);
    g->calls++;
    if (!g->inside) {
        g->inside = 1;
        pthread_cond_broadcast(&g->cv);
        while (!g->acted) pthread_cond_wait(&g->cv, &g->mu);
    }
    const int cancel = g->cancel;
    pthread_mutex_unlock(&g->mu);
    return cancel;
}

static void gate_init(gate *g)
{
    pthread_mutex_init(&g->mu, NULL);
    pthread_cond_init(&g->cv, NULL);
    g->inside = g->acted = g->calls = g->done = g->cancel = 0;
}

/* 1 once the render waits in its callback, 0 if it returned without */
static int gate_wait_inside(gate *g)
{
    pthread_mutex_lock(&g->mu);
    while (!g->inside && !g->done) pthread_cond_wait(&g->cv, &g->mu);
    int inside = g->inside;
    pthread_mutex_unlock(&g->mu);
    return inside;
}

static void gate_release(gate *g, int cancel)
{
    pthread_mutex_lock(&g->mu);
    g->cancel = cancel;
    g->acted = 1;
    pthread_cond_broadcast(&g->cv);
    pthread_mutex_unlock(&g->mu);
}

typedef struct gated_job {
    gate *g;
    vs_context *ctx;
    vs_settings s;
    vs_image img;
    vs_status st;
} gated_job;

static void *gated_render(void *arg)
{
    gated_job *j = arg;
    j->st = vs_render(j->ctx, vol, &j->s, &j->img, NULL);
    pthread_mutex_lock(&j->g->mu);
    j->g->done = 1;
    pthread_cond_broadcast(&j->g->cv);
    pthread_mutex_unlock(&j->g->mu);
    return NULL;
}

/* Another thread sets the cancel flag while the render waits in its
 * callback; the callback returns it. */
static void *canceller(void *arg)
{
    gate *g = arg;
    if (!gate_wait_inside(g)) return NULL;
    gate_release(g, 1);
    return NULL;
}

static void check_cancel(const vs_image *ref)
{
    vs_context *c;
    if (vs_context_create(&c) != VS_OK) return;
    for (int threads = 1; threads <= 2; threads++) {
        gate g;
        gate_init(&g);
        gated_job j = {.g = &g, .ctx = c};
        settings_for(1, &j.s);
        /* one worker: the calling thread renders every tile and so reaches
         * the callback; with two it takes part in the tiles (should the
         * other worker take all 25 first, this case is not exercised) */
        j.s.threads = threads;
        j.s.progress = gated_progress;
        j.s.progress_user = &g;
        pthread_t tr, tc;
        pthread_create(&tc, NULL, canceller, &g);
        pthread_create(&tr, NULL, gated_render, &j);
        pthread_join(tr, NULL);
        pthread_join(tc, NULL);
        if (!g.inside) {
            printf("note: with %d threads the calling thread rendered no tile; cancel not exercised\n", threads);
            vs_image_free(&j.img);
            continue;
        }
        CHECK(j.st == VS_ERR_CANCELLED, "%d threads: cancelled render returned %s (%s)", threads,
              vs_status_string(j.st), vs_last_error(c));
        CHECK(j.img.rgba == NULL, "%d threads: a cancelled render left an image", threads);
        CHECK(strstr(vs_last_error(c), "cancel"), "message: %s", vs_last_error(c));
        vs_image_free(&j.img);
        pthread_mutex_destroy(&g.mu);
        pthread_cond_destroy(&g.cv);

        /* the same context afterwards: the reference image, twice */
        vs_settings s;
        settings_for(1, &s);
        s.threads = threads;
        for (int f = 0; f < 2; f++) {
            vs_image img;
            vs_status st = vs_render(c, vol, &s, &img, NULL);
            CHECK(st == VS_OK, "render after cancel: %s", vs_last_error(c));
            CHECK(st != VS_OK || same_image(&img, &ref[1]), "%d threads: image after a cancel differs", threads);
            vs_image_free(&img);
        }
    }
    vs_context_release(c);
    printf("cancelled from another thread through the progress callback: VS_ERR_CANCELLED, then the "
           "context renders the reference again\n");
}

static void check_busy(const vs_image *ref)
{
    vs_context *c;
    if (vs_context_create(&c) != VS_OK) return;
    gate g;
    gate_init(&g);
    gated_job j = {.g = &g, .ctx = c};
    settings_for(2, &j.s);
    j.s.threads = 1;
    j.s.progress = gated_progress;
    j.s.progress_user = &g;
    pthread_t tr;
    pthread_create(&tr, NULL, gated_render, &j);
    CHECK(gate_wait_inside(&g), "one worker: the callback was never called");
    /* the context is rendering (held in its callback): this thread is refused */
    vs_settings s;
    settings_for(2, &s);
    vs_image img = {7, 7, (float *)&s};
    vs_status st = vs_render(c, vol, &s, &img, NULL);
    CHECK(st == VS_ERR_BUSY, "second thread on a rendering context got %s", vs_status_string(st));
    CHECK(img.rgba == NULL && img.width == 0, "busy render left an image");
    gate_release(&g, 0);
    pthread_join(tr, NULL);
    CHECK(j.st == VS_OK && same_image(&j.img, &ref[2]), "the first thread's frame after the refusal: %s",
          vs_status_string(j.st));
    vs_image_free(&j.img);
    /* and free again */
    st = vs_render(c, vol, &s, &img, NULL);
    CHECK(st == VS_OK && same_image(&img, &ref[2]), "render after the busy refusal: %s", vs_last_error(c));
    vs_image_free(&img);
    pthread_mutex_destroy(&g.mu);
    pthread_cond_destroy(&g.cv);
    vs_context_release(c);
    printf("a second thread's vs_render on a busy context: %s\n", vs_status_string(VS_ERR_BUSY));
}

int main(void)
{
    const char *q = getenv("VSPLAT_TEST_QUICK");
    if (q && *q && *q != '0') size = 96;
    vs_context *ctx;
    if (vs_context_create(&ctx) != VS_OK) return 2;
    vol = tu_scene(ctx, q && *q && *q != '0' ? "cell:48" : "cell:96");
    if (!vol) TEST_DONE();
    /* the references: one context, one frame after the other */
    vs_image ref[NCTX];
    for (int i = 0; i < NCTX; i++) {
        vs_settings s;
        settings_for(i, &s);
        if (vs_render(ctx, vol, &s, &ref[i], NULL) != VS_OK) {
            fprintf(stderr, "reference render failed: %s\n", vs_last_error(ctx));
            return 1;
        }
    }
    check_parallel(ref);
    check_cancel(ref);
    check_busy(ref);
    for (int i = 0; i < NCTX; i++) vs_image_free(&ref[i]);
    vs_volume_release(vol);
    vs_context_release(ctx);
    TEST_DONE();
}
