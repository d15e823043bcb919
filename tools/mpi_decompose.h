/* vsplat-mpi: the k-d split of a volume into one brick per rank, balanced
 * by relevant voxels, and the visibility order of the bricks.  No MPI here:
 * rank 0 computes the split and sends it. */
#ifndef VSPLAT_MPI_DECOMPOSE_H
#define VSPLAT_MPI_DECOMPOSE_H

#include "vsplat.h"

#include <stdint.h>

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

/* What the split balances: per cell of cell^3 voxels, how many voxels can
 * be non-transparent (value in the open range (alpha_lo, alpha_hi)).  Cells
 * are as small as 2^21 of them allow, so the grid is a few MB whatever the
 * volume; the ranks that read a volume in parts each add their slabs and
 * sum the grids, and every split agrees with the one of the whole volume. */
typedef struct mpi_weights {
    int dims[3];      /* the volume's                                      */
    int cell;         /* voxels per cell side                              */
    int g[3];         /* cells per axis                                    */
    uint32_t *count;  /* g[0]*g[1]*g[2], x fastest                         */
} mpi_weights;
/* Zeroed counts for a volume of dims; 1 if out of memory. */
int mpi_weights_init(mpi_weights *W, const int dims[3]);
void mpi_weights_free(mpi_weights *W);
/* Counts the voxels of part, which holds slices z0 .. z0 + its depth of the
 * volume (every x and y). */
void mpi_weights_add(mpi_weights *W, const vs_volume *part, int z0, double alpha_lo, double alpha_hi);

/* Split the volume into n bricks: at each node the longest axis (in mm) is
 * cut at a cell boundary where the weight of its cell slabs divides in the
 * ratio of the ranks on each side.  A cell weighs its count plus 1/16 of its
 * voxels, so empty space is split by size.  ghost: voxels added on each
 * inner face.  Returns 0, or 1 if the volume is too small for n bricks (a
 * side thinner than one cell). */
int mpi_decompose(const mpi_weights *W, const double spacing[3], int n, int ghost, mpi_decomp *D);

/* Front-to-back order of the ranks.  eye: the eye in index coordinates
 * (perspective), or NULL for orthographic with view direction dir in
 * index coordinates. */
void mpi_visibility_order(const mpi_decomp *D, const double eye[3], const double dir[3], int *order);

#endif
