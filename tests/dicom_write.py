#!/usr/bin/python3
"""Write the DICOM series tests/test_dicom.c reads, with pydicom (Debian's
python3-pydicom; run with /usr/bin/python3).  Usage: dicom_write.py OUTDIR.
Exit 3 when pydicom or numpy is missing (the test then skips).

Every voxel of the main series holds round(2R + 3A + 5S), its world
position (RAS, mm) by the DICOM rule P = IPP + i*row_dir*dc + j*col_dir*dr
turned from LPS; the test checks that against the transform it loads.  The
slices are oblique, written under random names in random order, half with
the 128-byte preamble and a meta header, half bare implicit VR as old
scanners wrote them."""
import copy
import os
import random
import shutil
import subprocess
import sys

try:
    import numpy as np
    import pydicom
    from pydicom.dataset import Dataset, FileMetaDataset
    from pydicom.uid import (ExplicitVRBigEndian, ExplicitVRLittleEndian, ImplicitVRLittleEndian, RLELossless,
                             generate_uid)
except ImportError:
    sys.exit(3)

OUT = sys.argv[1]
rng = random.Random(19)
COLS, ROWS, N = 16, 12, 7
DC, DR = 0.6, 0.8          # between columns, between rows (mm)
STEP = 1.5                 # between slices along the normal
ORIGIN = np.array([-20.0, 30.0, 10.0])


def rot(ax, ay, az):
    cx, sx, cy, sy, cz, sz = np.cos(ax), np.sin(ax), np.cos(ay), np.sin(ay), np.cos(az), np.sin(az)
    rx = np.array([[1, 0, 0], [0, cx, -sx], [0, sx, cx]])
    ry = np.array([[cy, 0, sy], [0, 1, 0], [-sy, 0, cy]])
    rz = np.array([[cz, -sz, 0], [sz, cz, 0], [0, 0, 1]])
    return rz @ ry @ rx


R = rot(0.3, -0.2, 0.5)
ROW_DIR, COL_DIR = R[:, 0], R[:, 1]
NORMAL = np.cross(ROW_DIR, COL_DIR)


def world_values(k):
    """round(2R + 3A + 5S) of slice k, rows x cols."""
    j, i = np.mgrid[0:ROWS, 0:COLS]
    p = (ORIGIN[None, None, :] + i[..., None] * DC * ROW_DIR + j[..., None] * DR * COL_DIR
         + k * STEP * NORMAL)
    r, a, s = -p[..., 0], -p[..., 1], p[..., 2]
    return np.floor(2 * r + 3 * a + 5 * s + 0.5).astype(np.int16)


def fmt(v):
    return ["%.10g" % x for x in v]


def make_slice(k, pixels, series_uid, desc="oblique", slope=None, intercept=None, position=True,
               origin=ORIGIN, step=STEP):
    ds = Dataset()
    ds.SOPClassUID = "1.2.840.10008.5.1.4.1.1.2"
    ds.SOPInstanceUID = generate_uid()
    ds.Modality = "CT"
    ds.SeriesDescription = desc
    ds.StudyInstanceUID = "1.2.826.0.1.3680043.8.498.1"
    ds.SeriesInstanceUID = series_uid
    ds.InstanceNumber = k + 1
    if position:
        ds.ImagePositionPatient = fmt(origin + k * step * NORMAL)
    ds.ImageOrientationPatient = fmt(list(ROW_DIR) + list(COL_DIR))
    ds.PixelSpacing = fmt([DR, DC])
    ds.SliceThickness = "%g" % step
    ds.SamplesPerPixel = 1
    ds.PhotometricInterpretation = "MONOCHROME2"
    ds.Rows, ds.Columns = pixels.shape
    ds.BitsAllocated = 16
    ds.BitsStored = 16
    ds.HighBit = 15
    ds.PixelRepresentation = 1 if pixels.dtype == np.int16 else 0
    if slope is not None:
        ds.RescaleSlope = "%g" % slope
        ds.RescaleIntercept = "%g" % intercept
    ds.PixelData = pixels.tobytes()
    return ds


def save(ds, path, bare):
    ds = copy.deepcopy(ds)
    ds.is_little_endian = True
    if bare:  # no preamble, no meta header, implicit VR
        ds.file_meta = FileMetaDataset()
        ds.preamble = None
        ds.is_implicit_VR = True
        ds.save_as(path, write_like_original=True)
    else:
        ds.file_meta = FileMetaDataset()
        ds.file_meta.MediaStorageSOPClassUID = ds.SOPClassUID
        ds.file_meta.MediaStorageSOPInstanceUID = ds.SOPInstanceUID
        ds.file_meta.TransferSyntaxUID = ExplicitVRLittleEndian
        ds.is_implicit_VR = False
        ds.save_as(path, write_like_original=False)


def write_series(folder, slices, names=None, bare=None):
    os.makedirs(folder, exist_ok=True)
    order = list(range(len(slices)))
    rng.shuffle(order)
    for n, k in enumerate(order):
        name = names[k] if names else "%08x" % rng.getrandbits(32)
        save(slices[k], os.path.join(folder, name), (k % 2 == 0) if bare is None else bare)


shutil.rmtree(OUT, ignore_errors=True)
os.makedirs(OUT)
uid = generate_uid()
vox = [world_values(k) for k in range(N)]
main = [make_slice(k, vox[k], uid) for k in range(N)]
write_series(os.path.join(OUT, "oblique"), main)
# the same slices under other names: the same volume
write_series(os.path.join(OUT, "renamed"), main, names=["s%02d.dcm" % (N - k) for k in range(N)])

# rescaled: stored u16 = value + 1024 with slope 1, intercept -1024 (-> i16)
# and stored u16 with slope 0.25, intercept -10.5 (-> f32)
stored = [(v.astype(np.int32) + 1024).astype(np.uint16) for v in vox]
u16, f32 = generate_uid(), generate_uid()
write_series(os.path.join(OUT, "rescale_i16"),
             [make_slice(k, stored[k], u16, slope=1, intercept=-1024) for k in range(N)])
write_series(os.path.join(OUT, "rescale_f32"),
             [make_slice(k, stored[k], f32, slope=0.25, intercept=-10.5) for k in range(N)])

# Explicit VR Big Endian (retired, still written by old systems): the
# length walk of src/io/dicom_check.c reads it in its own byte order
os.makedirs(os.path.join(OUT, "bigendian"))
for k in range(N):
    ds = make_slice(k, vox[k], main[0].SeriesInstanceUID)
    ds.PixelData = vox[k].astype(">i2").tobytes()
    ds.file_meta = FileMetaDataset()
    ds.file_meta.MediaStorageSOPClassUID = ds.SOPClassUID
    ds.file_meta.MediaStorageSOPInstanceUID = ds.SOPInstanceUID
    ds.file_meta.TransferSyntaxUID = ExplicitVRBigEndian
    ds.is_little_endian = False
    ds.is_implicit_VR = False
    ds.save_as(os.path.join(OUT, "bigendian", "%d.dcm" % k), write_like_original=False)

# RLE Lossless (pydicom's encoder) and, if gdcmconv is there, JPEG-LS
# lossless: GDCM decodes both
rle = []
for k in range(N):
    ds = make_slice(k, vox[k], generate_uid() if k == 0 else rle[0].SeriesInstanceUID)
    save(ds, os.path.join(OUT, "tmp.dcm"), False)
    ds = pydicom.dcmread(os.path.join(OUT, "tmp.dcm"))
    ds.compress(RLELossless)
    rle.append(ds)
os.unlink(os.path.join(OUT, "tmp.dcm"))
os.makedirs(os.path.join(OUT, "rle"))
for k, ds in enumerate(rle):
    ds.save_as(os.path.join(OUT, "rle", "%d.dcm" % k), write_like_original=False)
if shutil.which("gdcmconv"):
    os.makedirs(os.path.join(OUT, "jpegls"))
    for k in range(N):
        src = os.path.join(OUT, "rle", "%d.dcm" % k)
        subprocess.run(["gdcmconv", "--jpegls", src, os.path.join(OUT, "jpegls", "%d.dcm" % k)], check=True)

# hostile and awkward folders
two = os.path.join(OUT, "two_series")
write_series(two, [make_slice(k, vox[k], "1.2.3.4.1", desc="first") for k in range(3)])
write_series(two, [make_slice(k, vox[k], "1.2.3.4.2", desc="second") for k in range(4)])

gap = os.path.join(OUT, "gap")
write_series(gap, [make_slice(k, vox[k], uid) for k in range(N) if k != 3])

dup = os.path.join(OUT, "duplicate")
write_series(dup, [make_slice(k, vox[k], uid) for k in range(N)] + [make_slice(2, vox[2], uid)])

noipp = os.path.join(OUT, "no_position")
write_series(noipp, [make_slice(k, vox[k], uid, position=(k != 4)) for k in range(N)])

trunc = os.path.join(OUT, "truncated_pixels")
write_series(trunc, main, names=["t%d" % k for k in range(N)])
path = os.path.join(trunc, "t2")
size = os.path.getsize(path)
with open(path, "r+b") as f:
    f.truncate(size - COLS * ROWS)  # half the pixel data gone

trunc = os.path.join(OUT, "truncated_header")
write_series(trunc, main, names=["t%d" % k for k in range(N)], bare=True)
with open(os.path.join(trunc, "t5"), "r+b") as f:
    f.truncate(200)

# a series with files that are not DICOM beside it: they are ignored
extra = os.path.join(OUT, "with_other_files")
write_series(extra, main)
with open(os.path.join(extra, "README.md"), "w") as f:
    f.write("# a scanner's export\nnot DICOM\n")
with open(os.path.join(extra, "thumbs.db"), "wb") as f:
    f.write(bytes(rng.getrandbits(8) for _ in range(300)))

# a single slice: its spacing across is SliceThickness
write_series(os.path.join(OUT, "single"), [make_slice(0, vox[0], generate_uid())])
