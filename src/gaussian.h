/* The splatting kernel: a Gaussian h(r) = b 2^(-2 r^2), truncated at
 * radius R (gaussian.c). */
#ifndef VS_GAUSSIAN_H
#define VS_GAUSSIAN_H

/* The normalising constant b for radius R. */
double vs_kernel_b(double radius);

#endif
