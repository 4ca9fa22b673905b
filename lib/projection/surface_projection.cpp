/// @file surface_projection.cpp
#include "projection/surface_projection.h"

#include <vdb_ewa/ewa_kernel.h>

#include <algorithm>
#include <cmath>

namespace vdb_ewa {
namespace detail {

bool facesEye(const SurfaceKernel& kernel, const Camera& camera, Vec3d& t, Vec3d& normal)
{
    t = camera.cameraFromWorldPoint(kernel.pWorld);
    if (!(t.z > camera.near()) || !(t.z < camera.far())) return false;
    normal = camera.cameraFromWorld() * kernel.normal;
    return !(glm::dot(normal, camera.projection() == Projection::Perspective ? t : Vec3d(0, 0, 1)) > 0.0);
}

bool boxMayBeSeen(const Camera& camera, const Vec3d& lo, const Vec3d& hi, double pixelMargin)
{
    // Camera-space planes n . t + d >= 0 of the frustum; the box is outside when its 8
    // corners all fail one of them.
    const double f = camera.focalPixels();
    const double ax = (0.5 * camera.width() + pixelMargin) / f, ay = (0.5 * camera.height() + pixelMargin) / f;
    const bool perspective = camera.projection() == Projection::Perspective;
    struct Plane
    {
        Vec3d n;
        double d;
    };
    const Plane planes[6] = {
        {Vec3d(0, 0, 1), -camera.near()},
        {Vec3d(0, 0, -1), camera.far()},
        {perspective ? Vec3d(1, 0, ax) : Vec3d(1, 0, 0), perspective ? 0.0 : ax},
        {perspective ? Vec3d(-1, 0, ax) : Vec3d(-1, 0, 0), perspective ? 0.0 : ax},
        {perspective ? Vec3d(0, 1, ay) : Vec3d(0, 1, 0), perspective ? 0.0 : ay},
        {perspective ? Vec3d(0, -1, ay) : Vec3d(0, -1, 0), perspective ? 0.0 : ay},
    };
    Vec3d corners[8];
    for (int c = 0; c < 8; ++c) {
        corners[c] = camera.cameraFromWorldPoint(Vec3d((c & 1) ? hi.x : lo.x, (c & 2) ? hi.y : lo.y, (c & 4) ? hi.z : lo.z));
    }
    for (const Plane& p : planes) {
        bool allOutside = true;
        for (int c = 0; c < 8 && allOutside; ++c) allOutside = glm::dot(p.n, corners[c]) + p.d < 0.0;
        if (allOutside) return false;
    }
    return true;
}

SurfaceRequest levelSetRequest(const RenderSettings& settings, const Camera& camera, double voxelLength, int lattice)
{
    SurfaceRequest request;
    request.isovalue = settings.surface.isovalue;
    request.kernelSigma = settings.surface.sigma;
    request.lattice = lattice;
    request.drawn = [camera](const SurfaceKernel& k) {
        Vec3d t, normal;
        return facesEye(k, camera, t, normal);
    };
    const double worldReach = std::max(settings.splat.cutoffRadius, kDiscRadiusSigmas) * settings.surface.sigma * voxelLength * lattice;
    const double pixelReach = settings.splat.cutoffRadius * std::sqrt(std::max(settings.splat.lowpass, 0.0)) + 1.0;
    request.leafMayBeSeen = [camera, worldReach, pixelReach](const Vec3d& lo, const Vec3d& hi) {
        return boxMayBeSeen(camera, lo - Vec3d(worldReach), hi + Vec3d(worldReach), pixelReach);
    };
    return request;
}

bool projectSurface(const Vec3d& t, const Vec3d& normal, double sigma, const ProjectionParams& params, Footprint& fp)
{
    const Vec3d helper = std::abs(normal.x) < 0.6 ? Vec3d(1, 0, 0) : Vec3d(0, 1, 0);
    const Vec3d t0 = glm::normalize(glm::cross(normal, helper)), t1 = glm::cross(normal, t0);
    fp = projectSurfaceKernel(t, t0, t1, sigma, params);
    return fp.valid;
}

} // namespace detail
} // namespace vdb_ewa
