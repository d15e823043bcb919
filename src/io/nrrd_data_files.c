/* A NRRD's data files as Teem 1.12 finds them: "data file: NAME", a LIST
 * of names, or a template "NAME%03d.raw <min> <max> <step>" numbered from
 * min by step while not past max.  The template was checked before Teem
 * parsed it (nrrd_header_check.c): one %d, numbers that fit an int. */
#include "nrrd_data_files.h"

#include <stdio.h>
#include <string.h>

unsigned vs_nrrd_data_count(const NrrdIoState *nio)
{
    if (nio->dataFNFormat) {
        const long long min = nio->dataFNMin, max = nio->dataFNMax, step = nio->dataFNStep;
        if (step > 0) return max < min ? 0 : (unsigned)((max - min) / step + 1);
        if (step < 0) return max > min ? 0 : (unsigned)((min - max) / -step + 1);
        return 0;
    }
    return nio->dataFNArr->len ? nio->dataFNArr->len : 1;
}

/* Teem's test for a name relative to the header's folder: not "-", not
 * absolute, not a Windows drive ("C:..."). */
static int relative(const char *name)
{
    return strcmp(name, "-") && name[0] != '/' && (!name[0] || name[1] != ':');
}

int vs_nrrd_data_path(const NrrdIoState *nio, unsigned i, char *buf, size_t cap)
{
    char name[4096];
    int n, rel;
    if (nio->dataFNFormat) {
        const long long num = nio->dataFNMin + (long long)i * nio->dataFNStep;
#if defined(__GNUC__)
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wformat-nonliteral" /* checked: one %d */
#endif
        n = snprintf(name, sizeof name, nio->dataFNFormat, (int)num);
#if defined(__GNUC__)
#pragma GCC diagnostic pop
#endif
        rel = relative(nio->dataFNFormat); /* as Teem: the template decides */
    } else if (i < nio->dataFNArr->len && nio->dataFN[i]) {
        n = snprintf(name, sizeof name, "%s", nio->dataFN[i]);
        rel = relative(name);
    } else {
        return 0;
    }
    if (n < 0 || (size_t)n >= sizeof name) return 0;
    if (rel && nio->path && *nio->path)
        n = snprintf(buf, cap, "%s/%s", nio->path, name);
    else
        n = snprintf(buf, cap, "%s", name);
    return n >= 0 && (size_t)n < cap;
}
