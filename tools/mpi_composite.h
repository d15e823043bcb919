/* vsplat-mpi: sort-last compositing of the ranks' partial images. */
#ifndef VSPLAT_MPI_COMPOSITE_H
#define VSPLAT_MPI_COMPOSITE_H

#include "vsplat.h"

#include <mpi.h>
#include <stdint.h>

/* The pixels a partial image touches (alpha > 0): [x0, x1) x [y0, y1),
 * empty when x0 == x1. */
typedef struct mpi_rect {
    int x0, y0, x1, y1;
} mpi_rect;

mpi_rect mpi_touched(const vs_image *img);

/* Depth-ordered gather: every rank sends the premultiplied RGBA of its
 * touched rectangle to rank 0, which composites them front to back in
 * `order` (the same on every rank) over the background and returns the
 * straight image in *out (rank 0 only).  A fixed order, so the image does
 * not depend on timing.  *bytes_sent: what this rank sent.  Collective;
 * returns 0, or 1 on rank 0 when out of memory (the others still complete). */
int mpi_composite_gather(MPI_Comm comm, const vs_image *partial, const int *order, const float background[4],
                         vs_image *out, uint64_t *bytes_sent);

/* The same image by an MPI reduction: the ranks, renumbered front to back
 * in `order`, reduce the union of their touched rectangles with a
 * non-commutative "over" operator, which MPI may evaluate as a tree (Open
 * MPI has an in-order binary tree for such operators: log N rounds, rank
 * 0 receiving log N messages instead of N - 1), at the price of every
 * rank sending the union rather than its own rectangle.  The result differs from the gather's only by
 * float association (|over| is associative in exact arithmetic), and is
 * the same run to run for a given N.  Same contract as the gather. */
int mpi_composite_reduce(MPI_Comm comm, const vs_image *partial, const int *order, const float background[4],
                         vs_image *out, uint64_t *bytes_sent);

/* The same image by binary swap (Ma et al. 1994) over the union of the
 * touched rectangles, ranks renumbered front to back in `order`: with N not
 * a power of two the first 2(N - P) ranks first fold pairwise to P, a power
 * of two; then log2 P rounds, in each of which a rank gives its partner
 * one half of the rows it still holds and composites the partner's other
 * half into its own (over or under, by which of the two is nearer the eye),
 * sending only the part of the half that holds any opacity; then the P
 * disjoint pieces go to rank 0.  Every rank sends about 16 bytes per pixel
 * of the union in all, whatever N, and composites in parallel.  Differs
 * from the gather by float association only; the same run to run.  Same
 * contract as the gather. */
int mpi_composite_swap(MPI_Comm comm, const vs_image *partial, const int *order, const float background[4],
                       vs_image *out, uint64_t *bytes_sent);

#endif
