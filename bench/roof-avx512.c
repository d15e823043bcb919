/* The roofline loops (roof_body.h) for avx512, built with its flags. */
#define ROOF_VW 16
#define ROOF_FILL bench_roof_avx512
#include "roof_body.h"
