/// @file point_light_map.h
/// @brief Point and spot lights (RenderSettings::pointLights): their geometry (the inverse
///        square and the spot's cone, pointLightFalloff) and their shadows: a light map in the
///        light's own projection, a cube of rays from its position through the volume, each
///        keeping the optical depth from the light at every --shadowstep along it. A lookup is
///        bilinear across the rays and linear along them, as the directional light's map
///        (docs/lighting.md#point-and-spot-lights). The reference marches a shadow ray from each
///        sample to the light instead (pointShadowDepth).
#pragma once

#include "shading/optical_model.h"
#include "source/source.h"
#include "support/progress.h"

#include <vdb_ewa/render_settings.h>

#include <array>
#include <cstdint>
#include <vector>

namespace vdb_ewa {
namespace detail {

/// The light's geometric factor at world point @a p: 1 / (r^2 + R^2) at distance r, R its core
/// (PointLight::radius, at least half of @a voxelLength), times a spot light's cone: smoothstep
/// from the cone's edge inwards over the spotBlend fraction of its cosine's range (0 outside
/// the cone, 1 well inside it).
double pointLightFalloff(const PointLight& light, const Vec3d& p, double voxelLength);

/// Unit-extinction optical depth, in voxel lengths, between index-space point @a pIndex and
/// world point @a lightWorld along the straight segment (midpoint rule, one sample every
/// @a step voxel lengths, trilinear density, samples below @a cutoff taken as 0), clipped to
/// the padded active box [@a boxMin, @a boxMax] (index space): the reference's shadow ray.
/// @a accessor: the thread's accessor of grid.field.
double pointShadowDepth(const GridSource::Impl& grid, openvdb::FloatGrid::ConstAccessor& accessor, const Vec3d& pIndex,
    const Vec3d& lightWorld, double step, double cutoff, const Vec3d& boxMin, const Vec3d& boxMax);

class PointLightMap
{
public:
    /// March the rays of @a light through @a grid's field (which must outlive the map):
    /// six faces of rays, each face's rays only where they cross the grid's padded active box,
    /// spaced so that they lie --shadow-res voxel lengths apart where the box is farthest from
    /// the light, each sampled every --shadowstep voxel lengths; both raised by one factor
    /// where the lattice would exceed @a pointBudget points. @a progress: one unit per face;
    /// throws Cancelled.
    PointLightMap(const GridSource::Impl& grid, const RenderSettings& settings, const PointLight& light,
        double pointBudget, Progress* progress = nullptr);

    /// Unit-extinction optical depth between the light and world point @a p (voxel lengths):
    /// bilinear across the four rays around p's direction, linear along them.
    float depth(const Vec3d& p) const;

    /// The shadow step and ray spacing used (voxel lengths): the settings', unless the budget
    /// raised them.
    double shadowStep() const { return mStepVoxels; }
    double shadowResolution() const { return mResolutionVoxels; }
    /// Rays held.
    std::uint64_t rays() const;

private:
    /// One face of the cube: rays through (axis + tan(a) e1 + tan(b) e2), a = u0 + i du,
    /// b = v0 + j du (angles: the rays spread about evenly).
    struct Face
    {
        Vec3d axis{0.0}, e1{0.0}, e2{0.0};
        double u0 = 0.0, v0 = 0.0;
        int nu = 0, nv = 0;
        std::size_t firstRay = 0; ///< its rays' index in mRayKLo etc., row-major (j * nu + i)
    };
    Vec3d rayDirection(const Face& face, int i, int j) const;
    float depthOnRay(std::size_t ray, double w) const;

    Vec3d mLight{0.0};          ///< world position
    double mStep = 0.0;         ///< world units between samples along a ray
    double mDu = 0.0;           ///< the angle between rays of a face (radians)
    double mStepVoxels = 0.0, mResolutionVoxels = 0.0;
    std::array<Face, 6> mFaces;
    /// Per ray: the sample index (k: at distance k x mStep) of its first stored sample, the
    /// number stored (0: the ray misses the box) and where they start in mDepth; past the last
    /// one the depth stays the last one's.
    std::vector<std::int64_t> mRayKLo;
    std::vector<std::int32_t> mRayCount;
    std::vector<std::uint64_t> mRayOffset;
    std::vector<float> mDepth;
};

/// The point and spot lights of a frame that scatter light, with their maps: the compositor
/// lights each (pixel, slab) sample with them, as it does with the directional lights' maps.
class PointLights
{
public:
    PointLights() = default;
    /// A map for every light that scatters (OpticalModel::pointDark), each within @a pointBudget
    /// lattice points. @a progress: throws Cancelled.
    PointLights(const GridSource::Impl& grid, const RenderSettings& settings, double pointBudget, Progress* progress = nullptr);

    bool empty() const { return mMaps.empty(); }
    /// The lights that scatter, and their maps, in the settings' order.
    const std::vector<PointLight>& lights() const { return mLights; }
    const std::vector<PointLightMap>& maps() const { return mMaps; }
    /// Light @a l's transmittance at world point @a p, per channel.
    std::array<double, 3> transmittance(std::size_t l, const Vec3d& p) const;

    /// Light @a l's intensity x scattering albedo per channel (OpticalModel::pointScale).
    const std::array<double, 3>& scale(std::size_t l) const { return mScale[l]; }

    /// Light @a l across a layer of a pixel's ray from world point @a w0 to @a w1 (shading per
    /// slab sample): its transmittance at the front per channel, ln(front / back) (lightLogRatio),
    /// and its falloff (pointLightFalloff) at the layer's middle.
    void acrossLayer(std::size_t l, const Vec3d& w0, const Vec3d& w1, std::array<float, 3>& front, std::array<float, 3>& logRatio,
        float& falloff) const;

private:
    std::vector<PointLight> mLights;                ///< the lights that scatter, as mMaps
    std::vector<std::array<double, 3>> mScale;      ///< OpticalModel::pointScale of each
    std::vector<PointLightMap> mMaps;
    double mExtinction[3] = {0.0, 0.0, 0.0};
    double mVoxelLength = 1.0;
};

} // namespace detail
} // namespace vdb_ewa
