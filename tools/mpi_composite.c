/* vsplat-mpi: depth-ordered gather of premultiplied partial images. */
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
    /* the background under what is left, stored straight (as vs_finish_pixel) */
    const size_t np = (size_t)partial->width * partial->height;
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
    out->width = partial->width;
    out->height = partial->height;
    out->rgba = acc;
    free(buf);
    free(rects);
    return 0;
}
