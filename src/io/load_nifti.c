/* NIfTI-1 (.nii, .nii.gz, .hdr/.img pairs, also Analyze 7.5).  nifticlib's
 * niftiio (the library the build links) parses the header and finds the
 * image file; the voxels are then read here with zlib, because niftiio's
 * data reader prints to stderr on short reads and frees the caller's buffer.
 * niftiio cannot read NIfTI-2 (540-byte header); such files are recognised
 * and rejected clearly (linking libnifti2 instead would add them).
 *
 * Policy: u8/i16/u16/f32 stay as they are; other real types become f32; a
 * scl_slope that is finite, non-zero and not the identity (1,0) turns the
 * data into f32 = slope*v + inter.  Only the first 3-D volume of a 4-D+ file
 * is read.  Spacing is |pixdim[1..3]| as stored: 0 or NaN on an axis with
 * more than one voxel is an error (niftiio would silently make it 1).
 * Orientation (index to RAS mm), as the NIfTI-1 standard orders it: the
 * sform if sform_code > 0, else the qform if qform_code > 0, else none
 * (pixdim only); a transform that is singular or not finite counts as
 * absent, so the next one is tried.  With one, the spacing is its column
 * lengths. */
#include "context.h"
#include "load.h"
#include "load_common.h"

#include <errno.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <zlib.h>

#include <nifti1_io.h>

static int supported_real(int dt)
{
    switch (dt) {
    case DT_UINT8: case DT_INT8: case DT_INT16: case DT_UINT16: case DT_INT32: case DT_UINT32:
    case DT_INT64: case DT_UINT64: case DT_FLOAT32: case DT_FLOAT64: return 1;
    default: return 0;
    }
}

static unsigned rd16(const unsigned char *p, int big)
{
    return big ? (unsigned)p[0] << 8 | p[1] : (unsigned)p[1] << 8 | p[0];
}

static float rd_f32(const unsigned char *p, int big)
{
    uint32_t u = big ? (uint32_t)p[0] << 24 | (uint32_t)p[1] << 16 | (uint32_t)p[2] << 8 | p[3]
                     : (uint32_t)p[3] << 24 | (uint32_t)p[2] << 16 | (uint32_t)p[1] << 8 | p[0];
    float f;
    memcpy(&f, &u, 4); /* float and integer byte order agree on every host we target */
    return f;
}

/* Reads the header's leading sizeof_hdr so that garbage and NIfTI-2 files get
 * a precise message instead of nifticlib's generic failure; also returns the
 * raw pixdim[1..3] (niftiio replaces bad values before we could see them). */
static vs_status peek_header(vs_context *ctx, const char *path, const char *hdr, float pixdim[3])
{
    gzFile gz = gzopen(hdr, "rb");
    if (!gz) return vs_set_error(ctx, VS_ERR_IO, "%s: cannot open: %s", hdr, strerror(errno));
    unsigned char h[348];
    int n = gzread(gz, h, sizeof h);
    gzclose(gz);
    if (n < 4) return vs_set_error(ctx, VS_ERR_FORMAT, "%s: not a NIfTI file (too short)", path);
    uint32_t le = (uint32_t)h[0] | (uint32_t)h[1] << 8 | (uint32_t)h[2] << 16 | (uint32_t)h[3] << 24;
    uint32_t be = (uint32_t)h[3] | (uint32_t)h[2] << 8 | (uint32_t)h[1] << 16 | (uint32_t)h[0] << 24;
    if (le == 540 || be == 540)
        return vs_set_error(ctx, VS_ERR_UNSUPPORTED,
                            "%s: NIfTI-2 files are not supported by this build (niftiio reads "
                            "NIfTI-1 only)",
                            path);
    if (le != 348 && be != 348)
        return vs_set_error(ctx, VS_ERR_FORMAT,
                            "%s: not a NIfTI-1 file (sizeof_hdr is %lu, expected 348)", path,
                            (unsigned long)le);
    if (n < (int)sizeof h)
        return vs_set_error(ctx, VS_ERR_FORMAT,
                            "%s: truncated: the NIfTI header needs 348 bytes, file has %d", path, n);
    /* nifticlib prints to stderr (whatever its debug level) when dim[0],
     * dim[1] or datatype are bad, so those are checked here first, with its
     * byte-order rule: dim[0] in 1..7 as read natively, else byte-swapped;
     * dim[0] == 0 lets sizeof_hdr decide. */
    const uint16_t one = 1;
    int host_big = *(const unsigned char *)&one == 0;
    int big = host_big;
    int dim0 = (int16_t)rd16(h + 40, big);
    if (dim0 == 0) {
        big = le != 348;
    } else if (dim0 < 0 || dim0 > 7) {
        big = !host_big;
        dim0 = (int16_t)rd16(h + 40, big);
        if (dim0 < 0 || dim0 > 7)
            return vs_set_error(ctx, VS_ERR_FORMAT, "%s: bad NIfTI header: dim[0] is %d", path,
                                (int16_t)rd16(h + 40, host_big));
    }
    int dim1 = (int16_t)rd16(h + 42, big), datatype = (int16_t)rd16(h + 70, big);
    if (dim1 <= 0)
        return vs_set_error(ctx, VS_ERR_FORMAT, "%s: bad NIfTI header: dim[1] is %d", path, dim1);
    if (!supported_real(datatype))
        return vs_set_error(ctx, VS_ERR_UNSUPPORTED, "%s: unsupported NIfTI datatype %s (%d)", path,
                            nifti_datatype_string(datatype), datatype);
    /* nifticlib silently turns dim[2..dim[0]] <= 0 into 1 and an unusable
     * vox_offset into some offset: a malformed header must not become a
     * different volume. */
    for (int a = 2; a <= dim0; a++) {
        int da = (int16_t)rd16(h + 40 + 2 * a, big);
        if (da <= 0)
            return vs_set_error(ctx, VS_ERR_FORMAT, "%s: bad NIfTI header: dim[%d] is %d", path, a, da);
    }
    float vox_offset = rd_f32(h + 108, big);
    if (!(vox_offset >= 0.0f && vox_offset <= 1e15f))
        return vs_set_error(ctx, VS_ERR_FORMAT, "%s: bad NIfTI header: vox_offset is %g", path, vox_offset);
    for (int a = 0; a < 3; a++) pixdim[a] = rd_f32(h + 76 + 4 * (a + 1), big);
    return VS_OK;
}

/* The first `need` bytes of voxel data at `offset` of the (maybe gzip'd)
 * image file. */
static vs_status read_voxels(vs_context *ctx, const char *path, const char *iname, uint64_t offset,
                             uint64_t need, void *dst)
{
    gzFile gz = gzopen(iname, "rb");
    if (!gz) return vs_set_error(ctx, VS_ERR_IO, "%s: cannot open: %s", iname, strerror(errno));
    gzbuffer(gz, 1 << 18);
    if (offset > 0 && gzseek(gz, (z_off_t)offset, SEEK_SET) != (z_off_t)offset) {
        gzclose(gz);
        return vs_set_error(ctx, VS_ERR_FORMAT, "%s: truncated: no voxel data at offset %llu", path,
                            (unsigned long long)offset);
    }
    const uint64_t got = vs_load_gzread(gz, dst, need);
    int zerr = Z_OK;
    const char *msg = gzerror(gz, &zerr);
    vs_status st = VS_OK;
    if (got < need)
        st = vs_set_error(ctx, VS_ERR_FORMAT,
                          "%s: truncated: expected %llu bytes of voxel data, got %llu%s%s%s", path,
                          (unsigned long long)need, (unsigned long long)got,
                          zerr != Z_OK && zerr != Z_BUF_ERROR ? " (gzip: " : "",
                          zerr != Z_OK && zerr != Z_BUF_ERROR ? msg : "",
                          zerr != Z_OK && zerr != Z_BUF_ERROR ? ")" : "");
    gzclose(gz);
    return st;
}

static double nifti_value(const void *p, int dt, size_t i)
{
    switch (dt) {
    case DT_UINT8: return ((const uint8_t *)p)[i];
    case DT_INT8: return ((const int8_t *)p)[i];
    case DT_INT16: return ((const int16_t *)p)[i];
    case DT_UINT16: return ((const uint16_t *)p)[i];
    case DT_INT32: return ((const int32_t *)p)[i];
    case DT_UINT32: return ((const uint32_t *)p)[i];
    case DT_INT64: return (double)((const int64_t *)p)[i];
    case DT_UINT64: return (double)((const uint64_t *)p)[i];
    case DT_FLOAT32: return ((const float *)p)[i];
    default: return ((const double *)p)[i];
    }
}

static int try_affine(vs_volume *v, const mat44 *m)
{
    double a[3][4];
    for (int r = 0; r < 3; r++)
        for (int c = 0; c < 4; c++) a[r][c] = m->m[r][c];
    return vs_volume_set_affine(NULL, v, a) == VS_OK;
}

static void set_orientation(vs_volume *v, const nifti_image *nim)
{
    if (nim->sform_code > 0 && try_affine(v, &nim->sto_xyz)) return;
    if (nim->qform_code > 0) try_affine(v, &nim->qto_xyz);
}

vs_status vs_load_nifti(vs_context *ctx, const char *path, vs_load_box *box, vs_volume **out)
{
    uint64_t fsize;
    vs_status st = vs_load_file_size(ctx, path, &fsize);
    if (st != VS_OK) return st;
    if (fsize == 0) return vs_set_error(ctx, VS_ERR_FORMAT, "%s: empty file", path);
    /* For an .img the header lives in the .hdr beside it: peek after nifticlib
     * has found it. */
    int is_img = vs_load_ends_with(path, ".img") || vs_load_ends_with(path, ".img.gz");
    float pixdim[3] = {1, 1, 1};
    if (!is_img) {
        st = peek_header(ctx, path, path, pixdim);
        if (st != VS_OK) return st;
    }

    nifti_set_debug_level(0); /* the library never prints */
    nifti_image *nim = nifti_image_read(path, 0);
    if (!nim)
        return vs_set_error(ctx, VS_ERR_FORMAT, "%s: cannot read the NIfTI header (corrupt or "
                                                "missing image file)", path);
    vs_volume *v = NULL;
    void *tmp = NULL;
    int dt = nim->datatype;
    if (is_img && (st = peek_header(ctx, path, nim->fname ? nim->fname : path, pixdim)) != VS_OK)
        goto done;
    int64_t d[3] = {nim->nx, nim->ndim >= 2 ? nim->ny : 1, nim->ndim >= 3 ? nim->nz : 1};
    uint64_t need;
    st = vs_load_check_dims(ctx, path, d, (size_t)(nim->nbyper > 0 ? nim->nbyper : 1), &need);
    if (st != VS_OK) goto done;
    if (!supported_real(dt) || nim->nbyper < 1) {
        st = vs_set_error(ctx, VS_ERR_UNSUPPORTED, "%s: unsupported NIfTI datatype %s (%d)", path,
                          nifti_datatype_string(dt), dt);
        goto done;
    }
    for (int a = 4; a <= 7 && a <= nim->ndim; a++)
        if (nim->dim[a] < 1) {
            st = vs_set_error(ctx, VS_ERR_FORMAT, "%s: dim[%d] is %d", path, a, nim->dim[a]);
            goto done;
        }

    /* Check the image file can hold the first volume before allocating. */
    if (!nim->iname) {
        st = vs_set_error(ctx, VS_ERR_FORMAT, "%s: no image file name", path);
        goto done;
    }
    uint64_t isize;
    st = vs_load_file_size(ctx, nim->iname, &isize);
    if (st != VS_OK) {
        if (strcmp(nim->iname, path) != 0)
            st = vs_set_error(ctx, st, "%s: cannot read its image file %s", path, nim->iname);
        goto done;
    }
    uint64_t offset = nim->iname_offset > 0 ? (uint64_t)nim->iname_offset : 0;
    int compressed = vs_load_ends_with(nim->iname, ".gz");
    if (compressed ? need > vs_load_inflate_bound(isize) : offset + need > isize) {
        st = vs_set_error(ctx, VS_ERR_FORMAT, "%s: truncated: expected %llu bytes, file has %llu",
                          path, (unsigned long long)(offset + need), (unsigned long long)isize);
        goto done;
    }

    double spacing[3] = {fabs(pixdim[0]), fabs(pixdim[1]), fabs(pixdim[2])};
    int dims[3] = {(int)d[0], (int)d[1], (int)d[2]};
    for (int a = 0; a < 3; a++) {
        /* pixdim of an absent axis is often 0: harmless for a single slice. */
        if (dims[a] == 1 && !(spacing[a] > 0.0 && isfinite(spacing[a]))) spacing[a] = 1.0;
        if (!(spacing[a] > 0.0) || !isfinite(spacing[a])) {
            st = vs_set_error(ctx, VS_ERR_FORMAT, "%s: invalid voxel spacing pixdim[%d] = %g", path,
                              a + 1, spacing[a]);
            goto done;
        }
    }

    if (box) {
        memcpy(box->dims, dims, sizeof box->dims);
        if (box->dims_only) goto done; /* st is VS_OK */
        if ((st = vs_load_check_box(ctx, path, box, dims)) != VS_OK) goto done;
    }
    const int whole[3] = {dims[0], dims[1], dims[2]};
    if (box) {
        for (int a = 0; a < 3; a++) dims[a] = box->hi[a] - box->lo[a];
        need = (uint64_t)dims[0] * (uint64_t)dims[1] * (uint64_t)dims[2] * (uint64_t)nim->nbyper;
    }

    double slope = nim->scl_slope, inter = isfinite(nim->scl_inter) ? nim->scl_inter : 0.0;
    int scale = isfinite(slope) && slope != 0.0 && !(slope == 1.0 && inter == 0.0);
    vs_type type;
    switch (dt) {
    case DT_UINT8: type = VS_U8; break;
    case DT_INT16: type = VS_I16; break;
    case DT_UINT16: type = VS_U16; break;
    default: type = VS_F32; break;
    }
    int direct = !scale && (type != VS_F32 || dt == DT_FLOAT32);
    if (scale) type = VS_F32;
    st = vs_load_alloc(ctx, path, type, dims, spacing, &v);
    if (st != VS_OK) goto done;

    /* The first volume is the first `need` bytes (x, y, z vary fastest);
     * a box is read row by row from it. */
    if (!direct) {
        tmp = malloc((size_t)need);
        if (!tmp) {
            st = vs_set_error(ctx, VS_ERR_OUT_OF_MEMORY, "%s: out of memory", path);
            goto done;
        }
    }
    st = box ? vs_load_read_box(ctx, path, nim->iname, offset, whole, (size_t)nim->nbyper, box, direct ? v->data : tmp)
             : read_voxels(ctx, path, nim->iname, offset, need, direct ? v->data : tmp);
    if (st != VS_OK) goto done;
    if (nim->swapsize > 1 && nim->byteorder != nifti_short_order())
        vs_load_swap_bytes(direct ? v->data : tmp, (size_t)(need / (uint64_t)nim->swapsize), (size_t)nim->swapsize);
    if (!direct) {
        size_t n = (size_t)(need / (uint64_t)nim->nbyper);
        float *f = v->data;
        for (size_t i = 0; i < n; i++) {
            double x = nifti_value(tmp, dt, i);
            f[i] = (float)(scale ? slope * x + inter : x);
        }
    }
    set_orientation(v, nim);
    st = VS_OK;
done:
    if (tmp) free(tmp);
    nifti_image_free(nim);
    if (st != VS_OK) {
        vs_volume_release(v);
        return st;
    }
    *out = v;
    return VS_OK;
}
