#!/usr/bin/python3
"""docs/scattering.png: light scattered many times, beside Cycles' and the path tracer's.

Top row, the fog sphere of bench/cycles_scattering.py (albedo 1, optical depth 4 across, a sun
from the side and behind): Cycles at 16 Volume Bounces | vdb_ewa --method pathtrace --bounces 16
| the splatter --multiple-scattering 4 | the splatter's single scattering (vdb_render's model).
Bottom row, bench/multiple_scattering.py's dense cloud: the path-traced truth at 16 bounces |
--multiple-scattering 4 | single scattering. Each row exposed alike (its truth's 99th
percentile at 0.6), sRGB over black, scaled x2.

    /usr/bin/python3 bench/cycles_scattering.py --out CS --vdb-ewa-args --method pathtrace --bounces 16 --samples 2048
    cp CS/vdb_ewa.exr CS/pathtrace.exr   (then the same with --method splat --multiple-scattering 4, as octaves.exr,
                                          and --multiple-scattering 1, as single.exr)
    PYTHONPATH=build/python /usr/bin/python3 bench/multiple_scattering.py --out MS
    /usr/bin/python3 docs/figures/make_scattering.py --cycles-dir CS --bench-dir MS [--out docs]

Needs numpy and OpenImageIO for /usr/bin/python3; a few seconds from those outputs (the
benchmarks take about 15 minutes, Cycles' two renders another 5)."""
import argparse
import glob
import os
import tempfile

import numpy as np
import OpenImageIO as oiio


def read(path):
    buf = oiio.ImageBuf(path)
    pixels = buf.get_pixels(oiio.FLOAT)
    return pixels[..., :3]


def srgb(x):
    x = np.clip(x, 0.0, 1.0)
    return np.where(x <= 0.0031308, 12.92 * x, 1.055 * np.power(x, 1 / 2.4) - 0.055)


def row(images, reference):
    scale = 0.6 / max(float(np.percentile(reference, 99)), 1e-6)
    height = max(i.shape[0] for i in images)
    padded = [np.pad(i, ((0, height - i.shape[0]), (0, 4), (0, 0))) for i in images]
    return np.concatenate([srgb(p * scale) for p in padded], axis=1)


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--cycles-dir", required=True)
    parser.add_argument("--bench-dir", required=True)
    parser.add_argument("--out", default=tempfile.mkdtemp(prefix="vdb_ewa_figure_"))
    args = parser.parse_args()
    cycles = [read(p) for p in sorted(glob.glob(os.path.join(args.cycles_dir, "cycles_g0_b16_s*.exr")))]
    cycles = sum(cycles) / len(cycles)
    top = [cycles] + [read(os.path.join(args.cycles_dir, name + ".exr")) for name in ("pathtrace", "octaves", "single")]
    truth = np.load(glob.glob(os.path.join(args.bench_dir, "dense_cloud_truth_*.npy"))[0])[0][..., :3]
    bottom = [truth] + [read(os.path.join(args.bench_dir, "dense_cloud_%s.exr" % n)) for n in ("octaves", "single")]
    rows = [row(top, cycles), row(bottom, truth)]
    width = max(r.shape[1] for r in rows)
    image = np.concatenate([np.pad(r, ((0, 4), (0, width - r.shape[1]), (0, 0))) for r in rows], axis=0)
    buf = oiio.ImageBuf(oiio.ImageSpec(image.shape[1], image.shape[0], 3, oiio.FLOAT))
    buf.set_pixels(oiio.ROI(), np.ascontiguousarray(image.astype(np.float32)))
    buf = oiio.ImageBufAlgo.resize(buf, roi=oiio.ROI(0, 2 * image.shape[1], 0, 2 * image.shape[0]))
    path = os.path.join(args.out, "scattering.png")
    buf.write(path, oiio.UINT8)
    print(path)


if __name__ == "__main__":
    main()
