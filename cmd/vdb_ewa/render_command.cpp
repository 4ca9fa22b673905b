/// @file render_command.cpp
/// @brief `vdb_ewa render IN.vdb OUT.exr [options]`: vdb_render's options, GNU spelling.
#include "camera_file_option.h"
#include "command_line.h"
#include "commands.h"
#include "exit_codes.h"
#include "farm_folder.h"
#include "frame_sequence.h"
#include "option_values.h"
#include "render_options.h"
#include "progress_report.h"
#include "test_stall.h"

#include <vdb_ewa/vdb_ewa.h>

#include <algorithm>
#include <cctype>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <iomanip>
#include <iostream>
#include <optional>
#include <sstream>

#include <sys/stat.h>
#include <unistd.h>

namespace vdb_ewa::cli {
namespace {

/// A frame's files exist: @a output, and @a preview unless it is empty.
bool outputsExist(const std::string& output, const std::string& preview)
{
    return std::filesystem::exists(output) && (preview.empty() || std::filesystem::exists(preview));
}

/// A frame's files were written at or after @a since (seconds since 1970).
bool outputsWrittenSince(const std::string& output, const std::string& preview, long long since)
{
    const auto newer = [since](const std::string& path) {
        struct stat st{};
        return ::stat(path.c_str(), &st) == 0 && (long long)st.st_mtime >= since;
    };
    return newer(output) && (preview.empty() || newer(preview));
}

/// " (at every pixel A, every 2nd B, ...)": the footprint samples of each image level
/// (--image-lod), when any was accumulated at a coarser level than every pixel.
std::string levelSamples(const RenderStats& s)
{
    const std::uint64_t* at = s.footprintSamplesAtLevel;
    if (at[1] + at[2] + at[3] == 0) return "";
    return " (" + std::to_string(at[0]) + " at every pixel, " + std::to_string(at[1]) + " every 2nd, " + std::to_string(at[2]) +
           " every 4th, " + std::to_string(at[3]) + " every 8th by --image-lod)";
}

/// " (at every pixel A, every 2nd B, ...)": the slab composites of each image level
/// (--image-lod-composite), when any tile was composited at a coarser level than the pixels.
std::string levelComposites(const RenderStats& s)
{
    const std::uint64_t* at = s.slabCompositesAtLevel;
    if (at[1] + at[2] + at[3] == 0) return "";
    return " (" + std::to_string(at[0]) + " at every pixel, " + std::to_string(at[1]) + " every 2nd, " + std::to_string(at[2]) +
           " every 4th, " + std::to_string(at[3]) + " every 8th by --image-lod-composite)";
}

class RenderCommand : public Command
{
public:
    explicit RenderCommand(CLI::App& app)
    {
        mApp = app.add_subcommand("render", "Render a VDB volume or level set to an image with EWA splatting (the default subcommand: vdb_ewa IN OUT [options] is vdb_ewa render IN OUT [options])");
        mApp->footer("Every option also takes vdb_render's one-dash spelling (-res, -translate). Other commands: "
                     "vdb_ewa make-grid --help (the sample grids), vdb_ewa submit --help and vdb_ewa status --help (Slurm job "
                     "arrays, docs/farm.md), vdb_ewa --version.");
        mApp->add_option("input", mInput, "input .vdb file")->required();
        mApp->add_option("output", mOutput,
            "output image, its format by its extension: .exr (premultiplied RGBA and Z in --output-space), .png, .jpg, "
            ".tif or .ppm (8-bit RGB: the beauty over black through --display and --view) or .hdr (float RGB over black "
            "in --output-space) (docs/output.md)")->required();
        mOptions.add(mApp);
        // Batch jobs.
        mApp->add_option("--frames", mFrames,
            "render a sequence: frames N, A-B, A-BxS (every S), comma-separated (1-10,20); IN and OUT (and "
            "--preview) hold a frame pattern, #### (padded to the number of #) or %04d; IN may have none where --camera-file "
            "moves the camera (a turntable): the frames then render from one scene, the grid read once and its light kept "
            "(default: one frame)");
        mApp->add_flag("--skip-existing", mSkipExisting,
            "skip frames whose output (and --preview, if given) exist (outputs are written whole or not at all, so a killed job resumes)");
        mApp->add_option("--skip-newer-than", mSkipNewerThan,
            "skip frames whose output (and --preview) were written at or after this time, in seconds since 1970 (UTC): a farm "
            "task that was requeued does not redo the frames it wrote, yet older outputs are rendered again (default: none; "
            "docs/farm.md)")
            ->check(CLI::NonNegativeNumber);
        CLI::Option* chunk = mApp->add_option("--chunk", mChunk,
            "farm array tasks: render only this task's chunk of N frames of --frames, frames [I*N, (I+1)*N) for task I "
            "(--task, or $SLURM_ARRAY_TASK_ID), in [1, 1000000] (default: every frame; docs/farm.md)")
            ->check(CLI::Range(1, 1000000));
        mApp->add_option("--task", mTask,
            "with --chunk: the task's index I, from 0 (default: $SLURM_ARRAY_TASK_ID)")
            ->check(CLI::Range(0, 1000000))
            ->needs(chunk);
        mApp->add_option("--job", mJob,
            "JSON job file of option: value pairs (long option names, plus input and output); options on the "
            "command line override it, unknown keys are an error (docs/batch.md)");
        mApp->add_flag("-v,--verbose", mVerbose,
            "-v: also print the resolved settings, counts, stage timings and the peak memory; -vv: for every frame (default: "
            "progress, warnings and one line per frame)");
        mApp->add_flag("-q,--quiet", mQuiet, "print errors only");
    }

    CLI::App* subcommand() const override { return mApp; }

    void validate() const override
    {
        CameraSettings cam;
        RenderSettings rs;
        mOptions.resolve(firstFrame(), cam, rs);
        const Renderer renderer(rs); // validates the render settings
    }

    /// The parsed command line's frames (all of them: --chunk does not apply) and files.
    RenderJob job() const
    {
        validate();
        RenderJob job;
        job.frames = isSequence() ? parseFrameList(mFrames) : std::vector<int>{0};
        job.sequence = isSequence();
        job.input = mInput;
        job.output = mOutput;
        job.preview = mOptions.output().previewOption();
        job.skipExisting = mSkipExisting;
        return job;
    }

    int run() override
    {
        const Verbosity verbosity = mQuiet ? Verbosity::Quiet
            : mVerbose >= 2                ? Verbosity::Debug
            : mVerbose == 1                ? Verbosity::Verbose
                                           : Verbosity::Normal;
        CameraSettings cam;
        RenderSettings rs;
        mOptions.resolve(firstFrame(), cam, rs);
        const std::string grants = mOptions.grantedText();
        const Renderer validated(rs); // the render settings are checked before any file is read
        const std::vector<int> frames = frameList();
        if (verbosity != Verbosity::Quiet && (mChunk || !grants.empty())) {
            std::cout << "vdb_ewa: " << (mChunk ? "task " + std::to_string(taskIndex()) + ": frames " + frameListText(frames) + (grants.empty() ? "" : "; ") : "")
                      << grants << "\n";
        }
        std::vector<std::string> warnings;
        // The colour values as given (printed by -v, kept in the EXR) and in the working space.
        const RenderSettings working = mOptions.prepare(pathOf(mOutput, frames.front()),
            pathOf(mOptions.output().previewOption(), frames.front()), rs, warnings);
        const Renderer renderer(working);
        if (verbosity != Verbosity::Quiet) {
            for (const std::string& w : warnings) std::cerr << "vdb_ewa: warning: " << w << "\n";
        }
        setExrThreadsProcessWide(rs.threads);

        // One grid for every frame (a turntable): the frames render from one scene, which reads it
        // once and keeps what the frames share (vdb_ewa::Scene).
        std::unique_ptr<Scene> scene;
        std::unique_ptr<Scene>* oneGrid = isSequence() && !hasFramePattern(mInput) ? &scene : nullptr;
        ProgressReport report(int(frames.size()), verbosity);
        installStopHandlers(report);
        std::vector<int> failed;
        int failCode = kExitOk, written = 0, skipped = 0;
        for (std::size_t i = 0; i < frames.size(); ++i) {
            report.beginFrame(int(i));
            // In flight from here, so a stop between two frames reports the one that did not start.
            if (isSequence()) report.frameInFlight(frames[i]);
            if (stopRequested()) break;
            const std::string output = pathOf(mOutput, frames[i]);
            // A frame is done when all its files are: an EXR without its --preview is rendered again.
            const std::string preview = pathOf(mOptions.output().previewOption(), frames[i]);
            const char* skip = mSkipExisting && outputsExist(output, preview) ? " exists"
                : mSkipNewerThan && outputsWrittenSince(output, preview, *mSkipNewerThan) ? " was written after --skip-newer-than"
                : nullptr;
            if (skip) {
                report.frameEnded();
                ++skipped;
                if (verbosity != Verbosity::Quiet) report.line(frameLogLine(frames[i], FrameEntry::Skipped, output + skip));
                continue;
            }
            try {
                renderOneFrame(renderer, mOptions.cameraFile().empty() ? cam : mOptions.cameraFor(frameOf(frames[i])), rs, frames[i], output, report,
                    verbosity, i == 0, oneGrid);
                report.framesWritten(++written);
                stallForTests("between-frames", stopRequested);
            } catch (const Cancelled&) {
                break;
            } catch (const std::exception& e) {
                report.frameEnded();
                if (!isSequence()) throw;
                report.line(frameLogLine(frames[i], FrameEntry::Failed, e.what(), exitCodeFor(e)), stderr);
                failed.push_back(frames[i]);
                if (failCode == kExitOk) failCode = exitCodeFor(e);
            }
        }
        if (stopRequested() || report.cancelled()) report.reportInterruptedFrame();
        report.finishJob();
        if (stopRequested() || report.cancelled()) {
            std::cerr << "vdb_ewa: interrupted: " << written << " of " << counted(std::int64_t(frames.size()), "frame") << " written\n";
            return kExitInterrupted;
        }
        if (!failed.empty()) {
            std::ostringstream list;
            for (std::size_t i = 0; i < failed.size(); ++i) list << (i ? ", " : "") << failed[i];
            std::cerr << "vdb_ewa: " << failed.size() << " of " << counted(std::int64_t(frames.size()), "frame") << " failed: " << list.str() << "\n";
            return failCode;
        }
        if (isSequence() && verbosity != Verbosity::Quiet) {
            std::cout << "vdb_ewa: " << counted(written, "frame") << " written, " << skipped << " skipped (--skip-existing)\n";
        }
        return kExitOk;
    }

private:
    static double seconds(std::chrono::steady_clock::time_point since)
    {
        return std::chrono::duration<double>(std::chrono::steady_clock::now() - since).count();
    }

    bool isSequence() const { return !mFrames.empty(); }

    /// --frames, checked against the paths' frame patterns; {0} (unused) without --frames.
    std::vector<int> frameList() const
    {
        if (!isSequence()) {
            if (hasFramePattern(mInput)) throw ValueError(mInput + ": a frame pattern (#### or %04d) needs --frames");
            if (mChunk) throw ValueError("--chunk: a task's chunk of --frames: give --frames");
            return {0};
        }
        const std::vector<int> frames = parseFrameList(mFrames);
        if (!hasFramePattern(mInput) && mOptions.cameraFile().empty()) {
            throw ValueError("--frames: the input " + mInput + " has no frame pattern (#### or %04d) and no --camera-file moves the camera: "
                             "every frame would be the same");
        }
        for (const std::string& out : {mOutput, mOptions.output().previewOption()}) {
            if (!out.empty() && frames.size() > 1 && !hasFramePattern(out)) { // every task's frames, not only this one's
                throw ValueError("--frames: " + out + " has no frame pattern (#### or %04d): every frame would overwrite it");
            }
        }
        return mChunk ? frameChunk(frames, *mChunk, taskIndex()) : frames;
    }

    /// --task, else $SLURM_ARRAY_TASK_ID (with --chunk).
    int taskIndex() const
    {
        if (mTask) return *mTask;
        const char* id = std::getenv("SLURM_ARRAY_TASK_ID");
        if (!id) throw ValueError("--chunk: no task index: give --task or run inside a Slurm array task (SLURM_ARRAY_TASK_ID)");
        char* end = nullptr;
        const long task = std::strtol(id, &end, 10);
        if (end == id || *end || task < 0 || task > 1000000) throw ValueError(std::string("--chunk: SLURM_ARRAY_TASK_ID '") + id + "' is not a task index");
        return int(task);
    }

    /// @a frame as RenderOptions takes it: none outside a sequence.
    std::optional<int> frameOf(int frame) const { return isSequence() ? std::optional<int>(frame) : std::nullopt; }
    /// The first frame (frameList's checks first).
    std::optional<int> firstFrame() const { return frameOf(frameList().front()); }

    /// @a path for @a frame (as it is without --frames).
    std::string pathOf(const std::string& path, int frame) const { return isSequence() ? framePath(path, frame) : path; }

    /// Load, render and write one frame. @a first: print the settings (-v). @a scene: where every
    /// frame renders the same grid, the scene they render from (made at the first frame rendered).
    void renderOneFrame(const Renderer& renderer, const CameraSettings& cam, const RenderSettings& rs, int frameNumber,
        const std::string& output, ProgressReport& report, Verbosity verbosity, bool first, std::unique_ptr<Scene>* scene) const
    {
        const std::string input = pathOf(mInput, frameNumber);
        const std::string preview = pathOf(mOptions.output().previewOption(), frameNumber);
        std::vector<std::string> inputs{input, mJob, mOptions.environment()};
        for (const std::string& file : mOptions.addedVolumeFiles()) inputs.push_back(file);
        mOptions.output().refuseInputs(output, preview, inputs);
        const auto t0 = std::chrono::steady_clock::now();
        resetPeakMemory(); // each frame reports its own peak
        stallForTests("read");
        const GridSource grid = scene && *scene ? (*scene)->grid() : mOptions.open(input);
        if (scene && !*scene) *scene = std::make_unique<Scene>(grid, renderer.settings());
        const double loadSeconds = seconds(t0);
        const Camera camera(cam, grid.worldCentre());
        if (verbosity != Verbosity::Quiet) {
            for (const std::string& w : RenderOptions::cameraWarnings(camera)) report.line("vdb_ewa: warning: " + input + ": " + w, stderr);
        }
        const std::vector<Attributes> options = mOptions.resolvedOptions(grid, camera, rs);
        if (verbosity >= Verbosity::Verbose && (first || verbosity >= Verbosity::Debug)) {
            report.line(settingsText(grid, input, options));
            const std::string working = workingColoursText(rs, renderer.settings());
            if (!working.empty()) report.line(working);
        }

        RenderStats stats;
        Frame frame = scene ? (*scene)->render(camera, mOptions.output().passes(), &stats, &report)
                            : renderer.renderFrame(grid, camera, mOptions.output().passes(), &stats, &report);
        if (verbosity != Verbosity::Quiet) {
            for (const std::string& w : stats.warnings) report.line("vdb_ewa: warning: " + input + ": " + w, stderr);
        }
        const auto t1 = std::chrono::steady_clock::now();
        const Attributes attributes = mOptions.headerAttributes(grid, camera, rs, input, seconds(t0), frameOf(frameNumber), stats);
        try {
            mOptions.output().write(frame, camera, output, preview, attributes);
        } catch (const IoError& e) {
            throw std::runtime_error(e.what()); // a failed write is a render failure (exit 4), not bad input
        }
        if (verbosity >= Verbosity::Verbose) report.line(statsText(stats, loadSeconds, seconds(t1)));
        if (isSequence() && verbosity >= Verbosity::Normal) {
            std::ostringstream line;
            line << frameLogLine(frameNumber, FrameEntry::Done, output) << " (" << std::fixed << std::setprecision(2) << seconds(t0)
                 << " s, peak " << std::setprecision(0) << peakMegabytes() << " MB)";
            report.line(line.str());
        }
    }

    /// The colour values the renderer uses, where --input-space changed them (-v); empty where
    /// it did not.
    static std::string workingColoursText(const RenderSettings& given, const RenderSettings& working)
    {
        const auto same = [](const Vec3d& a, const Vec3d& b) { return a.x == b.x && a.y == b.y && a.z == b.z; };
        bool lightsSame = true;
        for (std::size_t l = 0; l < given.lights.size(); ++l) lightsSame = lightsSame && same(given.lights[l].color, working.lights[l].color);
        if (same(given.medium.absorb, working.medium.absorb) && same(given.medium.scatter, working.medium.scatter) &&
            same(given.medium.emission, working.medium.emission) && lightsSame && same(given.ambient, working.ambient))
            return "";
        return "vdb_ewa: model in the working space: --absorb " + fmt3(working.medium.absorb) + " --scatter " + fmt3(working.medium.scatter) +
               " --emission " + fmt3(working.medium.emission) + " --light " + RenderOptions::lightsText(working.lights, " --light ") + " --ambient " +
               fmt3(working.ambient);
    }

    /// -v's settings of a frame: the grid, then one line per group of options.
    static std::string settingsText(const GridSource& grid, const std::string& input, const std::vector<Attributes>& groups)
    {
        std::ostringstream out;
        out << "vdb_ewa: grid '" << grid.name() << "' (" << grid.storedType() << ") from " << input << ": "
            << counted(std::int64_t(grid.activeVoxelCount()), "active voxel") << ", " << counted(std::int64_t(grid.activeTileCount()), "active tile")
            << ", " << (grid.isLinear() ? "affine" : "non-linear") << " transform";
        const char* titles[] = {"camera", "model", "splat", "output"};
        for (std::size_t g = 0; g < groups.size(); ++g) {
            out << "\nvdb_ewa: " << titles[g];
            for (const auto& [key, value] : groups[g]) {
                if (key == "light" || key == "point-light" || key == "spot-light" || key == "add-volume" || key == "add-volume-transform" ||
                    key == "add-volume-material") { // one option each (lightsText)
                    for (std::size_t at = 0, end; at != std::string::npos; at = end == std::string::npos ? end : end + 2) {
                        end = value.find("; ", at);
                        const std::string one = value.substr(at, end == std::string::npos ? end : end - at);
                        out << " --" << key << " " << (one.find(' ') != std::string::npos ? "\"" + one + "\"" : one);
                    }
                    continue;
                }
                const bool spaces = value.find(' ') != std::string::npos;
                out << " --" << key << " " << (spaces ? "\"" + value + "\"" : value);
            }
        }
        return out.str();
    }

    /// -v's counts and stage timings of a frame (two lines).
    static std::string statsText(const RenderStats& s, double loadSeconds, double writeSeconds)
    {
        std::ostringstream out;
        out << "vdb_ewa: " << s.activeVoxels << " active voxels and " << counted(s.activeTiles, "active tile") << " read; "
                  << s.kernels << " kernels (" << s.voxelsMerged << " voxels merged into " << s.mergedKernels
                  << " by --lod, " << (s.surfaceLattice > 1 ? "one surface kernel a " + std::to_string(s.surfaceLattice) + "^3 block by --lod, " : "")
                  << s.haloKernels << " halo kernels by --prefilter, " << s.refinedVoxels << " voxels sampled by --refine"
                  << (s.emitterKernels ? ", " + std::to_string(s.emitterKernels) + " of the emission grids" : "")
                  << (s.movingKernels ? ", " + std::to_string(s.movingKernels) + " moving over the shutter, " + std::to_string(s.motionSubKernels) +
                                            " sub-kernels added along their paths by motion blur" : "") << "), " << s.kernelsSkipped << " values skipped (below --cutoff or NaN), "
                  << s.kernelsCulled << " kernels culled, " << s.splats << " splatted into " << s.splatTilePairs
                  << " (splat, tile) pairs; " << s.screenTilesOpaque << " of " << s.screenTiles
                  << " screen tiles turned opaque early, skipping " << s.splatTilePairsSkipped << " pairs; "
                  << s.footprintSamples << " footprint samples" << levelSamples(s) << ", " << s.slabComposites << " slab composites" << levelComposites(s) << " (" << s.rasterBackend << " rasteriser)";
        if (s.streamed) {
            out << "; streamed front to back: " << counted(s.bricks, "brick") << " in " << counted(s.windows, "depth window") << ", "
                << s.bricksExpanded << " expanded, " << s.bricksHidden << " hidden behind opaque tiles, " << s.bricksOutside << " outside the frame, "
                << s.splatsInFlight << " splats in flight at most";
        }
        if (s.lightRays > 0 && (s.streamed || s.lightRaysMarched < s.lightRays)) {
            out << "; light on demand: " << s.lightRaysMarched << " of " << s.lightRays << " light-map rays marched";
            if (s.lightRaysReused > 0) out << " (and " << s.lightRaysReused << " kept from earlier frames)";
        }
        if (s.supersample > 1) {
            out << "; composited at " << s.supersample << "x" << s.supersample << " sub-pixels a pixel over " << s.supersampleWindow[2] << "x"
                << s.supersampleWindow[3] << " pixels from (" << s.supersampleWindow[0] << ", " << s.supersampleWindow[1]
                << ") by --supersample (the median voxel spans " << s.voxelPixels << " pixels)";
        }
        if (s.pixelSize > 1) {
            out << "; splatted at one sample a " << s.pixelSize << "x" << s.pixelSize << " block of pixels by --pixel-size (the median voxel in view spans "
                << s.voxelPixels << " pixels)";
        }
        out << "\n"
                  << std::fixed << std::setprecision(3) << "vdb_ewa: timings (s): load " << loadSeconds << ", kernels "
                  << s.kernelSeconds << ", shadows " << s.shadowSeconds << ", project " << s.projectSeconds
                  << ", rasterise " << s.rasterSeconds << ", write " << writeSeconds << "; peak memory ";
        const double peak = peakMegabytes();
        out << std::setprecision(0) << peak << " MB";
        if (s.activeVoxels > 0) out << " (" << std::setprecision(1) << peak * 1e6 / double(s.activeVoxels) << " bytes per active voxel)";
        return out.str();
    }

    CLI::App* mApp = nullptr;
    std::string mInput, mOutput;
    RenderOptions mOptions;
    int mVerbose = 0;
    bool mQuiet = false, mSkipExisting = false;
    std::optional<int> mChunk, mTask;
    std::optional<long long> mSkipNewerThan;
    std::string mFrames, mJob;
};

} // namespace

std::unique_ptr<Command> addRenderCommand(CLI::App& app) { return std::make_unique<RenderCommand>(app); }

std::string RenderJob::pathOf(const std::string& pattern, int frame) const
{
    return sequence && !pattern.empty() ? framePath(pattern, frame) : pattern;
}

bool RenderJob::done(int frame, const std::string& folder) const
{
    const auto in = [&](const std::string& path) {
        return folder.empty() || path.empty() || std::filesystem::path(path).is_absolute() ? path : (std::filesystem::path(folder) / path).string();
    };
    return outputsExist(in(pathOf(output, frame)), in(pathOf(preview, frame)));
}

RenderJob renderJobOf(const std::vector<std::string>& renderArguments)
{
    std::vector<std::string> args{"render"};
    args.insert(args.end(), renderArguments.begin(), renderArguments.end());
    CommandLine commandLine; // the CLI's own parse: one-dash spellings, --job
    return dynamic_cast<const RenderCommand&>(commandLine.parse(args)).job();
}

RenderJob renderJobOfFile(const std::string& jobFile, const std::string& frames)
{
    std::vector<std::string> args{"--job", jobFile};
    if (!frames.empty()) args.insert(args.end(), {"--frames", frames});
    return renderJobOf(args);
}

} // namespace vdb_ewa::cli
