"""The Python package (tools/python/vsplat) against the C library it wraps.

Run by CTest with Debian's python3 (tests/CMakeLists.txt) with the build's
package first on PYTHONPATH; prints "SKIP: why" and exits 0 without NumPy.
What it checks, each against an independent truth:
  - the ctypes structs agree with the C compiler's layout of vsplat.h, field
    for field (tests/python/layout.c prints it);
  - the package finds the build's library by itself (no VSPLAT_LIBRARY);
  - a NumPy volume renders bit-identically to the same voxels written to a
    raw file and loaded by the library, for every dtype and pipeline, and is
    used without a copy when it can be; other layouts are copied, other
    dtypes converted or refused;
  - library errors arrive as vsplat.Error with the library's message;
  - the stats dict names the pipeline and counts the voxels;
  - two Python threads render at once (the GIL is released: Python runs
    while a frame is inside the library) and get the images one thread gets;
  - compare() agrees with NumPy's RMSE; save/load_image round-trip;
  - the Colin27 example writes its PNG (skipped without the data).
"""

import json
import os
import subprocess
import sys
import tempfile
import threading
import time
import unittest

try:
    import numpy as np
except ImportError:
    print("SKIP: NumPy is not installed for %s (Debian: apt-get install python3-numpy)" % sys.executable)
    sys.exit(0)

# the package must find the build's library through its own look-up
EXPECT_LIB = os.environ.get("VSPLAT_TEST_LIBRARY")
os.environ.pop("VSPLAT_LIBRARY", None)
import vsplat  # noqa: E402
from vsplat import _lib  # noqa: E402

SRC = os.environ.get("VSPLAT_SOURCE_DIR", os.path.join(os.path.dirname(__file__), "..", ".."))


def data_dir():
    for d in (os.environ.get("VSPLAT_DATA"), os.path.join(SRC, "..", "shared", "data")):
        if d and os.path.isdir(d):
            return d
    return None


def blob(shape, dtype, shift=0):
    """A ball with a shell and some texture, in the dtype's range."""
    z, y, x = np.indices(shape, dtype=np.float64)
    r = np.sqrt(((x - shape[2] / 2 + shift) / (shape[2] / 2)) ** 2 + ((y - shape[1] / 2) / (shape[1] / 2)) ** 2 +
                ((z - shape[0] / 2) / (shape[0] / 2)) ** 2)
    f = np.where(r < 0.7, 0.8 - 0.3 * r, np.where(r < 0.9, 0.3, 0.05 * ((x * 7 + y * 3 + z) % 5)))
    scale = {np.uint8: (250, 0), np.int16: (3000, -1000), np.uint16: (60000, 0), np.float32: (1, 0)}[dtype]
    return (f * scale[0] + scale[1]).astype(dtype)


SMALL = dict(size=(80, 64), view=(30, 20), threads=2, pin=False)


class Layout(unittest.TestCase):
    def test_structs_match_c(self):
        exe = os.environ.get("VSPLAT_TEST_LAYOUT")
        if not exe:
            self.skipTest("VSPLAT_TEST_LAYOUT not set (run through CTest)")
        c = json.loads(subprocess.check_output([exe]))
        for name, info in c.items():
            T = _lib.STRUCTS[name]
            self.assertEqual(ctypes_size(T), info["size"], "sizeof(%s)" % name)
            py = {f[0] for f in T._fields_}
            self.assertEqual(py, set(info["fields"]), "%s: fields" % name)
            for field, (off, size) in info["fields"].items():
                d = getattr(T, field)
                self.assertEqual((d.offset, d.size), (off, size), "%s.%s offset, size" % (name, field))

    def test_finds_build_library(self):
        if EXPECT_LIB:
            self.assertEqual(os.path.realpath(vsplat.library_path()), os.path.realpath(EXPECT_LIB))
        self.assertRegex(vsplat.library_version(), r"^\d+\.\d+\.\d+$")


def ctypes_size(T):
    import ctypes
    return ctypes.sizeof(T)


class Volumes(unittest.TestCase):
    def test_numpy_equals_file(self):
        """A NumPy volume and the same bytes loaded from a raw file render
        the same floats (the library's loader is the independent path)."""
        shape = (30, 36, 40)
        with tempfile.TemporaryDirectory() as tmp:
            for dtype in (np.uint8, np.int16, np.uint16, np.float32):
                a = blob(shape, dtype)
                path = os.path.join(tmp, "v.raw")
                a.astype(np.dtype(dtype).newbyteorder("<")).tofile(path)
                fv = vsplat.load(path, dims=shape[::-1], dtype=dtype, spacing=(1, 1.1, 1.4))
                nv = vsplat.Volume(a, spacing=(1, 1.1, 1.4))
                self.assertFalse(nv.copied)
                self.assertTrue(np.shares_memory(nv.array, a), "the array was copied")
                self.assertEqual(nv.dims, (40, 36, 30))
                self.assertEqual(fv.dims, nv.dims)
                self.assertEqual(nv.range, fv.range)
                self.assertEqual(nv.range, (float(a.min()), float(a.max())))
                self.assertTrue(np.array_equal(fv.array, a))
                for p in vsplat.PIPELINES:
                    kw = dict(SMALL, pipeline=p, ray_step=0.5)
                    i1 = vsplat.render(nv, **kw)
                    i2 = vsplat.render(fv, **kw)
                    self.assertEqual(i1.shape, (64, 80, 4))
                    self.assertEqual(i1.dtype, np.float32)
                    self.assertGreater(i1[..., 3].max(), 0.5, "%s %s: nothing visible" % (dtype.__name__, p))
                    self.assertEqual(i1.tobytes(), i2.tobytes(), "%s %s: NumPy != file" % (dtype.__name__, p))

    def test_layouts_and_dtypes(self):
        a = blob((24, 28, 32), np.float32)
        ref = vsplat.render(vsplat.Volume(a), **SMALL)
        # a strided view is copied into the dense layout, and renders as that copy
        b = np.zeros((24, 28, 64), np.float32)
        b[:, :, ::2] = a
        v = vsplat.Volume(b[:, :, ::2])
        self.assertTrue(v.copied)
        self.assertEqual(vsplat.render(v, **SMALL).tobytes(), ref.tobytes())
        # Fortran order, big-endian, float64: converted copies, same image
        for conv in (np.asfortranarray(a), a.astype(">f4"), a.astype(np.float64)):
            v = vsplat.Volume(conv)
            self.assertTrue(v.copied)
            self.assertEqual(v.dtype, np.float32)
            self.assertEqual(vsplat.render(v, **SMALL).tobytes(), ref.tobytes())
        self.assertEqual(vsplat.Volume(np.zeros((2, 2, 2), np.int8)).dtype, np.int16)
        for bad, what in ((np.zeros((4, 4, 4), np.int32), "int32"), (np.zeros((4, 4), np.float32), "dimensions"),
                          (np.zeros((0, 4, 4), np.uint8), "empty"), (np.zeros((4, 4, 4), np.complex64), "complex")):
            with self.assertRaises(vsplat.Error) as e:
                vsplat.Volume(bad)
            self.assertIn(what, str(e.exception))

    def test_write_then_update(self):
        a = blob((24, 28, 32), np.uint8)
        v = vsplat.Volume(a)
        before = vsplat.render(v, iso=100, ramp=10, **SMALL)
        a[:] = blob((24, 28, 32), np.uint8, shift=5)
        v.update()
        after = vsplat.render(v, iso=100, ramp=10, **SMALL)
        fresh = vsplat.render(vsplat.Volume(a.copy()), iso=100, ramp=10, **SMALL)
        self.assertNotEqual(before.tobytes(), after.tobytes())
        self.assertEqual(after.tobytes(), fresh.tobytes())

    def test_volume_outlives_array_name(self):
        v = vsplat.Volume(blob((16, 16, 16), np.float32))  # no other reference to the array
        import gc
        gc.collect()
        self.assertEqual(v.array.shape, (16, 16, 16))
        self.assertGreater(vsplat.render(v, size=32)[..., 3].max(), 0)
        v.close()
        with self.assertRaises(vsplat.Error):
            vsplat.render(v)


    def test_affine_orients(self):
        """The same voxels stored with x reversed and an x-flipping affine
        render as the original under its identity affine; without the
        affine they render mirrored."""
        a = np.zeros((24, 24, 24), np.float32)
        a[6:18, 6:18, 3:10] = 1.0  # a slab on the low-x side: not mirror-symmetric
        ras = np.array([[1.0, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, 0]])
        las = np.array([[-1.0, 0, 0, 23], [0, 1, 0, 0], [0, 0, 1, 0]])
        v0 = vsplat.Volume(a, affine=ras)
        v1 = vsplat.Volume(a[:, :, ::-1].copy(), affine=las)
        v2 = vsplat.Volume(a[:, :, ::-1].copy())
        m, oriented = v1.affine
        self.assertTrue(oriented)
        np.testing.assert_allclose(m, las)
        kw = dict(iso=0.5, size=64, view="anterior", threads=1)
        i0, i1 = vsplat.render(v0, **kw), vsplat.render(v1, **kw)
        i2 = vsplat.render(v2, iso=0.5, size=64, view=(180, 0), threads=1)
        self.assertGreater(vsplat.compare(i0, i1)["psnr"], 60)
        self.assertLess(vsplat.compare(i0, i2)["psnr"], 30)
        with self.assertRaises(vsplat.Error):
            vsplat.Volume(a, affine=np.zeros((3, 4)))
        with self.assertRaises(vsplat.Error):
            vsplat.render(v0, view="sideways")


class Errors(unittest.TestCase):
    def test_library_messages(self):
        with self.assertRaises(vsplat.Error) as e:
            vsplat.load("/nonexistent/head.nii.gz")
        self.assertIn("head.nii.gz", str(e.exception))
        self.assertEqual(e.exception.status, _lib.ERR_IO)
        with tempfile.NamedTemporaryFile(suffix=".nii") as f:
            f.write(b"not a nifti file at all")
            f.flush()
            with self.assertRaises(vsplat.Error) as e:
                vsplat.load(f.name)
            self.assertIn(os.path.basename(f.name), str(e.exception))
        v = vsplat.Volume(np.zeros((8, 8, 8), np.float32))
        with self.assertRaises(vsplat.Error) as e:
            vsplat.render(v, tile_size=3)
        self.assertIn("tile size 3", str(e.exception))  # the library's own message
        self.assertEqual(e.exception.status_name, "invalid argument")
        for kw in (dict(pipeline="nope"), dict(isa="mmx"), dict(no_such_setting=1), dict(tile_size="big"),
                   dict(light_dir=(1, 2))):
            with self.assertRaises(vsplat.Error):
                vsplat.render(v, **kw)
        for kw in (dict(dims=(2, 2, 2), dtype="f64"), dict(dims=(2, 2, 2), dtype="nonsense"), dict(dtype="u8")):
            with self.assertRaises(vsplat.Error):
                vsplat.load("/nonexistent.raw", **kw)
        with self.assertRaises(vsplat.Error):
            vsplat.compare(np.zeros((4, 4, 4), np.float32), np.zeros((5, 4, 4), np.float32))

    def test_cancel_and_callback_exceptions(self):
        v = vsplat.Volume(blob((24, 28, 32), np.float32))
        with self.assertRaises(vsplat.Error) as e:
            vsplat.render(v, progress=lambda f: True, size=128, tile_size=16, threads=1)
        self.assertEqual(e.exception.status_name, "cancelled")
        seen = []
        img = vsplat.render(v, progress=lambda f: seen.append(f) and False, size=64, tile_size=16, threads=1)
        self.assertGreater(len(seen), 1)
        self.assertEqual(seen[-1], 1.0)
        self.assertEqual(img.tobytes(), vsplat.render(v, size=64, tile_size=16, threads=1).tobytes())

        def boom(f):
            raise KeyError("from the callback")
        with self.assertRaises(KeyError):
            vsplat.render(v, progress=boom, size=64, threads=1)


class Render(unittest.TestCase):
    def test_stats(self):
        v = vsplat.Volume(blob((24, 28, 32), np.uint16))
        for p in ("pre", "post-gs"):
            img, st = vsplat.render(v, pipeline=p, stats=True, iso=20000, ramp=500, **SMALL)
            self.assertEqual(st["pipeline"], p)
            self.assertEqual((st["width"], st["height"]), (80, 64))
            self.assertEqual(st["voxels_total"], 24 * 28 * 32)
            self.assertEqual((st["iso_lo"], st["ramp"]), (20000, 500))
            self.assertEqual(st["threads"], 2)
            self.assertIn(st["isa"], ("scalar", "sse4", "avx2", "avx512"))
            self.assertGreater(st["voxels_splatted"], 0)
            self.assertEqual(set(st["ms_stage"]), {"setup", "rasterize", "gradient", "shade", "composite"})

    def test_settings_reach_the_library(self):
        v = vsplat.Volume(blob((24, 28, 32), np.float32))
        base = vsplat.render(v, **SMALL)
        # a background shows where nothing is: the corner pixel is exactly it
        bg = vsplat.render(v, background=(0.25, 0.5, 0.75, 1.0), **SMALL)
        self.assertEqual(bg[0, 0].tolist(), [0.25, 0.5, 0.75, 1.0])
        self.assertEqual(base[0, 0].tolist(), [0, 0, 0, 0])
        # the same view from the other side differs; size is (width, height)
        self.assertNotEqual(vsplat.render(v, **dict(SMALL, view=(210, -20))).tobytes(), base.tobytes())
        self.assertEqual(vsplat.render(v, size=(50, 20)).shape, (20, 50, 4))
        # transfer function as rows, and as a .vtf file with the same rows
        rows = [(0.0, 0, 1, 0, 0), (0.4, 0, 1, 0, 0), (0.6, 0, 1, 0, 0.5), (1.0, 0, 1, 0, 0.5)]
        img = vsplat.render(v, tf=rows, specular=0, **SMALL)  # specular light is white
        with tempfile.TemporaryDirectory() as tmp:
            path = os.path.join(tmp, "t.vtf")
            with open(path, "w") as f:
                f.writelines("point %g %g %g %g %g\n" % r for r in rows)
            self.assertEqual(vsplat.render(v, tf=path, specular=0, **SMALL).tobytes(), img.tobytes())
        self.assertGreater(img[..., 1].max(), 0.2)
        self.assertEqual(float(img[..., 0].max()), 0.0)  # green material: no red, unlike the white default
        self.assertGreater(float(base[..., 0].max()), 0.2)

    def test_compare_save_load(self):
        v = vsplat.Volume(blob((24, 28, 32), np.float32))
        a = vsplat.render(v, **SMALL)
        b = a.copy()
        b[10:20, 10:20] = np.clip(b[10:20, 10:20] + 0.1, 0, 1)
        d = vsplat.compare(a, a)
        self.assertEqual(d["psnr"], float("inf"))
        self.assertEqual(d["rmse"], 0.0)
        d = vsplat.compare(a, b)
        diff = a.astype(np.float64) - b
        self.assertAlmostEqual(d["rmse"], float(np.sqrt(np.mean(diff ** 2))), places=6)
        self.assertAlmostEqual(d["max_abs"], float(np.abs(diff).max()), places=6)
        with tempfile.TemporaryDirectory() as tmp:
            vsplat.save(a, os.path.join(tmp, "a.exr"))
            self.assertEqual(vsplat.load_image(os.path.join(tmp, "a.exr")).tobytes(), a.tobytes())
            vsplat.save(a, os.path.join(tmp, "a.png"))
            back = vsplat.load_image(os.path.join(tmp, "a.png"))
            opaque = a[..., 3] == 1.0  # 8 bits: within half a step (where alpha < 1 the reader may unassociate)
            self.assertGreater(int(opaque.sum()), 100)
            clipped = np.clip(a, 0, 1)  # highlights may pass 1
            self.assertLessEqual(float(np.abs(back[opaque] - clipped[opaque]).max()), 0.5 / 255 + 1e-6)
            self.assertLessEqual(float(np.abs(back[..., 3] - a[..., 3]).max()), 0.5 / 255 + 1e-6)
            with self.assertRaises(vsplat.Error):
                vsplat.save(a, os.path.join(tmp, "no", "such", "dir.png"))


class Threads(unittest.TestCase):
    def test_two_threads_render_at_once(self):
        v = vsplat.Volume(blob((48, 56, 64), np.float32))
        kws = [dict(SMALL, size=(160, 128), threads=1, pipeline="post-gs"),
               dict(SMALL, size=(160, 128), threads=1, pipeline="pre", view=(120, -10))]
        seq = [vsplat.render(v, **kw) for kw in kws]
        out = [None, None]
        errors = []

        def job(i):
            try:
                for _ in range(3):
                    img = vsplat.render(v, **kws[i])
                    if img.tobytes() != seq[i].tobytes():
                        errors.append("thread %d: image differs from the sequential one" % i)
                out[i] = True
            except Exception as e:  # noqa: BLE001 - reported below
                errors.append(repr(e))
        th = [threading.Thread(target=job, args=(i,)) for i in range(2)]
        for t in th:
            t.start()
        for t in th:
            t.join()
        self.assertEqual(errors, [])
        self.assertEqual(out, [True, True])

    def test_gil_released_while_rendering(self):
        """While a thread is inside vs_render, this thread calls the library:
        it finds that thread's context busy (VS_ERR_BUSY).  Were the GIL held
        for the call (ctypes.PyDLL), this thread could only run between
        frames and would never see it busy."""
        import ctypes
        v = vsplat.Volume(blob((64, 64, 64), np.float32))
        ready, done = threading.Event(), threading.Event()
        ctx = []

        def job():
            ctx.append(vsplat._context())
            ready.set()
            while True:  # a probe from the main thread may hold the context for an instant
                try:
                    vsplat.render(v, pipeline="raycast", ray_step=0.05, size=160, threads=1)
                    break
                except vsplat.Error as e:
                    if e.status != _lib.ERR_BUSY:
                        raise
            done.set()
        t = threading.Thread(target=job)
        t.start()
        self.assertTrue(ready.wait(60))
        busy = probes = 0
        img = _lib.Image()
        while not done.is_set():
            # NULL volume: refused at once when the context is free
            st = vsplat._LIB.vs_render(ctx[0].h, None, None, ctypes.byref(img), None)
            probes += 1
            busy += st == _lib.ERR_BUSY
            time.sleep(0.0005)
        t.join()
        self.assertGreater(busy, 0, "never found the rendering context busy in %d probes" % probes)


class Example(unittest.TestCase):
    def test_render_colin27(self):
        d = data_dir()
        head = d and os.path.join(d, "colin27_ch2_mri_t1_head_181x217x181_u8.nii.gz")
        if not head or not os.path.exists(head):
            self.skipTest("Colin27 not in $VSPLAT_DATA or ../shared/data")
        ex = os.path.join(SRC, "tools", "python", "examples", "render_colin27.py")
        with tempfile.TemporaryDirectory() as tmp:
            out = os.path.join(tmp, "head.png")
            r = subprocess.run([sys.executable, ex, head, out, "--size", "128"], capture_output=True, text=True)
            self.assertEqual(r.returncode, 0, r.stderr)
            img = vsplat.load_image(out)
            self.assertEqual(img.shape, (128, 128, 4))
            self.assertGreater(float((img[..., 3] > 0.99).mean()), 0.2, "the head covers the image centre")
            self.assertIn("post-cd", r.stdout)


if __name__ == "__main__":
    print("vsplat %s from %s, NumPy %s, %s" % (vsplat.library_version(), vsplat.library_path(), np.__version__,
                                              sys.executable))
    prog = unittest.main(exit=False, verbosity=2)
    sys.exit(0 if prog.result.wasSuccessful() else 1)
