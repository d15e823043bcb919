/* libFuzzer harness: the DICOM series loader through the GDCM module.  The
 * first byte picks how many files (1 to 3) the rest is cut into, equal
 * parts, written to a folder of this process's own, which is then loaded:
 * header parsing, series grouping, sorting and pixel decoding all see the
 * input.  The same promises as fuzz_common.h's; the module must load. */
#include "fuzz_common.h"

#include <stdlib.h>

/* internal (src/io/load.h), reached through the static library: inputs
 * that do not look like DICOM would go to the PNG stack loader */
int vs_dicom_folder(const char *dir);

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);
int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    static char dir[512];
    if (size < 2) return 0;
    if (!fz_ctx && vs_context_create(&fz_ctx) != VS_OK) abort();
    if (!dir[0]) {
        const char *t = getenv("TMPDIR");
        snprintf(dir, sizeof dir, "%s/vsplat_fuzz_dicom_XXXXXX", (t && *t) ? t : "/tmp");
        if (!mkdtemp(dir)) abort();
    }
    char path[600];
    for (int i = 0; i < 3; i++) {
        snprintf(path, sizeof path, "%s/f%d", dir, i);
        unlink(path);
    }
    int files = data[0] % 3 + 1;
    data++;
    size--;
    size_t part = size / (size_t)files;
    for (int i = 0; i < files; i++) {
        size_t n = i == files - 1 ? size - part * (size_t)i : part;
        snprintf(path, sizeof path, "%s/f%d", dir, i);
        if (!fz_write(path, data + part * (size_t)i, n)) abort();
    }
    if (!vs_dicom_folder(dir)) return 0;
    vs_volume *v = NULL;
    vs_status st = vs_volume_load(fz_ctx, dir, NULL, &v);
    if (st == VS_OK) {
        int d[3];
        double lo, hi;
        vs_volume_dims(v, d);
        vs_volume_range(v, &lo, &hi);
        if (d[0] < 1 || d[1] < 1 || d[2] < 1 || !(lo <= hi)) abort();
        vs_volume_release(v);
    } else {
        if (v) abort();
        if (!*vs_last_error(fz_ctx)) abort();
        static const char no_module[] = "DICOM: cannot load the GDCM module";
        if (!strncmp(vs_last_error(fz_ctx), no_module, sizeof no_module - 1)) {
            fprintf(stderr, "fuzz: %s\n", vs_last_error(fz_ctx));
            abort();
        }
    }
    return 0;
}
