/// @file render_options.h
/// @brief The options of one frame, shared by the CLI's render command and the Python module
///        (python/): registered on a CLI11 app under vdb_render's names and defaults, then
///        resolved to the camera, the render settings in the working space, the grid's extra
///        grids, the output stage and the EXR header. The render command adds what belongs to
///        a batch job (input, output, --frames, --job, verbosity).
#pragma once

#include "granted_resources.h"
#include "output_options.h"

#include <vdb_ewa/vdb_ewa.h>

#include <CLI/CLI.hpp>

#include <optional>
#include <string>
#include <vector>

namespace vdb_ewa::cli {

class RenderOptions
{
public:
    /// Register every option of one frame on @a app: the grid's names, the camera, the optical
    /// model, splatting, execution and the output stage (OutputOptions::add).
    void add(CLI::App* app);

    /// The camera and render settings as given (colours in --input-space): --quality's preset,
    /// then each option given; --threads 0 and --max-memory 0 as the farm task or container
    /// grants (granted_resources.h). @a frame: the frame of a sequence (it picks --camera-file's file
    /// and keyframe); none outside a sequence. @throw ValueError naming the option.
    void resolve(std::optional<int> frame, CameraSettings& camera, RenderSettings& settings) const;
    /// What --threads 0 and --max-memory 0 took from the farm's or container's grant
    /// (granted_resources.h), for the log; empty where nothing was granted.
    std::string grantedText() const;
    /// The camera of @a frame (as resolve()).
    CameraSettings cameraFor(std::optional<int> frame) const;

    /// Everything that can fail before rendering (OutputOptions::prepare; @a output empty: an
    /// image kept in memory), then @a given's colours in the working space: the settings to
    /// render with. Warnings (fallbacks, options that change nothing) go to @a warnings.
    /// @a attachedVelocity: the grid to render has a velocity grid already (a host's), so the
    /// motion blur options apply without --velocity-grid.
    RenderSettings prepare(const std::string& output, const std::string& preview, const RenderSettings& given,
        std::vector<std::string>& warnings, bool attachedVelocity = false);

    /// The grid to render, @a path's --name grid (default: the first scalar floating-point grid).
    GridSource open(const std::string& path) const;
    /// @a grid with the --color, --emission-grid and --temperature grids of its file.
    GridSource withExtraGrids(const GridSource& grid) const;
    /// What @a camera chose on its own that a user should know (the default target at the eye,
    /// another up axis), one line each, without the grid they concern.
    static std::vector<std::string> cameraWarnings(const Camera& camera);

    /// The --name given (empty: vdb_render's rule).
    const std::string& gridName() const { return mName; }

    /// The EXR header of a frame rendered from @a input (empty for a host's grid) in
    /// @a renderSeconds: the software, input, grid, preset, host, time, @a frame (of a
    /// sequence), the camera's exact record, every resolved option as vdb_ewa/NAME, and the
    /// render's counters (statsAttributes).
    Attributes headerAttributes(const GridSource& grid, const Camera& camera, const RenderSettings& settings,
        const std::string& input, double renderSeconds, std::optional<int> frame, const RenderStats& stats) const;
    /// The counters a render reports (what -v prints), as vdb_ewa/NAME: what was read, built,
    /// projected, binned and composited, the streamed frame's bricks and the light-map rays
    /// marched, and the peak resident memory, also per active voxel (docs/output.md#flat-exr-the-default).
    static Attributes statsAttributes(const RenderStats& stats);
    /// The resolved options in groups (camera, optical model, method and splatting, output),
    /// as (option, value): printed by -v and written to the EXR header.
    std::vector<Attributes> resolvedOptions(const GridSource& grid, const Camera& camera, const RenderSettings& settings) const;

    /// --camera-file and --environment as given (empty: none): inputs an output must not overwrite.
    const std::string& cameraFile() const { return mCameraFile; }
    const std::string& environment() const { return mEnvironment; }
    /// The files of --add-volume: inputs an output must not overwrite either.
    std::vector<std::string> addedVolumeFiles() const;
    /// The i-th --add-volume-transform as a matrix (column vectors). @throw ValueError naming it.
    Mat4d addedVolumeTransform(std::size_t i) const;
    /// The i-th --add-volume-material: the volume's own medium (input space; what it does not
    /// name is the input's --absorb, --scatter, --emission) and grids, or none ("same": the
    /// input's optical model). @throw ValueError naming it.
    struct VolumeMaterial
    {
        Medium medium;
        std::string color, emissionGrid, temperature;
    };
    std::optional<VolumeMaterial> addedVolumeMaterial(std::size_t i) const;
    /// --add-volume's FILE[:GRID] as (file, grid): the whole text where it names a file.
    static std::pair<std::string, std::string> splitVolume(const std::string& volume);
    OutputOptions& output() { return mOutputOptions; }
    const OutputOptions& output() const { return mOutputOptions; }

    /// The lights as --light takes them, X,Y,Z,R,G,B each, separated by @a separator ("none"
    /// without).
    static std::string lightsText(const std::vector<Light>& lights, const std::string& separator = "; ");
    /// The point lights as --point-light takes them (X,Y,Z,R,G,B) and the spot lights as
    /// --spot-light does (all eleven values), each list separated by "; " (empty without).
    static std::pair<std::string, std::string> pointLightsText(const std::vector<PointLight>& lights);

private:
    /// --threads and --max-memory under the farm's or container's grant (granted_resources.h).
    GrantedSettings grantedExecution() const;
    /// A line for each option given without the one it qualifies: it would change nothing.
    void ignoredOptionWarnings(std::vector<std::string>& warnings, bool attachedVelocity) const;

    CLI::App* mApp = nullptr;
    std::string mCameraFile, mName, mRes, mTranslate, mRotate, mLookAt, mUp, mCamera;
    std::vector<std::string> mLights, mPointLights, mSpotLights, mAddVolumes, mAddVolumeTransforms, mAddVolumeMaterials;
    std::optional<double> mPointLightRadius;
    std::string mAbsorb, mScatter, mEmission, mAmbient, mAa, mMethod, mQuality, mExp, mRenormalize, mTaper, mPrefilter, mPrecision;
    std::optional<int> mTileSpacing, mRefine, mRefineEmission, mSamples, mPixelSize, mOctaves, mBounces;
    std::optional<double> mAnisotropy, mOctaveScatter, mOctaveExtinction, mOctaveAnisotropy;
    std::optional<double> mShadowRes;
    std::optional<double> mIsovalue, mIso, mIsoOpacity;
    std::string mShader, mColor, mEmissionGrid, mTemperatureGrid, mEmissionColor, mEnvironment;
    int mEnvironmentLights = 16;
    double mEnvironmentIntensity = 1.0;
    mutable std::size_t mEnvironmentLightCount = 0; ///< the last lights of the settings come from --environment
    mutable std::optional<std::vector<Light>> mEnvironmentFill; ///< --environment's lights, once read
    std::optional<double> mEmissionIntensity, mKelvinScale, mKelvinOffset, mBlackbodyIntensity;
    std::optional<double> mFov, mFocal, mAperture, mFrame, mNear, mFar, mGain, mCutoff, mShadowStep, mStep, mLod, mLodError, mSupersampleSpan, mPixelSizeBlur;
    std::string mImageLod;
    std::string mImageLodComposite;
    std::optional<double> mKernelSigma, mSurfaceSigma, mLowpass, mCutoffRadius, mSlab;
    int mThreads = 0;
    std::string mSimd;
    std::string mCull;
    std::string mMaxMemory;
    // Motion blur and depth of field.
    std::string mVelocityGrid, mVelocityUnit, mShutter, mMotionLight;
    std::optional<double> mVelocityScale, mFps, mFstop, mFocusDistance;
    std::optional<int> mBlurSamples, mPixelSamples, mMotionSamples, mMotionLayers, mLensSamples, mSupersample;
    std::optional<double> mMotionSplit;
    OutputOptions mOutputOptions;
};

} // namespace vdb_ewa::cli
