/* Persistent pthread worker pool (libvips-style): tasks are handed out from
 * an atomic cursor; the caller runs as worker 0.  Workers are spread over the
 * cores the process may use with hwloc_distrib, each set singlified, and each
 * worker binds itself; a binding failure is recorded, never fatal. */
#include "pool.h"
#include "context.h" /* struct vs_context, vs_set_error */

#include <errno.h>
#include <hwloc.h>
#include <pthread.h>
#include <stdatomic.h>
#include <limits.h>
#include <stdlib.h>
#include <time.h>

typedef struct vs_worker {
    struct vs_pool *pool;
    int index;
    pthread_t thread;
    hwloc_bitmap_t cpuset; /* NULL: not pinned */
} vs_worker;

struct vs_pool {
    int nthreads;
    int pin_failed;
    hwloc_topology_t topo;
    vs_worker *workers;
    hwloc_bitmap_t caller_set; /* pinned: the caller's own binding, kept while
                                  it runs as worker 0 and restored after   */
    pthread_mutex_t lock;
    pthread_cond_t start_cv, done_cv;
    unsigned long generation; /* bumped for each run                      */
    int quit;
    int running;              /* workers still busy in this run           */
    /* the current job */
    vs_task_fn fn;
    void *arg;
    int ntasks;
    atomic_int cursor;
};

static void run_tasks(struct vs_pool *p, int worker)
{
    for (;;) {
        int t = atomic_fetch_add_explicit(&p->cursor, 1, memory_order_relaxed);
        if (t >= p->ntasks) break;
        p->fn(p->arg, worker, t);
    }
}

static void bind_self(vs_worker *w)
{
    if (!w->cpuset) return;
    if (hwloc_set_cpubind(w->pool->topo, w->cpuset, HWLOC_CPUBIND_THREAD) != 0) {
        pthread_mutex_lock(&w->pool->lock);
        w->pool->pin_failed = 1;
        pthread_mutex_unlock(&w->pool->lock);
    }
}

static void *worker_main(void *arg)
{
    vs_worker *w = arg;
    struct vs_pool *p = w->pool;
    bind_self(w);
    unsigned long seen = 0;
    pthread_mutex_lock(&p->lock);
    for (;;) {
        while (!p->quit && p->generation == seen) pthread_cond_wait(&p->start_cv, &p->lock);
        if (p->quit) break;
        seen = p->generation;
        pthread_mutex_unlock(&p->lock);
        run_tasks(p, w->index);
        pthread_mutex_lock(&p->lock);
        if (--p->running == 0) pthread_cond_signal(&p->done_cv);
    }
    pthread_mutex_unlock(&p->lock);
    return NULL;
}

static int count_cores(hwloc_topology_t topo)
{
    hwloc_const_cpuset_t allowed = hwloc_topology_get_allowed_cpuset(topo);
    int n = hwloc_get_nbobjs_inside_cpuset_by_type(topo, allowed, HWLOC_OBJ_CORE);
    if (n <= 0) n = hwloc_get_nbobjs_inside_cpuset_by_type(topo, allowed, HWLOC_OBJ_PU);
    return n > 0 ? n : 1;
}

int vs_physical_cores(void)
{
    hwloc_topology_t topo;
    if (hwloc_topology_init(&topo) != 0) return 1;
    int n = 1;
    if (hwloc_topology_load(topo) == 0) n = count_cores(topo);
    hwloc_topology_destroy(topo);
    return n;
}

struct vs_pool *vs_pool_create(int threads, int pin)
{
    struct vs_pool *p = calloc(1, sizeof *p);
    if (!p) return NULL;
    if (hwloc_topology_init(&p->topo) != 0) {
        free(p);
        return NULL;
    }
    int have_topo = hwloc_topology_load(p->topo) == 0;
    if (threads <= 0) threads = have_topo ? count_cores(p->topo) : 1;
    if (threads > 256) threads = 256;
    p->nthreads = threads;
    p->workers = calloc((size_t)threads, sizeof *p->workers);
    if (!p->workers) {
        hwloc_topology_destroy(p->topo);
        free(p);
        return NULL;
    }
    pthread_mutex_init(&p->lock, NULL);
    pthread_cond_init(&p->start_cv, NULL);
    {
        /* the watched wait times out on the monotonic clock: setting the
         * wall clock back must not silence a frame's progress */
        pthread_condattr_t ca;
        pthread_condattr_init(&ca);
        pthread_condattr_setclock(&ca, CLOCK_MONOTONIC);
        pthread_cond_init(&p->done_cv, &ca);
        pthread_condattr_destroy(&ca);
    }
    if (pin && have_topo && threads > 1) {
        /* Spread over the cores this process is allowed to use (respects
         * taskset / cgroups): one worker per core before any SMT sibling. */
        hwloc_bitmap_t allowed = hwloc_bitmap_alloc();
        hwloc_bitmap_t *sets = calloc((size_t)threads, sizeof *sets);
        if (allowed && sets && hwloc_get_cpubind(p->topo, allowed, HWLOC_CPUBIND_PROCESS) == 0) {
            hwloc_obj_t root = hwloc_get_root_obj(p->topo);
            hwloc_obj_t roots[1] = {root};
            /* restrict distribution to our binding */
            hwloc_topology_t t = p->topo;
            if (hwloc_distrib(t, roots, 1, sets, (unsigned)threads, INT_MAX, 0) == 0) {
                for (int i = 0; i < threads; i++) {
                    if (!sets[i]) continue;
                    hwloc_bitmap_and(sets[i], sets[i], allowed);
                    if (hwloc_bitmap_iszero(sets[i])) {
                        hwloc_bitmap_free(sets[i]);
                        sets[i] = NULL;
                        continue;
                    }
                    hwloc_bitmap_singlify(sets[i]);
                    p->workers[i].cpuset = sets[i];
                    sets[i] = NULL;
                }
            } else {
                p->pin_failed = 1;
            }
        } else {
            p->pin_failed = 1;
        }
        if (sets)
            for (int i = 0; i < threads; i++)
                if (sets[i]) hwloc_bitmap_free(sets[i]);
        free(sets);
        if (allowed) hwloc_bitmap_free(allowed);
    }
    for (int i = 0; i < threads; i++) {
        p->workers[i].pool = p;
        p->workers[i].index = i;
    }
    /* worker 0 is the calling thread: it is bound to its core only while it
     * runs tasks (vs_pool_run restores its own binding after), the others
     * bind themselves for good.  Left unbound, the caller could be scheduled
     * onto a pinned worker's core, which that worker cannot leave. */
    if (p->workers[0].cpuset) p->caller_set = hwloc_bitmap_alloc();
    for (int i = 1; i < threads; i++) {
        if (pthread_create(&p->workers[i].thread, NULL, worker_main, &p->workers[i]) != 0) {
            p->nthreads = i; /* run with fewer workers */
            break;
        }
    }
    return p;
}

void vs_pool_destroy(struct vs_pool *p)
{
    if (!p) return;
    pthread_mutex_lock(&p->lock);
    p->quit = 1;
    pthread_cond_broadcast(&p->start_cv);
    pthread_mutex_unlock(&p->lock);
    for (int i = 1; i < p->nthreads; i++) pthread_join(p->workers[i].thread, NULL);
    for (int i = 0; i < p->nthreads; i++)
        if (p->workers[i].cpuset) hwloc_bitmap_free(p->workers[i].cpuset);
    if (p->caller_set) hwloc_bitmap_free(p->caller_set);
    pthread_mutex_destroy(&p->lock);
    pthread_cond_destroy(&p->start_cv);
    pthread_cond_destroy(&p->done_cv);
    hwloc_topology_destroy(p->topo);
    free(p->workers);
    free(p);
}

int vs_pool_threads(const struct vs_pool *p) { return p ? p->nthreads : 1; }
int vs_pool_pin_failed(const struct vs_pool *p) { return p ? p->pin_failed : 0; }

void vs_pool_run(struct vs_pool *p, int ntasks, vs_task_fn fn, void *arg)
{
    vs_pool_run_watched(p, ntasks, fn, arg, NULL, NULL);
}

void vs_pool_run_watched(struct vs_pool *p, int ntasks, vs_task_fn fn, void *arg, void (*watch)(void *),
                         void *watch_arg)
{
    if (ntasks <= 0) return;
    if (!p || p->nthreads <= 1) {
        for (int t = 0; t < ntasks; t++) fn(arg, 0, t);
        return;
    }
    pthread_mutex_lock(&p->lock);
    p->fn = fn;
    p->arg = arg;
    p->ntasks = ntasks;
    atomic_store(&p->cursor, 0);
    p->running = p->nthreads - 1;
    p->generation++;
    pthread_cond_broadcast(&p->start_cv);
    pthread_mutex_unlock(&p->lock);
    /* pinned: the caller takes worker 0's core for the run, then gets its
     * own binding back (a failure is a warning, like any binding) */
    int rebind = 0;
    if (p->caller_set && hwloc_get_cpubind(p->topo, p->caller_set, HWLOC_CPUBIND_THREAD) == 0) {
        if (hwloc_set_cpubind(p->topo, p->workers[0].cpuset, HWLOC_CPUBIND_THREAD) == 0) rebind = 1;
    }
    int failed = p->caller_set && !rebind;
    run_tasks(p, 0);
    if (rebind && hwloc_set_cpubind(p->topo, p->caller_set, HWLOC_CPUBIND_THREAD) != 0) failed = 1;
    pthread_mutex_lock(&p->lock);
    if (failed) p->pin_failed = 1;
    while (p->running > 0) {
        if (!watch) {
            pthread_cond_wait(&p->done_cv, &p->lock);
            continue;
        }
        struct timespec until;
        clock_gettime(CLOCK_MONOTONIC, &until); /* done_cv's clock */
        until.tv_nsec += VS_POOL_WATCH_MS * 1000000L;
        if (until.tv_nsec >= 1000000000L) {
            until.tv_sec++;
            until.tv_nsec -= 1000000000L;
        }
        if (pthread_cond_timedwait(&p->done_cv, &p->lock, &until) == ETIMEDOUT && p->running > 0) {
            pthread_mutex_unlock(&p->lock);
            watch(watch_arg);
            pthread_mutex_lock(&p->lock);
        }
    }
    pthread_mutex_unlock(&p->lock);
}

vs_status vs_context_pool(vs_context *ctx, const vs_settings *s)
{
    int want = s->threads;
    if (want <= 0) want = vs_physical_cores();
    if (ctx->pool && ctx->pool_threads == want && ctx->pool_pin == s->pin) return VS_OK;
    vs_pool_destroy(ctx->pool);
    ctx->pool = vs_pool_create(want, s->pin);
    if (!ctx->pool) return vs_set_error(ctx, VS_ERR_OUT_OF_MEMORY, "cannot create the worker pool");
    ctx->pool_threads = want;
    ctx->pool_pin = s->pin;
    return VS_OK;
}
