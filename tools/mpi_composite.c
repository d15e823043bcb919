/* vsplat-mpi: compositing of premultiplied partial images, by a
 * depth-ordered gather at rank 0, by a non-commutative MPI reduction, or by
 * binary swap. */
#include "mpi_composite.h"

#include <stdlib.h>
#include <string.h>

/* The part of rows [y0, y1) of RGBA pixels w wide that holds any opacity
 * (straight or premultiplied: alpha is the fourth float either way). */
static mpi_rect touched_rows(const float *rgba, int w, int y0, int y1)
{
    mpi_rect r = {w, y1, 0, y0};
    for (int y = y0; y < y1; y++)
        for (int x = 0; x < w; x++)
            if (rgba[4 * ((size_t)y * w + x) + 3] > 0.0f) {
                if (x < r.x0) r.x0 = x;
                if (x >= r.x1) r.x1 = x + 1;
                if (y < r.y0) r.y0 = y;
                if (y >= r.y1) r.y1 = y + 1;
            }
    if (r.x1 <= r.x0 || r.y1 <= r.y0) r = (mpi_rect){0, 0, 0, 0};
    return r;
}

mpi_rect mpi_touched(const vs_image *img) { return touched_rows(img->rgba, img->width, 0, img->height); }

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

static void finish(float *acc, const vs_image *partial, const float background[4], vs_image *out);

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
    finish(acc, partial, background, out);
    free(buf);
    free(rects);
    return 0;
}

/* The background under what is left, stored straight (as vs_finish_pixel),
 * as the image *out. */
static void finish(float *acc, const vs_image *partial, const float background[4], vs_image *out)
{
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
}

/* The union of all ranks' touched rectangles (an empty one adds nothing). */
static mpi_rect union_rect(MPI_Comm comm, const vs_image *partial)
{
    const mpi_rect mine = mpi_touched(partial);
    const int empty = mine.x1 == mine.x0;
    int b[4] = {empty ? -partial->width : -mine.x0, empty ? -partial->height : -mine.y0, mine.x1, mine.y1}, u[4];
    MPI_Allreduce(b, u, 4, MPI_INT, MPI_MAX, comm);
    mpi_rect all = {-u[0], -u[1], u[2], u[3]};
    if (all.x1 <= all.x0 || all.y1 <= all.y0) all = (mpi_rect){0, 0, 0, 0};
    return all;
}

/* Where a rank stands in the front-to-back order. */
static int position_of(const int *order, int n, int rank)
{
    for (int i = 0; i < n; i++)
        if (order[i] == rank) return i;
    return 0;
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
    const mpi_rect all = union_rect(comm, partial);
    /* ranks numbered front to back; rank 0 of comm is where the image ends */
    const int pos = position_of(order, n, rank), root = position_of(order, n, 0);
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
    finish(acc, partial, background, out);
    return 0;
}

/* ---- binary swap ---- */

/* A piece: an mpi_rect in the coordinates of the premultiplied buffer
 * over the union rectangle (w wide). */
static size_t piece_px(const mpi_rect *p) { return rect_floats(p) / 4; }

/* The piece's pixels of buf, row after row, into dst. */
static void copy_piece(const float *buf, int w, const mpi_rect *p, float *dst)
{
    for (int y = p->y0; y < p->y1; y++) {
        const size_t n = 4 * (size_t)(p->x1 - p->x0);
        memcpy(dst, buf + 4 * ((size_t)y * w + p->x0), n * sizeof *dst);
        dst += n;
    }
}

/* Composites the received piece into buf: over it when this rank is
 * nearer the eye (front), under it otherwise. */
static void merge(float *buf, int w, const mpi_rect *p, const float *src, int front)
{
    for (int y = p->y0; y < p->y1; y++)
        for (int x = p->x0; x < p->x1; x++, src += 4) {
            float *d = buf + 4 * ((size_t)y * w + x);
            if (front) {
                const float t = 1.0f - d[3];
                for (int c = 0; c < 4; c++) d[c] += t * src[c];
            } else {
                const float t = 1.0f - src[3];
                for (int c = 0; c < 4; c++) d[c] = src[c] + t * d[c];
            }
        }
}

/* Sends the touched part of rows [y0, y1) to `to` and takes `from`'s piece
 * into tmp (room for the rows); returns the piece received. */
static mpi_rect swap_rows(MPI_Comm depth, const float *buf, int w, int y0, int y1, int to, int from, float *tmp,
                       float *out, uint64_t *bytes_sent)
{
    mpi_rect mine = to >= 0 ? touched_rows(buf, w, y0, y1) : (mpi_rect){0, 0, 0, 0}, got = {0, 0, 0, 0};
    MPI_Sendrecv(&mine, 4, MPI_INT, to >= 0 ? to : MPI_PROC_NULL, 2, &got, 4, MPI_INT,
                 from >= 0 ? from : MPI_PROC_NULL, 2, depth, MPI_STATUS_IGNORE);
    const size_t ns = piece_px(&mine), nr = piece_px(&got);
    if (ns) copy_piece(buf, w, &mine, out);
    MPI_Sendrecv(out, (int)(4 * ns), MPI_FLOAT, ns ? to : MPI_PROC_NULL, 3, tmp, (int)(4 * nr), MPI_FLOAT,
                 nr ? from : MPI_PROC_NULL, 3, depth, MPI_STATUS_IGNORE);
    if (to >= 0) *bytes_sent += sizeof mine + 16 * (uint64_t)ns;
    return got;
}

int mpi_composite_swap(MPI_Comm comm, const vs_image *partial, const int *order, const float background[4],
                       vs_image *out, uint64_t *bytes_sent)
{
    int rank, n;
    MPI_Comm_rank(comm, &rank);
    MPI_Comm_size(comm, &n);
    *bytes_sent = 0;
    const mpi_rect all = union_rect(comm, partial);
    const int w = all.x1 - all.x0, h = all.y1 - all.y0;
    const size_t count = rect_floats(&all);
    float *buf = malloc((count ? count : 4) * sizeof *buf), *tmp = malloc((count ? count : 4) * sizeof *tmp),
          *snd = malloc((count ? count : 4) * sizeof *snd);
    float *acc = rank == 0 ? calloc((size_t)partial->width * partial->height * 4, sizeof *acc) : NULL;
    int failed = !buf || !tmp || !snd || (rank == 0 && !acc), any;
    MPI_Allreduce(&failed, &any, 1, MPI_INT, MPI_MAX, comm);
    if (any || count > (size_t)INT32_MAX) {
        free(buf);
        free(tmp);
        free(snd);
        free(acc);
        if (!any) MPI_Abort(comm, 2); /* 2^31 floats: not an image this makes */
        return rank == 0;
    }
    /* ranks numbered front to back */
    const int pos = position_of(order, n, rank);
    MPI_Comm depth;
    MPI_Comm_split(comm, 0, pos, &depth);
    if (count) pack(partial, &all, buf);

    /* fold down to a power of two: of the first 2*extra ranks, each odd one
     * (behind) hands its image to the even one before it */
    int p2 = 1;
    while (2 * p2 <= n) p2 *= 2;
    const int extra = n - p2;
    int vi = pos < 2 * extra ? (pos % 2 ? -1 : pos / 2) : pos - extra;
    if (pos < 2 * extra) {
        const int odd = pos % 2;
        mpi_rect got = swap_rows(depth, buf, w, 0, h, odd ? pos - 1 : -1, odd ? -1 : pos + 1, tmp, snd, bytes_sent);
        if (!odd) merge(buf, w, &got, tmp, 1);
    }
    /* binary swap among the p2 ranks left: each round halves the rows a
     * rank keeps and composites its partner's half into them */
    int y0 = 0, y1 = h;
    if (vi >= 0)
        for (int bit = 1; bit < p2; bit *= 2) {
            const int pv = vi ^ bit, partner = pv < extra ? 2 * pv : pv + extra;
            const int mid = y0 + (y1 - y0) / 2, keep_low = !(vi & bit);
            const int sy0 = keep_low ? mid : y0, sy1 = keep_low ? y1 : mid;
            mpi_rect got = swap_rows(depth, buf, w, sy0, sy1, partner, partner, tmp, snd, bytes_sent);
            merge(buf, w, &got, tmp, vi < pv);
            if (keep_low) y1 = mid;
            else y0 = mid;
        }
    /* rank 0 of comm gathers the disjoint pieces */
    mpi_rect fin = vi >= 0 ? touched_rows(buf, w, y0, y1) : (mpi_rect){0, 0, 0, 0};
    mpi_rect *pieces = rank == 0 ? malloc(sizeof *pieces * (size_t)n) : NULL;
    if (rank == 0 && !pieces) MPI_Abort(comm, 2);
    MPI_Gather(&fin, 4, MPI_INT, pieces, 4, MPI_INT, 0, comm);
    if (rank != 0) {
        if (piece_px(&fin)) {
            copy_piece(buf, w, &fin, snd);
            MPI_Send(snd, (int)(4 * piece_px(&fin)), MPI_FLOAT, 0, 4, comm);
            *bytes_sent += sizeof fin + 16 * (uint64_t)piece_px(&fin);
        }
    } else {
        for (int r = 0; r < n; r++) {
            const mpi_rect *p = &pieces[r];
            if (!piece_px(p)) continue;
            if (r == 0) copy_piece(buf, w, p, tmp);
            else MPI_Recv(tmp, (int)(4 * piece_px(p)), MPI_FLOAT, r, 4, comm, MPI_STATUS_IGNORE);
            const float *src = tmp;
            for (int y = p->y0; y < p->y1; y++, src += 4 * (size_t)(p->x1 - p->x0))
                memcpy(acc + 4 * ((size_t)(all.y0 + y) * partial->width + all.x0 + p->x0), src,
                       4 * (size_t)(p->x1 - p->x0) * sizeof *src);
        }
    }
    MPI_Comm_free(&depth);
    free(pieces);
    free(buf);
    free(tmp);
    free(snd);
    if (rank != 0) return 0;
    finish(acc, partial, background, out);
    return 0;
}
