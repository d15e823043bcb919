/* libFuzzer harness: the nifti loader (see fuzz_common.h). */
#include "fuzz_common.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);
int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    if (size == 0) return 0;
    fz_load(data, size, data[0] == 0x1f ? ".nii.gz" : ".nii", NULL);
    return 0;
}
