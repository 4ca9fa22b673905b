"""Issue 16's figures: level-set coverage against vdb_render's hit mask.

For each closed level set (a sphere, a torus, the shared cube and bunny) and each camera (the
whole object in about 50 pixels, a default view, an orthographic view, a close-up where one
voxel covers about 50 pixels, a grazing view), both renderers draw `-shader matte` at the same
camera. vdb_render's mask is its matte colour (it writes alpha 1 everywhere on level sets);
ours is alpha. Reported: IoU of (alpha > 0.5) with the mask, holes = pixels of the mask whose
5x5 neighbourhood is all hits (two pixels inside the silhouette) where alpha < 0.99, and the
same with a 3x3 neighbourhood (one pixel inside), and the wall times of both.
Needs python3-numpy, python3-openvdb and python3-openimageio (scripts/install-deps.sh --bench).
"""
import math
import os

import numpy as np


def _unit(v):
    v = np.asarray(v, dtype=float)
    return v / np.linalg.norm(v)


def torus_mesh(major, minor, n_major=256, n_minor=96):
    """A triangulated torus around the y axis (quads split in two)."""
    u = np.linspace(0, 2 * math.pi, n_major, endpoint=False)
    v = np.linspace(0, 2 * math.pi, n_minor, endpoint=False)
    uu, vv = np.meshgrid(u, v, indexing="ij")
    r = major + minor * np.cos(vv)
    pts = np.stack([r * np.cos(uu), minor * np.sin(vv), r * np.sin(uu)], axis=-1).reshape(-1, 3)
    i, j = np.meshgrid(np.arange(n_major), np.arange(n_minor), indexing="ij")
    a = i * n_minor + j
    b = ((i + 1) % n_major) * n_minor + j
    c = ((i + 1) % n_major) * n_minor + (j + 1) % n_minor
    d = i * n_minor + (j + 1) % n_minor
    quads = np.stack([a, d, c, b], axis=-1).reshape(-1, 4)
    return pts.astype(np.float32), quads.astype(np.int32)


def write_generated(folder):
    """The sphere and torus level sets (voxel 0.02, half width 3 voxels); their paths."""
    import pyopenvdb as vdb
    paths = {}
    sphere = vdb.createLevelSetSphere(radius=1.0, center=(0, 0, 0), voxelSize=0.02, halfWidth=3.0)
    sphere.name = "surface"
    paths["sphere"] = os.path.join(folder, "sphere.vdb")
    vdb.write(paths["sphere"], grids=[sphere])
    pts, quads = torus_mesh(1.0, 0.35)
    torus = vdb.FloatGrid.createLevelSetFromPolygons(pts, quads=quads,
                                                     transform=vdb.createLinearTransform(voxelSize=0.02),
                                                     halfWidth=3.0)
    torus.name = "surface"
    paths["torus"] = os.path.join(folder, "torus.vdb")
    vdb.write(paths["torus"], grids=[torus])
    return paths


def surface_point(path, origin, direction):
    """Where the ray origin + s direction first meets the zero crossing (nearest-voxel lookups,
    refined by linear interpolation), and the voxel size."""
    import pyopenvdb as vdb
    grid = vdb.readAll(path)[0][0]
    h = grid.transform.voxelSize()[0]
    acc = grid.getConstAccessor()
    xf = grid.transform
    o, d = np.asarray(origin, float), _unit(direction)

    def f(s):
        ijk = xf.worldToIndexCellCentered(tuple(o + s * d))
        return acc.getValue(ijk)

    s, step = 0.0, 0.25 * h
    prev = f(s)
    for _ in range(200000):
        s += step
        cur = f(s)
        if (prev > 0) != (cur > 0):
            s -= step * cur / (cur - prev) if cur != prev else 0.0
            return o + s * d, h
        prev = cur
    raise RuntimeError(f"no surface along the ray from {origin} in {path}")


def cameras(path, centre, size, default_eye, focus):
    """{label: vdb_render camera args} for one level set: far, default, ortho, and a close-up and
    a grazing view of the surface point that the ray from the default eye towards @a focus meets."""
    fov_half = math.atan(41.2136 / 2 / 50)  # vdb_render's default aperture and focal length
    view = _unit(np.asarray(default_eye) - centre)
    c = np.asarray(centre, float)
    fmt = lambda v: ",".join(f"{x:.5g}" for x in v)
    cams = {}
    far = c + view * size * 640 / 50 / (2 * math.tan(fov_half))
    cams["far (50 px)"] = f"-translate {fmt(far)} -lookat {fmt(c)}"
    cams["default"] = f"-translate {fmt(default_eye)} -lookat {fmt(c)}"
    cams["ortho"] = f"-camera ortho -frame {1.3 * size:.5g} -translate {fmt(c + view * 3 * size)} -lookat {fmt(c)}"
    # Close-up: the surface point seen from the default view, one voxel about 50 pixels wide.
    p, h = surface_point(path, default_eye, np.asarray(focus, float) - np.asarray(default_eye))
    near = p + view * h * 640 / 50 / (2 * math.tan(fov_half))
    cams["close-up (1 voxel = 50 px)"] = f"-translate {fmt(near)} -lookat {fmt(p)}"
    # Grazing: 5 degrees above the tangent plane at that point, half the object's size away.
    n = _unit(np.asarray(default_eye) - p)  # near enough to the normal for the framing
    t = _unit(np.cross(n, [0.0, 1.0, 0.0]) if abs(n[1]) < 0.9 else np.cross(n, [1.0, 0.0, 0.0]))
    g = _unit(t * math.cos(math.radians(5)) + n * math.sin(math.radians(5)))
    cams["grazing (5 deg)"] = f"-translate {fmt(p + g * 0.5 * size)} -lookat {fmt(p)}"
    return cams


def read_channels(path):
    import OpenImageIO as oiio
    buf = oiio.ImageBuf(path)
    px = buf.get_pixels(oiio.FLOAT)
    names = list(buf.spec().channelnames)
    return {name: px[:, :, i] for i, name in enumerate(names)}


def _eroded(mask, radius):
    out = mask.copy()
    h, w = mask.shape
    for dy in range(-radius, radius + 1):
        for dx in range(-radius, radius + 1):
            shifted = np.zeros_like(mask)
            ys, yd = (slice(dy, h), slice(0, h - dy)) if dy >= 0 else (slice(0, h + dy), slice(-dy, h))
            xs, xd = (slice(dx, w), slice(0, w - dx)) if dx >= 0 else (slice(0, w + dx), slice(-dx, w))
            shifted[yd, xd] = mask[ys, xs]
            out &= shifted
    return out


def coverage(ours_exr, theirs_exr):
    """(IoU, holes two pixels inside, holes one pixel inside, pixels hit by vdb_render)."""
    alpha = read_channels(ours_exr)["A"]
    mask = read_channels(theirs_exr)["R"] > 0.5
    ours = alpha > 0.5
    union = np.count_nonzero(ours | mask)
    iou = np.count_nonzero(ours & mask) / union if union else 1.0
    holes2 = np.count_nonzero(_eroded(mask, 2) & (alpha < 0.99))
    holes1 = np.count_nonzero(_eroded(mask, 1) & (alpha < 0.99))
    return iou, holes2, holes1, int(np.count_nonzero(mask))
