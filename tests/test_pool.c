/* The worker pool (src/pool.h): every task runs exactly once for any
 * thread count, the calling thread takes part as worker 0, and with
 * vs_pool_run_watched the calling thread, once it has no task left, calls
 * the watch every VS_POOL_WATCH_MS while another worker still runs one,
 * on its own thread only.  (A frame's
 * progress and cancel go through the watch: without it, a frame whose
 * calling thread got no long tile was silent and could not be cancelled
 * until it ended.)  The moment that matters is forced, not left to timing:
 * the caller's task waits until another worker has taken the long one. */
#include "pool.h"
#include "testutil.h"

#include <pthread.h>
#include <stdatomic.h>
#include <time.h>

static void sleep_ms(int ms)
{
    struct timespec t = {ms / 1000, (long)(ms % 1000) * 1000000L};
    nanosleep(&t, NULL);
}

typedef struct count_job {
    atomic_int runs[1000];
    atomic_int bad_worker;
    int nthreads;
} count_job;

static void count_task(void *arg, int worker, int task)
{
    count_job *J = arg;
    atomic_fetch_add(&J->runs[task], 1);
    if (worker < 0 || worker >= J->nthreads) atomic_fetch_add(&J->bad_worker, 1);
}

static void test_every_task_once(void)
{
    static count_job J;
    for (int threads = 1; threads <= 4; threads *= 2) {
        struct vs_pool *p = vs_pool_create(threads, 0);
        CHECK(p != NULL, "pool of %d", threads);
        if (!p) continue;
        J.nthreads = vs_pool_threads(p);
        for (int round = 0; round < 3; round++) {
            for (int i = 0; i < 1000; i++) atomic_store(&J.runs[i], 0);
            atomic_store(&J.bad_worker, 0);
            vs_pool_run(p, 1000, count_task, &J);
            int wrong = 0;
            for (int i = 0; i < 1000; i++) wrong += atomic_load(&J.runs[i]) != 1;
            CHECK(wrong == 0, "%d threads, round %d: %d tasks did not run exactly once", threads, round, wrong);
            CHECK(atomic_load(&J.bad_worker) == 0, "%d threads: a worker index out of range", threads);
        }
        vs_pool_destroy(p);
    }
}

typedef struct watch_job {
    pthread_t caller;
    atomic_int long_started; /* a worker other than the caller took its task */
    atomic_int watched, wrong_thread;
} watch_job;

/* Two tasks: the caller's returns once another worker has taken the other,
 * which runs 200 ms. */
static void watch_task(void *arg, int worker, int task)
{
    (void)task;
    watch_job *J = arg;
    if (worker != 0) {
        atomic_store(&J->long_started, 1);
        sleep_ms(200);
        return;
    }
    for (int i = 0; i < 2000 && !atomic_load(&J->long_started); i++) sleep_ms(1);
}

static void watch_fn(void *arg)
{
    watch_job *J = arg;
    atomic_fetch_add(&J->watched, 1);
    if (!pthread_equal(pthread_self(), J->caller)) atomic_fetch_add(&J->wrong_thread, 1);
}

static void test_watch(void)
{
    struct vs_pool *p = vs_pool_create(2, 0);
    CHECK(p != NULL, "pool of 2");
    if (!p) return;
    if (vs_pool_threads(p) < 2) {
        printf("note: the pool has one thread; the watch is not exercised\n");
        vs_pool_destroy(p);
        return;
    }
    for (int watched = 0; watched < 2; watched++) {
        watch_job J = {.caller = pthread_self()};
        vs_pool_run_watched(p, 2, watch_task, &J, watched ? watch_fn : NULL, &J);
        const int n = atomic_load(&J.watched);
        printf("caller waiting 200 ms for another worker, watch %s: %d calls\n", watched ? "on" : "off", n);
        CHECK(atomic_load(&J.long_started), "no other worker took a task");
        if (watched) /* about 10 in 200 ms; 3 leaves room for a loaded machine */
            CHECK(n >= 3, "the watch ran %d times while the caller waited 200 ms", n);
        else
            CHECK(n == 0, "a run without a watch called it %d times", n);
        CHECK(atomic_load(&J.wrong_thread) == 0, "the watch ran on another thread");
    }
    /* one thread: no one to wait for */
    struct vs_pool *one = vs_pool_create(1, 0);
    if (one) {
        watch_job J = {.caller = pthread_self()};
        atomic_store(&J.long_started, 1);
        vs_pool_run_watched(one, 2, watch_task, &J, watch_fn, &J);
        CHECK(atomic_load(&J.watched) == 0, "a one-thread run called the watch");
        vs_pool_destroy(one);
    }
    vs_pool_destroy(p);
}

int main(void)
{
    test_every_task_once();
    test_watch();
    TEST_DONE();
}
