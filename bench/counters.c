/* vsplat-bench: hardware counters around a whole frame (roof.h).
 *
 * perf_event_open on this process, inherited by the threads it creates
 * after opening (the library's workers, when the vs_context is created
 * afterwards); reading a counter sums the live threads.  Per stage would
 * need counting inside the library, which it does not do.  Many VMs expose
 * no PMU (ENOENT) and kernel.perf_event_paranoid may forbid it (EACCES):
 * the caller prints why[] and carries on. */
#include "roof.h"

#include <errno.h>
#include <linux/perf_event.h>
#include <stdio.h>
#include <string.h>
#include <sys/ioctl.h>
#include <sys/syscall.h>
#include <unistd.h>

static const unsigned long long hwc_config[HWC_N] = {PERF_COUNT_HW_CPU_CYCLES, PERF_COUNT_HW_INSTRUCTIONS,
                                                     PERF_COUNT_HW_CACHE_MISSES};

int bench_hwc_open(bench_hwc *h)
{
    memset(h, 0, sizeof *h);
    for (int i = 0; i < HWC_N; i++) h->fd[i] = -1;
    for (int i = 0; i < HWC_N; i++) {
        struct perf_event_attr a;
        memset(&a, 0, sizeof a);
        a.size = sizeof a;
        a.type = PERF_TYPE_HARDWARE;
        a.config = hwc_config[i];
        a.disabled = 1;
        a.inherit = 1;
        a.exclude_kernel = 1; /* allowed at perf_event_paranoid 2 */
        a.exclude_hv = 1;
        long fd = syscall(SYS_perf_event_open, &a, 0, -1, -1, 0);
        if (fd < 0) {
            int e = errno;
            snprintf(h->why, sizeof h->why, "perf_event_open: %s (%s)", strerror(e),
                     e == ENOENT || e == EOPNOTSUPP ? "no hardware counters exposed, as in many VMs"
                     : e == EACCES || e == EPERM   ? "not permitted: see kernel.perf_event_paranoid"
                                                   : "counter refused");
            bench_hwc_close(h);
            return -1;
        }
        h->fd[i] = (int)fd;
    }
    return 0;
}

void bench_hwc_start(bench_hwc *h)
{
    for (int i = 0; i < HWC_N; i++) {
        if (h->fd[i] < 0) continue;
        ioctl(h->fd[i], PERF_EVENT_IOC_RESET, 0);
        ioctl(h->fd[i], PERF_EVENT_IOC_ENABLE, 0);
    }
}

int bench_hwc_stop(bench_hwc *h, unsigned long long out[HWC_N])
{
    int rc = 0;
    for (int i = 0; i < HWC_N; i++) {
        out[i] = 0;
        if (h->fd[i] < 0) {
            rc = -1;
            continue;
        }
        ioctl(h->fd[i], PERF_EVENT_IOC_DISABLE, 0);
        unsigned long long v = 0;
        if (read(h->fd[i], &v, sizeof v) != (ssize_t)sizeof v) rc = -1;
        out[i] = v;
    }
    return rc;
}

void bench_hwc_close(bench_hwc *h)
{
    for (int i = 0; i < HWC_N; i++) {
        if (h->fd[i] >= 0) close(h->fd[i]);
        h->fd[i] = -1;
    }
}
