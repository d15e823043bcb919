// DICOM through GDCM, one file at a time (src/io/dicom_adapter.h).  The
// module's C table is all the library sees; no exception leaves it.
#include "dicom_adapter.h"

#include <gdcmDataSet.h>
#include <gdcmImage.h>
#include <gdcmImageReader.h>
#include <gdcmPixelFormat.h>
#include <gdcmReader.h>
#include <gdcmStringFilter.h>
#include <gdcmTrace.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <exception>
#include <set>
#include <sys/stat.h>
#include <ostream>
#include <string>
#include <vector>

namespace {

void fail(char *err, size_t cap, const char *fmt, const char *a = "", const char *b = "")
{
    if (err && cap) std::snprintf(err, cap, fmt, a, b);
}

// Value of a tag as text (binary VRs formatted by GDCM), trimmed.
std::string text(const gdcm::StringFilter &sf, const gdcm::DataSet &ds, uint16_t g, uint16_t e)
{
    gdcm::Tag t(g, e);
    if (!ds.FindDataElement(t)) return std::string();
    const gdcm::DataElement &de = ds.GetDataElement(t);
    if (de.IsEmpty()) return std::string();
    std::string s = sf.ToString(t);
    size_t z = s.find('\0');
    if (z != std::string::npos) s.resize(z);
    size_t a = s.find_first_not_of(" \t\r\n"), b = s.find_last_not_of(" \t\r\n");
    return a == std::string::npos ? std::string() : s.substr(a, b - a + 1);
}

// Up to n backslash-separated finite numbers; returns how many were read.
int numbers(const std::string &s, double *out, int n)
{
    int k = 0;
    size_t pos = 0;
    while (k < n && pos <= s.size()) {
        size_t end = s.find('\\', pos);
        std::string part = s.substr(pos, end == std::string::npos ? std::string::npos : end - pos);
        char *stop = nullptr;
        double v = std::strtod(part.c_str(), &stop);
        if (stop == part.c_str() || !std::isfinite(v)) return k;
        while (*stop == ' ') stop++;
        if (*stop) return k;
        out[k++] = v;
        if (end == std::string::npos) break;
        pos = end + 1;
    }
    return k;
}

int integer(const std::string &s, int dflt)
{
    double v;
    if (numbers(s, &v, 1) != 1 || v < -2147483647.0 || v > 2147483647.0) return dflt;
    return (int)v;
}

void copy(char *dst, size_t cap, const std::string &s)
{
    std::snprintf(dst, cap, "%s", s.c_str());
}

vs_status read_header(const char *path, vs_dicom_header *h, char *err, size_t errcap)
{
    try {
        std::memset(h, 0, sizeof *h);
        gdcm::Reader r;
        r.SetFileName(path);
        const gdcm::Tag pixel(0x7fe0, 0x0010);
        std::set<gdcm::Tag> skip;
        skip.insert(pixel);
        if (!r.ReadUpToTag(pixel, skip)) {
            fail(err, errcap, "not a DICOM file GDCM can parse");
            return VS_ERR_FORMAT;
        }
        const gdcm::File &f = r.GetFile();
        const gdcm::DataSet &ds = f.GetDataSet();
        gdcm::StringFilter sf;
        sf.SetFile(f);
        h->rows = integer(text(sf, ds, 0x0028, 0x0010), 0);
        h->cols = integer(text(sf, ds, 0x0028, 0x0011), 0);
        h->frames = integer(text(sf, ds, 0x0028, 0x0008), 1);
        h->samples = integer(text(sf, ds, 0x0028, 0x0002), 1);
        h->bits_allocated = integer(text(sf, ds, 0x0028, 0x0100), 0);
        h->pixel_representation = integer(text(sf, ds, 0x0028, 0x0103), 0);
        // ReadUpToTag stops before the pixel data; it is there when the
        // file goes on past that point
        struct stat sb;
        h->has_pixel_data = stat(path, &sb) == 0 && (uint64_t)sb.st_size > (uint64_t)r.GetStreamCurrentPosition();
        h->has_position = numbers(text(sf, ds, 0x0020, 0x0032), h->position, 3) == 3;
        h->has_orientation = numbers(text(sf, ds, 0x0020, 0x0037), h->orientation, 6) == 6;
        h->has_pixel_spacing = numbers(text(sf, ds, 0x0028, 0x0030), h->pixel_spacing, 2) == 2;
        h->has_thickness = numbers(text(sf, ds, 0x0018, 0x0050), &h->thickness, 1) == 1;
        if (numbers(text(sf, ds, 0x0028, 0x1053), &h->slope, 1) != 1) h->slope = 1.0;
        if (numbers(text(sf, ds, 0x0028, 0x1052), &h->intercept, 1) != 1) h->intercept = 0.0;
        h->instance = integer(text(sf, ds, 0x0020, 0x0013), 0);
        copy(h->series_uid, sizeof h->series_uid, text(sf, ds, 0x0020, 0x000e));
        copy(h->description, sizeof h->description, text(sf, ds, 0x0008, 0x103e));
        copy(h->modality, sizeof h->modality, text(sf, ds, 0x0008, 0x0060));
        copy(h->photometric, sizeof h->photometric, text(sf, ds, 0x0028, 0x0004));
        const gdcm::DataSet &meta = f.GetHeader();
        gdcm::Tag ts(0x0002, 0x0010);
        if (meta.FindDataElement(ts)) {
            const gdcm::ByteValue *bv = meta.GetDataElement(ts).GetByteValue();
            if (bv) copy(h->transfer_syntax, sizeof h->transfer_syntax,
                         std::string(bv->GetPointer(), bv->GetLength()).c_str());
        }
        return VS_OK;
    } catch (const std::exception &e) {
        fail(err, errcap, "cannot parse the DICOM header: %s", e.what());
    } catch (...) {
        fail(err, errcap, "cannot parse the DICOM header");
    }
    return VS_ERR_FORMAT;
}

vs_status read_pixels(const char *path, int rows, int cols, void *dst, size_t dst_bytes,
                      vs_dicom_sample *type, char *err, size_t errcap)
{
    try {
        gdcm::ImageReader r;
        r.SetFileName(path);
        if (!r.Read()) {
            fail(err, errcap, "cannot read the image (truncated, or pixel data GDCM cannot decode)");
            return VS_ERR_FORMAT;
        }
        const gdcm::Image &img = r.GetImage();
        const unsigned int *d = img.GetDimensions();
        unsigned nd = img.GetNumberOfDimensions();
        if (nd < 2 || d[0] != (unsigned)cols || d[1] != (unsigned)rows || (nd > 2 && d[2] > 1)) {
            fail(err, errcap, "image size differs from its header, or has several frames");
            return VS_ERR_FORMAT;
        }
        const gdcm::PixelFormat &pf = img.GetPixelFormat();
        if (pf.GetSamplesPerPixel() != 1) {
            fail(err, errcap, "colour images are not volumes (one sample per pixel expected)");
            return VS_ERR_UNSUPPORTED;
        }
        size_t elem = 0;
        switch (pf.GetScalarType()) {
        case gdcm::PixelFormat::UINT8: *type = VS_DCM_U8; elem = 1; break;
        case gdcm::PixelFormat::INT8: *type = VS_DCM_I8; elem = 1; break;
        case gdcm::PixelFormat::UINT16: *type = VS_DCM_U16; elem = 2; break;
        case gdcm::PixelFormat::INT16: *type = VS_DCM_I16; elem = 2; break;
        case gdcm::PixelFormat::UINT32: *type = VS_DCM_U32; elem = 4; break;
        case gdcm::PixelFormat::INT32: *type = VS_DCM_I32; elem = 4; break;
        default:
            *type = VS_DCM_OTHER;
            fail(err, errcap, "sample type %s is not supported", pf.GetScalarTypeAsString());
            return VS_ERR_UNSUPPORTED;
        }
        size_t need = (size_t)rows * (size_t)cols * elem;
        if (img.GetBufferLength() != need || dst_bytes < need) {
            fail(err, errcap, "pixel data size differs from rows x columns x sample size");
            return VS_ERR_FORMAT;
        }
        if (!img.GetBuffer(static_cast<char *>(dst))) {
            fail(err, errcap, "cannot decode the pixel data (transfer syntax not supported by GDCM, or damaged)");
            return VS_ERR_FORMAT;
        }
        return VS_OK;
    } catch (const std::exception &e) {
        fail(err, errcap, "cannot read the pixel data: %s", e.what());
    } catch (...) {
        fail(err, errcap, "cannot read the pixel data");
    }
    return VS_ERR_FORMAT;
}

const vs_dicom_api table = {read_header, read_pixels};

} // namespace

const vs_dicom_api *vs_dicom_module_api(void)
{
    // the library never prints: GDCM's trace messages off, into a sink
    static std::ostream sink(nullptr); // no buffer: writes are dropped
    gdcm::Trace::SetDebug(false);
    gdcm::Trace::SetWarning(false);
    gdcm::Trace::SetError(false);
    gdcm::Trace::SetStream(sink);
    return &table;
}
