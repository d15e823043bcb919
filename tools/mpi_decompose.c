/* vsplat-mpi: k-d split balanced by relevant voxels, visibility order. */
#include "mpi_decompose.h"

#include <stdlib.h>
#include <string.h>

static double value_at(const void *data, vs_type t, size_t i)
{
    switch (t) {
    case VS_U8: return ((const unsigned char *)data)[i];
    case VS_I16: return ((const int16_t *)data)[i];
    case VS_U16: return ((const uint16_t *)data)[i];
    default: return ((const float *)data)[i];
    }
}

/* Weight of each slab of box [lo, hi) along axis, into w[0 .. hi-lo). */
static void slab_weights(const vs_volume *vol, const int lo[3], const int hi[3], int axis, double alo,
                         double ahi, double *w)
{
    int d[3];
    vs_volume_dims(vol, d);
    const void *data = vs_volume_data((vs_volume *)vol);
    const vs_type t = vs_volume_type(vol);
    memset(w, 0, sizeof *w * (size_t)(hi[axis] - lo[axis]));
    for (int k = lo[2]; k < hi[2]; k++)
        for (int j = lo[1]; j < hi[1]; j++) {
            size_t row = ((size_t)k * d[1] + j) * d[0];
            for (int i = lo[0]; i < hi[0]; i++) {
                double v = value_at(data, t, row + i);
                const int c[3] = {i, j, k};
                w[c[axis] - lo[axis]] += (v > alo && v < ahi ? 1.0 : 0.0) + 1.0 / 16.0;
            }
        }
}

typedef struct split_job {
    const vs_volume *vol;
    double alo, ahi, sp[3];
    int ghost, dims[3];
    mpi_decomp *D;
    double *w;
} split_job;

static int split(split_job *J, const int lo[3], const int hi[3], int r0, int r1, double cost)
{
    mpi_decomp *D = J->D;
    const int id = D->nnodes++;
    mpi_kd_node *nd = &D->node[id];
    if (r1 - r0 == 1) {
        *nd = (mpi_kd_node){-1, 0, -1, -1, r0};
        mpi_brick *b = &D->brick[r0];
        for (int a = 0; a < 3; a++) {
            b->lo[a] = lo[a];
            b->hi[a] = hi[a];
            b->glo[a] = lo[a] - J->ghost > 0 ? lo[a] - J->ghost : 0;
            b->ghi[a] = hi[a] + J->ghost < J->dims[a] ? hi[a] + J->ghost : J->dims[a];
        }
        b->cost = cost;
        return 0;
    }
    int axis = -1;
    double best = 0.0;
    for (int a = 0; a < 3; a++) {
        double mm = (hi[a] - lo[a]) * J->sp[a];
        if (hi[a] - lo[a] >= 2 && mm > best) {
            best = mm;
            axis = a;
        }
    }
    if (axis < 0) return 1;
    const int rm = r0 + (r1 - r0) / 2;
    slab_weights(J->vol, lo, hi, axis, J->alo, J->ahi, J->w);
    const int w = hi[axis] - lo[axis];
    double total = 0.0;
    for (int i = 0; i < w; i++) total += J->w[i];
    const double target = total * (rm - r0) / (r1 - r0);
    /* the cut after slab c: the first whose prefix reaches the target, at
     * least one slab on each side */
    double run = 0.0;
    int c = 1;
    for (int i = 0; i < w - 1; i++) {
        run += J->w[i];
        c = i + 1;
        if (run >= target) break;
    }
    double low_cost = 0.0;
    for (int i = 0; i < c; i++) low_cost += J->w[i];
    int mid_hi[3], mid_lo[3];
    memcpy(mid_hi, hi, sizeof mid_hi);
    memcpy(mid_lo, lo, sizeof mid_lo);
    mid_hi[axis] = lo[axis] + c;
    mid_lo[axis] = lo[axis] + c;
    nd->axis = axis;
    nd->split = lo[axis] + c;
    nd->rank = -1;
    nd->low = D->nnodes;
    if (split(J, lo, mid_hi, r0, rm, low_cost)) return 1;
    D->node[id].high = D->nnodes;
    return split(J, mid_lo, hi, rm, r1, total - low_cost);
}

int mpi_decompose(const vs_volume *vol, double alpha_lo, double alpha_hi, int n, int ghost, mpi_decomp *D)
{
    if (n < 1 || n > MPI_MAX_RANKS) return 1;
    split_job J = {vol, alpha_lo, alpha_hi, {0, 0, 0}, ghost, {0, 0, 0}, D, NULL};
    vs_volume_dims(vol, J.dims);
    vs_volume_spacing(vol, J.sp);
    int maxd = J.dims[0] > J.dims[1] ? J.dims[0] : J.dims[1];
    if (J.dims[2] > maxd) maxd = J.dims[2];
    J.w = malloc(sizeof *J.w * (size_t)maxd);
    if (!J.w) return 1;
    D->n = n;
    D->nnodes = 0;
    const int lo[3] = {0, 0, 0};
    int rc = split(&J, lo, J.dims, 0, n, 0.0);
    free(J.w);
    return rc;
}

static void visit(const mpi_decomp *D, int id, const double eye[3], const double dir[3], int *order, int *k)
{
    const mpi_kd_node *nd = &D->node[id];
    if (nd->low < 0) {
        order[(*k)++] = nd->rank;
        return;
    }
    /* the side that holds the eye, or that the view enters first, is nearer */
    int low_first = eye ? eye[nd->axis] < nd->split - 0.5 : dir[nd->axis] >= 0.0;
    visit(D, low_first ? nd->low : nd->high, eye, dir, order, k);
    visit(D, low_first ? nd->high : nd->low, eye, dir, order, k);
}

void mpi_visibility_order(const mpi_decomp *D, const double eye[3], const double dir[3], int *order)
{
    int k = 0;
    visit(D, 0, eye, dir, order, &k);
}
