/* libFuzzer harness: the MetaImage reader, header and voxels (see
 * fuzz_common.h).  A .mha carries both; ElementDataFile names that point
 * elsewhere meet missing files, which is fine. */
#include "fuzz_common.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);
int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    if (size == 0) return 0;
    fz_load(data, size, ".mha", NULL);
    return 0;
}
