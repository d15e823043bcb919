/* The splatting kernel h(r) = b * 2^(-2 r^2) (paper eq. 6), r in voxel-index
 * units.  We truncate it to a cylinder of radius R aligned with the viewing
 * ray and half-length R (a Gaussian is separable, so each slab integral is a
 * 2-D footprint times a depth weight).  b normalises the truncated kernel to
 * integrate to one:  b = 1 / ( sqrt(pi/a) erf(sqrt(a) R) * (pi/a)(1-e^{-aR^2}) ),
 * a = 2 ln 2.  For R = 2: b = 0.29453 (the untruncated value is 0.29313; the
 * paper's 0.214 does not normalise this kernel). */
#include "gaussian.h"

#include <math.h>

double vs_kernel_b(double radius)
{
    const double a = 2.0 * M_LN2;
    double axial = sqrt(M_PI / a) * erf(sqrt(a) * radius);
    double radial = (M_PI / a) * (1.0 - exp(-a * radius * radius));
    return 1.0 / (axial * radial);
}
