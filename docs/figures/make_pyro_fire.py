#!/usr/bin/python3
"""Write the shared pyro's density with a synthetic temperature grid (Kelvin) beside it, for the
fire figure of docs/lighting.md: the shared asset has a density grid only. The temperature is
hottest (2800 K before cooling) at the plume's base and cools with height wherever there is smoke:
T = 2800 K x min(density / 0.5, 1) x exp(-(y - y0) / 1.2), 0 below 300 K (smooth, as a
simulation's temperature is: a hard edge at 0 K glows by a voxel more in vdb_ewa, which
classifies each voxel, than in a renderer that takes T^4 of the interpolated temperature;
docs/equations.md#emission-grids).

Usage: make_pyro_fire.py SHARED/grids/pyro.vdb OUT.vdb"""
import sys

import numpy as np
import pyopenvdb as vdb

density = vdb.read(sys.argv[1], "density")
lo, hi = density.evalActiveVoxelBoundingBox()
shape = tuple(h - l + 1 for l, h in zip(lo, hi))
rho = np.zeros(shape, np.float32)
density.copyToArray(rho, ijk=lo)
y = np.array([density.transform.indexToWorld((lo[0], j, lo[2]))[1] for j in range(lo[1], hi[1] + 1)])
height = np.exp(-(y - y.min()) / 1.2)[None, :, None]
kelvin = (2800.0 * np.minimum(rho / 0.5, 1.0) * height).astype(np.float32)
kelvin[kelvin < 300.0] = 0.0
temperature = vdb.FloatGrid()
temperature.copyFromArray(kelvin, ijk=lo, tolerance=0.0)
temperature.transform = density.transform
temperature.name = "temperature"
temperature.gridClass = vdb.GridClass.FOG_VOLUME
vdb.write(sys.argv[2], grids=[density, temperature])
print(f"{sys.argv[2]}: temperature up to {kelvin.max():.0f} K in {temperature.activeVoxelCount()} voxels")
