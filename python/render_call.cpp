/// @file render_call.cpp
#include "render_call.h"

#include "error_messages.h"
#include "job_file.h"

#include <nlohmann/json.hpp>

#include <chrono>
#include <condition_variable>
#include <deque>
#include <exception>
#include <functional>
#include <map>
#include <mutex>
#include <thread>

namespace py = pybind11;

namespace vdb_ewa::python {

/// The options of one render on their own CLI11 app (pinned: the app holds pointers into them).
struct ParsedOptions
{
    CLI::App app{"vdb_ewa.render", "vdb_ewa.render"};
    cli::RenderOptions options;

    ParsedOptions()
    {
        app.set_help_flag(); // no --help keyword
        options.add(&app);
    }

    /// Parse @a arguments (command-line words). @throw ValueError in the CLI's words.
    void parse(std::vector<std::string> arguments)
    {
        std::reverse(arguments.begin(), arguments.end()); // CLI11 takes a reversed vector
        try {
            app.parse(arguments);
        } catch (const CLI::ParseError& e) {
            throw ValueError(cli::inOurWords(e));
        }
    }
};

namespace {

std::string keywordOf(const std::string& longName)
{
    std::string k = longName;
    std::replace(k.begin(), k.end(), '-', '_');
    return k;
}

/// A Python value as a job file's JSON value (cli::optionArguments' rules).
nlohmann::json toJson(const py::handle& value, const std::string& where)
{
    if (py::isinstance<py::bool_>(value)) return value.cast<bool>();
    if (py::isinstance<py::int_>(value)) return value.cast<long long>();
    if (py::isinstance<py::float_>(value)) return value.cast<double>();
    if (py::isinstance<py::str>(value)) return value.cast<std::string>();
    if (py::hasattr(value, "__fspath__")) return py::module_::import("os").attr("fspath")(value).cast<std::string>();
    if (py::isinstance<py::array>(value)) return toJson(value.attr("tolist")(), where);
    if (py::hasattr(value, "item") && py::hasattr(value, "dtype")) return toJson(value.attr("item")(), where); // numpy scalars
    if (py::isinstance<py::sequence>(value)) {
        nlohmann::json list = nlohmann::json::array();
        for (const py::handle item : value) list.push_back(toJson(item, where));
        return list;
    }
    throw ValueError(where + ": expected a string, number, True/False or a sequence of numbers, got " +
                     std::string(py::str(value.get_type().attr("__name__"))));
}

/// @a kwargs as vdb_ewa render's command-line arguments.
std::vector<std::string> argumentsOf(const py::kwargs& kwargs, bool gridIsPath)
{
    std::map<std::string, std::pair<std::string, bool>> byKeyword; // keyword -> (long name, flag)
    for (const KeywordInfo& k : renderKeywords()) byKeyword[k.keyword] = {k.option.substr(2), k.type == "bool"};
    std::vector<std::string> arguments;
    for (const auto& [key, value] : kwargs) {
        const std::string keyword = key.cast<std::string>();
        const auto it = byKeyword.find(keyword);
        if (it == byKeyword.end()) {
            throw ValueError("unknown keyword argument '" + keyword + "' (vdb_ewa render's long options, - spelled _: help(vdb_ewa.render))");
        }
        if (value.is_none()) continue; // None: the default
        if (!gridIsPath && (it->second.first == "name" || it->second.first == "density-grid")) {
            throw ValueError(keyword + ": the grid is already open; name it in vdb_ewa.open(path, name)");
        }
        const std::vector<std::string> words =
            cli::optionArguments(it->second.first, toJson(value, keyword), it->second.second, keyword);
        arguments.insert(arguments.end(), words.begin(), words.end());
    }
    return arguments;
}

/// Progress from the render's worker threads to the caller's thread; cancellation back.
class CallInterrupter : public Interrupter
{
public:
    explicit CallInterrupter(std::shared_ptr<CancelToken> token) : mToken(std::move(token)) {}

    bool wasInterrupted(int percent) override
    {
        {
            const std::lock_guard<std::mutex> lock(mMutex);
            mPercent = percent;
        }
        mChanged.notify_all();
        return mToken && mToken->cancelled.load(std::memory_order_relaxed);
    }

    /// The render finished (or failed): wake the caller.
    void finish(std::exception_ptr error)
    {
        {
            const std::lock_guard<std::mutex> lock(mMutex);
            mDone = true;
            mError = std::move(error);
        }
        mChanged.notify_all();
    }

    /// A progressive render's coarse image, from the worker: the caller's thread takes it.
    void post(const Frame& frame, const RenderStats& stats)
    {
        {
            const std::lock_guard<std::mutex> lock(mMutex);
            mImages.push_back({frame, stats});
        }
        mChanged.notify_all();
    }

    /// The oldest image posted and not yet taken, if any, into @a image.
    bool take(std::pair<Frame, RenderStats>& image)
    {
        const std::lock_guard<std::mutex> lock(mMutex);
        if (mImages.empty()) return false;
        image = std::move(mImages.front());
        mImages.pop_front();
        return true;
    }

    /// Wait (without the GIL) up to @a timeout for news; @return the percent, and whether it is done.
    std::pair<int, bool> wait(int reported, std::chrono::milliseconds timeout)
    {
        py::gil_scoped_release release;
        std::unique_lock<std::mutex> lock(mMutex);
        mChanged.wait_for(lock, timeout, [&] { return mDone || mPercent != reported || !mImages.empty(); });
        return {mPercent, mDone};
    }

    std::exception_ptr error() const
    {
        const std::lock_guard<std::mutex> lock(mMutex);
        return mError;
    }

private:
    std::shared_ptr<CancelToken> mToken;
    mutable std::mutex mMutex;
    std::condition_variable mChanged;
    int mPercent = -1;
    bool mDone = false;
    std::exception_ptr mError;
    std::deque<std::pair<Frame, RenderStats>> mImages; ///< posted, not yet taken
};

/// Joins the render's thread whatever happens on the caller's (cancelling it first if the
/// caller is leaving early), without the GIL: the thread that would cancel may need it.
class WorkerGuard
{
public:
    WorkerGuard(std::thread& thread, CallInterrupter& interrupter) : mThread(thread), mInterrupter(interrupter) {}
    ~WorkerGuard()
    {
        if (!mThread.joinable()) return;
        mInterrupter.cancel();
        py::gil_scoped_release release;
        mThread.join();
    }
    void join()
    {
        py::gil_scoped_release release;
        mThread.join();
    }

private:
    std::thread& mThread;
    CallInterrupter& mInterrupter;
};

/// A progressive render's coarse image, handed to the caller's thread; true cancels the render.
using CoarseImage = std::function<bool(Frame&& frame, RenderStats&& stats)>;

/// Run @a renderFrame (a Renderer's or a Scene's) on a worker thread; serve @a progress,
/// Python's signals (Ctrl+C) and the coarse images it posts (@a coarse) here.
Frame renderOnWorker(const std::function<Frame(CallInterrupter&)>& renderFrame, const py::object& progress,
    const std::shared_ptr<CancelToken>& cancel, const CoarseImage& coarse)
{
    CallInterrupter interrupter(cancel);
    Frame frame;
    std::thread thread([&] {
        try {
            frame = renderFrame(interrupter);
            interrupter.finish(nullptr);
        } catch (...) {
            interrupter.finish(std::current_exception());
        }
    });
    WorkerGuard guard(thread, interrupter);
    int reported = -1;
    for (bool done = false; !done;) {
        int percent = 0;
        std::tie(percent, done) = interrupter.wait(reported, std::chrono::milliseconds(50));
        if (PyErr_CheckSignals() != 0) throw py::error_already_set(); // the guard cancels and joins
        if (cancel && cancel->cancelled.load(std::memory_order_relaxed)) interrupter.cancel(); // seen at the render's next check
        for (std::pair<Frame, RenderStats> image; interrupter.take(image);) {
            if (coarse(std::move(image.first), std::move(image.second))) interrupter.cancel(); // an exception: the guard cancels
        }
        if (done && !interrupter.error()) percent = 100;
        if (percent == reported) continue; // the 50 ms passed with no news
        reported = percent; // also without a callback, or the wait would return at once from now on
        if (!progress.is_none() && percent >= 0 && py::bool_(progress(percent))) interrupter.cancel(); // an exception: the guard cancels
    }
    guard.join();
    if (const std::exception_ptr error = interrupter.error()) std::rethrow_exception(error);
    return frame;
}

} // namespace

std::vector<KeywordInfo> renderKeywords()
{
    ParsedOptions names;
    std::vector<KeywordInfo> keywords;
    for (const CLI::Option* opt : names.app.get_options()) {
        if (opt->get_lnames().empty()) continue;
        const std::string type = opt->get_expected_min() == 0 ? "bool"
            : opt->get_type_name() == "INT"                   ? "int"
            : opt->get_type_name() == "FLOAT"                 ? "float"
                                                              : "str";
        for (const std::string& n : opt->get_lnames()) keywords.push_back({keywordOf(n), "--" + n, type, opt->get_description()});
    }
    return keywords;
}

std::unique_ptr<ParsedOptions> RenderedFrame::prepared(const std::string& path) const
{
    // The options again, prepared for @a path (its format, the preview, display and view) as the CLI prepares them.
    auto parsed = std::make_unique<ParsedOptions>();
    parsed->parse(arguments);
    CameraSettings cam;
    RenderSettings rs;
    parsed->options.resolve(std::nullopt, cam, rs);
    std::vector<std::string> ignored; // render() reported them
    parsed->options.prepare(path, parsed->options.output().previewOption(), rs, ignored);
    return parsed;
}

cli::Attributes RenderedFrame::metadata() const
{
    return options->options.headerAttributes(grid, camera, given, input, seconds, std::nullopt, stats);
}

void RenderedFrame::write(const std::string& path) const
{
    const std::unique_ptr<ParsedOptions> parsed = prepared(path);
    const cli::RenderOptions& options = parsed->options;
    const std::string& preview = options.output().previewOption();
    std::vector<std::string> inputs{input, options.environment(), options.cameraFile()};
    for (const std::string& file : options.addedVolumeFiles()) inputs.push_back(file);
    options.output().refuseInputs(path, preview, inputs);
    Frame copy = working; // write() converts in place
    options.output().write(copy, camera, path, preview, options.headerAttributes(grid, camera, given, input, seconds, std::nullopt, stats));
}

namespace {

/// A call's keyword arguments parsed, checked and prepared, before any grid is read.
struct PreparedCall
{
    std::vector<std::string> arguments;
    std::shared_ptr<ParsedOptions> options = std::make_shared<ParsedOptions>();
    CameraSettings camera;
    RenderSettings given, working;
    std::vector<std::string> warnings;
};

PreparedCall prepareCall(const py::kwargs& kwargs, bool gridIsPath, bool attachedVelocity)
{
    PreparedCall call;
    call.arguments = argumentsOf(kwargs, gridIsPath);
    ParsedOptions& parsed = *call.options;
    parsed.parse(call.arguments);
    parsed.options.resolve(std::nullopt, call.camera, call.given);
    const Renderer validated(call.given); // the settings are checked before any file is read
    call.working = parsed.options.prepare("", "", call.given, call.warnings, attachedVelocity);
    return call;
}

bool isPathLike(const py::object& gridOrPath)
{
    const bool isPath = py::isinstance<py::str>(gridOrPath) || py::hasattr(gridOrPath, "__fspath__");
    if (!isPath && !py::isinstance<GridSource>(gridOrPath)) throw ValueError("grid: expected a vdb_ewa.Grid or the path of a .vdb file");
    return isPath;
}

/// The grid a call renders: the file opened with the name and grid keywords, or the Grid given
/// with the colour, emission, temperature and velocity grids the keywords add. @a input: its file.
GridSource openGrid(const py::object& gridOrPath, bool isPath, const PreparedCall& call, const py::kwargs& kwargs, std::string& input)
{
    if (isPath) {
        input = py::module_::import("os").attr("fspath")(gridOrPath).cast<std::string>();
        py::gil_scoped_release release;
        return call.options->options.open(input);
    }
    const GridSource& opened = gridOrPath.cast<const GridSource&>();
    input = opened.path();
    for (const char* keyword : {"color", "emission_grid", "temperature", "velocity_grid"}) {
        if (opened.path().empty() && kwargs.contains(keyword) && !kwargs[keyword].is_none()) {
            throw ValueError(std::string(keyword) + ": the grid came from an array, with no file to read grids from (from_array takes "
                             "emission=, temperature= and velocity= arrays)");
        }
    }
    py::gil_scoped_release release; // reads and resamples the colour and emission grids
    return call.options->options.withExtraGrids(opened);
}

bool attachedVelocityOf(const py::object& gridOrPath, bool isPath)
{
    return !isPath && gridOrPath.cast<const GridSource&>().hasVelocityGrid(); // Grid.with_velocity_grid
}

/// How a call renders its frame on the worker: the camera, the passes, the stats to fill, the
/// interrupter, and where a progressive render's images go (Scene::render).
using FrameRender = std::function<Frame(const Camera&, const PassRequest&, RenderStats&, Interrupter&, const ProgressiveCallback&)>;

/// Render @a grid as @a call asks, through @a renderFrame on a worker thread: the frame with its
/// options, stats and warnings, in the output space. @a progressive: None, or a callable
/// called here with each image of a progressive render, coarse first (True cancels the rest),
/// then the frame returned.
std::shared_ptr<RenderedFrame> finishCall(PreparedCall&& call, const GridSource& grid, const std::string& input,
    const std::chrono::steady_clock::time_point& t0, const py::object& progress, const std::shared_ptr<CancelToken>& cancel,
    const py::object& progressive, const FrameRender& renderFrame)
{
    const Camera camera(call.camera, grid.worldCentre());
    const std::string what = input.empty() ? grid.name() : input;
    std::vector<std::string> warnings = std::move(call.warnings);
    for (const std::string& w : cli::RenderOptions::cameraWarnings(camera)) warnings.push_back(what + ": " + w);

    // A frame rendered with the call's options: the working frame, its stats and warnings, the output.
    const auto frameOf = [&](Frame&& working, RenderStats&& stats) {
        auto result = std::make_shared<RenderedFrame>(grid, camera);
        result->arguments = call.arguments;
        result->options = call.options;
        result->input = input;
        result->given = call.given;
        result->working = std::move(working);
        result->stats = std::move(stats);
        result->warnings = warnings;
        for (const std::string& w : result->stats.warnings) result->warnings.push_back(what + ": " + w);
        result->output = result->working;
        call.options->options.output().toOutputSpace(result->output);
        result->seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
        return result;
    };
    const auto handOver = [&](const std::shared_ptr<RenderedFrame>& frame) {
        return !progressive.is_none() && py::bool_(progressive(frame));
    };
    const PassRequest passes = call.options->options.output().passes();
    RenderStats stats;
    bool coarseCancelled = false; // the coarse frame's callback answered True
    Frame working = renderOnWorker(
        [&](CallInterrupter& interrupter) {
            // The coarse image goes to this thread; the last, the one returned, is handed over below.
            const ProgressiveCallback post = [&](const Frame& f, const RenderStats& s) {
                if (s.coarseScale > 1) interrupter.post(f, s);
            };
            return renderFrame(camera, passes, stats, interrupter, progressive.is_none() ? ProgressiveCallback{} : post);
        },
        progress, cancel, [&](Frame&& f, RenderStats&& s) { return coarseCancelled = handOver(frameOf(std::move(f), std::move(s))); });
    // The asked image may be done before this thread hands over the coarse one (a small frame):
    // a True for the coarse frame cancels all the same.
    if (coarseCancelled) throw Cancelled();
    std::shared_ptr<RenderedFrame> result = frameOf(std::move(working), std::move(stats));
    handOver(result); // the render is done: what it answers no longer matters
    return result;
}

} // namespace

std::shared_ptr<RenderedFrame> render(const py::object& gridOrPath, const py::object& progress,
    const std::shared_ptr<CancelToken>& cancel, const py::kwargs& kwargs)
{
    const auto t0 = std::chrono::steady_clock::now();
    const bool isPath = isPathLike(gridOrPath);
    if (!progress.is_none() && !PyCallable_Check(progress.ptr())) throw ValueError("progress: expected a callable taking the percent");
    PreparedCall call = prepareCall(kwargs, isPath, attachedVelocityOf(gridOrPath, isPath));
    std::string input;
    const GridSource grid = openGrid(gridOrPath, isPath, call, kwargs, input);
    const Renderer renderer(call.working);
    return finishCall(std::move(call), grid, input, t0, progress, cancel, py::none(),
        [&](const Camera& camera, const PassRequest& passes, RenderStats& stats, Interrupter& interrupter, const ProgressiveCallback&) {
            return renderer.renderFrame(grid, camera, passes, &stats, &interrupter);
        });
}

SceneCall::SceneCall(const py::object& gridOrPath, const py::kwargs& kwargs)
    : isPath(isPathLike(gridOrPath)), attachedVelocity(attachedVelocityOf(gridOrPath, isPath)), options(kwargs)
{
    PreparedCall call = prepareCall(kwargs, isPath, attachedVelocity);
    grid.emplace(openGrid(gridOrPath, isPath, call, kwargs, input));
    scene = std::make_unique<Scene>(*grid, call.working);
}

std::shared_ptr<RenderedFrame> SceneCall::render(const py::object& progress, const std::shared_ptr<CancelToken>& cancel,
    const py::object& progressive, const py::kwargs& kwargs)
{
    const auto t0 = std::chrono::steady_clock::now();
    if (!progress.is_none() && !PyCallable_Check(progress.ptr())) throw ValueError("progress: expected a callable taking the percent");
    if (!progressive.is_none() && !PyCallable_Check(progressive.ptr())) throw ValueError("progressive: expected a callable taking a Frame");
    for (const char* keyword : {"name", "density_grid", "color", "emission_grid", "temperature", "velocity_grid"}) {
        if (kwargs.contains(keyword)) {
            throw ValueError(std::string(keyword) + ": a Scene's grids are given when it is made (vdb_ewa.Scene(grid, " + keyword + "=...))");
        }
    }
    py::kwargs merged;
    for (const auto& [key, value] : options) merged[key] = value;
    for (const auto& [key, value] : kwargs) merged[key] = value;
    PreparedCall call = prepareCall(merged, isPath, attachedVelocity);
    const RenderSettings settings = call.working;
    return finishCall(std::move(call), *grid, input, t0, progress, cancel, progressive,
        [&](const Camera& camera, const PassRequest& passes, RenderStats& stats, Interrupter& interrupter, const ProgressiveCallback& images) {
            if (!images) return scene->render(camera, settings, passes, &stats, &interrupter);
            return scene->render(camera, settings, images, passes, &stats, &interrupter);
        });
}

} // namespace vdb_ewa::python
