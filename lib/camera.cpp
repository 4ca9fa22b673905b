/// @file camera.cpp
/// @brief vdb_render's camera conventions (OpenVDB tools/RayTracer.h, BaseCamera).
#include <vdb_ewa/camera.h>

#include <vdb_ewa/error.h>

#include <cmath>
#include <sstream>

namespace vdb_ewa {
namespace {

constexpr double kPi = 3.14159265358979323846;

bool finite3(const Vec3d& v) { return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z); }

std::string str3(const Vec3d& v)
{
    std::ostringstream s;
    s << v.x << "," << v.y << "," << v.z;
    return s.str();
}

/// Rotation about a coordinate axis, column-vector convention (OpenVDB math::rotation).
Mat3d axisRotation(int axis, double degrees)
{
    const double a = degrees * kPi / 180.0, c = std::cos(a), s = std::sin(a);
    switch (axis) {
    case 0: return mat3FromRows({1, 0, 0}, {0, c, -s}, {0, s, c});
    case 1: return mat3FromRows({c, 0, s}, {0, 1, 0}, {-s, 0, c});
    default: return mat3FromRows({c, -s, 0}, {s, c, 0}, {0, 0, 1});
    }
}

void validate(const CameraSettings& s)
{
    auto fail = [](const std::string& what) { throw ValueError("impossible camera: " + what); };
    if (s.width < 1 || s.height < 1 || s.width > 65536 || s.height > 65536) {
        fail("--res must be between 1x1 and 65536x65536, got " + std::to_string(s.width) + "x" +
             std::to_string(s.height));
    }
    // The frame's memory budget: 2^27 pixels (16384x8192) are 2 GiB of float RGBA, 7.5 GiB with
    // every flat pass; 65536x65536 would have died in bad_alloc after the whole render.
    if (double(s.width) * double(s.height) > double(kMaxPixels)) {
        fail("--res " + std::to_string(s.width) + "x" + std::to_string(s.height) + " has more than " +
             std::to_string(kMaxPixels) + " pixels (2^27, e.g. 16384x8192), the frame's memory budget");
    }
    if (!finite3(s.translate)) fail("--translate is not finite");
    if (s.rotate && !finite3(*s.rotate)) fail("--rotate is not finite");
    if (s.lookAt && !finite3(*s.lookAt)) fail("--lookat is not finite");
    if (s.rotate && s.lookAt) fail("specify --lookat or --rotate, but not both");
    if (s.projection == Projection::Perspective) {
        if (!(s.focal > 0.0) || !std::isfinite(s.focal)) fail("--focal must be > 0 mm");
        if (!(s.aperture > 0.0) || !std::isfinite(s.aperture)) fail("--aperture must be > 0 mm");
        if (!(s.fieldOfView() < 179.0)) fail("field of view must be below 179 degrees");
    } else if (!(s.frame > 0.0) || !std::isfinite(s.frame)) {
        fail("--frame must be > 0 world units");
    }
    if (!(s.fstop >= 0.0) || !(s.fstop <= 1e6)) fail("--fstop must be in [0, 1e6] (0: a pinhole)");
    if (s.fstop > 0.0 && s.projection != Projection::Perspective) fail("--fstop: depth of field needs a perspective camera");
    if (s.focusDistance && !(*s.focusDistance > 0.0 && std::isfinite(*s.focusDistance))) fail("--focus-distance must be > 0 world units and finite");
    if (!(s.near > 0.0) || !std::isfinite(s.near)) fail("--near must be > 0");
    if (!(s.far > s.near)) fail("--far must be greater than --near");
}

} // namespace

void CameraSettings::setFieldOfView(double degrees)
{
    if (!(degrees > 0.0 && degrees < 180.0)) {
        throw ValueError("impossible camera: --fov must be in (0, 180) degrees");
    }
    focal = aperture / (2.0 * std::tan(degrees * kPi / 360.0));
}

double CameraSettings::fieldOfView() const
{
    return 360.0 / kPi * std::atan(aperture / (2.0 * focal));
}

Camera::Camera(const CameraSettings& settings, const Vec3d& defaultTarget) : mSettings(settings)
{
    validate(mSettings);
    mEye = mSettings.translate;

    // Camera axes in world space: right, up, and "back" (vdb_render's local +z).
    Vec3d right, up, back;
    // With no --lookat or --rotate the camera looks at the default target; where the eye is
    // that very point (an empty or one-voxel grid at the origin, seen from the default eye),
    // it looks down -z instead, vdb_render's frame without either option.
    mLooksDownZ = !mSettings.rotate && !mSettings.lookAt && finite3(defaultTarget) && mEye == defaultTarget;
    if (mLooksDownZ) {
        right = Vec3d(1, 0, 0);
        up = Vec3d(0, 1, 0);
        back = Vec3d(0, 0, 1);
    } else if (mSettings.rotate) {
        const Vec3d r = *mSettings.rotate;
        const Mat3d localToWorld = axisRotation(2, r.z) * axisRotation(1, r.y) * axisRotation(0, r.x);
        right = localToWorld[0];
        up = localToWorld[1];
        back = localToWorld[2];
    } else {
        // math::aim: forward = unit(eye - target), horizontal = unit(up x forward).
        const Vec3d target = mSettings.lookAt ? *mSettings.lookAt : defaultTarget;
        if (!finite3(target)) throw ValueError("impossible camera: the look-at target is not finite");
        const Vec3d dir = mEye - target;
        const double len = glm::length(dir);
        if (!(len > 0.0)) {
            throw ValueError("impossible camera: the eye " + str3(mEye) + " is at the look-at target");
        }
        back = dir / len;
        const double upLen = glm::length(mSettings.up);
        if (!(upLen > 0.0)) throw ValueError("impossible camera: --up is the zero vector");
        Vec3d h = glm::cross(mSettings.up / upLen, back);
        double hLen = glm::length(h);
        // Looking straight along the default --up at the default target (a grid right above or
        // below the eye): another world axis becomes the image's up, +-z (or x where the view
        // is along z). An explicit --lookat or --up along the view stays impossible.
        if (!(hLen > 1e-9) && !mSettings.lookAt && mSettings.up == CameraSettings().up) {
            const Vec3d alternative = std::abs(back.z) < 0.9 ? Vec3d(0, 0, back.y > 0.0 ? 1.0 : -1.0) : Vec3d(1, 0, 0);
            h = glm::cross(alternative, back);
            hLen = glm::length(h);
            mUpReplaced = true;
        }
        if (!(hLen > 1e-9)) {
            throw ValueError("impossible camera: --up " + str3(mSettings.up) +
                             " is parallel to the view direction");
        }
        right = h / hLen;
        up = glm::normalize(glm::cross(back, right));
    }
    mCameraFromWorld = mat3FromRows(right, -up, -back);

    const double halfWidth = mSettings.projection == Projection::Perspective
        ? 0.5 * mSettings.aperture / mSettings.focal  // tan of the half field of view
        : 0.5 * mSettings.frame;                      // world units
    mFocalPixels = 0.5 * double(mSettings.width) / halfWidth;
    mPrincipalPoint = Vec2d(0.5 * mSettings.width, 0.5 * mSettings.height);

    // Depth of field: a thin lens focal / fstop wide (mm, world units taken as metres), in
    // focus at --focus-distance or at the depth of the point looked at.
    if (mSettings.fstop > 0.0) {
        mLensRadius = mSettings.focal / (2000.0 * mSettings.fstop);
        mLensCovariance = Mat2d(0.25 * mLensRadius * mLensRadius); // a uniform disc's second moment
        if (mSettings.focusDistance) {
            mFocusDepth = *mSettings.focusDistance;
        } else {
            const Vec3d target = mSettings.lookAt ? *mSettings.lookAt : defaultTarget;
            mFocusDepth = finite3(target) ? cameraFromWorldPoint(target).z : 0.0;
            if (!(mFocusDepth > mSettings.near)) {
                throw ValueError("impossible camera: --fstop without --focus-distance focuses at the point looked at, which lies at depth " +
                                 std::to_string(mFocusDepth) + ", not in front of the camera: give --focus-distance");
            }
        }
    }
}

double Camera::confusionRadius(double depth) const
{
    if (!(mLensRadius > 0.0)) return 0.0;
    // The disc of the same largest variance: (R/2)^2 = the covariance's larger eigenvalue.
    const Mat2d& c = mLensCovariance;
    const double mean = 0.5 * (c[0][0] + c[1][1]), d = 0.5 * (c[0][0] - c[1][1]);
    const double largest = mean + std::sqrt(d * d + c[1][0] * c[1][0]);
    return mFocalPixels * 2.0 * std::sqrt(std::max(largest, 0.0)) * std::abs(1.0 / depth - 1.0 / mFocusDepth);
}

LensPart lensPart(int part, int parts)
{
    if (parts < 1 || part < 0 || part >= parts) throw ValueError("lensPart: part " + std::to_string(part) + " of " + std::to_string(parts));
    // Rings: about sqrt(parts / 3); ring i takes parts x (its share of the area of equal-width
    // rings, (2i + 1) / rings^2), the last the rest; its radii keep each part's area 1 / parts.
    const int rings = std::max(1, int(std::lround(std::sqrt(parts / 3.0))));
    int first = 0, ring = 0, count = parts;
    for (; ring < rings; ++ring) {
        count = ring + 1 == rings ? parts - first : std::max(1, int(std::lround(parts * double(2 * ring + 1) / double(rings * rings))));
        if (part < first + count) break;
        first += count;
    }
    const double r0 = std::sqrt(double(first) / parts), r1 = std::sqrt(double(first + count) / parts);
    const double step = 2.0 * kPi / count, a0 = step * (part - first), a1 = a0 + step;
    // Moments of the annular sector [r0, r1] x [a0, a1] (polar integrals, r dr da).
    const double area = 0.5 * step * (r1 * r1 - r0 * r0);
    const double m1 = (r1 * r1 * r1 - r0 * r0 * r0) / 3.0, m2 = (r1 * r1 * r1 * r1 - r0 * r0 * r0 * r0) / 4.0;
    const Vec2d mean = Vec2d(m1 * (std::sin(a1) - std::sin(a0)), m1 * (std::cos(a0) - std::cos(a1))) / area;
    const double s2 = 0.25 * (std::sin(2.0 * a1) - std::sin(2.0 * a0));
    const double xx = m2 * (0.5 * step + s2) / area, yy = m2 * (0.5 * step - s2) / area;
    const double xy = m2 * 0.5 * (std::sin(a1) * std::sin(a1) - std::sin(a0) * std::sin(a0)) / area;
    LensPart out;
    out.centroid = mean;
    out.covariance = Mat2d(xx - mean.x * mean.x, xy - mean.x * mean.y, xy - mean.x * mean.y, yy - mean.y * mean.y);
    return out;
}

Camera Camera::throughLensPart(int part, int parts) const
{
    Camera sub = *this;
    if (!(mLensRadius > 0.0) || parts == 1) return sub;
    const LensPart p = lensPart(part, parts);
    // The pinhole at the lens point c: a point at the focus depth, t = (x, y, F), is seen from
    // it at (x - c.x, y - c.y, F): the principal point moves by f_pixels c / F to keep its image.
    const Vec2d c = mLensRadius * p.centroid;
    sub.mEye = mEye + glm::transpose(mCameraFromWorld) * Vec3d(c.x, c.y, 0.0);
    sub.mPrincipalPoint = mPrincipalPoint + mFocalPixels * c / mFocusDepth;
    sub.mLensCovariance = (mLensRadius * mLensRadius) * p.covariance;
    return sub;
}

Camera Camera::window(int x0, int y0, int width, int height, int factor) const
{
    if (factor < 1 || width < 1 || height < 1 || x0 < 0 || y0 < 0 || x0 + width > mSettings.width || y0 + height > mSettings.height) {
        throw ValueError("Camera::window: " + std::to_string(width) + "x" + std::to_string(height) + " pixels at (" + std::to_string(x0) + ", " +
                         std::to_string(y0) + ") x " + std::to_string(factor) + " does not fit a " + std::to_string(mSettings.width) + "x" +
                         std::to_string(mSettings.height) + " image");
    }
    Camera sub = *this;
    sub.mSettings.width = width * factor;
    sub.mSettings.height = height * factor;
    sub.mFocalPixels = mFocalPixels * factor;
    sub.mPrincipalPoint = (mPrincipalPoint - Vec2d(x0, y0)) * double(factor);
    return sub;
}

Camera Camera::withPixelSize(double size) const
{
    if (!(size >= 1.0 && size <= 64.0)) throw ValueError("Camera::withPixelSize: a pixel size of " + std::to_string(size) + " (in [1, 64])");
    const auto pixels = [size](int n) { return int(std::ceil((double(n) - 0.5) / size + 1.5)); };
    Camera big = *this;
    big.mSettings.width = pixels(mSettings.width);
    big.mSettings.height = pixels(mSettings.height);
    big.mFocalPixels = mFocalPixels / size;
    big.mPrincipalPoint = mPrincipalPoint / size + Vec2d(1.0);
    return big;
}

Vec2d Camera::rasterFromCamera(const Vec3d& t) const
{
    if (mSettings.projection == Projection::Perspective) {
        return principalPoint() + mFocalPixels * Vec2d(t.x / t.z, t.y / t.z);
    }
    return principalPoint() + mFocalPixels * Vec2d(t.x, t.y);
}

void Camera::lensRay(double xRaster, double yRaster, double lensX, double lensY, Vec3d& origin, Vec3d& direction) const
{
    worldRay(xRaster, yRaster, origin, direction);
    if (!(mLensRadius > 0.0)) return;
    // The pinhole ray's point at the focus depth, seen from the lens point (camera space).
    const Mat3d worldFromCamera = glm::transpose(mCameraFromWorld);
    const Vec2d plane = (Vec2d(xRaster, yRaster) - principalPoint()) / mFocalPixels;
    const Vec3d focus = Vec3d(plane.x, plane.y, 1.0) * mFocusDepth;
    const Vec3d lens(lensX * mLensRadius, lensY * mLensRadius, 0.0);
    const Vec3d d = glm::normalize(focus - lens);
    direction = worldFromCamera * d;
    origin = mEye + worldFromCamera * (lens + d * (mSettings.near / d.z)); // on the near plane
}

void Camera::worldRay(double xRaster, double yRaster, Vec3d& origin, Vec3d& direction) const
{
    const Mat3d worldFromCamera = glm::transpose(mCameraFromWorld);
    const Vec2d plane = (Vec2d(xRaster, yRaster) - principalPoint()) / mFocalPixels;
    if (mSettings.projection == Projection::Perspective) {
        const Vec3d dCam(plane.x, plane.y, 1.0);
        direction = glm::normalize(worldFromCamera * dCam);
        origin = mEye + direction * (mSettings.near * glm::length(dCam)); // on the near plane
    } else {
        direction = worldFromCamera * Vec3d(0, 0, 1);
        origin = mEye + worldFromCamera * Vec3d(plane.x, plane.y, mSettings.near);
    }
}

} // namespace vdb_ewa
