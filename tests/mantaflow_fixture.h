/// @file mantaflow_fixture.h
/// @brief A small fire laid out as Blender's Mantaflow writes its OpenVDB cache: density and
///        flame grids, and a staggered (MAC) velocity grid in cells per Mantaflow time unit,
///        active only where the density is (the cache clips every grid to it), each grid tagged
///        with Mantaflow's file_base_resolution and file_voxel_size.
#pragma once

#include <openvdb/openvdb.h>

#include <algorithm>
#include <cmath>
#include <string>

namespace vdb_ewa {
namespace test {

struct MantaflowFire
{
    static constexpr int kCells = 24;
    static constexpr double kVoxel = 0.05;
    /// The world units a second one stored unit stands for at Time Scale 1: 2.5 voxel lengths.
    static constexpr double kSecondsScale = 2.5 * kVoxel;
    static constexpr double kRise = 30.0, kSwirl = 2.0; ///< cells and radians per Mantaflow time unit

    openvdb::FloatGrid::Ptr density, flame;
    openvdb::Vec3SGrid::Ptr velocity;

    /// The flow at index point (x, y, z): rising along z (faster higher up) and turning about
    /// the vertical axis through the domain's middle.
    static openvdb::Vec3d flow(double x, double y, double z)
    {
        const double c = 0.5 * (kCells - 1);
        return openvdb::Vec3d(-kSwirl * (y - c), kSwirl * (x - c), kRise * (0.5 + 0.5 * z / (kCells - 1)));
    }

    MantaflowFire()
    {
        const auto transform = openvdb::math::Transform::createLinearTransform(kVoxel);
        density = openvdb::FloatGrid::create(0.0f);
        flame = openvdb::FloatGrid::create(0.0f);
        velocity = openvdb::Vec3SGrid::create(openvdb::Vec3s(0.0f));
        auto d = density->getAccessor();
        auto f = flame->getAccessor();
        auto v = velocity->getAccessor();
        const double c = 0.5 * (kCells - 1);
        for (int i = 0; i < kCells; ++i)
            for (int j = 0; j < kCells; ++j)
                for (int k = 0; k < kCells; ++k) {
                    // A plume widening upwards, fading at the domain's top.
                    const double r2 = (i - c) * (i - c) + (j - c) * (j - c), width = 3.0 + 0.25 * k;
                    const double z = double(k) / (kCells - 1);
                    const double value = 2.0 * std::exp(-r2 / (2.0 * width * width)) * std::max(0.0, 1.0 - z * z) - 0.05;
                    if (!(value > 0.0)) continue;
                    const openvdb::Coord ijk(i, j, k);
                    d.setValue(ijk, float(value));
                    if (k < 10) f.setValue(ijk, float(value * (1.0 - k / 10.0)));
                    // Each component at its face: x at (i - 1/2, j, k), y at (i, j - 1/2, k), z at (i, j, k - 1/2).
                    v.setValue(ijk, openvdb::Vec3s(float(flow(i - 0.5, j, k).x()), float(flow(i, j - 0.5, k).y()), float(flow(i, j, k - 0.5).z())));
                }
        density->setName("density");
        density->setGridClass(openvdb::GRID_FOG_VOLUME);
        flame->setName("flame");
        flame->setGridClass(openvdb::GRID_FOG_VOLUME);
        velocity->setName("velocity");
        velocity->setGridClass(openvdb::GRID_STAGGERED);
        for (openvdb::GridBase* g : {static_cast<openvdb::GridBase*>(density.get()), static_cast<openvdb::GridBase*>(flame.get()),
                 static_cast<openvdb::GridBase*>(velocity.get())}) {
            g->setTransform(transform->copy());
            g->insertMeta("file_base_resolution", openvdb::Vec3IMetadata(openvdb::Vec3i(kCells, kCells, kCells)));
            g->insertMeta("file_voxel_size", openvdb::FloatMetadata(float(kVoxel)));
        }
    }

    void write(const std::string& path) const
    {
        openvdb::GridPtrVec grids{density, flame, velocity};
        openvdb::io::File(path).write(grids);
    }
};

} // namespace test
} // namespace vdb_ewa
