/* The roofline loops (roof_body.h) for sse4, built with its flags. */
#define ROOF_VW 4
#define ROOF_FILL bench_roof_sse4
#include "roof_body.h"
