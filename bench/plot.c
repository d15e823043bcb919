/* vsplat-bench plots: gnuplot scripts written next to the CSVs and run there. */
#include "bench.h"

#include <stdlib.h>
#include <string.h>

static int have_gnuplot(void)
{
    static int known = -1;
    if (known < 0) known = system("command -v gnuplot >/dev/null 2>&1") == 0;
    return known;
}

const char *bench_plot_terminal(int width, int height)
{
    static char buf[400];
    snprintf(buf, sizeof buf,
             "if (strstrt(GPVAL_TERMINALS, 'pngcairo') > 0) {\n"
             "  set terminal pngcairo size %d,%d font 'sans,10'\n"
             "} else {\n"
             "  set terminal png size %d,%d\n"
             "}\n",
             width, height, width, height);
    return buf;
}

/* Single-quote a path for the shell. */
static void shell_quote(const char *s, char *out, size_t cap)
{
    size_t k = 0;
    if (cap < 3) return;
    out[k++] = '\'';
    for (; *s && k + 5 < cap; s++) {
        if (*s == '\'') {
            memcpy(out + k, "'\\''", 4);
            k += 4;
        } else {
            out[k++] = *s;
        }
    }
    out[k++] = '\'';
    out[k] = '\0';
}

int bench_plot(const bench_opts *o, const char *name, const char *script)
{
    char gp[300];
    snprintf(gp, sizeof gp, "%s.gp", name);
    FILE *f = bench_result_open(o, gp);
    if (!f) return 1;
    fputs(script, f);
    if (fclose(f) != 0) return 1;
    if (!o->plot) {
        printf("(plot skipped: --no-plot; script %s/%s)\n", o->out_dir, gp);
        return 0;
    }
    if (!have_gnuplot()) {
        printf("(plot skipped: gnuplot not found; install gnuplot-nox and run: cd %s && gnuplot %s)\n", o->out_dir,
               gp);
        return 0;
    }
    char dir[8400], cmd[9000];
    shell_quote(o->out_dir, dir, sizeof dir);
    snprintf(cmd, sizeof cmd, "cd %s && gnuplot %s", dir, gp);
    int rc = system(cmd);
    if (rc != 0) {
        fprintf(stderr, "vsplat-bench: gnuplot failed on %s/%s\n", o->out_dir, gp);
        return 1;
    }
    printf("plot: %s/%s.png\n", o->out_dir, name);
    return 0;
}
