/* Persistent worker pool: tasks 0..n-1 handed out from an atomic cursor.
 * Workers are placed on cores with hwloc (one per core before SMT siblings);
 * a failed binding is reported, never fatal.  The library's only threads:
 * the splatting pipelines and the ray caster run on the context's pool. */
#ifndef VS_POOL_H
#define VS_POOL_H

#include "vsplat.h"

typedef void (*vs_task_fn)(void *arg, int worker, int task);

struct vs_pool;
/* threads <= 0: one per physical core.  Returns NULL on failure. */
struct vs_pool *vs_pool_create(int threads, int pin);
void vs_pool_destroy(struct vs_pool *p);
int vs_pool_threads(const struct vs_pool *p);
int vs_pool_pin_failed(const struct vs_pool *p);
/* Run fn(arg, worker, task) for every task in [0, ntasks); blocks until done.
 * The calling thread takes part as worker 0. */
void vs_pool_run(struct vs_pool *p, int ntasks, vs_task_fn fn, void *arg);
/* The same, and while the calling thread has no task left but other workers
 * still run theirs, it calls watch(watch_arg) every VS_POOL_WATCH_MS (a
 * frame's progress and cancel stay live when the caller got no long task). */
#define VS_POOL_WATCH_MS 20
void vs_pool_run_watched(struct vs_pool *p, int ntasks, vs_task_fn fn, void *arg, void (*watch)(void *),
                         void *watch_arg);
/* Physical cores available to this process (respects its binding). */
int vs_physical_cores(void);
/* The context's pool for s->threads (0: one per physical core) and s->pin,
 * in ctx->pool: created on first use and again only when those change, so
 * frames reuse its threads.  Sets the context's error on failure. */
vs_status vs_context_pool(vs_context *ctx, const vs_settings *s);

#endif
