/// @file output_options.h
/// @brief The render command's output stage: colour management (OCIO), EXR type and
///        compression, passes, deep output and the PNG preview (docs/output.md).
#pragma once

#include <vdb_ewa/vdb_ewa.h>

#include <CLI/CLI.hpp>

#include <optional>
#include <string>
#include <utility>
#include <vector>

namespace vdb_ewa::cli {

using Attributes = std::vector<std::pair<std::string, std::string>>;

class OutputOptions
{
public:
    /// Register --ocio-config, --working-space, --output-space, --display, --view, --preview,
    /// --exr-type, --compression, --aov and --deep on @a app.
    void add(CLI::App* app);

    /// Everything that can fail before rendering: the config (warnings for fallbacks), the
    /// colour spaces, display and view, the option words, the paths @a output and @a preview
    /// (the first frame's; empty: no preview).
    /// @throw ValueError or IoError naming the option or path.
    void prepare(const std::string& output, const std::string& preview, std::vector<std::string>& warnings);

    /// --preview as given (it may hold a frame pattern); empty without one.
    const std::string& previewOption() const { return mPreview; }

    /// The passes the EXR will hold.
    PassRequest passes() const { return mPasses; }

    /// The resolved options, as (option, value) pairs, for -v and the EXR's attributes.
    Attributes resolved() const;

    /// Refuse to write @a output or @a preview (empty: none) over any of @a inputs or the OCIO
    /// config: compared by device and inode, so a name through `./`, `..`, a symlink or a hard
    /// link is the same file. Paths that do not exist yet are no input.
    /// @throw ValueError naming the output and the input.
    void refuseInputs(const std::string& output, const std::string& preview, std::vector<std::string> inputs) const;

    /// Convert @a frame from the working to the output space and write the EXR (flat or deep),
    /// then the preview @a preview (empty: none). @a attributes are added to the EXR header.
    void write(Frame& frame, const Camera& camera, const std::string& output, const std::string& preview,
        const Attributes& attributes) const;

private:
    void writeExrInOutputSpace(Frame& frame, const Camera& camera, const std::string& output,
        const Attributes& attributes) const;

    std::string mConfigPath, mWorkingSpace, mOutputSpace, mDisplay, mView, mPreview, mExrType, mCompression, mAov;
    bool mDeep = false;

    std::optional<ColorConfig> mConfig;
    PassRequest mPasses;
    ExrOptions mExr;
};

} // namespace vdb_ewa::cli
