"""vsplat from Python: the splatting volume renderer over NumPy arrays.

    import numpy, vsplat
    vol = vsplat.load("ch2.nii.gz")                        # or vsplat.Volume(array, spacing=(sx, sy, sz))
    img, st = vsplat.render(vol, iso=45, ramp=10, view=(180, 0), stats=True)
    vsplat.save(img, "head.png")                           # img: H x W x 4 float32, straight RGBA
    print(st["pipeline"], st["ms_total"], vsplat.compare(img, img)["psnr"])

The package is a thin layer over libvsplat.so through ctypes (no compiled
extension).  Failures raise vsplat.Error with the library's message.

Threads: every library call releases the GIL (ctypes.CDLL), so renders in
several Python threads run at the same time.  Each Python thread gets its
own library context (kept for its caches: worker pool, relevant voxels,
shading tables); a volume may be rendered by several threads at once as long
as nobody writes into its array meanwhile.  The library itself renders one
frame on `threads` workers (default: one per physical core), so threads that
render at once should each ask for fewer.
"""

import ctypes
import os
import threading

import numpy as np

from . import _lib

__all__ = ["Error", "Volume", "load", "scene", "render", "compare", "save", "load_image", "library_path",
           "library_version", "PIPELINES"]

_LIB, _LIB_PATH = _lib.load_library()

PIPELINES = ("pre", "post-cd", "post-gs", "post-alpha", "raycast")
_DTYPES = {np.dtype(np.uint8): _lib.U8, np.dtype(np.int16): _lib.I16, np.dtype(np.uint16): _lib.U16,
           np.dtype(np.float32): _lib.F32}
_NUMPY_OF = {v: k for k, v in _DTYPES.items()}
# converted without loss of meaning (a copy): wider floats to float32, bool and int8 to a supported integer
_CONVERT = {np.dtype(np.float64): np.float32, np.dtype(np.float16): np.float32, np.dtype(np.bool_): np.uint8,
            np.dtype(np.int8): np.int16}


class Error(Exception):
    """A failure, with the library's one-line message.

    status is the vs_status code (vsplat.h), status_name its name, e.g.
    "i/o error", "invalid argument", "cancelled"."""

    def __init__(self, message, status=_lib.ERR_INVALID_ARGUMENT):
        super().__init__(message)
        self.status = status
        self.status_name = _lib.STATUS_NAMES.get(status, "unknown status")


def library_path():
    """The path of the libvsplat.so this package uses."""
    return _LIB_PATH


def library_version():
    """The library's version string, e.g. "0.2.0"."""
    return _LIB.vs_version().decode()


class _Context:
    """One library context (vs_context), used by one thread."""

    def __init__(self):
        h = ctypes.c_void_p()
        st = _LIB.vs_context_create(ctypes.byref(h))
        if st != _lib.OK:
            raise Error("cannot create a vsplat context", st)
        self.h = h
        self._release = _LIB.vs_context_release

    def check(self, status):
        if status == _lib.OK:
            return
        if status == _lib.ERR_BUSY:  # the message belongs to the other call
            raise Error(_LIB.vs_status_string(status).decode(), status)
        raise Error(_LIB.vs_last_error(self.h).decode(errors="replace"), status)

    def __del__(self):
        if getattr(self, "h", None):
            self._release(self.h)
            self.h = None


_tls = threading.local()


def _context():
    """The calling thread's context (created on first use, released with the thread)."""
    c = getattr(_tls, "ctx", None)
    if c is None:
        c = _tls.ctx = _Context()
    return c


def _path_bytes(path):
    return os.fsencode(os.fspath(path))


class Volume:
    """A volume the library renders.

    Volume(array, spacing=(1, 1, 1), affine=None): a 3-D NumPy array of
    shape (z, y, x) in C order (x varies fastest), so the volume's
    dimensions are (x, y, z) = array.shape[::-1]; spacing is (sx, sy, sz) in
    millimetres.  affine, a 3x4 (or 4x4) index-to-world matrix in RAS
    millimetres (NIfTI's sform; world = affine[:3,:3] @ (x, y, z) +
    affine[:3,3]), gives the volume an orientation; its column lengths
    replace the spacing.
    uint8, int16, uint16 and float32 arrays that are C-contiguous, aligned
    and in native byte order are used in place, without a copy (the Volume
    keeps a reference to the array); others are copied into that layout
    (numpy.ascontiguousarray), float64 and float16 converted to float32, bool
    to uint8 and int8 to int16.  Other types are refused: convert them first.
    `copied` says whether a copy was made.  After writing into the array,
    call update(); never while a render of the volume runs.

    vsplat.load() and vsplat.scene() return Volumes too; their voxels are
    the library's, visible as `array` (shape (z, y, x), no copy).
    """

    def __init__(self, array, spacing=(1.0, 1.0, 1.0), affine=None):
        self._h = None
        orig = array
        a = np.asarray(array)
        if a.ndim != 3:
            raise Error("Volume: the array must have 3 dimensions (z, y, x), not %d" % a.ndim)
        dt = a.dtype.newbyteorder("=") if a.dtype.byteorder not in "=|" else a.dtype
        if dt in _CONVERT:
            dt = np.dtype(_CONVERT[dt])
        if dt not in _DTYPES:
            raise Error("Volume: arrays of %s are not supported (uint8, int16, uint16, float32; float64, float16, "
                        "bool and int8 are converted): convert with array.astype(numpy.float32)" % a.dtype)
        if a.size == 0:
            raise Error("Volume: the array is empty (shape %s)" % (a.shape,))
        a = np.require(a, dtype=dt, requirements=["C_CONTIGUOUS", "ALIGNED"])
        self.copied = not (isinstance(orig, np.ndarray) and a.__array_interface__["data"][0] ==
                           orig.__array_interface__["data"][0] and a.dtype == orig.dtype)
        sp = _spacing(spacing)
        dims = (ctypes.c_int * 3)(*a.shape[::-1])
        strides = (ctypes.c_size_t * 3)(*[s if s >= 0 else 0 for s in a.strides[::-1]])
        ctx = _context()
        h = ctypes.c_void_p()
        ctx.check(_LIB.vs_volume_wrap(ctx.h, _DTYPES[a.dtype], dims, strides, sp, a.ctypes.data,
                                      _lib.RELEASE_FN(), None, ctypes.byref(h)))
        self._h = h
        self._array = a  # the library reads it: kept alive as long as the volume
        self._release = _LIB.vs_volume_release
        if affine is not None:
            m = np.asarray(affine, dtype=np.float64)
            if m.shape not in ((3, 4), (4, 4)):
                self.close()
                raise Error("Volume: affine must be 3x4 or 4x4, not %s" % (m.shape,))
            st = _LIB.vs_volume_set_transform(ctx.h, h, (ctypes.c_double * 12)(*m[:3].ravel()))
            if st:
                self.close()
                ctx.check(st)

    @classmethod
    def _adopt(cls, h):
        v = cls.__new__(cls)
        v._h = h
        v._array = None
        v.copied = False
        v._release = _LIB.vs_volume_release
        return v

    def _handle(self):
        if not self._h:
            raise Error("the volume is closed")
        return self._h

    def close(self):
        """Release the library's volume now (else when garbage-collected).
        Arrays got from `array` of a loaded volume must not be used after."""
        if getattr(self, "_h", None):
            self._release(self._h)
            self._h = None

    def __del__(self):
        self.close()

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()

    @property
    def dims(self):
        """(x, y, z) voxel counts."""
        d = (ctypes.c_int * 3)()
        _LIB.vs_volume_dims(self._handle(), d)
        return tuple(d)

    @property
    def shape(self):
        """(z, y, x), the NumPy shape."""
        return self.dims[::-1]

    @property
    def dtype(self):
        return _NUMPY_OF[_LIB.vs_volume_type(self._handle())]

    @property
    def spacing(self):
        """(sx, sy, sz) in millimetres."""
        s = (ctypes.c_double * 3)()
        _LIB.vs_volume_spacing(self._handle(), s)
        return tuple(s)

    @property
    def affine(self):
        """(matrix, oriented): the 3x4 index-to-world matrix (RAS, mm) and
        whether the file gave an orientation (else diag(spacing))."""
        m = (ctypes.c_double * 12)()
        oriented = _LIB.vs_volume_affine(self._handle(), m)
        return np.array(m, dtype=np.float64).reshape(3, 4), bool(oriented)

    @property
    def range(self):
        """(min, max) of the finite voxel values."""
        lo, hi = ctypes.c_double(), ctypes.c_double()
        _LIB.vs_volume_range(self._handle(), ctypes.byref(lo), ctypes.byref(hi))
        return lo.value, hi.value

    @property
    def default_iso(self):
        """The iso-value the library picks without one (Otsu's threshold)."""
        return _LIB.vs_volume_default_iso(self._handle())

    @property
    def array(self):
        """The voxels as a (z, y, x) array, without a copy."""
        if self._array is not None:
            return self._array
        p = _LIB.vs_volume_data(self._handle())
        dt = self.dtype
        n = int(np.prod(self.shape))
        buf = (ctypes.c_char * (n * dt.itemsize)).from_address(p)
        buf._volume = self  # the library's memory lives as long as the volume
        return np.frombuffer(buf, dtype=dt).reshape(self.shape)

    def update(self):
        """Recompute the value range after writing into the array (and let
        the contexts' caches see the new voxels)."""
        _LIB.vs_volume_update_range(self._handle())

    def __repr__(self):
        if not self._h:
            return "<vsplat.Volume closed>"
        return "<vsplat.Volume %s %s spacing %s>" % ("x".join(map(str, self.dims)), self.dtype.name,
                                                    ",".join("%g" % s for s in self.spacing))


def _spacing(spacing):
    if spacing is None:
        spacing = (1.0, 1.0, 1.0)
    if np.isscalar(spacing):
        spacing = (spacing,) * 3
    sp = [float(s) for s in spacing]
    if len(sp) != 3:
        raise Error("spacing must be 3 numbers (sx, sy, sz), not %d" % len(sp))
    return (ctypes.c_double * 3)(*sp)


_TYPE_NAMES = {"u8": _lib.U8, "uint8": _lib.U8, "i16": _lib.I16, "int16": _lib.I16, "u16": _lib.U16,
               "uint16": _lib.U16, "f32": _lib.F32, "float32": _lib.F32}


def load(path, dims=None, dtype=None, endian="little", spacing=None):
    """Load a volume file: NIfTI (.nii, .nii.gz), NRRD (.nrrd, .nhdr), TIFF
    stacks, folders and .tar of PNG slices, VolPack .den; or headerless raw
    data (gzip accepted) with dims=(x, y, z) and dtype (uint8, int16, uint16,
    float32 or u8, i16, u16, f32), endian "little" or "big".  spacing
    (sx, sy, sz) overrides the file's."""
    ctx = _context()
    o = _lib.LoadOptions()
    _LIB.vs_load_options_init_sized(ctypes.byref(o), ctypes.sizeof(o))
    if dims is not None:
        if dtype is None:
            raise Error("load: raw data needs dims and dtype")
        o.raw = 1
        o.dims[:] = [int(d) for d in dims]
        key = dtype if isinstance(dtype, str) and dtype in _TYPE_NAMES else None
        if key is None:
            try:
                key = np.dtype(dtype).name
            except TypeError:
                pass
        if key not in _TYPE_NAMES:
            raise Error("load: raw dtype %s is not one of uint8, int16, uint16, float32" % dtype)
        o.type = _TYPE_NAMES[key]
        if endian not in ("little", "big"):
            raise Error("load: endian must be 'little' or 'big', not %r" % (endian,))
        o.endian = 0 if endian == "little" else 1
    elif dtype is not None:
        raise Error("load: dtype is for raw data: give dims too")
    if spacing is not None:
        o.has_spacing = 1
        o.spacing[:] = list(_spacing(spacing))
    h = ctypes.c_void_p()
    ctx.check(_LIB.vs_volume_load(ctx.h, _path_bytes(path), ctypes.byref(o), ctypes.byref(h)))
    return Volume._adopt(h)


def scene(spec):
    """A synthetic scene: "cube", "sphere", "ml[:N]", "head", "cell" (NAME:N scales it)."""
    ctx = _context()
    h = ctypes.c_void_p()
    ctx.check(_LIB.vs_volume_scene(ctx.h, str(spec).encode(), ctypes.byref(h)))
    return Volume._adopt(h)


def _enum(parse, kind, name):
    out = ctypes.c_int()
    if parse(str(name).encode(), ctypes.byref(out)) != _lib.OK:
        raise Error("unknown %s %r" % (kind, name))
    return out.value


def _tf_points(ctx, tf, vol):
    """(array of vs_tf_point, count, pointer to free or None) from a file or points."""
    if isinstance(tf, (str, bytes, os.PathLike)):
        pts = ctypes.POINTER(_lib.TfPoint)()
        n = ctypes.c_int()
        ctx.check(_LIB.vs_tf_load_for_volume(ctx.h, _path_bytes(tf), vol, ctypes.byref(pts), ctypes.byref(n)))
        return pts, n.value, pts
    a = np.asarray(tf, dtype=np.float64)
    if a.ndim != 2 or a.shape[1] != 5 or len(a) == 0:
        raise Error("tf: give a file name or rows (value, r, g, b, a), not an array of shape %s" % (a.shape,))
    pts = (_lib.TfPoint * len(a))(*[_lib.TfPoint(r[0], r[1], r[2], r[3], r[4]) for r in a])
    return pts, len(a), None


def render(volume, pipeline="post-cd", iso=None, ramp=None, tf=None, size=None, view=None, zoom=None,
           perspective=None, center=None, opacity=None, material=None, background=None, threads=None, isa=None,
           progress=None, stats=False, **settings):
    """Render a volume; returns an H x W x 4 float32 array (straight RGBA,
    row 0 at the top), or (image, stats dict) with stats=True.

    pipeline  "pre", "post-cd" (default), "post-gs", "post-alpha" or "raycast"
    iso       iso-value LO, or (LO, HI); default: the volume's Otsu threshold
    ramp      opacity ramp half-width in data units (default 2 % of the range)
    tf        a transfer-function file (.json ParaView preset, .1dt, .vtf) or
              rows (value, r, g, b, a): replaces the iso-range
    size      N or (width, height) in pixels (default 512 x 512)
    view      (azimuth, elevation) in degrees in the world frame (RAS); (0, 0)
              looks along +y, +z up; or "anterior", "posterior", "left",
              "right", "superior", "inferior" (default: anterior for a
              volume with an orientation, else (0, 0))
    zoom      fraction of the image width the largest extent spans (0.8)
    perspective  vertical field of view in degrees (default orthographic)
    center    (x, y, z) in voxel coordinates the view turns about
    opacity, material, background   peak opacity, RGB colour, RGBA background
    threads   workers for this frame (default one per physical core)
    isa       cap on the instruction set: "scalar", "sse4", "avx2", "avx512"
    progress  callable(fraction) -> truthy to cancel (vsplat.Error, status
              "cancelled"); called on this thread between tiles
    **settings  any other field of vs_settings (vsplat.h) by name, e.g.
              slab=0.5, exact_normals=True, occlusion=False, tile_size=32,
              lod_pixels=0 (full resolution however small the volume is seen),
              resample=0 (anisotropic voxels splatted as stored),
              cd_stencil=2 (post-cd: the paper's two-point differences
              at any size; 4 the four-point stencils; 0 auto),
              ray_normalize=1 (pipeline "raycast": Gaussian weights over
              their sum, without the kernel's lattice ripple),
              gs_normalize=0 (post-gs: the plain gradient splats, with that
              ripple)

    The GIL is released while the frame renders.
    """
    if not isinstance(volume, Volume):
        raise Error("render: expected a vsplat.Volume, not %s" % type(volume).__name__)
    ctx = _context()
    vh = volume._handle()
    s = _lib.Settings()
    _LIB.vs_settings_init_sized(ctypes.byref(s), ctypes.sizeof(_lib.Settings), ctypes.sizeof(_lib.Stats))
    s.pipeline = _enum(_LIB.vs_pipeline_parse, "pipeline", pipeline)
    if iso is not None:
        s.has_iso = 1
        if np.isscalar(iso):
            s.iso_lo = float(iso)
        else:
            s.iso_lo, s.iso_hi = (float(x) for x in iso)
    if ramp is not None:
        s.ramp = float(ramp)
    if size is not None:
        w, h = (size, size) if np.isscalar(size) else size
        s.width, s.height = int(w), int(h)
    if isinstance(view, str):
        s.view = _enum(_LIB.vs_view_parse, "view", view)
    elif view is not None:
        s.view = 1  # VS_VIEW_ANGLES: the angles alone, as vsplat --view AZ,EL
        s.azimuth, s.elevation = (float(x) for x in view)
    if zoom is not None:
        s.zoom = float(zoom)
    if perspective is not None:
        s.perspective_fov = float(perspective)
    if center is not None:
        s.has_center = 1
        s.center[:] = [float(x) for x in center]
    if opacity is not None:
        s.iso_opacity = float(opacity)
    if material is not None:
        s.material[:] = [float(x) for x in material]
    if background is not None:
        s.background[:] = [float(x) for x in background]
    if threads is not None:
        s.threads = int(threads)
    if isa is not None:
        s.isa = _enum(_LIB.vs_isa_parse, "ISA", isa)
    names = {f[0]: f[1] for f in _lib.Settings._fields_}
    for k, v in settings.items():
        if k not in names or k in ("struct_size", "stats_size", "tf", "tf_count", "progress", "progress_user",
                                   "trace"):
            raise Error("render: unknown setting %r" % k)
        try:
            if issubclass(names[k], ctypes.Array):
                getattr(s, k)[:] = [float(x) for x in v]
            else:
                setattr(s, k, v.item() if isinstance(v, np.generic) else v)
        except (TypeError, ValueError) as e:
            raise Error("render: setting %s=%r: %s" % (k, v, e)) from None
    raised = []
    if progress is not None:
        def call(user, fraction):
            try:
                return 1 if progress(fraction) else 0
            except BaseException as e:  # stop the frame, re-raise below
                raised.append(e)
                return 1
        s.progress = _lib.PROGRESS_FN(call)
    free_tf = None
    if tf is not None:
        pts, n, free_tf = _tf_points(ctx, tf, vh)
        s.tf = ctypes.cast(pts, ctypes.POINTER(_lib.TfPoint))
        s.tf_count = n
    img = _lib.Image()
    st = _lib.Stats()
    try:
        status = _LIB.vs_render(ctx.h, vh, ctypes.byref(s), ctypes.byref(img), ctypes.byref(st))
    finally:
        if free_tf is not None:
            _LIB.vs_tf_free(free_tf)
    if raised:
        _LIB.vs_image_free(ctypes.byref(img))
        raise raised[0]
    ctx.check(status)
    try:
        n = img.width * img.height * 4
        out = np.ctypeslib.as_array(img.rgba, shape=(n,)).copy().reshape(img.height, img.width, 4)
    finally:
        _LIB.vs_image_free(ctypes.byref(img))
    if not stats:
        return out
    return out, _stats_dict(st)


def _stats_dict(st):
    d = {}
    for name, _ in _lib.Stats._fields_:
        v = getattr(st, name)
        if isinstance(v, bytes):
            v = v.decode()
        elif isinstance(v, ctypes.Structure):
            v = {n: getattr(v, n) for n, _ in v._fields_}
        d[name] = v
    del d["struct_size"]
    return d


def _as_image(a, what):
    a = np.ascontiguousarray(a, dtype=np.float32)
    if a.ndim != 3 or a.shape[2] != 4:
        raise Error("%s: expected an H x W x 4 RGBA image, not shape %s" % (what, a.shape))
    img = _lib.Image(a.shape[1], a.shape[0], a.ctypes.data_as(ctypes.POINTER(ctypes.c_float)))
    return img, a


def compare(a, b):
    """Compare two H x W x 4 images over all four channels, as `vsplat
    compare` does: a dict with rmse, psnr (inf when identical), ssim, max_abs."""
    ctx = _context()
    ia, ka = _as_image(a, "compare")
    ib, kb = _as_image(b, "compare")
    d = _lib.ImageDiff()
    ctx.check(_LIB.vs_image_compare(ctx.h, ctypes.byref(ia), ctypes.byref(ib), ctypes.byref(d)))
    return {"rmse": d.rmse, "psnr": d.psnr, "ssim": d.ssim, "max_abs": d.max_abs}


def save(image, path, bits=8):
    """Write an H x W x 4 image; the format from the extension: .png (8-bit,
    or 16-bit with bits=16), .exr (float), .tif/.tiff.  Written to a
    temporary name and renamed."""
    ctx = _context()
    img, keep = _as_image(image, "save")
    ctx.check(_LIB.vs_image_write(ctx.h, _path_bytes(path), ctypes.byref(img), int(bits)))


def load_image(path):
    """Read an image (PNG, EXR, TIFF) as an H x W x 4 float32 array."""
    ctx = _context()
    img = _lib.Image()
    ctx.check(_LIB.vs_image_read(ctx.h, _path_bytes(path), ctypes.byref(img)))
    try:
        n = img.width * img.height * 4
        return np.ctypeslib.as_array(img.rgba, shape=(n,)).copy().reshape(img.height, img.width, 4)
    finally:
        _LIB.vs_image_free(ctypes.byref(img))

