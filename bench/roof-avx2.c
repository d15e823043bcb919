/* The roofline loops (roof_body.h) for avx2, built with its flags. */
#define ROOF_VW 8
#define ROOF_FILL bench_roof_avx2
#include "roof_body.h"
