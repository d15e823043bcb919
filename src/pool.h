/* Persistent worker pool: tasks 0..n-1 handed out from an atomic cursor.
 * Workers are placed on cores with hwloc (one per core before SMT siblings);
 * a failed binding is reported, never fatal. */
#ifndef VS_POOL_H
#define VS_POOL_H

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
/* Physical cores available to this process (respects its binding). */
int vs_physical_cores(void);

#endif
