"""The C side: finding libvsplat.so, the structs of include/vsplat.h, and the
prototypes of the functions the package calls.

The structs follow vsplat.h field by field (tests/python/test_vsplat.py
compares every offset and size with the C compiler's).  vs_settings and
vs_stats carry their own sizes: the package calls vs_settings_init_sized
with its ctypes sizes, so an older library refuses a layout it does not know
instead of misreading it (docs/ABI.md).
"""

import ctypes
import ctypes.util
import os

c_int, c_double, c_float, c_size_t, c_void_p, c_char_p = (
    ctypes.c_int, ctypes.c_double, ctypes.c_float, ctypes.c_size_t, ctypes.c_void_p, ctypes.c_char_p)
c_uint64 = ctypes.c_uint64

# vs_status, vs_type, vs_pipeline, vs_isa, vs_endian: C enums, int-sized.
STATUS_NAMES = {0: "ok", 1: "invalid argument", 2: "i/o error", 3: "malformed input", 4: "out of memory",
                5: "too large", 6: "unsupported", 7: "cancelled", 8: "internal error", 9: "busy"}
OK, ERR_INVALID_ARGUMENT, ERR_IO, ERR_FORMAT = 0, 1, 2, 3
ERR_UNSUPPORTED, ERR_CANCELLED, ERR_BUSY = 6, 7, 9
U8, I16, U16, F32 = 0, 1, 2, 3


class TfPoint(ctypes.Structure):
    _fields_ = [("value", c_double), ("r", c_float), ("g", c_float), ("b", c_float), ("a", c_float)]


PROGRESS_FN = ctypes.CFUNCTYPE(c_int, c_void_p, c_double)
RELEASE_FN = ctypes.CFUNCTYPE(None, c_void_p, c_void_p)


class Settings(ctypes.Structure):
    _fields_ = [
        ("struct_size", c_size_t), ("stats_size", c_size_t),
        ("pipeline", c_int),
        ("width", c_int), ("height", c_int),
        ("azimuth", c_double), ("elevation", c_double),
        ("zoom", c_double),
        ("has_center", c_int), ("center", c_double * 3),
        ("perspective_fov", c_double),
        ("slab", c_double), ("kernel_radius", c_double),
        ("footprint_resolution", c_int), ("depth_resolution", c_int), ("seam", c_int),
        ("has_iso", c_int), ("iso_lo", c_double), ("iso_hi", c_double), ("ramp", c_double),
        ("iso_opacity", c_float), ("material", c_float * 3),
        ("tf", ctypes.POINTER(TfPoint)), ("tf_count", c_int),
        ("headlight", c_int), ("light_dir", c_double * 3),
        ("ambient", c_double), ("diffuse", c_double), ("specular", c_double), ("shininess", c_double),
        ("background", c_float * 4),
        ("occlusion", c_int), ("occlusion_threshold", c_double), ("tile_counters", c_int),
        ("tile_size", c_int), ("exact_normals", c_int), ("normal_lut_size", c_int),
        ("threads", c_int), ("isa", c_int), ("pin", c_int),
        ("ray_step", c_double), ("ray_trilinear", c_int), ("ray_analytic", c_int),
        ("progress", PROGRESS_FN), ("progress_user", c_void_p),
        ("trace", c_void_p),
        ("view", c_int), ("has_up", c_int), ("up", c_double * 3), ("roll", c_double),
        ("has_crop", c_int), ("crop_lo", c_int * 3), ("crop_hi", c_int * 3),
        ("preintegration", c_int),
        ("lod_pixels", c_double),
        ("resample", c_int),
        ("cd_stencil", c_int),
        ("ray_normalize", c_int),
        ("gs_normalize", c_int),
    ]


class StageTimes(ctypes.Structure):
    _fields_ = [(n, c_double) for n in ("setup", "rasterize", "gradient", "shade", "composite")]


class StageBytes(ctypes.Structure):
    _fields_ = [(n, c_uint64) for n in ("rasterize", "gradient", "shade", "composite")]


class Stats(ctypes.Structure):
    _fields_ = [
        ("struct_size", c_size_t),
        ("pipeline", c_char_p), ("isa", c_char_p),
        ("threads", c_int), ("width", c_int), ("height", c_int),
        ("voxels_total", c_uint64), ("voxels_relevant", c_uint64), ("voxels_splatted", c_uint64),
        ("voxels_culled", c_uint64), ("sheets", c_uint64), ("tiles_total", c_uint64), ("tiles_shaded", c_uint64),
        ("ms_total", c_double), ("ms_stage", StageTimes), ("ms_relevant", c_double),
        ("iso_lo", c_double), ("iso_hi", c_double), ("ramp", c_double),
        ("pin_warning", c_int),
        ("bricks_culled", c_uint64), ("voxels_projected", c_uint64), ("voxels_tested", c_uint64),
        ("footprint_floats", c_uint64), ("pixels_classified", c_uint64), ("pixels_shaded", c_uint64),
        ("bytes_read", StageBytes), ("bytes_written", StageBytes),
        ("ms_lod", c_double), ("lod_level", c_int),
        ("ms_resample", c_double), ("resampled", c_int),
    ]


class LoadOptions(ctypes.Structure):
    _fields_ = [
        ("struct_size", c_size_t), ("raw", c_int), ("dims", c_int * 3), ("type", c_int), ("endian", c_int),
        ("has_spacing", c_int), ("spacing", c_double * 3), ("series", c_char_p),
    ]


class Image(ctypes.Structure):
    _fields_ = [("width", c_int), ("height", c_int), ("rgba", ctypes.POINTER(c_float))]


class ImageDiff(ctypes.Structure):
    _fields_ = [("rmse", c_double), ("psnr", c_double), ("ssim", c_double), ("max_abs", c_double)]


STRUCTS = {"vs_settings": Settings, "vs_stats": Stats, "vs_load_options": LoadOptions, "vs_image": Image,
           "vs_image_diff": ImageDiff, "vs_tf_point": TfPoint, "vs_stage_times": StageTimes,
           "vs_stage_bytes": StageBytes}

P = ctypes.POINTER
_PROTOTYPES = {
    "vs_context_create": (c_int, [P(c_void_p)]),
    "vs_context_release": (None, [c_void_p]),
    "vs_last_error": (c_char_p, [c_void_p]),
    "vs_status_string": (c_char_p, [c_int]),
    "vs_version": (c_char_p, []),
    "vs_settings_init_sized": (None, [P(Settings), c_size_t, c_size_t]),
    "vs_load_options_init_sized": (None, [P(LoadOptions), c_size_t]),
    "vs_pipeline_parse": (c_int, [c_char_p, P(c_int)]),
    "vs_pipeline_name": (c_char_p, [c_int]),
    "vs_isa_parse": (c_int, [c_char_p, P(c_int)]),
    "vs_view_parse": (c_int, [c_char_p, P(c_int)]),
    "vs_volume_load": (c_int, [c_void_p, c_char_p, P(LoadOptions), P(c_void_p)]),
    "vs_volume_scene": (c_int, [c_void_p, c_char_p, P(c_void_p)]),
    "vs_volume_wrap": (c_int, [c_void_p, c_int, P(c_int), P(c_size_t), P(c_double), c_void_p, RELEASE_FN,
                               c_void_p, P(c_void_p)]),
    "vs_volume_release": (None, [c_void_p]),
    "vs_volume_data": (c_void_p, [c_void_p]),
    "vs_volume_dims": (None, [c_void_p, P(c_int)]),
    "vs_volume_spacing": (None, [c_void_p, P(c_double)]),
    "vs_volume_type": (c_int, [c_void_p]),
    "vs_volume_affine": (c_int, [c_void_p, P(c_double)]),
    "vs_volume_set_transform": (c_int, [c_void_p, c_void_p, P(c_double)]),
    "vs_volume_update_range": (None, [c_void_p]),
    "vs_volume_range": (None, [c_void_p, P(c_double), P(c_double)]),
    "vs_volume_default_iso": (c_double, [c_void_p]),
    "vs_tf_load_for_volume": (c_int, [c_void_p, c_char_p, c_void_p, P(P(TfPoint)), P(c_int)]),
    "vs_tf_free": (None, [P(TfPoint)]),
    "vs_render": (c_int, [c_void_p, c_void_p, P(Settings), P(Image), P(Stats)]),
    "vs_image_free": (None, [P(Image)]),
    "vs_image_write": (c_int, [c_void_p, c_char_p, P(Image), c_int]),
    "vs_image_read": (c_int, [c_void_p, c_char_p, P(Image)]),
    "vs_image_compare": (c_int, [c_void_p, P(Image), P(Image), P(ImageDiff)]),
}


def _candidates():
    """Where libvsplat.so may be, in the order they are tried."""
    env = os.environ.get("VSPLAT_LIBRARY")
    if env:
        return [("VSPLAT_LIBRARY", env)]
    here = os.path.dirname(os.path.abspath(__file__))
    out = []
    try:  # written by CMake: the build tree's library, or the installed one relative to the package
        from . import _paths
        if getattr(_paths, "LIBRARY", None):
            lib = _paths.LIBRARY
            lib = lib if os.path.isabs(lib) else os.path.normpath(os.path.join(here, lib))
            out.append(("the build or install", lib))
    except ImportError:
        pass
    # the package in the source tree (tools/python/vsplat): the default build folder
    root = os.path.normpath(os.path.join(here, "..", "..", ".."))
    build = os.environ.get("VSPLAT_BUILD_DIR") or os.path.join(root, "build")
    out.append(("the build folder", os.path.join(build, "libvsplat.so")))
    found = ctypes.util.find_library("vsplat")
    if found:
        out.append(("the system", found))
    return out


def load_library():
    """Open libvsplat.so and declare its functions; returns (CDLL, path).

    ctypes.CDLL releases the GIL for the length of every call, so renders in
    several Python threads run at once."""
    tried = []
    for where, path in _candidates():
        if os.path.sep in path and not os.path.exists(path):
            tried.append(path)
            continue
        try:
            lib = ctypes.CDLL(path)
        except OSError as e:
            tried.append("%s (%s)" % (path, e))
            continue
        for name, (res, args) in _PROTOTYPES.items():
            try:
                fn = getattr(lib, name)
            except AttributeError:
                raise ImportError("vsplat: %s (from %s) lacks %s: the library is older than this package"
                                  % (path, where, name))
            fn.restype = res
            fn.argtypes = args
        return lib, path
    raise ImportError("vsplat: cannot find libvsplat.so (tried: %s); build it (tools/build.sh) or set "
                      "VSPLAT_LIBRARY=/path/to/libvsplat.so" % (", ".join(tried) or "nothing"))
