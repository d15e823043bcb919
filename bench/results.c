/* vsplat-bench results: the results folder, files in it, the machine line. */
#include "bench.h"

#include <errno.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

int bench_runs(const bench_opts *o, int full_default, int quick_default)
{
    int r = o->runs > 0 ? o->runs : o->quick ? quick_default : full_default;
    return r < 1 ? 1 : r;
}

int bench_cpus(void)
{
    long n = sysconf(_SC_NPROCESSORS_ONLN);
    return n > 0 ? (int)n : 1;
}

int bench_results_dir(const bench_opts *o)
{
    char buf[4096];
    size_t len = strlen(o->out_dir);
    if (len == 0 || len >= sizeof buf) {
        fprintf(stderr, "vsplat-bench: --out: bad folder name\n");
        return 1;
    }
    memcpy(buf, o->out_dir, len + 1);
    for (char *p = buf + 1;; p++) { /* mkdir -p */
        int end = *p == '\0';
        if (*p == '/' || end) {
            *p = '\0';
            if (mkdir(buf, 0777) != 0 && errno != EEXIST) {
                fprintf(stderr, "vsplat-bench: %s: cannot create: %s\n", buf, strerror(errno));
                return 1;
            }
            if (end) break;
            *p = '/';
        }
    }
    struct stat sb;
    if (stat(o->out_dir, &sb) != 0 || !S_ISDIR(sb.st_mode)) {
        fprintf(stderr, "vsplat-bench: %s: not a folder\n", o->out_dir);
        return 1;
    }
    return 0;
}

static void bench_result_path(const bench_opts *o, const char *name, char *buf, size_t cap)
{
    snprintf(buf, cap, "%s/%s", o->out_dir, name);
}

FILE *bench_result_open(const bench_opts *o, const char *name)
{
    char path[4200];
    bench_result_path(o, name, path, sizeof path);
    FILE *f = fopen(path, "w");
    if (!f) fprintf(stderr, "vsplat-bench: %s: cannot write: %s\n", path, strerror(errno));
    return f;
}

const char *bench_machine(void)
{
    static char buf[300];
    if (buf[0]) return buf;
    char model[200] = "unknown CPU";
    FILE *f = fopen("/proc/cpuinfo", "r");
    if (f) {
        char line[512];
        while (fgets(line, sizeof line, f)) {
            if (!strncmp(line, "model name", 10)) {
                char *c = strchr(line, ':');
                if (c) {
                    c++;
                    while (*c == ' ' || *c == '\t') c++;
                    size_t n = strcspn(c, "\n");
                    if (n >= sizeof model) n = sizeof model - 1;
                    memcpy(model, c, n);
                    model[n] = '\0';
                }
                break;
            }
        }
        fclose(f);
    }
    snprintf(buf, sizeof buf, "%s, %d logical CPUs, ISA %s", model, bench_cpus(), vs_isa_name(vs_isa_detect()));
    return buf;
}

const char *bench_loadavg(void)
{
    static char buf[64];
    snprintf(buf, sizeof buf, "?");
    FILE *f = fopen("/proc/loadavg", "r");
    if (f) {
        double a = 0;
        if (fscanf(f, "%lf", &a) == 1) snprintf(buf, sizeof buf, "%.2f", a);
        fclose(f);
    }
    return buf;
}
