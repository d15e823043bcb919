/* One directional light, Blinn-Phong, two-sided (light.c). */
#ifndef VS_LIGHT_H
#define VS_LIGHT_H

#include "camera.h"

/* Normals and light live in the eye frame: e1 = right, e2 = down (-up),
 * e3 = viewing direction; orthonormal in world units. */
typedef struct vs_light {
    double L[3];   /* unit vector towards the light, eye frame              */
    double H[3];   /* Blinn half vector between L and the eye                */
    double ka, kd, ks, n;
} vs_light;
void vs_light_setup(const vs_settings *s, const vs_camera *cam, vs_light *l);
/* Phong terms for a normal in the eye frame (right, down, forward; any
 * length).  Two-sided: a normal facing away from the eye is flipped.  A zero
 * normal is treated as facing the eye, so homogeneous regions are defined.
 * colour = material * (*diffuse) + (*specular). */
void vs_light_eval(const vs_light *l, const double n[3], double *diffuse, double *specular);

#endif
