/* Orientation: one asymmetric "head" (a skull-like ellipsoid with a blob on
 * its left, a nose in front and a crest on top) stored five ways — NIfTI
 * RAS, LAS (x reversed), RAI (z reversed), axes permuted, a 90-degree
 * rotation written with rounded sines (an oblique-looking sform), and NRRD
 * in LPS space with x and y reversed — must render the same picture (PSNR
 * >= 45 dB) on post-cd and the ray caster; the stored voxels rendered
 * without their transform must not (so the test can fail).  The named views
 * are checked against where the blobs must appear (the conventions of
 * docs/DESIGN.md §2), and against their angle equivalents, --up and --roll. */
#include "internal.h"
#include "testutil.h"

#include <math.h>
#include <stdint.h>

static char tmp[1024];
static const int N[3] = {34, 38, 30};           /* RAS storage: x, y, z sizes */
static const double SP[3] = {1.0, 1.15, 1.3};   /* anisotropic, mm            */

/* The anatomy in RAS millimetres about the centre: value 0..100, iso 50. */
static double anatomy(const double p[3])
{
    static const struct {
        double c[3], r[3];
    } blobs[] = {
        {{0, 0, 0}, {11, 13, 10}},     /* head                              */
        {{-12, 2, 1}, {5, 5, 5}},      /* left (-x) ear-like blob            */
        {{0, 16, -2}, {4, 7, 4}},      /* nose (+y, anterior)                */
        {{3, -2, 12}, {4, 6, 3}},      /* crest on top (+z), a little right  */
    };
    double best = 0.0;
    for (size_t b = 0; b < sizeof blobs / sizeof blobs[0]; b++) {
        double q = 0.0;
        for (int a = 0; a < 3; a++) {
            double d = (p[a] - blobs[b].c[a]) / blobs[b].r[a];
            q += d * d;
        }
        double v = 100.0 * (1.0 - 0.5 * q);
        if (v > best) best = v;
    }
    return best;
}

/* One storage: stored sizes n[] and the index -> RAS transform. */
typedef struct storage {
    const char *name;
    int n[3];
    double m[3][4];
} storage;

/* A storage from a signed permutation: stored axis a runs along RAS axis
 * axis[a] with sign sgn[a]; the origin puts the centre at 0. */
static storage make_storage(const char *name, const int axis[3], const int sgn[3])
{
    storage s;
    memset(&s, 0, sizeof s);
    s.name = name;
    for (int a = 0; a < 3; a++) {
        s.n[a] = N[axis[a]];
        s.m[axis[a]][a] = sgn[a] * SP[axis[a]];
        s.m[axis[a]][3] = -sgn[a] * SP[axis[a]] * 0.5 * (s.n[a] - 1);
    }
    return s;
}

static float *fill(const storage *s)
{
    size_t n = (size_t)s->n[0] * s->n[1] * s->n[2];
    float *d = malloc(n * sizeof *d);
    if (!d) exit(1);
    size_t i = 0;
    for (int k = 0; k < s->n[2]; k++)
        for (int j = 0; j < s->n[1]; j++)
            for (int x = 0; x < s->n[0]; x++, i++) {
                double p[3];
                for (int r = 0; r < 3; r++) p[r] = s->m[r][0] * x + s->m[r][1] * j + s->m[r][2] * k + s->m[r][3];
                d[i] = (float)anatomy(p);
            }
    return d;
}

static void put_i16(unsigned char *h, int off, int v) { h[off] = (unsigned char)(v & 255), h[off + 1] = (unsigned char)((v >> 8) & 255); }
static void put_i32(unsigned char *h, int off, int32_t v) { memcpy(h + off, &v, 4); } /* little-endian host */
static void put_f32(unsigned char *h, int off, double v)
{
    float f = (float)v;
    memcpy(h + off, &f, 4);
}

/* NIfTI-1 single file, float32, sform_code 1 (scanner), qform_code 0:
 * written byte by byte from the standard's layout, not with nifticlib. */
static void write_nifti(const char *path, const storage *s, const float *d)
{
    unsigned char h[352];
    memset(h, 0, sizeof h);
    put_i32(h, 0, 348);
    put_i16(h, 40, 3);
    for (int a = 0; a < 3; a++) put_i16(h, 42 + 2 * a, s->n[a]);
    put_i16(h, 48, 1), put_i16(h, 50, 1), put_i16(h, 52, 1), put_i16(h, 54, 1);
    put_i16(h, 70, 16); /* DT_FLOAT32 */
    put_i16(h, 72, 32);
    put_f32(h, 76, 1.0); /* qfac */
    for (int a = 0; a < 3; a++) {
        double len = sqrt(s->m[0][a] * s->m[0][a] + s->m[1][a] * s->m[1][a] + s->m[2][a] * s->m[2][a]);
        put_f32(h, 80 + 4 * a, len);
    }
    put_f32(h, 108, 352.0); /* vox_offset */
    put_f32(h, 112, 1.0);   /* scl_slope: identity */
    put_i16(h, 252, 0);     /* qform_code */
    put_i16(h, 254, 1);     /* sform_code */
    for (int r = 0; r < 3; r++)
        for (int c = 0; c < 4; c++) put_f32(h, 280 + 16 * r + 4 * c, s->m[r][c]);
    memcpy(h + 344, "n+1", 4);
    size_t n = (size_t)s->n[0] * s->n[1] * s->n[2];
    FILE *f = fopen(path, "wb");
    if (!f || fwrite(h, 1, sizeof h, f) != sizeof h || fwrite(d, sizeof *d, n, f) != n) exit(1);
    fclose(f);
}

/* NRRD in LPS space: the RAS transform with x and y negated. */
static void write_nrrd_lps(const char *path, const storage *s, const float *d)
{
    FILE *f = fopen(path, "wb");
    if (!f) exit(1);
    const double fl[3] = {-1, -1, 1};
    fprintf(f, "NRRD0004\ntype: float\ndimension: 3\nspace: left-posterior-superior\nsizes: %d %d %d\n", s->n[0],
            s->n[1], s->n[2]);
    fprintf(f, "space directions:");
    for (int c = 0; c < 3; c++)
        fprintf(f, " (%.17g,%.17g,%.17g)", fl[0] * s->m[0][c] + 0.0, fl[1] * s->m[1][c] + 0.0, fl[2] * s->m[2][c] + 0.0);
    fprintf(f, "\nspace origin: (%.17g,%.17g,%.17g)\nencoding: raw\nendian: little\n\n", fl[0] * s->m[0][3] + 0.0,
            fl[1] * s->m[1][3] + 0.0, fl[2] * s->m[2][3] + 0.0);
    size_t n = (size_t)s->n[0] * s->n[1] * s->n[2];
    if (fwrite(d, sizeof *d, n, f) != n) exit(1);
    fclose(f);
}

static double psnr(vs_context *ctx, const vs_image *a, const vs_image *b)
{
    vs_image_diff d;
    if (vs_image_compare(ctx, a, b, &d) != VS_OK) return -1.0;
    return d.psnr;
}

static int render(vs_context *ctx, const vs_volume *v, const vs_settings *s, vs_image *img)
{
    vs_status st = vs_render(ctx, v, s, img, NULL);
    CHECK(st == VS_OK, "render: %s", vs_last_error(ctx));
    return st == VS_OK;
}

static void base_settings(vs_settings *s, vs_pipeline p)
{
    vs_settings_init(s);
    s->width = s->height = 96;
    s->pipeline = p;
    s->has_iso = 1;
    s->iso_lo = 50.0;
    s->ramp = 8.0;
    s->threads = 2;
    s->ray_step = 0.2;
}

/* Alpha in image halves: [left, right, top, bottom]. */
static void halves(const vs_image *im, double h[4])
{
    h[0] = h[1] = h[2] = h[3] = 0.0;
    for (int y = 0; y < im->height; y++)
        for (int x = 0; x < im->width; x++) {
            double a = im->rgba[4 * ((size_t)y * im->width + x) + 3];
            h[x < im->width / 2 ? 0 : 1] += a;
            h[y < im->height / 2 ? 2 : 3] += a;
        }
}

static vs_volume *load(vs_context *ctx, const char *path)
{
    vs_volume *v = NULL;
    vs_status st = vs_volume_load(ctx, path, NULL, &v);
    CHECK(st == VS_OK, "%s: %s", path, vs_last_error(ctx));
    return v;
}

int main(void)
{
    if (!tu_make_tmpdir(tmp, sizeof tmp, "orient")) return 1;
    vs_context *ctx = NULL;
    if (vs_context_create(&ctx) != VS_OK) return 1;

    static const int id[3] = {0, 1, 2}, pos[3] = {1, 1, 1};
    static const int las_s[3] = {-1, 1, 1}, rai_s[3] = {1, 1, -1}, lps_s[3] = {-1, -1, 1};
    static const int perm_a[3] = {1, 2, 0}, perm_s[3] = {1, -1, 1};
    storage st[6] = {make_storage("RAS", id, pos), make_storage("LAS", id, las_s), make_storage("RAI", id, rai_s),
                     make_storage("permuted (stored y,z,x; z reversed)", perm_a, perm_s),
                     make_storage("NRRD LPS", id, lps_s), make_storage("rotated 90 about z, rounded", id, pos)};
    /* the last one: x stored along -y, y stored along +x, in a rotation matrix
     * built from cos/sin of 90 degrees (1e-16, not 0: the general path) */
    {
        storage *r = &st[5];
        double c = cos(M_PI / 2), s = sin(M_PI / 2);
        r->n[0] = N[1], r->n[1] = N[0], r->n[2] = N[2];
        double m[3][3] = {{c * SP[1], s * SP[0], 0}, {-s * SP[1], c * SP[0], 0}, {0, 0, SP[2]}};
        /* columns: i along (c,-s,0)*SP[1] ~ -y, j along (s,c,0)*SP[0] ~ +x */
        for (int a = 0; a < 3; a++)
            for (int b = 0; b < 3; b++) r->m[a][b] = m[a][b];
        for (int a = 0; a < 3; a++)
            r->m[a][3] = -(r->m[a][0] * 0.5 * (r->n[0] - 1) + r->m[a][1] * 0.5 * (r->n[1] - 1) +
                           r->m[a][2] * 0.5 * (r->n[2] - 1));
    }
    vs_volume *vol[6] = {NULL};
    float *las_data = NULL;
    for (int i = 0; i < 6; i++) {
        float *d = fill(&st[i]);
        char path[1200];
        snprintf(path, sizeof path, "%s/v%d.%s", tmp, i, i == 4 ? "nrrd" : "nii");
        if (i == 4) write_nrrd_lps(path, &st[i], d);
        else write_nifti(path, &st[i], d);
        vol[i] = load(ctx, path);
        if (i == 1) las_data = d;
        else free(d);
        if (!vol[i]) continue;
        double m[12];
        CHECK(vs_volume_affine(vol[i], m) == 1, "%s: no orientation read", st[i].name);
        double err = 0;
        for (int r = 0; r < 3; r++)
            for (int c = 0; c < 4; c++) err = fmax(err, fabs(m[4 * r + c] - st[i].m[r][c]));
        CHECK(err < 1e-4, "%s: transform read off by %g", st[i].name, err);
    }
    /* the LAS voxels without their transform: a mirrored head */
    vs_volume *bare = NULL;
    if (vs_volume_create(ctx, VS_F32, st[1].n, SP, &bare) == VS_OK) {
        memcpy(vs_volume_data(bare), las_data, (size_t)N[0] * N[1] * N[2] * sizeof(float));
        vs_volume_update_range(bare);
    }
    free(las_data);
    if (!vol[0] || !bare) {
        vs_context_release(ctx);
        TEST_DONE();
    }

    /* the same picture however stored */
    const vs_pipeline pipes[2] = {VS_PIPELINE_POST_CD, VS_PIPELINE_RAYCAST};
    const struct {
        vs_view view;
        double az, el;
    } views[3] = {{VS_VIEW_AUTO, 0, 0}, {VS_VIEW_ANGLES, 30, 25}, {VS_VIEW_SUPERIOR, 0, 0}};
    for (int p = 0; p < 2; p++)
        for (int w = 0; w < 3; w++) {
            vs_settings s;
            base_settings(&s, pipes[p]);
            s.view = views[w].view;
            s.azimuth = views[w].az;
            s.elevation = views[w].el;
            vs_image ref = {0, 0, NULL};
            if (!render(ctx, vol[0], &s, &ref)) continue;
            for (int i = 1; i < 6; i++) {
                vs_image im = {0, 0, NULL};
                if (!vol[i] || !render(ctx, vol[i], &s, &im)) continue;
                double db = psnr(ctx, &ref, &im);
                printf("%-10s view %d (%g,%g) %-36s vs RAS: %.1f dB\n", vs_pipeline_name(pipes[p]), (int)views[w].view,
                       views[w].az, views[w].el, st[i].name, db);
                CHECK(db >= 45.0, "%s view %d: %s differs from RAS: %.1f dB", vs_pipeline_name(pipes[p]),
                      (int)views[w].view, st[i].name, db);
                vs_image_free(&im);
            }
            /* the mirrored voxels, seen from the same (explicit) direction */
            vs_settings b = s;
            if (b.view == VS_VIEW_AUTO) b.view = VS_VIEW_ANTERIOR;
            vs_image im = {0, 0, NULL};
            if (render(ctx, bare, &b, &im)) {
                double db = psnr(ctx, &ref, &im);
                printf("%-10s view %d: LAS voxels without their transform vs RAS: %.1f dB\n", vs_pipeline_name(pipes[p]),
                       (int)views[w].view, db);
                CHECK(db < 30.0, "%s: the mirrored volume matches at %.1f dB: the test cannot fail",
                      vs_pipeline_name(pipes[p]), db);
            }
            vs_image_free(&im);
            vs_image_free(&ref);
        }

    /* where the anatomy appears (docs/DESIGN.md §2): anterior view, the
     * patient's left (the ear) on the image's right and the crest on top;
     * left view, the nose on the image's left; superior view, the nose up;
     * inferior view, the nose up and the ear on the image's left... */
    {
        vs_settings s;
        base_settings(&s, VS_PIPELINE_POST_CD);
        struct {
            vs_view v;
            int a, b; /* halves index: a must hold more alpha than b */
            const char *what;
        } cases[] = {{VS_VIEW_ANTERIOR, 1, 0, "anterior: the left ear on the image's right"},
                     {VS_VIEW_ANTERIOR, 2, 3, "anterior: the crest at the top"},
                     {VS_VIEW_POSTERIOR, 0, 1, "posterior: the left ear on the image's left"},
                     {VS_VIEW_LEFT, 0, 1, "left: the nose on the image's left"},
                     {VS_VIEW_RIGHT, 1, 0, "right: the nose on the image's right"},
                     {VS_VIEW_SUPERIOR, 2, 3, "superior: the nose at the top"},
                     {VS_VIEW_SUPERIOR, 0, 1, "superior: the left ear on the image's left"},
                     {VS_VIEW_INFERIOR, 2, 3, "inferior: the nose at the top"},
                     {VS_VIEW_INFERIOR, 1, 0, "inferior: the left ear on the image's right"}};
        for (size_t c = 0; c < sizeof cases / sizeof cases[0]; c++) {
            s.view = cases[c].v;
            for (int i = 0; i < 6; i += 5) { /* RAS and the rotated storage */
                vs_image im = {0, 0, NULL};
                if (!render(ctx, vol[i], &s, &im)) continue;
                double h[4];
                halves(&im, h);
                CHECK(h[cases[c].a] > 1.05 * h[cases[c].b], "%s (%s): %.1f vs %.1f", cases[c].what, st[i].name,
                      h[cases[c].a], h[cases[c].b]);
                vs_image_free(&im);
            }
        }
    }

    /* named views are angle pairs; AUTO is anterior when oriented, else 0,0;
     * up and roll */
    {
        struct {
            vs_view v;
            double az, el;
            int has_up;
            double up[3], roll;
            vs_view v2;
            double az2, el2;
            int has_up2;
            double up2[3], roll2;
            int vol;
        } eq[] = {
            {VS_VIEW_AUTO, 0, 0, 0, {0}, 0, VS_VIEW_ANTERIOR, 0, 0, 0, {0}, 0, 0},
            /* a program's own angles keep their world meaning */
            {VS_VIEW_AUTO, 180, 0, 0, {0}, 0, VS_VIEW_ANGLES, 180, 0, 0, {0}, 0, 0},
            {VS_VIEW_AUTO, 30, 20, 0, {0}, 0, VS_VIEW_ANGLES, 30, 20, 0, {0}, 0, 0},
            {VS_VIEW_ANTERIOR, 0, 0, 0, {0}, 0, VS_VIEW_ANGLES, 180, 0, 0, {0}, 0, 0},
            {VS_VIEW_LEFT, 0, 0, 0, {0}, 0, VS_VIEW_ANGLES, 270, 0, 0, {0}, 0, 0},
            {VS_VIEW_RIGHT, 0, 0, 0, {0}, 0, VS_VIEW_ANGLES, -270, 0, 0, {0}, 0, 0},
            {VS_VIEW_SUPERIOR, 0, 0, 0, {0}, 0, VS_VIEW_ANGLES, 0, 90, 0, {0}, 0, 0},
            {VS_VIEW_INFERIOR, 0, 0, 0, {0}, 0, VS_VIEW_ANGLES, 180, -90, 0, {0}, 0, 0},
            {VS_VIEW_ANTERIOR, 20, 10, 0, {0}, 0, VS_VIEW_ANGLES, 200, 10, 0, {0}, 0, 0},
            /* upside down: 180,180 = the anterior view rolled by 180 = up -z */
            {VS_VIEW_ANGLES, 180, 180, 0, {0}, 0, VS_VIEW_POSTERIOR, 0, 0, 0, {0}, 180, 0},
            {VS_VIEW_POSTERIOR, 0, 0, 1, {0, 0, -1}, 0, VS_VIEW_POSTERIOR, 0, 0, 0, {0}, 180, 0},
            /* superior view with the patient's right (+x) up = anterior
             * (top) turned to the left: rolled 90 counter-clockwise */
            {VS_VIEW_SUPERIOR, 0, 0, 1, {1, 0, 0.5}, 0, VS_VIEW_SUPERIOR, 0, 0, 0, {0}, -90, 0},
            /* an unoriented volume: AUTO is the angles alone */
            {VS_VIEW_AUTO, 0, 0, 0, {0}, 0, VS_VIEW_ANGLES, 0, 0, 0, {0}, 0, -1},
        };
        for (size_t c = 0; c < sizeof eq / sizeof eq[0]; c++) {
            vs_settings a, b;
            base_settings(&a, VS_PIPELINE_POST_CD);
            b = a;
            a.view = eq[c].v, a.azimuth = eq[c].az, a.elevation = eq[c].el, a.has_up = eq[c].has_up, a.roll = eq[c].roll;
            memcpy(a.up, eq[c].up, sizeof a.up);
            b.view = eq[c].v2, b.azimuth = eq[c].az2, b.elevation = eq[c].el2, b.has_up = eq[c].has_up2, b.roll = eq[c].roll2;
            memcpy(b.up, eq[c].up2, sizeof b.up);
            const vs_volume *v = eq[c].vol < 0 ? bare : vol[0];
            vs_image ia = {0, 0, NULL}, ib = {0, 0, NULL};
            if (render(ctx, v, &a, &ia) && render(ctx, v, &b, &ib)) {
                double m = tu_max_diff(&ia, &ib);
                CHECK(m == 0.0, "view case %zu: differs by %g", c, m);
            }
            vs_image_free(&ia);
            vs_image_free(&ib);
        }
        /* and a roll is not a no-op */
        vs_settings a, b;
        base_settings(&a, VS_PIPELINE_POST_CD);
        b = a;
        b.roll = 90;
        vs_image ia = {0, 0, NULL}, ib = {0, 0, NULL};
        if (render(ctx, vol[0], &a, &ia) && render(ctx, vol[0], &b, &ib))
            CHECK(psnr(ctx, &ia, &ib) < 30.0, "roll 90 looks like roll 0");
        vs_image_free(&ia);
        vs_image_free(&ib);
        /* up along the view is refused, as is a bad view */
        b.roll = 0;
        b.view = VS_VIEW_ANTERIOR;
        b.has_up = 1;
        b.up[0] = 0, b.up[1] = 2, b.up[2] = 0;
        CHECK(vs_render(ctx, vol[0], &b, &ia, NULL) == VS_ERR_INVALID_ARGUMENT, "up along the view accepted");
        CHECK(strstr(vs_last_error(ctx), "up"), "message: %s", vs_last_error(ctx));
        b.up[1] = NAN;
        CHECK(vs_render(ctx, vol[0], &b, &ia, NULL) == VS_ERR_INVALID_ARGUMENT, "up NaN accepted");
        b.has_up = 0;
        b.roll = INFINITY;
        CHECK(vs_render(ctx, vol[0], &b, &ia, NULL) == VS_ERR_INVALID_ARGUMENT, "roll inf accepted");
        b.roll = 0;
        b.view = (vs_view)42;
        CHECK(vs_render(ctx, vol[0], &b, &ia, NULL) == VS_ERR_INVALID_ARGUMENT, "view 42 accepted");
        b.view = (vs_view)-1;
        CHECK(vs_render(ctx, vol[0], &b, &ia, NULL) == VS_ERR_INVALID_ARGUMENT, "view -1 accepted");
    }

    /* a sheared transform renders as it says: voxels sampled on a sheared
     * grid (k steps also move 0.3 of a step along x) look like the RAS
     * volume; the same voxels with the shear left out of the sform do not */
    {
        storage sh = make_storage("sheared", id, pos), flat;
        sh.m[0][2] = 0.3 * SP[2];
        sh.m[0][3] = -(sh.m[0][0] * 0.5 * (sh.n[0] - 1) + sh.m[0][2] * 0.5 * (sh.n[2] - 1));
        flat = sh;
        flat.m[0][2] = 0.0;
        flat.m[0][3] = -flat.m[0][0] * 0.5 * (flat.n[0] - 1);
        float *d = fill(&sh);
        char p1[1200], p2[1200];
        snprintf(p1, sizeof p1, "%s/sheared.nii", tmp);
        snprintf(p2, sizeof p2, "%s/shear-left-out.nii", tmp);
        write_nifti(p1, &sh, d);
        write_nifti(p2, &flat, d);
        free(d);
        vs_volume *vs = load(ctx, p1), *vf = load(ctx, p2);
        for (int p = 0; p < 2 && vs && vf; p++) {
            vs_settings s;
            base_settings(&s, pipes[p]);
            s.view = VS_VIEW_ANGLES;
            s.azimuth = 180.0; /* the front */
            s.elevation = 10.0;
            vs_image ref = {0, 0, NULL}, a = {0, 0, NULL}, b = {0, 0, NULL};
            if (render(ctx, vol[0], &s, &ref) && render(ctx, vs, &s, &a) && render(ctx, vf, &s, &b)) {
                double da = psnr(ctx, &ref, &a), db = psnr(ctx, &ref, &b);
                printf("%-10s sheared grid vs RAS: %.1f dB; shear left out: %.1f dB\n", vs_pipeline_name(pipes[p]), da,
                       db);
                CHECK(da >= 30.0 && db < da - 8.0, "%s: sheared %.1f dB, shear left out %.1f dB",
                      vs_pipeline_name(pipes[p]), da, db);
            }
            vs_image_free(&ref);
            vs_image_free(&a);
            vs_image_free(&b);
        }
        vs_volume_release(vs);
        vs_volume_release(vf);
    }

    /* vs_view_in_index and vs_volume_set_transform: the viewing direction in
     * index units per view unit (the smallest spacing), through a flip; the
     * perspective eye on the line through the centre against it */
    {
        vs_volume *v = NULL;
        const int dims[3] = {10, 20, 30};
        const double sp[3] = {1, 2, 3};
        CHECK(vs_volume_create(ctx, VS_U8, dims, sp, &v) == VS_OK, "create: %s", vs_last_error(ctx));
        vs_settings s;
        vs_settings_init(&s);
        s.view = VS_VIEW_ANGLES;
        s.azimuth = 90.0; /* world direction -x */
        double dir[3], eye[3];
        CHECK(vs_view_in_index(ctx, v, &s, dir, eye) == VS_OK, "view: %s", vs_last_error(ctx));
        CHECK(fabs(dir[0] + 1.0) < 1e-12 && fabs(dir[1]) < 1e-12 && fabs(dir[2]) < 1e-12 && isnan(eye[0]),
              "az 90 unoriented: dir %g %g %g", dir[0], dir[1], dir[2]);
        const double flip[12] = {-1, 0, 0, 9, 0, 2, 0, 0, 0, 0, 3, 0};
        CHECK(vs_volume_set_transform(ctx, v, flip) == VS_OK, "transform: %s", vs_last_error(ctx));
        s.elevation = 0.0;
        s.perspective_fov = 30.0;
        CHECK(vs_view_in_index(ctx, v, &s, dir, eye) == VS_OK, "view: %s", vs_last_error(ctx));
        CHECK(fabs(dir[0] - 1.0) < 1e-12 && fabs(dir[1]) < 1e-12 && fabs(dir[2]) < 1e-12,
              "az 90, x stored reversed: dir %g %g %g (want 1 0 0)", dir[0], dir[1], dir[2]);
        CHECK(eye[0] < 0.0 && fabs(eye[1] - 9.5) < 1e-9 && fabs(eye[2] - 14.5) < 1e-9,
              "perspective eye %g %g %g: not before the centre against dir", eye[0], eye[1], eye[2]);
        vs_view pv = VS_VIEW_AUTO;
        CHECK(vs_view_parse("Left", &pv) == VS_OK && pv == VS_VIEW_LEFT && vs_view_parse("inferior", &pv) == VS_OK &&
                  pv == VS_VIEW_INFERIOR && vs_view_parse("sideways", &pv) != VS_OK,
              "vs_view_parse");
        const double singular[12] = {1, 0, 0, 0, 1, 0, 0, 0, 0, 0, 0, 0};
        CHECK(vs_volume_set_transform(ctx, v, singular) != VS_OK, "a singular transform was taken");
        vs_volume_release(v);
    }

    for (int i = 0; i < 6; i++) vs_volume_release(vol[i]);
    vs_volume_release(bare);
    vs_context_release(ctx);
    tu_remove_tmpdir(tmp);
    TEST_DONE();
}
