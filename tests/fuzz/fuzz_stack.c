/* libFuzzer harness: single image files through OpenImageIO, as stacks:
 * PNG when the input starts with the PNG signature, else TIFF. */
#include "fuzz_common.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);
int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    if (size == 0) return 0;
    int png = size >= 4 && data[0] == 0x89 && data[1] == 'P' && data[2] == 'N' && data[3] == 'G';
    fz_load(data, size, png ? ".png" : ".tif", NULL);
    return 0;
}
