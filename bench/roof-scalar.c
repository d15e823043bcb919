/* The roofline loops (roof_body.h) for scalar, built with its flags. */
#define ROOF_VW 1
#define ROOF_FILL bench_roof_scalar
#include "roof_body.h"
