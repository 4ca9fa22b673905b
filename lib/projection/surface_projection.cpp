/// @file surface_projection.cpp
#include "projection/surface_projection.h"

#include <vdb_ewa/ewa_kernel.h>

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>

namespace vdb_ewa {
namespace detail {
namespace {

/// The weights' cut-off in standard deviations of the filtered footprint (at most
/// --cutoff-radius). The colour is the weights' normalised sum, and coverage comes from the discs.
constexpr double kSurfaceCutoffRadius = 2.0;

/// vdb_render's shaders (RayTracer.h) with a white material (multiplied by the kernel's albedo).
Vec3d shade(SurfaceShader shader, const Vec3d& normal, const Vec3d& rayDir, const Vec3d& p, const SurfaceSet& set)
{
    switch (shader) {
    case SurfaceShader::Diffuse: return Vec3d(std::abs(glm::dot(normal, rayDir)));
    case SurfaceShader::Matte: return Vec3d(1.0);
    case SurfaceShader::Normal: return 0.5 * (normal + 1.0);
    case SurfaceShader::Position: {
        const Vec3d size = set.boundsMax - set.boundsMin;
        return Vec3d(size.x > 0 ? (p.x - set.boundsMin.x) / size.x : 0.0, size.y > 0 ? (p.y - set.boundsMin.y) / size.y : 0.0,
            size.z > 0 ? (p.z - set.boundsMin.z) / size.z : 0.0);
    }
    }
    return Vec3d(1.0);
}

/// Projects kernel @a k, facing the eye with camera-space centre @a t and @a normal (facesEye),
/// into @a s: false where it is not drawn (outside the frame). The pixels visited are those whose centre lies in the footprint's cut-off (the
/// weights) or whose square meets the disc's raster box (coverage is sampled across each
/// pixel's square).
bool projectSurfaceSplat(const SurfaceKernel& k, const Vec3d& t, const Vec3d& normal, const SurfaceSet& set, const Camera& camera,
    const ProjectionParams& params, SurfaceShader shader, const Mat3d& inputToWorking, const Rgb* colour, SurfaceSplat& s)
{
    Footprint fp;
    if (!projectSurface(t, normal, set.sigma, params, fp)) return false;
    Vec3d clipDirections[3];
    double clipDistances[3];
    for (int l = 0; l < k.clipCount; ++l) {
        clipDirections[l] = camera.cameraFromWorld() * Vec3d(k.clips[std::size_t(l)].direction);
        clipDistances[l] = double(k.clips[std::size_t(l)].distance);
    }
    s.disc = discCoverage(t, normal, k.discRadius, clipDirections, clipDistances, k.clipCount, camera);
    // The union of the cut-off's box and the disc's box widened by half a pixel.
    const double* b = s.disc.box;
    const double lo[2] = {std::min(fp.centre.x - fp.halfExtent.x, b[0] - 0.5), std::min(fp.centre.y - fp.halfExtent.y, b[1] - 0.5)};
    const double hi[2] = {std::max(fp.centre.x + fp.halfExtent.x, b[2] + 0.5), std::max(fp.centre.y + fp.halfExtent.y, b[3] + 0.5)};
    Footprint box = fp;
    box.centre = 0.5 * Vec2d(lo[0] + hi[0], lo[1] + hi[1]);
    box.halfExtent = 0.5 * Vec2d(hi[0] - lo[0], hi[1] - lo[1]);
    if (!std::isfinite(box.centre.x + box.centre.y + box.halfExtent.x + box.halfExtent.y)) box = fp; // a disc through the eye plane
    if (!pixelBox(box, camera.width(), camera.height(), s.x0, s.y0, s.x1, s.y1)) return false;
    setFootprint(s, fp, params.cutoffRadius);
    s.weight = float(k.area * fp.peak);
    if (colour) {
        for (int ch = 0; ch < 3; ++ch) s.colour[ch] = (*colour)[std::size_t(ch)];
    } else {
        const Vec3d rayDir = params.perspective ? glm::normalize(k.pWorld - camera.eye()) : glm::transpose(camera.cameraFromWorld())[2];
        // vdb_render's material colour times its shader, in the input space (as it writes them).
        const Vec3d c = workingColor(inputToWorking, k.albedo * shade(shader, k.normal, rayDir, k.pWorld, set));
        for (int ch = 0; ch < 3; ++ch) s.colour[ch] = float(c[ch]);
    }
    s.depth = t.z;
    s.depthRange = k.discRadius + 2.0 * (params.perspective ? t.z : 1.0) / camera.focalPixels();
    return true;
}

} // namespace

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

SurfaceSplatSet projectSurfaceSplats(const SurfaceSet& set, const Camera& camera, const RenderSettings& settings, const std::vector<Rgb>* colours)
{
    ProjectionParams params = projectionParams(camera, settings.splat);
    params.cutoffRadius = std::min(params.cutoffRadius, kSurfaceCutoffRadius);
    params.taper = false; // surface splats are weight-normalised per pixel (Sec. 7.2): their edge is not tapered
    const std::size_t n = set.kernels.size();
    constexpr std::size_t kChunk = 4096;
    const std::size_t chunks = (n + kChunk - 1) / kChunk;
    std::vector<std::size_t> firstOfChunk(chunks + 1, 0);
    tbb::parallel_for(std::size_t(0), chunks, [&](std::size_t c) {
        Vec3d t, normal;
        std::size_t count = 0;
        for (std::size_t i = c * kChunk; i < std::min(n, (c + 1) * kChunk); ++i) count += facesEye(set.kernels[i], camera, t, normal) ? 1 : 0;
        firstOfChunk[c + 1] = count;
    });
    for (std::size_t c = 0; c < chunks; ++c) firstOfChunk[c + 1] += firstOfChunk[c];
    SurfaceSplatSet out;
    out.kernels = n;
    out.spacing = set.spacing;
    LargeArray<SurfaceSplat>& splats = out.splats;
    splats.resize(firstOfChunk[chunks]);
    tbb::parallel_for(std::size_t(0), chunks, [&](std::size_t c) {
        std::size_t next = firstOfChunk[c];
        Vec3d t, normal;
        for (std::size_t i = c * kChunk; i < std::min(n, (c + 1) * kChunk); ++i) {
            if (!facesEye(set.kernels[i], camera, t, normal)) continue;
            SurfaceSplat& s = splats[next++];
            if (!projectSurfaceSplat(set.kernels[i], t, normal, set, camera, params, settings.surface.shader, settings.inputToWorking, colours ? &(*colours)[i] : nullptr, s)) {
                s.x0 = s.y0 = 0;
                s.x1 = s.y1 = -1;
            }
        }
    });
    return out;
}

} // namespace detail
} // namespace vdb_ewa
