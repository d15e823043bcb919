/* vsplat-mpi: the k-d split of a volume into one brick per rank, balanced
 * by relevant voxels, and the visibility order of the bricks.  No MPI here:
 * rank 0 computes the split and sends it. */
#ifndef VSPLAT_MPI_DECOMPOSE_H
#define VSPLAT_MPI_DECOMPOSE_H

#include "vsplat.h"

#define MPI_MAX_RANKS 4096

/* One rank's part: it owns (composites) voxels [lo, hi) and holds
 * [glo, ghi), the owned box with the ghost layer, clamped to the volume. */
typedef struct mpi_brick {
    int lo[3], hi[3];
    int glo[3], ghi[3];
    double cost; /* relevant-voxel weight of the owned box */
} mpi_brick;

/* The k-d tree: node 0 is the root; a leaf holds one rank. */
typedef struct mpi_kd_node {
    int axis, split;   /* inner node: low child owns index < split on axis */
    int low, high;     /* children (node indices), -1 for a leaf          */
    int rank;          /* leaf: the rank                                  */
} mpi_kd_node;

typedef struct mpi_decomp {
    int n;
    mpi_brick brick[MPI_MAX_RANKS];
    mpi_kd_node node[2 * MPI_MAX_RANKS];
    int nnodes;
} mpi_decomp;

/* Split vol into n bricks: at each node the longest axis (in mm) is cut
 * where the weight of its slabs divides in the ratio of the ranks on each
 * side.  A voxel weighs 1 if its value can be non-transparent (value in
 * the open range (alpha_lo, alpha_hi)) plus 1/16, so empty space is split
 * by size.  ghost: voxels added on each inner face.  Returns 0, or 1 if the
 * volume is too small for n bricks (a side thinner than one voxel). */
int mpi_decompose(const vs_volume *vol, double alpha_lo, double alpha_hi, int n, int ghost, mpi_decomp *D);

/* Front-to-back order of the ranks.  eye: the eye in index coordinates
 * (perspective), or NULL for orthographic with view direction dir in
 * index coordinates. */
void mpi_visibility_order(const mpi_decomp *D, const double eye[3], const double dir[3], int *order);

#endif
