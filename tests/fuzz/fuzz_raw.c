/* libFuzzer harness: headerless raw with fixed options (8x8x8, u16, big
 * endian); gzip is detected by its magic whatever the name. */
#include "fuzz_common.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);
int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    vs_load_options o;
    vs_load_options_init(&o);
    o.raw = 1;
    o.dims[0] = o.dims[1] = o.dims[2] = 8;
    o.type = VS_U16;
    o.endian = VS_ENDIAN_BIG;
    fz_load(data, size, ".raw", &o);
    return 0;
}
