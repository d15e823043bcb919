/* One directional light, Blinn-Phong, two-sided; shared by every pipeline and
 * the reference ray caster so that their images are comparable. */
#include "light.h"
#include "camera.h"

#include <math.h>

static void normalize3(double v[3])
{
    double m = sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
    if (m > 0) {
        v[0] /= m; v[1] /= m; v[2] /= m;
    }
}

void vs_light_setup(const vs_settings *s, const vs_camera *cam, vs_light *l)
{
    if (s->headlight) {
        l->L[0] = 0.0; l->L[1] = 0.0; l->L[2] = -1.0;
    } else {
        const double *d = s->light_dir;
        /* light_dir is in world space (RAS for an oriented volume) */
        l->L[0] = d[0] * cam->wright[0] + d[1] * cam->wright[1] + d[2] * cam->wright[2];
        l->L[1] = -(d[0] * cam->wup[0] + d[1] * cam->wup[1] + d[2] * cam->wup[2]);
        l->L[2] = d[0] * cam->wdir[0] + d[1] * cam->wdir[1] + d[2] * cam->wdir[2];
        normalize3(l->L);
        if (!(l->L[0] * l->L[0] + l->L[1] * l->L[1] + l->L[2] * l->L[2] > 0)) {
            l->L[0] = 0.0; l->L[1] = 0.0; l->L[2] = -1.0;
        }
    }
    /* the eye is at -z in the eye frame */
    l->H[0] = l->L[0];
    l->H[1] = l->L[1];
    l->H[2] = l->L[2] - 1.0;
    normalize3(l->H);
    if (!(l->H[0] * l->H[0] + l->H[1] * l->H[1] + l->H[2] * l->H[2] > 0)) {
        l->H[0] = 0.0; l->H[1] = 0.0; l->H[2] = -1.0; /* light straight behind */
    }
    l->ka = s->ambient;
    l->kd = s->diffuse;
    l->ks = s->specular;
    l->n = s->shininess;
}

void vs_light_eval(const vs_light *l, const double n_in[3], double *diffuse, double *specular)
{
    double n[3] = {n_in[0], n_in[1], n_in[2]};
    double m = sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
    if (!(m > 1e-30) || !isfinite(m)) {
        n[0] = 0.0; n[1] = 0.0; n[2] = -1.0; /* facing the eye */
    } else {
        n[0] /= m; n[1] /= m; n[2] /= m;
        if (n[2] > 0.0) { /* facing away from the eye: flip */
            n[0] = -n[0]; n[1] = -n[1]; n[2] = -n[2];
        }
    }
    double nl = n[0] * l->L[0] + n[1] * l->L[1] + n[2] * l->L[2];
    double nh = n[0] * l->H[0] + n[1] * l->H[1] + n[2] * l->H[2];
    *diffuse = l->ka + l->kd * (nl > 0.0 ? nl : 0.0);
    *specular = nh > 0.0 ? l->ks * pow(nh, l->n) : 0.0;
}
