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

int mpi_weights_init(mpi_weights *W, const int dims[3])
{
    memset(W, 0, sizeof *W);
    memcpy(W->dims, dims, sizeof W->dims);
    size_t cells;
    for (W->cell = 1;; W->cell++) {
        cells = 1;
        for (int a = 0; a < 3; a++) cells *= (size_t)(W->g[a] = (dims[a] + W->cell - 1) / W->cell);
        if (cells <= (size_t)1 << 21) break;
    }
    W->count = calloc(cells, sizeof *W->count);
    return !W->count;
}

void mpi_weights_free(mpi_weights *W)
{
    free(W->count);
    W->count = NULL;
}

void mpi_weights_add(mpi_weights *W, const vs_volume *part, int z0, double alo, double ahi)
{
    int d[3];
    vs_volume_dims(part, d);
    const void *data = vs_volume_data((vs_volume *)part);
    const vs_type t = vs_volume_type(part);
    const int c = W->cell;
    for (int k = 0; k < d[2]; k++)
        for (int j = 0; j < d[1]; j++) {
            uint32_t *row = W->count + ((size_t)((z0 + k) / c) * W->g[1] + (size_t)(j / c)) * W->g[0];
            const size_t at = ((size_t)k * d[1] + j) * d[0];
            for (int i = 0; i < d[0]; i++) {
                double v = value_at(data, t, at + i);
                row[i / c] += v > alo && v < ahi;
            }
        }
}

/* Voxels of the volume in cell index ci along axis a. */
static int cell_extent(const mpi_weights *W, int a, int ci)
{
    int lo = ci * W->cell, hi = lo + W->cell < W->dims[a] ? lo + W->cell : W->dims[a];
    return hi - lo;
}

/* Weight of each cell slab of cell box [lo, hi) along axis, into w. */
static void slab_weights(const mpi_weights *W, const int lo[3], const int hi[3], int axis, double *w)
{
    memset(w, 0, sizeof *w * (size_t)(hi[axis] - lo[axis]));
    for (int k = lo[2]; k < hi[2]; k++)
        for (int j = lo[1]; j < hi[1]; j++) {
            const uint32_t *row = W->count + ((size_t)k * W->g[1] + j) * W->g[0];
            const int ej = cell_extent(W, 1, j) * cell_extent(W, 2, k);
            for (int i = lo[0]; i < hi[0]; i++) {
                const int c[3] = {i, j, k};
                w[c[axis] - lo[axis]] += row[i] + ej * cell_extent(W, 0, i) / 16.0;
            }
        }
}

typedef struct split_job {
    const mpi_weights *W;
    double sp[3];
    int ghost;
    mpi_decomp *D;
    double *w;
} split_job;

/* The voxel index where cell index ci begins. */
static int voxel_of(const mpi_weights *W, int a, int ci)
{
    long v = (long)ci * W->cell;
    return v < W->dims[a] ? (int)v : W->dims[a];
}

/* lo, hi: the box in cells */
static int split(split_job *J, const int lo[3], const int hi[3], int r0, int r1, double cost)
{
    mpi_decomp *D = J->D;
    const mpi_weights *W = J->W;
    const int id = D->nnodes++;
    mpi_kd_node *nd = &D->node[id];
    if (r1 - r0 == 1) {
        *nd = (mpi_kd_node){-1, 0, -1, -1, r0};
        mpi_brick *b = &D->brick[r0];
        for (int a = 0; a < 3; a++) {
            b->lo[a] = voxel_of(W, a, lo[a]);
            b->hi[a] = voxel_of(W, a, hi[a]);
            b->glo[a] = b->lo[a] - J->ghost > 0 ? b->lo[a] - J->ghost : 0;
            b->ghi[a] = b->hi[a] + J->ghost < W->dims[a] ? b->hi[a] + J->ghost : W->dims[a];
        }
        b->cost = cost;
        return 0;
    }
    int axis = -1;
    double best = 0.0;
    for (int a = 0; a < 3; a++) {
        double mm = (voxel_of(W, a, hi[a]) - voxel_of(W, a, lo[a])) * J->sp[a];
        if (hi[a] - lo[a] >= 2 && mm > best) {
            best = mm;
            axis = a;
        }
    }
    if (axis < 0) return 1;
    const int rm = r0 + (r1 - r0) / 2;
    slab_weights(W, lo, hi, axis, J->w);
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
    nd->split = voxel_of(W, axis, lo[axis] + c);
    nd->rank = -1;
    nd->low = D->nnodes;
    if (split(J, lo, mid_hi, r0, rm, low_cost)) return 1;
    D->node[id].high = D->nnodes;
    return split(J, mid_lo, hi, rm, r1, total - low_cost);
}

int mpi_decompose(const mpi_weights *W, const double spacing[3], int n, int ghost, mpi_decomp *D)
{
    if (n < 1 || n > MPI_MAX_RANKS) return 1;
    split_job J = {W, {spacing[0], spacing[1], spacing[2]}, ghost, D, NULL};
    int maxg = W->g[0] > W->g[1] ? W->g[0] : W->g[1];
    if (W->g[2] > maxg) maxg = W->g[2];
    J.w = malloc(sizeof *J.w * (size_t)maxg);
    if (!J.w) return 1;
    D->n = n;
    D->nnodes = 0;
    const int lo[3] = {0, 0, 0};
    int rc = split(&J, lo, W->g, 0, n, 0.0);
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
