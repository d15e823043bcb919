#!/usr/bin/env python3
"""Render the Colin27 MRI head's skin (iso 45, ramp 10, from the front) to a PNG.

    python3 render_colin27.py [HEAD.nii.gz] [OUT.png] [--size N] [--pipeline P]

HEAD defaults to $VSPLAT_DATA/colin27_ch2_mri_t1_head_181x217x181_u8.nii.gz,
else /work/shared/data/..., else Debian's mricron-data copy
(/usr/share/mricron/templates/ch2.nii.gz).  OUT defaults to colin27.png.
"""
import argparse
import os
import sys

import vsplat

NAME = "colin27_ch2_mri_t1_head_181x217x181_u8.nii.gz"


def default_head():
    for d in (os.environ.get("VSPLAT_DATA"), "/work/shared/data"):
        if d and os.path.exists(os.path.join(d, NAME)):
            return os.path.join(d, NAME)
    return "/usr/share/mricron/templates/ch2.nii.gz"


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("head", nargs="?", default=default_head())
    ap.add_argument("out", nargs="?", default="colin27.png")
    ap.add_argument("--size", type=int, default=512)
    ap.add_argument("--pipeline", default="post-cd", choices=vsplat.PIPELINES)
    a = ap.parse_args()
    try:
        vol = vsplat.load(a.head)
        img, st = vsplat.render(vol, pipeline=a.pipeline, iso=45, ramp=10, view=(180, 0), size=a.size, stats=True)
        vsplat.save(img, a.out)
    except vsplat.Error as e:
        print("render_colin27: %s" % e, file=sys.stderr)
        return 1
    print("%s: %s, %s pipeline, %d threads, %.1f ms, %d sections splatted -> %s"
          % (os.path.basename(a.head), vol, st["pipeline"], st["threads"], st["ms_total"], st["voxels_splatted"],
             a.out))
    return 0


if __name__ == "__main__":
    sys.exit(main())
