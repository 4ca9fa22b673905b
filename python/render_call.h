/// @file render_call.h
/// @brief vdb_ewa.render() in C++: keyword arguments parsed as the CLI parses its command line
///        (cli::RenderOptions, the same names, defaults and messages), the render on a worker
///        thread with the GIL released, progress and cancellation served on the caller's thread,
///        and the frame it returns (arrays in --output-space, as the EXR holds them; write()).
#pragma once

#include "render_options.h"

#include <vdb_ewa/vdb_ewa.h>

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include <atomic>
#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace vdb_ewa::python {

/// One option of vdb_ewa render as a keyword argument (docstrings and the .pyi stub).
struct KeywordInfo
{
    std::string keyword;     ///< the long option name, - spelled _ ("refine_emission")
    std::string option;      ///< "--refine-emission"
    std::string type;        ///< "bool" (a flag), "int", "float" or "str"
    std::string description; ///< --help's text, with its default
};

/// Every keyword render() takes besides grid, progress and cancel, in --help's order.
std::vector<KeywordInfo> renderKeywords();

struct ParsedOptions;

/// A cancellation flag another Python thread may set while render() runs.
struct CancelToken
{
    std::atomic<bool> cancelled{false};
};

/// A rendered frame: the beauty and passes in --output-space (what the EXR would hold, as
/// float), the working-space frame and the options for write().
struct RenderedFrame
{
    RenderedFrame(const GridSource& grid, const Camera& camera) : grid(grid), camera(camera) {}

    Frame output;                       ///< in --output-space
    Frame working;                      ///< in the working space, for write()
    std::vector<std::string> arguments; ///< the keyword arguments as command-line arguments
    std::shared_ptr<const ParsedOptions> options; ///< as render() resolved and prepared them
    GridSource grid;
    std::string input; ///< the grid's file, empty for an array
    Camera camera;
    RenderSettings given;  ///< colours as given (--input-space), for the header
    double seconds = 0;
    RenderStats stats;
    std::vector<std::string> warnings;

    /// Write the frame to @a path as vdb_ewa render would (the format by its extension, the
    /// EXR type, compression, passes, --preview and the header of the options rendered with).
    /// @throw IoError, ValueError as the CLI.
    void write(const std::string& path) const;
    /// The EXR header's attributes (vdb_ewa/NAME: every resolved option, the camera record).
    cli::Attributes metadata() const;

private:
    /// The render's options parsed again and prepared for @a path.
    std::unique_ptr<ParsedOptions> prepared(const std::string& path) const;
};

/// Render @a grid (a GridSource, or a path opened with the name, color, emission_grid and
/// temperature keywords) with @a kwargs. @a progress: a callable taking the percent, called on
/// this thread (return True to cancel); @a cancel: a CancelToken or None.
/// @throw vdb_ewa::Error as the CLI (translated to Python by the module); Cancelled.
std::shared_ptr<RenderedFrame> render(const pybind11::object& grid, const pybind11::object& progress,
    const std::shared_ptr<CancelToken>& cancel, const pybind11::kwargs& kwargs);

/// vdb_ewa.Scene: a grid opened once (with the grid keywords given when it is made) and the
/// keywords every render starts from; each render's keywords override them for that render.
/// What the renders can share they share (vdb_ewa::Scene).
struct SceneCall
{
    /// @throw vdb_ewa::Error as render().
    SceneCall(const pybind11::object& grid, const pybind11::kwargs& kwargs);
    /// As render(), with the scene's keywords updated by @a kwargs (not the grid keywords: those
    /// are the scene's). @a progressive: None, or a callable taking each Frame of a progressive
    /// render on this thread, the coarse one first (True cancels the rest), then the one returned.
    std::shared_ptr<RenderedFrame> render(const pybind11::object& progress, const std::shared_ptr<CancelToken>& cancel,
        const pybind11::object& progressive, const pybind11::kwargs& kwargs);

    bool isPath;
    bool attachedVelocity;    ///< the Grid given had a velocity grid (Grid.with_velocity_grid)
    pybind11::dict options;   ///< the keywords it was made with
    std::optional<GridSource> grid;
    std::string input;        ///< the grid's file, empty for an array
    std::unique_ptr<Scene> scene;
};

} // namespace vdb_ewa::python
