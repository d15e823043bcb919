/* Teem 1.12's NRRD field parsers leak memory on some malformed headers
 * (issue 24; found by fuzz_nrrd, confirmed with LSan and valgrind): they
 * allocate, then return an error without freeing, so no cleanup by the
 * caller can reach it.  Each case is a header that Teem refuses anyway, so
 * refusing it first loses no valid file:
 *  - "centers"/"centerings", "kinds", or a "data file" given as a %d
 *    template, LIST or SKIPLIST before "dimension" (Teem's per-field mop is leaked
 *    when it finds it has no dimension yet; the NRRD spec puts dimension
 *    before every per-axis field);
 *  - "labels", "units" or "space units" with an unterminated quoted string
 *    (the string's buffer is leaked);
 *  - "labels", "units" or "space units" with another number of strings
 *    than the axes (or the space's dimensions) they describe: fewer leak
 *    the strings read before the missing one, more leak the extra one;
 *  - "labels", "units" or "space units" as the file's last line without a
 *    newline: Teem may cut such a line short, and the string it cuts is
 *    unterminated (leaked as above).
 * A "data file" template ("slice%03d.raw <min> <max> <step>") goes to
 * sprintf as the format and to a loop over its numbers, unchecked, so it is
 * refused unless its only conversion is one %d of width at most 10
 * (another conversion reads or writes through a stray pointer; a wider one
 * overruns Teem's name buffer), its numbers and Teem's arithmetic on them
 * fit an int (its loop would never end) and they name at most VS_MAX_DIM
 * files (each count is a loop over them).  Teem reads a name as a template by the same test
 * as `template_at` below.
 * An axis "kind" with a fixed size (a vector, colour or tensor: "3-vector",
 * "RGB-color", ...) is not an axis of a scalar volume; refused before Teem
 * reads on, which leaks when such a kind disagrees with "sizes".
 * A data file named "-" is standard input to Teem: a volume file must not
 * read its host program's input, nor wait on a terminal.  A LIST's names
 * run to the end of the file, empty lines included: an empty name is
 * refused too (Teem reads past it and opens the header's folder).
 * The header is the lines up to the first empty line (or the whole file,
 * for a detached .nhdr), each ended by "\n", "\r\n" or "\r". */
#include "nrrd_header_check.h"

#include "vsplat.h"

#include <ctype.h>
#include <limits.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>

#define LINE_MAX_BYTES (1 << 20)

/* The field name before the first ':' lower-cased without blanks ("data
 * file" -> "datafile"); "" for comments, key/value pairs and non-fields. */
static void field_name(const char *line, char *name, size_t cap)
{
    size_t j = 0;
    name[0] = '\0';
    if (line[0] == '#') return;
    const char *col = strchr(line, ':');
    if (!col || col[1] == '=') return;
    for (const char *p = line; p < col && j + 1 < cap; p++)
        if (*p != ' ' && *p != '\t') name[j++] = (char)tolower((unsigned char)*p);
    name[j] = '\0';
}

/* Counts the quoted strings as Teem's _nrrdGetQuotedString reads them
 * (blanks between, \" inside); -1 if one is not terminated. */
static int quoted_strings(const char *s)
{
    int n = 0;
    for (;;) {
        s += strspn(s, " \t");
        if (*s != '"') return n;
        for (s++; *s && *s != '"'; s++)
            if (s[0] == '\\' && s[1] == '"') s++;
        if (*s != '"') return -1;
        s++;
        n++;
    }
}

/* Whether Teem takes a "data file" value as a %d template: its first
 * '%' that is not "%%" is followed by digits and 'd'. */
static int template_at(const char *info)
{
    const char *p = info;
    while ((p = strchr(p, '%')) && p[1] == '%') p += 2;
    if (!p || !p[1]) return 0;
    p += 1 + strspn(p + 1, "0123456789");
    return *p == 'd';
}

/* NULL if the template is safe to hand to Teem, else why not. */
static const char *template_problem(const char *info)
{
    const size_t len = strcspn(info, " \t"); /* the template is the first word */
    int convs = 0;
    for (size_t i = 0; i < len; i++) {
        if (info[i] != '%') continue;
        if (i + 1 < len && info[i + 1] == '%') {
            i++;
            continue;
        }
        size_t j = i + 1, width = 0;
        for (; j < len && isdigit((unsigned char)info[j]); j++)
            if ((width = width * 10 + (size_t)(info[j] - '0')) > 10) return "a %d wider than 10";
        if (j >= len || info[j] != 'd') return "a conversion other than %d";
        convs++;
        i = j;
    }
    if (convs != 1) return convs ? "more than one %d" : "no %d in its first word";
    long num[3];
    char *end;
    const char *p = info + len;
    for (int k = 0; k < 3; k++) {
        num[k] = strtol(p, &end, 10);
        if (end == p) return NULL; /* Teem refuses it without looping */
        p = end;
    }
    const long long min = num[0], max = num[1], step = num[2];
    if (min < INT_MIN || min > INT_MAX || max < INT_MIN || max > INT_MAX || step < INT_MIN || step > INT_MAX ||
        (step > 0 && max > INT_MAX - step) || (step < 0 && max < INT_MIN - step) || max - min > INT_MAX ||
        min - max > INT_MAX || llabs((max - min) * step) > INT_MAX)
        return "file numbers that overflow an int";
    /* Teem counts the files in loops, several times: bound the count */
    if (step != 0 && (max - min) / step >= VS_MAX_DIM) return "more data files than a volume has slices";
    return NULL;
}

/* NULL if every axis kind in a "kinds" value can be an axis of a scalar
 * volume, else the first that cannot. */
static const char *kind_problem(const char *info, char *word, size_t cap)
{
    static const char *const ok[] = {"domain", "space", "time", "list", "point", "vector",
                                     "covariant-vector", "normal", "???", "none"};
    for (const char *p = info;;) {
        p += strspn(p, " \t");
        const size_t n = strcspn(p, " \t");
        if (!n) return NULL;
        snprintf(word, cap, "%.*s", (int)(n < cap ? n : cap - 1), p);
        size_t k = 0;
        while (k < sizeof ok / sizeof *ok && strcasecmp(word, ok[k])) k++;
        if (k == sizeof ok / sizeof *ok) return word;
        p += n;
    }
}

/* Dimensions of a named space: the "-time"/"...T" spaces have 4. */
static int space_dim(const char *name)
{
    size_t n = strlen(name);
    while (n && (name[n - 1] == ' ' || name[n - 1] == '\t')) n--;
    if (n >= 4 && !strncasecmp(name + n - 4, "time", 4)) return 4;
    if (n == 4 && (name[3] == 't' || name[3] == 'T')) return 4; /* RAST, LAST, LPST */
    return 3;
}

/* The field as NRRD files spell it, for messages. */
static const char *spelled(const char *name)
{
    if (!strcmp(name, "spaceunits")) return "space units";
    if (!strcmp(name, "datafile")) return "data file";
    return name;
}

static vs_status check_line(vs_context *ctx, const char *path, const char *line, int last, int *dim, int *sdim,
                            int *list)
{
    if (*list) { /* a name in a data file LIST ("<skip> <name>" in a SKIPLIST), not a field */
        const char *fn = line;
        if (*list == 2) {
            fn += strspn(fn, " \t");
            fn += strcspn(fn, " \t");
            fn += strspn(fn, " \t");
        }
        if (!*fn) return vs_set_error(ctx, VS_ERR_FORMAT, "%s: NRRD data file LIST with an empty name", path);
        if (strcmp(fn, "-")) return VS_OK;
        return vs_set_error(ctx, VS_ERR_FORMAT, "%s: NRRD data file \"-\" (standard input) is not supported", path);
    }
    char name[64];
    field_name(line, name, sizeof name);
    if (!*name) return VS_OK;
    if (last && (!strcmp(name, "labels") || !strcmp(name, "units") || !strcmp(name, "spaceunits")))
        return vs_set_error(ctx, VS_ERR_FORMAT, "%s: NRRD field \"%s\" on the last line without a newline", path,
                            spelled(name));
    const char *info = strchr(line, ':') + 1;
    info += strspn(info, " \t");
    if (!strcmp(name, "dimension")) {
        *dim = atoi(info) > 0 ? atoi(info) : -1; /* -1: given, not a count */
    } else if (!strcmp(name, "spacedimension")) {
        *sdim = atoi(info);
    } else if (!strcmp(name, "space")) {
        *sdim = space_dim(info);
    } else if (!*dim && (!strcmp(name, "centers") || !strcmp(name, "centerings") || !strcmp(name, "kinds") ||
                              (!strcmp(name, "datafile") &&
                               (strchr(info, '%') || !strncmp(info, "LIST", 4) || !strncmp(info, "SKIPLIST", 8))))) {
        return vs_set_error(ctx, VS_ERR_FORMAT, "%s: NRRD field \"%s\" before \"dimension\"", path,
                            spelled(name));
    }
    if (!strcmp(name, "kinds")) {
        char word[64];
        if (kind_problem(info, word, sizeof word))
            return vs_set_error(ctx, VS_ERR_UNSUPPORTED,
                                "%s: NRRD axis kind \"%s\": a vector, colour or tensor axis, not a scalar volume's",
                                path, word);
    }
    if (!strcmp(name, "datafile")) {
        if (!strcmp(info, "-"))
            return vs_set_error(ctx, VS_ERR_FORMAT, "%s: NRRD data file \"-\" (standard input) is not supported",
                                path);
        const char *why = template_at(info) ? template_problem(info) : NULL;
        if (why) return vs_set_error(ctx, VS_ERR_FORMAT, "%s: NRRD data file template with %s", path, why);
        *list = !strncmp(info, "LIST", 4) ? 1 : !strncmp(info, "SKIPLIST", 8) ? 2 : 0;
    }
    if (!strcmp(name, "labels") || !strcmp(name, "units") || !strcmp(name, "spaceunits")) {
        int n = quoted_strings(info);
        if (n < 0)
            return vs_set_error(ctx, VS_ERR_FORMAT, "%s: NRRD field \"%s\" has an unterminated quoted string", path,
                                spelled(name));
        const int want = !strcmp(name, "spaceunits") ? *sdim : *dim;
        if (want > 0 && n != want)
            return vs_set_error(ctx, VS_ERR_FORMAT, "%s: NRRD field \"%s\" has %d strings for %d %s", path,
                                spelled(name), n,
                                want, !strcmp(name, "spaceunits") ? "space dimensions" : "axes");
    }
    return VS_OK;
}

vs_status vs_nrrd_header_check(vs_context *ctx, const char *path)
{
    FILE *f = fopen(path, "rb");
    if (!f) return vs_set_error(ctx, VS_ERR_IO, "%s: cannot open", path);
    char *line = malloc(LINE_MAX_BYTES + 1);
    if (!line) {
        fclose(f);
        return vs_set_error(ctx, VS_ERR_OUT_OF_MEMORY, "%s: out of memory", path);
    }
    vs_status st = VS_OK;
    int dim = 0, sdim = 0, list = 0, first = 1;
    for (;;) {
        size_t n = 0;
        int c;
        /* lines end at "\n", "\r\n" or a lone "\r", as Teem's airOneLine
         * reads them */
        while ((c = getc(f)) != EOF && c != '\n') {
            if (c == '\r') {
                const int d = getc(f);
                if (d != '\n' && d != EOF) ungetc(d, f);
                c = '\n';
                break;
            }
            if (n == LINE_MAX_BYTES) {
                st = vs_set_error(ctx, VS_ERR_FORMAT, "%s: NRRD header line over %d bytes", path, LINE_MAX_BYTES);
                break;
            }
            if (c == '\0') { /* Teem reads past it, this check would not */
                st = vs_set_error(ctx, VS_ERR_FORMAT, "%s: NRRD header line holds a NUL byte", path);
                break;
            }
            line[n++] = (char)c;
        }
        if (st != VS_OK) break;
        line[n] = '\0';
        if (n == 0 && c != EOF && !list) break; /* end of the header; a LIST runs to the end of the file */
        if (n == 0 && c == EOF) break;
        if (!first) st = check_line(ctx, path, line, c == EOF, &dim, &sdim, &list);
        first = 0;
        if (st != VS_OK || c == EOF) break;
    }
    free(line);
    fclose(f);
    return st;
}
