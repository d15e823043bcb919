/* vsplat-mpi: compositing of premultiplied partial images, by a
 * depth-ordered gather at rank 0 or by a non-commutative MPI reduction. */
#include "mpi_composite.h"

#include <stdlib.h>
#include <string.h>

mpi_rect mpi_touched(const vs_image *img)
{
    mpi_rect r = {img->width, img->height, 0, 0};
    for (int y = 0; y < img->height; y++)
        for (int x = 0; x < img->width; x++)
            if (img->rgba[4 * ((size_t)y * img->width + x) + 3] > 0.0f) {
                if (x < r.x0) r.x0 = x;
                if (x >= r.x1) r.x1 = x + 1;
                if (y < r.y0) r.y0 = y;
                if (y >= r.y1) r.y1 = y + 1;
            }
    if (r.x1 <= r.x0 || r.y1 <= r.y0) r = (mpi_rect){0, 0, 0, 0};
    return r;
}

static size_t rect_floats(const mpi_rect *r) { return (size_t)(r->x1 - r->x0) * (size_t)(r->y1 - r->y0) * 4; }

/* The rectangle of a straight image as premultiplied RGBA. */
static void pack(const vs_image *img, const mpi_rect *r, float *buf)
{
    for (int y = r->y0; y < r->y1; y++)
        for (int x = r->x0; x < r->x1; x++) {
            const float *p = img->rgba + 4 * ((size_t)y * img->width + x);
            float a = p[3];
            buf[0] = p[0] * a;
            buf[1] = p[1] * a;
            buf[2] = p[2] * a;
            buf[3] = a;
            buf += 4;
        }
}

/* acc (front) over the premultiplied rectangle behind it. */
static void under(float *acc, int width, const mpi_rect *r, const float *src)
{
    for (int y = r->y0; y < r->y1; y++)
        for (int x = r->x0; x < r->x1; x++) {
            float *d = acc + 4 * ((size_t)y * width + x);
            float t = 1.0f - d[3];
            for (int c = 0; c < 4; c++) d[c] += t * src[c];
            src += 4;
        }
}

static void finish(float *acc, size_t np, const float background[4]);

int mpi_composite_gather(MPI_Comm comm, const vs_image *partial, const int *order, const float background[4],
                         vs_image *out, uint64_t *bytes_sent)
{
    int rank, n;
    MPI_Comm_rank(comm, &rank);
    MPI_Comm_size(comm, &n);
    mpi_rect mine = mpi_touched(partial);
    mpi_rect *rects = rank == 0 ? malloc(sizeof *rects * (size_t)n) : NULL;
    int failed = rank == 0 && !rects;
    MPI_Bcast(&failed, 1, MPI_INT, 0, comm);
    if (failed) return rank == 0;
    MPI_Gather(&mine, 4, MPI_INT, rects, 4, MPI_INT, 0, comm);
    *bytes_sent = rank == 0 ? 0 : sizeof mine;

    /* rank 0 needs the image and the largest rectangle; others their own */
    size_t cap = rect_floats(&mine);
    float *acc = NULL;
    if (rank == 0) {
        for (int r = 0; r < n; r++)
            if (rect_floats(&rects[r]) > cap) cap = rect_floats(&rects[r]);
        acc = calloc((size_t)partial->width * partial->height * 4, sizeof *acc);
    }
    float *buf = malloc((cap ? cap : 1) * sizeof *buf);
    failed = rank == 0 && (!acc || !buf);
    MPI_Bcast(&failed, 1, MPI_INT, 0, comm); /* nobody sends to a root that cannot take it */
    if (failed || !buf) {
        /* a non-root rank without memory cannot send: MPI aborts all ranks
         * rather than leave rank 0 waiting */
        if (!failed) MPI_Abort(comm, 2);
        free(buf);
        free(acc);
        free(rects);
        return rank == 0;
    }
    if (rank != 0) {
        pack(partial, &mine, buf);
        MPI_Send(buf, (int)rect_floats(&mine), MPI_FLOAT, 0, 1, comm);
        *bytes_sent += rect_floats(&mine) * sizeof *buf;
        free(buf);
        return 0;
    }
    /* rank 0: front to back, receiving each rank's rectangle in turn */
    for (int i = 0; i < n; i++) {
        const int r = order[i];
        if (r == 0)
            pack(partial, &mine, buf);
        else
            MPI_Recv(buf, (int)rect_floats(&rects[r]), MPI_FLOAT, r, 1, comm, MPI_STATUS_IGNORE);
        under(acc, partial->width, &rects[r], buf);
    }
    finish(acc, (size_t)partial->width * partial->height, background);
    out->width = partial->width;
    out->height = partial->height;
    out->rgba = acc;
    free(buf);
    free(rects);
    return 0;
}

/* The background under what is left, stored straight (as vs_finish_pixel). */
static void finish(float *acc, size_t np, const float background[4])
{
    for (size_t p = 0; p < np; p++) {
        float *d = acc + 4 * p;
        float t = 1.0f - d[3];
        float a = d[3] + t * background[3];
        for (int c = 0; c < 3; c++) {
            float rgb = d[c] + t * background[c] * background[3];
            d[c] = a > 0.0f ? rgb / a : 0.0f;
        }
        d[3] = a;
    }
}

/* inout = in over inout, pixel by pixel: MPI passes the operand of the
 * lower rank (nearer the eye) as `in` for a non-commutative operator. */
static void over_op(void *in, void *inout, int *len, MPI_Datatype *type)
{
    (void)type;
    const float *a = in;
    float *b = inout;
    for (int i = 0; i < *len; i++, a += 4, b += 4) {
        const float t = 1.0f - a[3];
        for (int c = 0; c < 4; c++) b[c] = a[c] + t * b[c];
    }
}

int mpi_composite_reduce(MPI_Comm comm, const vs_image *partial, const int *order, const float background[4],
                         vs_image *out, uint64_t *bytes_sent)
{
    int rank, n;
    MPI_Comm_rank(comm, &rank);
    MPI_Comm_size(comm, &n);
    *bytes_sent = 0;
    /* the union of the touched rectangles (an empty one adds nothing) */
    const mpi_rect mine = mpi_touched(partial);
    const int empty = mine.x1 == mine.x0;
    int b[4] = {empty ? -partial->width : -mine.x0, empty ? -partial->height : -mine.y0, mine.x1, mine.y1}, u[4];
    MPI_Allreduce(b, u, 4, MPI_INT, MPI_MAX, comm);
    mpi_rect all = {-u[0], -u[1], u[2], u[3]};
    if (all.x1 <= all.x0 || all.y1 <= all.y0) all = (mpi_rect){0, 0, 0, 0};
    /* ranks numbered front to back; rank 0 of comm is where the image ends */
    int pos = 0, root = 0;
    for (int i = 0; i < n; i++) {
        if (order[i] == rank) pos = i;
        if (order[i] == 0) root = i;
    }
    const size_t count = rect_floats(&all) / 4;
    float *buf = malloc((count ? 4 * count : 4) * sizeof *buf);
    float *acc = rank == 0 ? calloc((size_t)partial->width * partial->height * 4, sizeof *acc) : NULL;
    float *res = rank == 0 ? malloc((count ? 4 * count : 4) * sizeof *res) : NULL;
    int failed = !buf || (rank == 0 && (!acc || !res)), any;
    MPI_Allreduce(&failed, &any, 1, MPI_INT, MPI_MAX, comm);
    if (any) {
        free(buf);
        free(acc);
        free(res);
        return rank == 0; /* reported once, by rank 0 */
    }
    if (count) {
        pack(partial, &all, buf);
        MPI_Comm depth;
        MPI_Datatype px;
        MPI_Op op;
        MPI_Comm_split(comm, 0, pos, &depth);
        MPI_Type_contiguous(4, MPI_FLOAT, &px); /* MPI may cut a message, never a pixel */
        MPI_Type_commit(&px);
        MPI_Op_create(over_op, 0, &op);
        if (count > (size_t)INT32_MAX) MPI_Abort(comm, 2); /* 2^31 pixels: not an image this makes */
        MPI_Reduce(buf, res, (int)count, px, op, root, depth);
        MPI_Op_free(&op);
        MPI_Type_free(&px);
        MPI_Comm_free(&depth);
        if (pos != root) *bytes_sent = 16 * (uint64_t)count; /* a tree: about one message per rank */
        if (rank == 0) {
            const float *src = res;
            for (int y = all.y0; y < all.y1; y++, src += 4 * (size_t)(all.x1 - all.x0))
                memcpy(acc + 4 * ((size_t)y * partial->width + all.x0), src,
                       4 * (size_t)(all.x1 - all.x0) * sizeof *src);
        }
    }
    free(buf);
    free(res);
    if (rank != 0) return 0;
    finish(acc, (size_t)partial->width * partial->height, background);
    out->width = partial->width;
    out->height = partial->height;
    out->rgba = acc;
    return 0;
}
