/// @file reference_integrator.cpp
#include "reference/reference_integrator.h"

#include "reference/halton_points.h"
#include "reference/moved_voxels.h"

#include "shading/shading.h"
#include "source/source.h"
#include "support/blank_frame.h"
#include "support/empty_space.h"
#include "support/matrix_norm.h"
#include "support/openvdb_tools.h"

#include <vdb_ewa/error.h>
#include <vdb_ewa/slab_share.h>

#include <tbb/parallel_for.h>

#include <chrono>
#include <cmath>
#include <limits>
#include <optional>

namespace vdb_ewa {
namespace detail {
namespace {

using Vec3fGrid = openvdb::Vec3SGrid;

/// The reconstruction's inputs per voxel: density (sanitised as for kernels) and density x
/// source colour (albedo x material colour x light x shadow transmittance + emission /
/// extinction), on the
/// same topology.
struct ReferenceVolume
{
    openvdb::FloatGrid::Ptr density;
    Vec3fGrid::Ptr emission;
};

ReferenceVolume buildVolume(const GridSource::Impl& grid, const RenderSettings& settings, RenderStats& stats,
    Progress* progress)
{
    auto t0 = std::chrono::steady_clock::now();
    // Unit-spaced kernels everywhere: voxelise the tiles of a copy.
    auto voxels = openvdb::gridPtrCast<openvdb::FloatGrid>(grid.grid->deepCopyGrid());
    voxels->tree().voxelizeActiveTiles();
    auto impl = std::make_shared<GridSource::Impl>(grid);
    impl->grid = voxels;
    RenderSettings unit = settings;
    unit.splat.tileKernelSpacing = 1;
    KernelSet kernels = extractKernels(*impl, unit);
    if (settings.splat.prefilter) quasiInterpolate(*impl, quasiInterpolationAlpha(settings.splat.kernelSigma), kernels);
    stats.activeVoxels = kernels.activeVoxels;
    stats.kernels = kernels.kernels.size();
    stats.kernelsSkipped = kernels.belowCutoff + kernels.notANumber;
    const double t1 = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    const std::vector<Rgb> shadows = shadowTransmittance(*impl, kernels, settings, progress);
    const std::vector<Rgb> colors = kernelColors(*impl, kernels, settings.inputToWorking);
    stats.kernelSeconds = t1;
    stats.shadowSeconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count() - t1;

    const OpticalModel model(settings);
    ReferenceVolume v;
    v.density = openvdb::FloatGrid::create(0.0f);
    v.density->setTransform(grid.grid->transform().copy());
    v.emission = Vec3fGrid::create(openvdb::Vec3s(0.0f));
    auto dAcc = v.density->getAccessor();
    auto eAcc = v.emission->getAccessor();
    for (std::size_t i = 0; i < kernels.kernels.size(); ++i) {
        const Kernel& k = kernels.kernels[i];
        const openvdb::Coord ijk(int(std::lround(k.pIndex.x)), int(std::lround(k.pIndex.y)), int(std::lround(k.pIndex.z)));
        dAcc.setValueOn(ijk, k.density);
        openvdb::Vec3s source;
        for (int c = 0; c < 3; ++c) {
            const double color = colors.empty() ? 1.0 : double(colors[i][c]);
            source[c] = float(k.density * model.source(c, shadows.data() + i * settings.lights.size(), color));
        }
        eAcc.setValueOn(ijk, source);
    }
    return v;
}

/// Samples sum_n v_n G_sigma(p - n) over voxels n within the truncation radius (index space,
/// unit-integral Gaussian: |det A| G_world = G_index, Eq. 19). One per thread.
class KernelSum
{
public:
    KernelSum(const ReferenceVolume& v, double sigma)
        : mDensity(v.density->tree()), mEmission(v.emission->tree()), mSigma(sigma),
          mRadius(int(std::ceil(kReferenceTruncation * sigma)))
    {
        mNorm = 1.0 / (std::sqrt(2.0 * 3.14159265358979323846) * sigma);
    }

    int radius() const { return mRadius; }

    void sample(const Vec3d& p, double& density, Vec3d& emission)
    {
        int lo[3];
        double w[3][40];
        int n[3];
        for (int a = 0; a < 3; ++a) {
            lo[a] = int(std::ceil(p[a] - kReferenceTruncation * mSigma));
            const int hi = int(std::floor(p[a] + kReferenceTruncation * mSigma));
            n[a] = std::min(hi - lo[a] + 1, 40);
            for (int i = 0; i < n[a]; ++i) {
                const double d = p[a] - double(lo[a] + i);
                w[a][i] = mNorm * std::exp(-0.5 * d * d / (mSigma * mSigma));
            }
        }
        density = 0.0;
        emission = Vec3d(0.0);
        for (int i = 0; i < n[0]; ++i)
            for (int j = 0; j < n[1]; ++j) {
                const double wij = w[0][i] * w[1][j];
                for (int k = 0; k < n[2]; ++k) {
                    const openvdb::Coord c(lo[0] + i, lo[1] + j, lo[2] + k);
                    const float v = mDensity.getValue(c);
                    if (v == 0.0f) continue;
                    const double wt = wij * w[2][k];
                    density += wt * double(v);
                    const openvdb::Vec3s e = mEmission.getValue(c);
                    emission += wt * Vec3d(e.x(), e.y(), e.z());
                }
            }
    }

private:
    openvdb::FloatGrid::ConstAccessor mDensity;
    Vec3fGrid::ConstAccessor mEmission;
    double mSigma, mNorm;
    int mRadius;
};

/// The Gaussian sum's sampler: density and source per unit optical depth from the pre-shaded
/// kernels (shadows at kernel centres). One per thread.
class GaussianSumSampler
{
public:
    GaussianSumSampler(const ReferenceVolume& v, double sigma) : mSum(v, sigma) {}
    void setTime(double) {} // still: rayMarchGaussianSum has no motion blur
    void setDirection(const Vec3d&) {} // isotropic single scattering: rayMarchGaussianSum refuses the others
    bool sample(const Vec3d& pIndex, double& density, double source[3], Vec3d& emitted)
    {
        emitted = Vec3d(0.0);
        Vec3d sourceSum;
        mSum.sample(pIndex, density, sourceSum);
        if (!(density > 0.0)) return false;
        for (int c = 0; c < 3; ++c) source[c] = sourceSum[c] / density;
        return true;
    }

private:
    KernelSum mSum;
};

/// The field's sampler: trilinear density, the source from a shadow ray towards each light
/// marched from the sample itself and the material colour there, and the emission grids'
/// radiance per voxel length (EmissionSampler, with the frame's @a emission model). One per
/// thread.
class TrilinearSampler
{
public:
    /// @a moved: motion blur's moved voxels (null: a still field).
    TrilinearSampler(const GridSource::Impl& grid, const RenderSettings& settings, const EmissionModel* emission, const MovedVoxels* moved)
        : mGrid(grid), mSettings(settings), mAccessor(grid.field->getConstAccessor()), mColor(grid), mInputToWorking(settings.inputToWorking), mModel(settings), mCutoff(settings.cutoff),
          mTinted(bool(grid.color)), mShadow(settings.lights.size(), Rgb{1.0f, 1.0f, 1.0f}), mOctaves(settings.scattering),
          mCosTheta(settings.lights.size(), 0.0), mEmission(grid, emission)
    {
        if (moved) mMoved.emplace(*moved);
        for (std::size_t l = 0; l < settings.lights.size(); ++l) {
            if (!mModel.dark(l)) mShadows.emplace_back(l, ShadowMarcher(grid, settings, l));
        }
        for (std::size_t l = 0; l < settings.pointLights.size(); ++l) {
            if (!mModel.pointDark(l)) mPointLights.push_back(l);
        }
        const openvdb::CoordBBox box = grid.field->evalActiveVoxelBoundingBox();
        mBoxMin = Vec3d(box.min().x(), box.min().y(), box.min().z()) - 1.0;
        mBoxMax = Vec3d(box.max().x(), box.max().y(), box.max().z()) + 1.0;
    }
    /// Motion blur: the shutter time of the samples to come, as the factor a velocity is
    /// multiplied by to move a point there from the frame's time (MotionBlur::displacementPerVelocity).
    void setTime(double displacementPerVelocity) { mTime = displacementPerVelocity; }
    /// The ray the samples to come are on (world direction): the lights' scattering angles.
    void setDirection(const Vec3d& dirWorld)
    {
        mDirection = glm::normalize(dirWorld);
        for (std::size_t l = 0; l < mCosTheta.size(); ++l) mCosTheta[l] = glm::dot(mSettings.lights[l].unitDirection(), mDirection);
    }

    bool sample(Vec3d pIndex, double& density, double source[3], Vec3d& emitted)
    {
        if (mMoved) {
            // Each voxel moves linearly with the velocity at its centre: the material at p now
            // came from x = p - w t, w the velocity of the voxels whose moved tents cover p; the
            // sample (density, light, colour, emission) is the still field's there. No voxel
            // covers p: empty space.
            Vec3d from;
            if (!mMoved->origin(pIndex, mTime, from)) {
                density = 0.0;
                for (int c = 0; c < 3; ++c) source[c] = 0.0;
                emitted = Vec3d(0.0);
                return false;
            }
            pIndex = from;
        }
        float d = 0.0f;
        openvdb::tools::BoxSampler::sample(mAccessor, openvdb::Vec3d(pIndex.x, pIndex.y, pIndex.z), d);
        density = d;
        emitted = mEmission.any() ? mEmission.at(pIndex) : Vec3d(0.0);
        if (!(density >= mCutoff) || !(density > 0.0)) { // vdb_render skips samples below its cutoff
            density = 0.0;
            for (int c = 0; c < 3; ++c) source[c] = 0.0;
            return emitted.x > 0.0 || emitted.y > 0.0 || emitted.z > 0.0;
        }
        for (auto& [l, marcher] : mShadows) {
            mShadow[l] = marcher.march(pIndex);
            // The phase function and the octaves (scattering_octaves.h): the light's
            // transmittance becomes what it scatters towards the eye per unit isotropic light.
            if (mOctaves.shaped()) {
                for (float& t : mShadow[l]) t = float(mOctaves.response(mCosTheta[l], double(t)));
            }
        }
        const Vec3d color = mTinted ? workingColor(mInputToWorking, mColor.at(mGrid.indexToWorld(pIndex))) : Vec3d(1.0);
        for (int c = 0; c < 3; ++c) source[c] = mModel.source(c, mShadow.data(), color[c]);
        // Point and spot lights: a shadow ray from the sample to the light.
        for (const std::size_t l : mPointLights) {
            const PointLight& light = mSettings.pointLights[l];
            const double falloff = pointLightFalloff(light, mGrid.indexToWorld(pIndex), mGrid.voxelLength);
            if (!(falloff > 0.0)) continue;
            const double depth = pointShadowDepth(mGrid, mAccessor, pIndex, light.position, mSettings.shadow.step, mCutoff, mBoxMin, mBoxMax);
            const Vec3d towards = light.position - mGrid.indexToWorld(pIndex);
            const double length = glm::length(towards);
            const double cosTheta = length > 0.0 ? glm::dot(towards, mDirection) / length : 0.0;
            for (int c = 0; c < 3; ++c) {
                source[c] += mModel.pointScale(l, c) * color[c] * falloff * mOctaves.response(cosTheta, std::exp(-mModel.extinction(c) * depth));
            }
        }
        return true;
    }

private:
    const GridSource::Impl& mGrid;
    const RenderSettings& mSettings;
    std::vector<std::size_t> mPointLights; ///< the point lights that are not dark
    Vec3d mBoxMin{0.0}, mBoxMax{0.0};      ///< the padded active box (index space): where shadow rays see density
    openvdb::FloatGrid::ConstAccessor mAccessor;
    std::vector<std::pair<std::size_t, ShadowMarcher>> mShadows; ///< the lights that are not dark
    MaterialColor mColor;
    Mat3d mInputToWorking;
    OpticalModel mModel;
    double mCutoff;
    bool mTinted;
    std::vector<Rgb> mShadow; ///< per light: its transmittance at the sample (1 if dark), or its octaves' response
    ScatteringOctaves mOctaves;
    Vec3d mDirection{0.0, 0.0, 1.0};  ///< the ray's unit direction (setDirection)
    std::vector<double> mCosTheta;    ///< per light: the cosine of its scattering angle on the ray
    EmissionSampler mEmission;
    std::optional<MovedVoxels::Finder> mMoved;
    double mTime = 0.0;
};

/// A pixel's own pseudo-random numbers in [0, 1), from a hash of (@a x, @a y) with the given
/// multipliers and seed (a SplitMix64-style mixer): the Cranley-Patterson rotations of the
/// pixel's samples, no pattern shared between pixels, the same for any thread count.
class PixelRandom
{
public:
    PixelRandom(int x, int y, std::uint64_t mx, std::uint64_t my, std::uint64_t seed = 0)
        : mHash(std::uint64_t(std::uint32_t(x)) * mx ^ std::uint64_t(std::uint32_t(y)) * my ^ seed)
    {
    }
    double next()
    {
        mHash ^= mHash >> 31;
        mHash *= 0xBF58476D1CE4E5B9ull;
        mHash ^= mHash >> 29;
        return double(mHash >> 11) * 0x1.0p-53;
    }

private:
    std::uint64_t mHash;
};

/// A ray's place in the shutter (in [0, 1)) and on the lens (the unit disc).
struct BlurSample
{
    double shutter, lensX, lensY;
};

/// Sample @a i of @a n of pixel (@a x, @a y): the shutter stratified in n equal parts and the
/// lens by the R2 sequence (Roberts 2018), both rotated by a hash of the pixel (no pattern
/// shared between pixels; the same for any thread count), the lens square mapped onto the
/// disc by Shirley and Chiu's concentric map.
BlurSample blurSample(int x, int y, int i, int n)
{
    PixelRandom random(x, y, 0x9E3779B97F4A7C15ull, 0xC2B2AE3D27D4EB4Full);
    const double r0 = random.next(), r1 = random.next(), r2 = random.next();
    BlurSample b;
    b.shutter = std::fmod((double(i) + 0.5) / double(n) + r0, 1.0);
    const double u = 2.0 * std::fmod(double(i) * 0.7548776662466927 + r1, 1.0) - 1.0;
    const double v = 2.0 * std::fmod(double(i) * 0.5698402909980532 + r2, 1.0) - 1.0;
    constexpr double kQuarterPi = 0.78539816339744830962;
    double r = 0.0, phi = 0.0;
    if (u == 0.0 && v == 0.0) {
        r = 0.0;
    } else if (std::abs(u) > std::abs(v)) {
        r = u;
        phi = kQuarterPi * (v / u);
    } else {
        r = v;
        phi = 2.0 * kQuarterPi - kQuarterPi * (u / v);
    }
    b.lensX = r * std::cos(phi);
    b.lensY = r * std::sin(phi);
    return b;
}

/// Ray @a i's place in pixel (@a x, @a y), in [0, 1)^2: the Halton points of bases 2
/// and 3 (well spread for any n, unlike the R2 points blurSample gives the lens), rotated by the
/// pixel's PixelRandom (its own multipliers and seed: independent of blurSample's).
Vec2d pixelSample(int x, int y, int i)
{
    PixelRandom random(x, y, 0xD6E8FEB86659FD93ull, 0x9E3779B97F4A7C15ull, 0x5851F42D4C957F2Dull);
    const double r0 = random.next(), r1 = random.next();
    return rotatedHalton(i, r0, r1);
}

void checkMarchable(const GridSource::Impl& grid, const PassRequest& passes, const char* method)
{
    if (std::string(method) != "raymarch" && (grid.emission || grid.temperature)) {
        throw ValueError(std::string("--method ") + method + " has no emission grids (--emission-grid, --temperature): use --method splat or raymarch");
    }
    if (!grid.linear) throw ValueError(std::string("--method ") + method + " needs an affine grid transform (this grid has a frustum map)");
    if (passes.shadow || passes.emission || passes.deep) {
        throw ValueError(std::string("--method ") + method + " renders the beauty, Z and transmittance only (shadow, emission and deep passes need --method splat)");
    }
}

/// March every pixel's centre ray through the index-space box [boxLo, boxHi] in steps of
/// settings.step voxel lengths, sampling at step midpoints (@a makeSampler() gives one
/// sampler per thread) and compositing each step with the exact homogeneous update.
/// Empty nodes of @a occupancy are skipped with @a skipMargin. Progress: one unit per row;
/// the cancel is checked every 16 rays.
template <typename MakeSampler>
Frame marchRays(const GridSource::Impl& grid, const Camera& camera, const RenderSettings& settings,
    const PassRequest& passes, const openvdb::FloatGrid& occupancy, int skipMargin, const Vec3d& boxLo,
    const Vec3d& boxHi, MakeSampler makeSampler, Progress* progress)
{
    const OpticalModel model(settings);
    const Mat3d indexFromWorld = glm::inverse(grid.indexToWorldLinear);
    const double ell = grid.voxelLength;
    const double step = settings.step; // voxel lengths
    const float cutoff = float(settings.cutoff);
    const int width = camera.width(), height = camera.height();
    Frame frame = blankFrame(width, height, passes);
    const Vec3d forward = glm::transpose(camera.cameraFromWorld())[2];
    const bool blurred = (grid.velocity && settings.motionBlur.shutterClose > settings.motionBlur.shutterOpen) || camera.lensRadius() > 0.0;
    // Rays per pixel: spread over the pixel's square (settings.pixelSamples), and each at its
    // own shutter time and lens point where the frame is blurred.
    const bool spread = settings.pixelSamples > 1;
    const int samples = std::max(blurred ? settings.blurSamples : 1, settings.pixelSamples);

    setUnits(progress, std::uint64_t(height));
    tbb::parallel_for(tbb::blocked_range<int>(0, height), [&](const tbb::blocked_range<int>& rows) {
        auto sampler = makeSampler();
        EmptySpaceSkipper skipper(occupancy, skipMargin);
        std::uint64_t rays = 0;
        for (int y = rows.begin(); y < rows.end(); ++y) {
            advance(progress);
            for (int x = 0; x < width; ++x) {
                // Motion blur and depth of field: blurSamples rays, each at its own shutter time
                // and lens point (stratified, rotated per pixel: deterministic), averaged.
                float sumC[3] = {0.0f, 0.0f, 0.0f}, sumT[3] = {0.0f, 0.0f, 0.0f};
                float z = std::numeric_limits<float>::infinity();
                for (int sample = 0; sample < samples; ++sample) {
                    // A row of long rays takes 0.3-0.6 s under the sanitizers: a cancel is
                    // seen within 16 rays' time, not a row's (nor a pixel's, with --blur-samples).
                    if (progress && ++rays % 16 == 0) progress->check();
                    Vec3d origin, dir;
                    const Vec2d at = spread ? Vec2d(x, y) + pixelSample(x, y, sample) : Vec2d(x + 0.5, y + 0.5);
                    if (!blurred || samples == 1) {
                        camera.worldRay(at.x, at.y, origin, dir);
                    } else {
                        const BlurSample b = blurSample(x, y, sample, samples);
                        sampler.setTime(settings.motionBlur.displacementPerVelocity(
                            settings.motionBlur.shutterOpen + b.shutter * (settings.motionBlur.shutterClose - settings.motionBlur.shutterOpen)));
                        camera.lensRay(at.x, at.y, b.lensX, b.lensY, origin, dir);
                    }
                    sampler.setDirection(dir);
                    float T[3] = {1.0f, 1.0f, 1.0f}, C[3] = {0.0f, 0.0f, 0.0f};
                    float zRay = std::numeric_limits<float>::infinity();
                    // Parameter s: world distance from the near-plane origin; far plane likewise.
                    const double sFar = camera.projection() == Projection::Perspective
                        ? (camera.far() - camera.near()) / glm::dot(dir, forward)
                        : camera.far() - camera.near();
                    const Vec3d oIndex = indexFromWorld * (origin - grid.indexToWorldOffset);
                    const Vec3d dIndex = indexFromWorld * dir; // index units per world unit
                    double s0, s1;
                    if (boxClip(oIndex, dIndex, boxLo, boxHi, s0, s1)) {
                        s0 = std::max(s0, 0.0);
                        s1 = std::min(s1, sFar);
                        const double ds = step * ell;
                        // Steps are anchored at the near plane, so neighbouring rays sample alike.
                        for (double s = ds * std::floor(s0 / ds); s < s1; s += ds) {
                            const Vec3d p = oIndex + (s + 0.5 * ds) * dIndex;
                            const double jump = skipper.emptyExit(p, dIndex);
                            if (jump > ds) {
                                s += ds * std::floor(jump / ds) - ds;
                                continue;
                            }
                            double density, source[3];
                            Vec3d emitted;
                            if (!sampler.sample(p, density, source, emitted)) continue;
                            const float before = (T[0] + T[1] + T[2]) / 3.0f;
                            for (int c = 0; c < 3; ++c) {
                                // The emission grids' radiance per voxel length over the step (no
                                // optical depth of their own: compositeSlab's exact update).
                                const float tau = float(model.opticalDepth(c, density, step));
                                compositeSlab(tau, float(tau * source[c] + emitted[c] * step), C[c], T[c]);
                            }
                            if (passes.depth && before > 0.5f && !std::isfinite(zRay)) {
                                const double u = halfAlphaFraction(before, (T[0] + T[1] + T[2]) / 3.0f);
                                if (u <= 1.0) zRay = float(camera.near() + (s + u * ds) * glm::dot(dir, forward));
                            }
                            if (T[0] * T[0] + T[1] * T[1] + T[2] * T[2] < cutoff) break;
                        }
                    }
                    for (int c = 0; c < 3; ++c) {
                        sumC[c] += C[c];
                        sumT[c] += T[c];
                    }
                    if (!std::isfinite(z)) z = zRay; // the first sample's ray that reached half opacity
                }
                float C[3], T[3];
                for (int c = 0; c < 3; ++c) {
                    C[c] = sumC[c] / float(samples);
                    T[c] = sumT[c] / float(samples);
                }
                float* px = frame.beauty.pixel(x, y);
                for (int c = 0; c < 3; ++c) px[c] = C[c];
                px[3] = 1.0f - (T[0] + T[1] + T[2]) / 3.0f;
                const std::size_t i = std::size_t(y) * std::size_t(width) + std::size_t(x);
                if (passes.depth) frame.depth[i] = z;
                if (passes.transmittance) std::copy(T, T + 3, &frame.transmittance[3 * i]);
            }
        }
    });
    return frame;
}

} // namespace

Frame rayMarchReference(const GridSource::Impl& grid, const Camera& camera, const RenderSettings& settings,
    const PassRequest& passes, const MemoryBudget& budget, RenderStats& stats, Progress* progress)
{
    checkMarchable(grid, passes, "raymarch");
    const auto t0 = std::chrono::steady_clock::now();
    stats.activeVoxels = grid.activeVoxels;
    stats.activeTiles = grid.activeTiles;
    // Emission grids (in the grid's index space) emit where there is no density: the march
    // covers and skips by the union of their active voxels. One emission model for every ray.
    openvdb::FloatGrid::ConstPtr occupancy = grid.field;
    std::optional<EmissionModel> emission;
    if (grid.emission || grid.temperature) {
        emission.emplace(settings);
        openvdb::FloatGrid::Ptr all = grid.field->deepCopy();
        for (const auto& emitter : {grid.emission, grid.temperature}) {
            if (emitter) all->tree().topologyUnion(emitter->field->tree());
        }
        occupancy = all;
    }
    const openvdb::CoordBBox box = occupancy->evalActiveVoxelBoundingBox();
    if (box.empty()) return blankFrame(camera.width(), camera.height(), passes);
    // Trilinear support: one voxel beyond the active ones; with motion blur, as far again as
    // any point travels (|A^-1| <= its Frobenius norm takes world lengths to index lengths), and
    // empty space is skipped only that far from the still field.
    const double travel = largestTravel(grid, settings) * frobeniusNorm(glm::inverse(grid.indexToWorldLinear));
    const Vec3d boxLo = Vec3d(box.min().x(), box.min().y(), box.min().z()) - 1.0 - travel;
    const Vec3d boxHi = Vec3d(box.max().x(), box.max().y(), box.max().z()) + 1.0 + travel;
    // Motion blur: the voxels the material moves with, indexed where they are over the shutter.
    std::optional<MovedVoxels> moved;
    if (grid.velocity && settings.motionBlur.shutterClose > settings.motionBlur.shutterOpen) {
        moved.emplace(grid, *occupancy, settings, budget, progress);
    }
    if (progress) progress->stage(0, 100);
    Frame frame = marchRays(grid, camera, settings, passes, *occupancy, int(std::ceil(travel)), boxLo, boxHi,
        [&] { return TrilinearSampler(grid, settings, emission ? &*emission : nullptr, moved ? &*moved : nullptr); }, progress);
    stats.rasterSeconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    return frame;
}

Frame rayMarchGaussianSum(const GridSource::Impl& grid, const Camera& camera, const RenderSettings& settings,
    const PassRequest& passes, RenderStats& stats, Progress* progress)
{
    checkMarchable(grid, passes, "raymarch-gaussian");
    if (grid.velocity || camera.lensRadius() > 0.0) {
        throw ValueError("--method raymarch-gaussian renders still pinhole frames: motion blur (--velocity-grid) and depth of field (--fstop) need --method splat or raymarch");
    }
    if (!settings.pointLights.empty()) {
        throw ValueError("--method raymarch-gaussian lights with --light only: --point-light and --spot-light need --method splat or raymarch");
    }
    if (OpticalModel(settings).octaves().shaped()) {
        throw ValueError("--method raymarch-gaussian scatters once and isotropically: --anisotropy and --multiple-scattering need --method splat, raymarch or pathtrace");
    }
    if (progress) progress->stage(0, 15); // kernels and shadows, then the rays
    const ReferenceVolume volume = buildVolume(grid, settings, stats, progress);
    const auto t0 = std::chrono::steady_clock::now();
    const openvdb::CoordBBox box = volume.density->evalActiveVoxelBoundingBox();
    if (box.empty()) return blankFrame(camera.width(), camera.height(), passes);
    const double pad = kReferenceTruncation * settings.splat.kernelSigma + 1.0;
    const Vec3d boxLo = Vec3d(box.min().x(), box.min().y(), box.min().z()) - pad;
    const Vec3d boxHi = Vec3d(box.max().x(), box.max().y(), box.max().z()) + pad;
    if (progress) progress->stage(15, 100);
    const int radius = int(std::ceil(kReferenceTruncation * settings.splat.kernelSigma));
    Frame frame = marchRays(grid, camera, settings, passes, *volume.density, radius, boxLo, boxHi,
        [&] { return GaussianSumSampler(volume, settings.splat.kernelSigma); }, progress);
    stats.rasterSeconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    return frame;
}

} // namespace detail
} // namespace vdb_ewa
