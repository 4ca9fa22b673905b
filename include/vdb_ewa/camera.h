/// @file camera.h
/// @brief Pinhole and orthographic cameras with vdb_render's options and semantics
///        (OpenVDB tools/RayTracer.h: PerspectiveCamera, OrthographicCamera, lookAt).
/// @note Camera space t (Zwicker et al. 2002, Sec. 6.2): origin at the eye, t0 to the right,
///       t1 down the image, t2 along the view direction (t2 > 0 is in front). Raster space:
///       continuous pixel coordinates, pixel (i, j) has its centre at (i + 0.5, j + 0.5),
///       row 0 at the top.
#pragma once

#include <cmath>
#include <limits>
#include <optional>

#include "types.h"

namespace vdb_ewa {

enum class Projection { Perspective, Orthographic };

struct VDB_EWA_API CameraSettings
{
    Projection projection = Projection::Perspective;
    int width = 1920;                 ///< image width in pixels
    int height = 1080;                ///< image height in pixels
    Vec3d translate{0.0};             ///< eye position, world units
    std::optional<Vec3d> rotate;      ///< rotation in degrees about x, then y, then z
    std::optional<Vec3d> lookAt;      ///< world point to look at (exclusive with rotate)
    Vec3d up{0.0, 1.0, 0.0};          ///< world vector that points up after lookAt
    double focal = 50.0;              ///< perspective focal length, mm
    double aperture = 41.2136;        ///< perspective frame width (film back), mm
    double frame = 1.0;               ///< orthographic frame width, world units
    /// Depth of field (perspective): the thin lens's f-number; 0: a pinhole (no depth of field).
    /// The lens's aperture is focal / fstop wide, in world units taken as metres (Houdini's and
    /// Blender's), so focal / (2000 fstop) world units in radius.
    double fstop = 0.0;
    /// Depth of field: the depth in focus, world units along the view axis; unset: the depth of
    /// the point looked at (--lookat, else the grid's centre).
    std::optional<double> focusDistance;
    double near = 1.0e-3;             ///< near plane depth, world units
    double far = std::numeric_limits<float>::max(); ///< far plane depth, world units

    /// Set the focal length from a horizontal field of view in degrees (vdb_render -fov).
    void setFieldOfView(double degrees);
    /// Horizontal field of view in degrees.
    double fieldOfView() const;
};

/// Part @a part of the unit disc cut into @a parts parts of equal area: rings of equal-area
/// sectors, about sqrt(parts / 3) rings, the outer ones cut into more sectors (the centre ring
/// is a disc or its sectors). Its centroid and its points' covariance about the centroid.
struct LensPart
{
    Vec2d centroid{0.0};
    Mat2d covariance{0.0};
};
VDB_EWA_API LensPart lensPart(int part, int parts);

/// Most pixels an image may have (the frame's memory budget): 2^27, e.g. 16384x8192.
constexpr long long kMaxPixels = 1LL << 27;

class VDB_EWA_API Camera
{
public:
    /// @param settings      camera options; validated (ValueError on an impossible camera)
    /// @param defaultTarget world point looked at when neither rotate nor lookAt is given
    ///                      (vdb_render looks at the centre of the active voxel bounding box);
    ///                      if the eye is at that point, the camera looks down -z
    ///                      (looksDownZByDefault)
    Camera(const CameraSettings& settings, const Vec3d& defaultTarget);

    /// True where the eye sat at the default target, so the camera looks down -z instead.
    bool looksDownZByDefault() const { return mLooksDownZ; }
    /// True where the view of the default target ran along --up, so another world axis is the
    /// image's up (z, or x where the view is along z).
    bool upReplacedByDefault() const { return mUpReplaced; }

    const CameraSettings& settings() const { return mSettings; }
    Projection projection() const { return mSettings.projection; }
    int width() const { return mSettings.width; }
    int height() const { return mSettings.height; }
    /// Eye position in world units.
    const Vec3d& eye() const { return mEye; }
    /// Rotation taking world vectors to camera space (rows: right, down, forward).
    const Mat3d& cameraFromWorld() const { return mCameraFromWorld; }
    /// Viewport scale S of Eq. (33): pixels per unit of the t2 = 1 plane (perspective) or per
    /// world unit (orthographic).
    double focalPixels() const { return mFocalPixels; }
    /// Raster position of the optical axis, pixels: the image's centre (a sub-aperture's is
    /// shifted, throughLensPart).
    Vec2d principalPoint() const { return mPrincipalPoint; }
    double near() const { return mSettings.near; }
    double far() const { return mSettings.far; }
    /// Depth of field: the lens's radius in world units (0: a pinhole) and the depth in focus.
    double lensRadius() const { return mLensRadius; }
    double focusDepth() const { return mFocusDepth; }
    /// Depth of field: the covariance of the lens's points about the pinhole, in the lens plane
    /// (camera t0, t1; world units^2): a point at depth z spreads over (f_pixels |1/z -
    /// 1/focus|)^2 times it on the raster. The whole lens, a uniform disc of radius L: (L/2)^2 I;
    /// a sub-aperture: its part's (throughLensPart). Zero for a pinhole.
    const Mat2d& lensCovariance() const { return mLensCovariance; }
    /// The raster radius of the circle of confusion of a point at camera depth @a depth (thin
    /// lens: f_pixels x lens radius x |1/depth - 1/focus|; a sub-aperture's, the radius of the
    /// disc of its largest variance; 0 for a pinhole).
    double confusionRadius(double depth) const;

    /// Depth of field by sub-apertures (docs/equations.md#depth-of-field): the lens cut into
    /// @a parts parts of equal area (rings of sectors, lensPart), seen through part @a part
    /// alone: a pinhole at the part's centroid whose image of the focus plane is this camera's
    /// (an off-axis projection: the principal point moves), with a residual lens of the part's
    /// covariance about its centroid. The average of all parts' images converges to the lens's
    /// as parts grow. A pinhole, or @a parts 1: this camera.
    Camera throughLensPart(int part, int parts) const;

    /// Supersampling (docs/equations.md#sub-pixel-samples): the window of @a width x @a height
    /// pixels from pixel (@a x0, @a y0) of this camera's image, each pixel cut into @a factor x
    /// @a factor sub-pixels: a camera of (width x factor) x (height x factor) pixels seeing
    /// exactly that window (focal length in pixels and principal point scaled, the eye and the
    /// lens unchanged). Sub-pixel (i, j) lies in pixel (x0 + i / factor, y0 + j / factor).
    /// @throw ValueError if the window is empty, leaves the image, or factor < 1.
    Camera window(int x0, int y0, int width, int height, int factor) const;

    /// Larger pixels (--pixel-size, docs/equations.md#larger-pixels): a camera whose pixels
    /// are @a size of this camera's a side (@a size >= 1, not necessarily whole), seeing this
    /// camera's image with one more of its pixels on every side: its pixel i's centre lies at
    /// this raster's size (i - 1/2), so its first and last centres lie on or beyond this image's
    /// first and last pixel centres, ceil((width - 1/2) / size + 3/2) x ceil((height - 1/2) /
    /// size + 3/2) pixels (focal length in pixels divided by @a size, the principal point moved
    /// to match; the eye and the lens unchanged). Raster position p here is p / size + 1 there.
    /// @throw ValueError unless 1 <= @a size <= 64.
    Camera withPixelSize(double size) const;

    /// World point -> camera space t.
    Vec3d cameraFromWorldPoint(const Vec3d& pWorld) const
    {
        return mCameraFromWorld * (pWorld - mEye);
    }
    /// Camera space -> raster (perspective divide for perspective cameras).
    Vec2d rasterFromCamera(const Vec3d& t) const;
    /// World-space ray through a raster position: origin on the near plane and unit direction,
    /// as vdb_render's getRay (used by tests and reference integrators).
    void worldRay(double xRaster, double yRaster, Vec3d& origin, Vec3d& direction) const;
    /// The thin lens's ray through a raster position from the lens point (@a lensX, @a lensY)
    /// in the unit disc: from that point of the lens, through the point of the pinhole ray at
    /// the focus depth; origin where it crosses the near plane, unit direction. A pinhole's is
    /// worldRay.
    void lensRay(double xRaster, double yRaster, double lensX, double lensY, Vec3d& origin, Vec3d& direction) const;

private:
    CameraSettings mSettings;
    Vec3d mEye;
    Mat3d mCameraFromWorld;
    double mFocalPixels;
    double mLensRadius = 0.0, mFocusDepth = 1.0;
    Mat2d mLensCovariance{0.0};
    Vec2d mPrincipalPoint{0.0};
    bool mLooksDownZ = false;
    bool mUpReplaced = false;
};

} // namespace vdb_ewa
