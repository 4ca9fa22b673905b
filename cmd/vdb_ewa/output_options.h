/// @file output_options.h
/// @brief The render command's output stage: the image format by the output's extension,
///        colour management (OCIO), EXR type and compression, passes, deep output and the PNG
///        preview (docs/output.md).
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
    /// Register --ocio-config, --input-space, --working-space, --output-space, --display,
    /// --view, --preview, --exr-type, --compression, --aov and --deep on @a app.
    void add(CLI::App* app);

    /// Everything that can fail before rendering: the config (warnings for fallbacks), the
    /// colour spaces, display and view, the option words, the paths @a output (empty: none,
    /// the frame is kept in memory as an EXR would hold it) and @a preview (the first frame's;
    /// empty: no preview).
    /// @throw ValueError or IoError naming the option or path.
    void prepare(const std::string& output, const std::string& preview, std::vector<std::string>& warnings);

    /// --preview as given (it may hold a frame pattern); empty without one.
    const std::string& previewOption() const { return mPreview; }

    /// Convert the colour values of @a rs (the --light colours, --ambient, --absorb, --scatter,
    /// --emission, --emission-color) from --input-space to the working space (after prepare), and
    /// set the blackbody's Rec.709 -> working-space matrix. A grey value the conversion
    /// leaves grey stays bit for bit what it was; components outside the working space's gamut
    /// (negative) become 0, with a line in @a warnings.
    void toWorkingSpace(RenderSettings& rs, std::vector<std::string>& warnings) const;
    /// True if the config has a linear Rec.709 space (after prepare): the blackbody's colours
    /// are brought from it.
    bool hasLinearRec709() const { return mRec709ToWorking.has_value(); }

    /// The passes the EXR will hold.
    PassRequest passes() const { return mPasses; }

    /// The resolved options, as (option, value) pairs, for -v and the EXR's attributes.
    Attributes resolved() const;

    /// Refuse to write @a output or @a preview (empty: none) over any of @a inputs or the OCIO
    /// config: compared by device and inode, so a name through `./`, `..`, a symlink or a hard
    /// link is the same file. Paths that do not exist yet are no input.
    /// @throw ValueError naming the output and the input.
    void refuseInputs(const std::string& output, const std::string& preview, std::vector<std::string> inputs) const;

    /// Convert @a frame (the beauty, the shadow and emission passes, deep samples) from the
    /// working space to --output-space in place, as an EXR holds it (after prepare).
    void toOutputSpace(Frame& frame) const;

    /// Write @a frame to @a output in its format: an EXR (flat or deep) or .hdr converted from
    /// the working to the output space, an 8-bit image through --display and --view; then the
    /// preview @a preview (empty: none). @a attributes are added to the file's metadata.
    void write(Frame& frame, const Camera& camera, const std::string& output, const std::string& preview,
        const Attributes& attributes) const;

private:
    void writeExrInOutputSpace(Frame& frame, const Camera& camera, const std::string& output,
        const Attributes& attributes) const;

    std::string mConfigPath, mInputSpace, mWorkingSpace, mOutputSpace, mDisplay, mView, mPreview, mExrType, mCompression, mAov;
    std::optional<int> mZipLevel;
    bool mDeep = false;
    ImageFormat mFormat = ImageFormat::Exr; ///< the output's, by its extension
    std::string mDisplaySpace;              ///< what --display and --view encode to (8-bit outputs, --preview)

    std::optional<ColorConfig> mConfig;
    std::optional<ColorTransform> mInputToWorking;
    std::optional<ColorTransform> mRec709ToWorking; ///< null where the config has no linear Rec.709
    PassRequest mPasses;
    ExrOptions mExr;
};

} // namespace vdb_ewa::cli
