// Thin extern "C" adapter over OpenImageIO 2.4: the only C++ in the library.
// Every entry point catches all exceptions and turns them (and OIIO's own
// error strings) into a vs_status plus a message that names the file.  Error
// strings are always retrieved so OIIO never reports stale errors later.
#include "oiio_adapter.h"

#include <OpenImageIO/filesystem.h>
#include <OpenImageIO/imageio.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <functional>
#include <memory>
#include <string>
#include <thread>
#include <vector>

#include <unistd.h>

using namespace OIIO;

struct vs_oiio_reader {
    std::string name;
    std::unique_ptr<Filesystem::IOMemReader> mem; // must outlive `in`
    std::unique_ptr<ImageInput> in;
    ~vs_oiio_reader() { in.reset(); } // close the input before the proxy goes
};

namespace {

vs_status fail(char *err, size_t cap, vs_status st, const std::string &msg)
{
    if (err && cap) {
        std::string m = msg;
        while (!m.empty() && (m.back() == '\n' || m.back() == ' ')) m.pop_back();
        std::snprintf(err, cap, "%s", m.c_str());
    }
    return st;
}

// OIIO messages can span lines; keep them to one line for our error strings.
std::string one_line(std::string s)
{
    for (char &c : s)
        if (c == '\n' || c == '\r') c = ' ';
    while (!s.empty() && s.back() == ' ') s.pop_back();
    return s.empty() ? std::string("unknown error") : s;
}

std::string input_error(ImageInput *in)
{
    std::string e = in ? in->geterror() : std::string();
    std::string g = OIIO::geterror();
    if (e.empty()) e = g;
    return one_line(e);
}

std::string output_error(ImageOutput *out)
{
    std::string e = out ? out->geterror() : std::string();
    std::string g = OIIO::geterror();
    if (e.empty()) e = g;
    return one_line(e);
}

TypeDesc to_typedesc(vs_pixel_type t)
{
    switch (t) {
    case VS_PIX_U8: return TypeDesc::UINT8;
    case VS_PIX_I16: return TypeDesc::INT16;
    case VS_PIX_U16: return TypeDesc::UINT16;
    case VS_PIX_F32: return TypeDesc::FLOAT;
    default: return TypeDesc::UNKNOWN;
    }
}

vs_pixel_type from_typedesc(TypeDesc t)
{
    switch (t.basetype) {
    case TypeDesc::UINT8: return VS_PIX_U8;
    case TypeDesc::INT16: return VS_PIX_I16;
    case TypeDesc::UINT16: return VS_PIX_U16;
    case TypeDesc::HALF:
    case TypeDesc::FLOAT:
    case TypeDesc::DOUBLE: return VS_PIX_F32;
    default: return VS_PIX_OTHER;
    }
}

size_t pix_size(vs_pixel_type t)
{
    switch (t) {
    case VS_PIX_U8: return 1;
    case VS_PIX_I16:
    case VS_PIX_U16: return 2;
    case VS_PIX_F32: return 4;
    default: return 0;
    }
}

std::string lower_ext(const std::string &path)
{
    std::string ext = Filesystem::extension(path, false);
    std::transform(ext.begin(), ext.end(), ext.begin(),
                   [](unsigned char c) { return (char)std::tolower(c); });
    return ext;
}

// Checks a page's shape; the message names the file.
vs_status check_spec(const std::string &name, const ImageSpec &sp, char *err, size_t cap)
{
    if (sp.deep) return fail(err, cap, VS_ERR_UNSUPPORTED, name + ": deep images are not supported");
    if (sp.depth > 1)
        return fail(err, cap, VS_ERR_UNSUPPORTED, name + ": 3-D (volume) image files are not supported");
    if (sp.width < 1 || sp.height < 1 || sp.width > VS_MAX_IMAGE_DIM || sp.height > VS_MAX_IMAGE_DIM)
        return fail(err, cap, VS_ERR_TOO_LARGE,
                    name + ": image size " + std::to_string(sp.width) + "x" + std::to_string(sp.height) +
                        " is outside 1.." + std::to_string(VS_MAX_IMAGE_DIM));
    if (sp.nchannels < 1 || sp.nchannels > 64)
        return fail(err, cap, VS_ERR_FORMAT,
                    name + ": unsupported channel count " + std::to_string(sp.nchannels));
    return VS_OK;
}

// Temporary name beside the target with the real extension last, so OIIO
// picks the right writer: "out.png" -> "out.png.tmp-<pid>-<tid>.png".
std::string temp_name(const std::string &path)
{
    size_t tid = std::hash<std::thread::id>()(std::this_thread::get_id()) % 100000000u;
    return path + ".tmp-" + std::to_string((long)getpid()) + "-" + std::to_string(tid) +
           Filesystem::extension(path, true);
}

// Opens `tmp`, writes all pages, closes; returns an error text or "".
std::string write_file(const std::string &tmp, const std::vector<ImageSpec> &specs,
                       TypeDesc datatype, const unsigned char *data, size_t page_bytes)
{
    auto out = ImageOutput::create(tmp);
    if (!out) return output_error(nullptr);
    size_t pages = specs.size();
    if (pages > 1 && !out->supports("multiimage"))
        return std::string("format '") + out->format_name() + "' cannot hold several pages";
    bool ok = pages > 1 ? out->open(tmp, (int)pages, specs.data()) : out->open(tmp, specs[0]);
    if (!ok) return output_error(out.get());
    for (size_t p = 0; p < pages; p++) {
        if (p > 0 && !out->open(tmp, specs[p], ImageOutput::AppendSubimage)) {
            std::string e = output_error(out.get());
            out->close();
            return e;
        }
        if (!out->write_image(datatype, data + p * page_bytes)) {
            std::string e = output_error(out.get());
            out->close();
            return e;
        }
    }
    if (!out->close()) return output_error(out.get());
    return std::string();
}

vs_status commit_or_cleanup(const std::string &path, const std::string &tmp, const std::string &werr,
                            char *err, size_t cap)
{
    if (!werr.empty()) {
        std::remove(tmp.c_str());
        return fail(err, cap, VS_ERR_IO, path + ": cannot write: " + werr);
    }
    if (std::rename(tmp.c_str(), path.c_str()) != 0) {
        std::string e = std::strerror(errno);
        std::remove(tmp.c_str());
        return fail(err, cap, VS_ERR_IO, path + ": cannot rename the temporary file into place: " + e);
    }
    return VS_OK;
}

} // namespace

extern "C" {

vs_status vs_oiio_open(const char *name, const void *mem, size_t size, vs_oiio_reader **out,
                       char *err, size_t errcap)
{
    if (!out) return fail(err, errcap, VS_ERR_INVALID_ARGUMENT, "image: NULL argument");
    *out = nullptr;
    if (!name) return fail(err, errcap, VS_ERR_INVALID_ARGUMENT, "image: NULL file name");
    try {
        std::unique_ptr<vs_oiio_reader> r(new vs_oiio_reader);
        r->name = name;
        ImageSpec config;
        // We want the stored values, not alpha-premultiplied ones.
        config.attribute("oiio:UnassociatedAlpha", 1);
        if (mem) {
            if (size == 0) return fail(err, errcap, VS_ERR_FORMAT, r->name + ": empty image data");
            r->mem.reset(new Filesystem::IOMemReader(mem, size));
            // OIIO 2.4 honours the proxy only when given through the config
            // (the ioproxy argument of open() still looks for a file).
            Filesystem::IOProxy *proxy = r->mem.get();
            config.attribute("oiio:ioproxy", TypeDesc::PTR, &proxy);
        }
        r->in = ImageInput::open(r->name, &config);
        if (!r->in)
            return fail(err, errcap, VS_ERR_FORMAT, r->name + ": cannot read image: " + input_error(nullptr));
        vs_status st = check_spec(r->name, r->in->spec(), err, errcap);
        if (st != VS_OK) return st;
        *out = r.release();
        return VS_OK;
    } catch (const std::bad_alloc &) {
        return fail(err, errcap, VS_ERR_OUT_OF_MEMORY, std::string(name) + ": out of memory");
    } catch (const std::exception &e) {
        return fail(err, errcap, VS_ERR_FORMAT, std::string(name) + ": cannot read image: " + e.what());
    } catch (...) {
        return fail(err, errcap, VS_ERR_INTERNAL, std::string(name) + ": unknown exception");
    }
}

void vs_oiio_close(vs_oiio_reader *r)
{
    try {
        if (r && r->in) {
            r->in->close();
            (void)r->in->geterror();
        }
        delete r;
    } catch (...) {
    }
}

vs_status vs_oiio_count_pages(vs_oiio_reader *r, int cap, int *count, char *err, size_t errcap)
{
    if (!r || !count) return fail(err, errcap, VS_ERR_INVALID_ARGUMENT, "image: NULL argument");
    try {
        int n = 0;
        while (n < cap && r->in->seek_subimage(n, 0)) n++;
        (void)r->in->geterror(); // the failed seek past the end is expected
        if (n < 1) return fail(err, errcap, VS_ERR_FORMAT, r->name + ": no readable page");
        *count = n;
        return VS_OK;
    } catch (const std::exception &e) {
        return fail(err, errcap, VS_ERR_FORMAT, r->name + ": " + e.what());
    } catch (...) {
        return fail(err, errcap, VS_ERR_INTERNAL, r->name + ": unknown exception");
    }
}

vs_status vs_oiio_page_info(vs_oiio_reader *r, int page, vs_oiio_info *info, char *err, size_t errcap)
{
    if (!r || !info) return fail(err, errcap, VS_ERR_INVALID_ARGUMENT, "image: NULL argument");
    try {
        std::memset(info, 0, sizeof *info);
        if (!r->in->seek_subimage(page, 0)) {
            (void)input_error(r->in.get());
            return fail(err, errcap, VS_ERR_FORMAT, r->name + ": no page " + std::to_string(page));
        }
        const ImageSpec &sp = r->in->spec();
        vs_status st = check_spec(r->name, sp, err, errcap);
        if (st != VS_OK) return st;
        info->width = sp.width;
        info->height = sp.height;
        info->channels = sp.nchannels;
        info->native = from_typedesc(sp.format);
        float xr = sp.get_float_attribute("XResolution", 0.0f);
        float yr = sp.get_float_attribute("YResolution", 0.0f);
        if (std::isfinite(xr) && std::isfinite(yr) && xr > 0.0f && yr > 0.0f) {
            info->has_resolution = 1;
            info->xres = xr;
            info->yres = yr;
        }
        std::string d = sp.get_string_attribute("ImageDescription");
        std::snprintf(info->description, sizeof info->description, "%s", d.c_str());
        return VS_OK;
    } catch (const std::exception &e) {
        return fail(err, errcap, VS_ERR_FORMAT, r->name + ": " + e.what());
    } catch (...) {
        return fail(err, errcap, VS_ERR_INTERNAL, r->name + ": unknown exception");
    }
}

vs_status vs_oiio_read_page(vs_oiio_reader *r, int page, vs_pixel_type type, void *dst,
                            size_t dst_bytes, char *err, size_t errcap)
{
    if (!r || !dst) return fail(err, errcap, VS_ERR_INVALID_ARGUMENT, "image: NULL argument");
    try {
        if (!r->in->seek_subimage(page, 0)) {
            (void)input_error(r->in.get());
            return fail(err, errcap, VS_ERR_FORMAT, r->name + ": no page " + std::to_string(page));
        }
        ImageSpec sp = r->in->spec();
        vs_status st = check_spec(r->name, sp, err, errcap);
        if (st != VS_OK) return st;
        vs_pixel_type native = from_typedesc(sp.format);
        if (pix_size(type) == 0 || (type != VS_PIX_F32 && type != native))
            return fail(err, errcap, VS_ERR_INVALID_ARGUMENT,
                        r->name + ": requested sample type does not match the file's");
        size_t need = (size_t)sp.width * sp.height * sp.nchannels * pix_size(type);
        if (dst_bytes < need)
            return fail(err, errcap, VS_ERR_INVALID_ARGUMENT, r->name + ": destination buffer too small");
        if (!r->in->read_image(page, 0, 0, sp.nchannels, to_typedesc(type), dst))
            return fail(err, errcap, VS_ERR_FORMAT,
                        r->name + ": page " + std::to_string(page) + ": " + input_error(r->in.get()));
        return VS_OK;
    } catch (const std::bad_alloc &) {
        return fail(err, errcap, VS_ERR_OUT_OF_MEMORY, r->name + ": out of memory");
    } catch (const std::exception &e) {
        return fail(err, errcap, VS_ERR_FORMAT, r->name + ": " + e.what());
    } catch (...) {
        return fail(err, errcap, VS_ERR_INTERNAL, r->name + ": unknown exception");
    }
}

vs_status vs_oiio_read_rgba(const char *path, int *width, int *height, float **rgba, char *err,
                            size_t errcap)
{
    if (!path || !width || !height || !rgba)
        return fail(err, errcap, VS_ERR_INVALID_ARGUMENT, "image: NULL argument");
    *rgba = nullptr;
    *width = *height = 0;
    std::string name = path;
    try {
        if (!Filesystem::exists(name))
            return fail(err, errcap, VS_ERR_IO, name + ": cannot open: no such file");
        ImageSpec config;
        config.attribute("oiio:UnassociatedAlpha", 1);
        auto in = ImageInput::open(name, &config);
        if (!in) return fail(err, errcap, VS_ERR_FORMAT, name + ": cannot read image: " + input_error(nullptr));
        ImageSpec sp = in->spec();
        vs_status st = check_spec(name, sp, err, errcap);
        if (st != VS_OK) return st;
        int w = sp.width, h = sp.height, nc = sp.nchannels;
        size_t npix = (size_t)w * h;
        std::vector<float> buf(npix * nc);
        if (!in->read_image(0, 0, 0, nc, TypeDesc::FLOAT, buf.data()))
            return fail(err, errcap, VS_ERR_FORMAT, name + ": " + input_error(in.get()));
        in->close();
        (void)in->geterror();
        int ach = sp.alpha_channel;
        if (ach < 0 && (nc == 2 || nc >= 4)) ach = nc == 2 ? 1 : 3;
        // Formats that store premultiplied colour (EXR, associated TIFF) are
        // brought back to straight alpha, the vs_image convention.
        bool premult = ach >= 0 && sp.get_int_attribute("oiio:UnassociatedAlpha", 0) == 0;
        float *o = (float *)std::malloc(npix * 4 * sizeof(float));
        if (!o) return fail(err, errcap, VS_ERR_OUT_OF_MEMORY, name + ": out of memory");
        for (size_t i = 0; i < npix; i++) {
            const float *p = &buf[i * nc];
            float r, g, b, a = ach >= 0 ? p[ach] : 1.0f;
            if (nc >= 3) {
                r = p[0]; g = p[1]; b = p[2];
            } else {
                r = g = b = p[0];
            }
            if (premult && a > 0.0f) {
                r /= a; g /= a; b /= a;
            }
            o[i * 4 + 0] = r;
            o[i * 4 + 1] = g;
            o[i * 4 + 2] = b;
            o[i * 4 + 3] = a;
        }
        *rgba = o;
        *width = w;
        *height = h;
        return VS_OK;
    } catch (const std::bad_alloc &) {
        return fail(err, errcap, VS_ERR_OUT_OF_MEMORY, name + ": out of memory");
    } catch (const std::exception &e) {
        return fail(err, errcap, VS_ERR_FORMAT, name + ": " + e.what());
    } catch (...) {
        return fail(err, errcap, VS_ERR_INTERNAL, name + ": unknown exception");
    }
}

vs_status vs_oiio_write_rgba(const char *path, int width, int height, const float *rgba, int bits,
                             char *err, size_t errcap)
{
    if (!path || !rgba) return fail(err, errcap, VS_ERR_INVALID_ARGUMENT, "image: NULL argument");
    std::string name = path;
    if (width < 1 || height < 1 || width > VS_MAX_IMAGE_DIM || height > VS_MAX_IMAGE_DIM)
        return fail(err, errcap, VS_ERR_INVALID_ARGUMENT, name + ": invalid image size");
    try {
        std::string ext = lower_ext(name);
        TypeDesc fmt;
        bool is_exr = false, clamp = true;
        if (ext == "png") {
            fmt = bits == 16 ? TypeDesc::UINT16 : TypeDesc::UINT8;
        } else if (ext == "exr") {
            fmt = bits == 16 ? TypeDesc::HALF : TypeDesc::FLOAT;
            is_exr = true;
            clamp = false;
        } else if (ext == "tif" || ext == "tiff") {
            if (bits == 8) fmt = TypeDesc::UINT8;
            else if (bits == 16) fmt = TypeDesc::UINT16;
            else {
                fmt = TypeDesc::FLOAT;
                clamp = false;
            }
        } else {
            return fail(err, errcap, VS_ERR_UNSUPPORTED,
                        name + ": unsupported output format (use .png, .exr, .tif or .tiff)");
        }
        size_t n = (size_t)width * height * 4;
        std::vector<float> px(rgba, rgba + n);
        for (size_t i = 0; i < n; i += 4) {
            for (int c = 0; c < 4; c++) {
                float v = px[i + c];
                if (std::isnan(v)) v = 0.0f; // integer encoders have no NaN
                if (clamp) v = v < 0.0f ? 0.0f : (v > 1.0f ? 1.0f : v);
                px[i + c] = v;
            }
            if (is_exr) // EXR colour is premultiplied by convention
                for (int c = 0; c < 3; c++) px[i + c] *= px[i + 3];
        }
        ImageSpec spec(width, height, 4, fmt);
        spec.alpha_channel = 3;
        if (!is_exr) spec.attribute("oiio:UnassociatedAlpha", 1);
        if (is_exr) spec.attribute("compression", "zip");
        std::string tmp = temp_name(name);
        std::vector<ImageSpec> specs(1, spec);
        std::string werr = write_file(tmp, specs, TypeDesc::FLOAT,
                                      (const unsigned char *)px.data(), n * sizeof(float));
        return commit_or_cleanup(name, tmp, werr, err, errcap);
    } catch (const std::bad_alloc &) {
        return fail(err, errcap, VS_ERR_OUT_OF_MEMORY, name + ": out of memory");
    } catch (const std::exception &e) {
        return fail(err, errcap, VS_ERR_IO, name + ": cannot write: " + e.what());
    } catch (...) {
        return fail(err, errcap, VS_ERR_INTERNAL, name + ": unknown exception");
    }
}

vs_status vs_oiio_write_pages(const char *path, int width, int height, int channels, int pages,
                              vs_pixel_type type, const void *data, double xres, double yres,
                              const char *description, char *err, size_t errcap)
{
    if (!path || !data) return fail(err, errcap, VS_ERR_INVALID_ARGUMENT, "image: NULL argument");
    std::string name = path;
    if (width < 1 || height < 1 || width > VS_MAX_IMAGE_DIM || height > VS_MAX_IMAGE_DIM ||
        channels < 1 || channels > 4 || pages < 1 || pages > VS_MAX_DIM || pix_size(type) == 0)
        return fail(err, errcap, VS_ERR_INVALID_ARGUMENT, name + ": invalid image size or type");
    try {
        ImageSpec spec(width, height, channels, to_typedesc(type));
        if (xres > 0.0 && yres > 0.0) {
            spec.attribute("XResolution", (float)xres);
            spec.attribute("YResolution", (float)yres);
            // OIIO's TIFF writer derives YResolution from this
            spec.attribute("PixelAspectRatio", (float)(yres / xres));
            spec.attribute("ResolutionUnit", "none");
        }
        if (description && *description) spec.attribute("ImageDescription", description);
        std::vector<ImageSpec> specs((size_t)pages, spec);
        size_t page_bytes = (size_t)width * height * channels * pix_size(type);
        std::string tmp = temp_name(name);
        std::string werr = write_file(tmp, specs, to_typedesc(type), (const unsigned char *)data,
                                      page_bytes);
        return commit_or_cleanup(name, tmp, werr, err, errcap);
    } catch (const std::bad_alloc &) {
        return fail(err, errcap, VS_ERR_OUT_OF_MEMORY, name + ": out of memory");
    } catch (const std::exception &e) {
        return fail(err, errcap, VS_ERR_IO, name + ": cannot write: " + e.what());
    } catch (...) {
        return fail(err, errcap, VS_ERR_INTERNAL, name + ": unknown exception");
    }
}

vs_status vs_oiio_write_frames(const char *path, int width, int height, int count,
                               const float *const *frames, double fps, char *err, size_t errcap)
{
    if (!path || !frames) return fail(err, errcap, VS_ERR_INVALID_ARGUMENT, "image: NULL argument");
    std::string name = path;
    if (width < 1 || height < 1 || width > VS_MAX_IMAGE_DIM || height > VS_MAX_IMAGE_DIM || count < 1)
        return fail(err, errcap, VS_ERR_INVALID_ARGUMENT, name + ": invalid image size or frame count");
    if (!(fps > 0.0 && fps <= 1000.0))
        return fail(err, errcap, VS_ERR_INVALID_ARGUMENT, name + ": frames per second must lie in (0, 1000]");
    for (int f = 0; f < count; f++)
        if (!frames[f])
            return fail(err, errcap, VS_ERR_INVALID_ARGUMENT, name + ": frame " + std::to_string(f) + " is NULL");
    try {
        std::string ext = lower_ext(name);
        bool gif = ext == "gif";
        if (!gif && ext != "tif" && ext != "tiff")
            return fail(err, errcap, VS_ERR_UNSUPPORTED,
                        name + ": unsupported multi-frame format (use .gif or .tif/.tiff)");
        // GIF: RGB composited over black (no partial transparency there);
        // TIFF: straight RGBA.  Both 8-bit.
        int nc = gif ? 3 : 4;
        ImageSpec spec(width, height, nc, TypeDesc::UINT8);
        if (gif) {
            int rate[2] = {(int)std::lround(fps * 1000.0), 1000};
            spec.attribute("FramesPerSecond", TypeRational, rate);
            spec.attribute("gif:LoopCount", 0); // loop forever
        } else {
            spec.alpha_channel = 3;
            spec.attribute("oiio:UnassociatedAlpha", 1);
        }
        std::string tmp = temp_name(name);
        std::string werr;
        {
            auto out = ImageOutput::create(tmp);
            if (!out) {
                werr = output_error(nullptr);
            } else if (count > 1 && !(out->supports("multiimage") && out->supports("appendsubimage"))) {
                werr = std::string("format '") + out->format_name() + "' cannot hold several frames";
            } else {
                std::vector<ImageSpec> specs((size_t)count, spec);
                bool ok = count > 1 ? out->open(tmp, count, specs.data()) : out->open(tmp, spec);
                if (!ok) werr = output_error(out.get());
                size_t npix = (size_t)width * height;
                std::vector<unsigned char> px(npix * nc);
                for (int f = 0; ok && f < count; f++) {
                    if (f > 0 && !out->open(tmp, spec, ImageOutput::AppendSubimage)) {
                        werr = output_error(out.get());
                        break;
                    }
                    const float *src = frames[f];
                    for (size_t i = 0; i < npix; i++) {
                        float a = src[i * 4 + 3];
                        a = std::isnan(a) ? 0.0f : (a < 0.0f ? 0.0f : (a > 1.0f ? 1.0f : a));
                        for (int c = 0; c < nc; c++) {
                            float v = c == 3 ? a : src[i * 4 + c];
                            if (std::isnan(v)) v = 0.0f;
                            v = v < 0.0f ? 0.0f : (v > 1.0f ? 1.0f : v);
                            if (gif) v *= a; // over black
                            px[i * nc + c] = (unsigned char)std::lround(v * 255.0f);
                        }
                    }
                    if (!out->write_image(TypeDesc::UINT8, px.data())) {
                        werr = output_error(out.get());
                        break;
                    }
                }
                if (ok && werr.empty()) {
                    if (!out->close()) werr = output_error(out.get());
                } else {
                    out->close();
                    (void)out->geterror();
                }
            }
        }
        return commit_or_cleanup(name, tmp, werr, err, errcap);
    } catch (const std::bad_alloc &) {
        return fail(err, errcap, VS_ERR_OUT_OF_MEMORY, name + ": out of memory");
    } catch (const std::exception &e) {
        return fail(err, errcap, VS_ERR_IO, name + ": cannot write: " + e.what());
    } catch (...) {
        return fail(err, errcap, VS_ERR_INTERNAL, name + ": unknown exception");
    }
}

const vs_oiio_api *vs_oiio_module_api(void)
{
    static const vs_oiio_api api = {vs_oiio_open,      vs_oiio_close,      vs_oiio_count_pages,
                                    vs_oiio_page_info, vs_oiio_read_page,  vs_oiio_read_rgba,
                                    vs_oiio_write_rgba, vs_oiio_write_pages, vs_oiio_write_frames};
    return &api;
}

} // extern "C"
