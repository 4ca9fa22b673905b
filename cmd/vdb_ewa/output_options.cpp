/// @file output_options.cpp
#include "output_options.h"

#include "option_values.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <sstream>

namespace vdb_ewa::cli {
namespace {

const Choices<ExrPixelType> kExrTypes = {{"half", ExrPixelType::Half}, {"float", ExrPixelType::Float}};
const Choices<ExrCompression> kCompressions = {{"none", ExrCompression::None}, {"rle", ExrCompression::Rle},
    {"zip", ExrCompression::Zip}, {"zips", ExrCompression::Zips}, {"piz", ExrCompression::Piz},
    {"dwaa", ExrCompression::Dwaa}, {"dwab", ExrCompression::Dwab}};

bool endsWith(std::string text, const std::string& suffix)
{
    std::transform(text.begin(), text.end(), text.begin(), [](unsigned char c) { return char(std::tolower(c)); });
    return text.size() >= suffix.size() && text.compare(text.size() - suffix.size(), suffix.size(), suffix) == 0;
}

PassRequest parseAovs(const std::string& list)
{
    PassRequest passes;
    std::stringstream words(list);
    std::string word;
    while (std::getline(words, word, ',')) {
        if (word == "transmittance") passes.transmittance = true;
        else if (word == "shadow") passes.shadow = true;
        else if (word == "emission") passes.emission = true;
        else if (word != "none" && !word.empty()) {
            throw ValueError("--aov: expected a comma-separated list of transmittance, shadow and emission, got '" + word + "'");
        }
    }
    return passes;
}

} // namespace

void OutputOptions::add(CLI::App* app)
{
    app->add_option("--ocio-config", mConfigPath,
        "OpenColorIO config file (default: $OCIO, else vdb_ewa's shipped ACES config); an unusable config "
        "is a warning and falls back to the next");
    app->add_option("--input-space", mInputSpace,
        "colour space of the colour values given on the command line and in job files (--light colour, --ambient, "
        "--absorb, --scatter, --emission): converted to the working space (default: lin_rec709, linear sRGB, what vdb_render's "
        "values mean)");
    app->add_option("--working-space", mWorkingSpace,
        "colour space the render is computed in (default: the config's scene_linear role; ACEScg in the shipped config)");
    app->add_option("--output-space", mOutputSpace,
        "colour space of .exr and .hdr outputs (default: with vdb_ewa's shipped config, --input-space (lin_rec709), what "
        "vdb_render writes; with your own config ($OCIO or --ocio-config), its scene_linear role)");
    app->add_option("--preview", mPreview, "also write an 8-bit display-referred PNG of the beauty over black");
    app->add_option("--display", mDisplay, "display of 8-bit outputs (.png, .jpg, .tif, .ppm) and --preview (default: the config's default display)");
    app->add_option("--view", mView,
        "view of 8-bit outputs and --preview (default: the display's default view; the shipped config's is Un-tone-mapped, "
        "the plain sRGB curve, and \"ACES 1.0 - SDR Video\" tone-maps)");
    app->add_option("--exr-type", mExrType, "pixel type of the colour channels: half or float; Z is always float (default: half)");
    app->add_option("--compression", mCompression,
        "EXR compression: " + choiceList(kCompressions) + "; other formats ignore it (a warning); --deep files take none, rle or zips (default: zip, zips for --deep)");
    app->add_option("--zip-level", mZipLevel,
        "deflate level of zip and zips EXR compression, 1 (fastest) to 9 (smallest), zlib's scale (flat files are deflated by "
        "libdeflate): at 1 a 1080p frame (half colour, float Z) writes in about 0.8x the time of level 4, up to 30 % larger; range [1, 9] (default: 1)");
    app->add_option("--aov", mAov,
        "extra passes as layer.R/G/B channels, comma-separated: transmittance, shadow, emission "
        "(alpha and Z are always written; definitions in docs/output.md)");
    app->add_flag("--deep", mDeep,
        "write a deep scanline EXR: one sample per non-empty slab (R, G, B, A premultiplied, Z, ZBack; tidy)");
}

void OutputOptions::prepare(const std::string& output, const std::string& preview, std::vector<std::string>& warnings)
{
    // No output: the frame stays in memory (the Python module), as an EXR would hold it.
    const std::optional<ImageFormat> format = output.empty() ? ImageFormat::Exr : imageFormatOf(output);
    if (!format) throw ValueError(output + ": unsupported output format (expected " + imageFormatExtensions() + ")");
    mFormat = *format;
    mExr.colorType = mExrType.empty() ? ExrPixelType::Half : parseChoice("exr-type", mExrType, kExrTypes);
    mExr.compression = !mCompression.empty() ? parseChoice("compression", mCompression, kCompressions)
                                              : mDeep ? ExrCompression::Zips : ExrCompression::Zip;
    if (mZipLevel) {
        if (!(*mZipLevel >= 1 && *mZipLevel <= 9)) throw ValueError("--zip-level must be in [1, 9] (deflate's level), got " + std::to_string(*mZipLevel));
        mExr.zipLevel = *mZipLevel;
    }
    mPasses = parseAovs(mAov);
    if (mFormat != ImageFormat::Exr) {
        if (mDeep) throw ValueError("--deep: " + output + ": deep samples are written to .exr files only");
        if (mPasses.transmittance || mPasses.shadow || mPasses.emission) {
            throw ValueError("--aov: " + output + ": passes are written to .exr files only");
        }
        // vdb_render takes -compression whatever the output, and ignores it for .ppm.
        for (const auto& [name, value] : {std::pair{"--compression", &mCompression}, {"--exr-type", &mExrType}}) {
            if (!value->empty()) warnings.push_back(std::string(name) + " applies to .exr files only; " + output + " is written without it");
        }
        if (mZipLevel) warnings.push_back("--zip-level applies to .exr files only; " + output + " is written without it");
        mPasses = PassRequest();
    } else if (mDeep) {
        if (mPasses.transmittance || mPasses.shadow || mPasses.emission) {
            throw ValueError("--aov passes are flat images; they cannot be written to a --deep file");
        }
        if (!validForDeep(mExr.compression)) {
            throw ValueError("--compression " + mCompression + " is not valid for --deep files (use none, rle or zips)");
        }
        mPasses.deep = true;
    } else {
        mPasses.depth = true;
    }

    mConfig = ColorConfig::resolve(mConfigPath, warnings);
    if (mWorkingSpace.empty()) {
        mWorkingSpace = mConfig->roleSpace("scene_linear");
        if (mWorkingSpace.empty()) throw ValueError(mConfig->origin() + ": the config has no scene_linear role; give --working-space");
    }
    mWorkingSpace = mConfig->colorSpace(mWorkingSpace);
    // vdb_render's colour values are linear sRGB: the config's name for it, if it has one. The
    // blackbody's colour is computed there too.
    std::string rec709;
    for (const char* name : {"lin_rec709", "Linear Rec.709 (sRGB)", "lin_srgb", "Utility - Linear - sRGB", "linear"}) {
        try {
            rec709 = mConfig->colorSpace(name);
            break;
        } catch (const ValueError&) {
        }
    }
    if (!rec709.empty()) mRec709ToWorking = ColorTransform::between(*mConfig, rec709, mWorkingSpace);
    if (mInputSpace.empty()) {
        mInputSpace = rec709;
        if (mInputSpace.empty()) {
            warnings.push_back(mConfig->origin() + " has no linear Rec.709 colour space: colour values are taken in the working space " +
                               mWorkingSpace + " (--input-space chooses)");
            mInputSpace = mWorkingSpace;
        }
    } else {
        mInputSpace = mConfig->colorSpace(mInputSpace);
    }
    if (mConfig->isData(mInputSpace)) throw ValueError("--input-space '" + mInputSpace + "' is a data space; colour values need a colour space");
    mInputToWorking = ColorTransform::between(*mConfig, mInputSpace, mWorkingSpace);
    // What reaches the file (docs/output.md#which-space-reaches-the-file): with the shipped
    // config, what vdb_render writes, the input space (linear Rec.709); with the user's own
    // config ($OCIO, --ocio-config), its scene_linear role, the working space.
    if (mOutputSpace.empty()) mOutputSpace = mConfig->isShipped() ? mInputSpace : mWorkingSpace;
    else mOutputSpace = mConfig->colorSpace(mOutputSpace);
    for (const std::string* space : {&mWorkingSpace, &mOutputSpace}) {
        if (mConfig->isData(*space)) throw ValueError("colour space '" + *space + "' is a data space; renders need a colour space");
    }
    ColorTransform::between(*mConfig, mWorkingSpace, mOutputSpace); // fails now, not after the render
    std::string how;
    mExr.chromaticities = chromaticitiesOf(*mConfig, mOutputSpace, &how);
    if (!mExr.chromaticities) warnings.push_back("no chromaticities attribute written (" + how + ")");

    if (output.empty()) return; // in memory: the preview, display and view are checked when the frame is written
    if (!mPreview.empty() && !endsWith(preview, ".png")) throw ValueError(preview + ": --preview writes a .png file");
    if (!mPreview.empty() || isDisplayReferred(mFormat)) {
        if (mDisplay.empty()) mDisplay = mConfig->defaultDisplay();
        if (mView.empty()) mView = mConfig->defaultView(mDisplay);
        mDisplaySpace = mConfig->displayColorSpace(mDisplay, mView);
        if (!mPreview.empty()) checkOutputWritable(preview);
    } else if (!mDisplay.empty() || !mView.empty()) {
        throw ValueError("--display and --view choose the transform of 8-bit outputs (.png, .jpg, .tif, .ppm) and --preview; " +
                         output + " is scene-referred");
    }
    if (!output.empty()) checkOutputWritable(output);
    if (!mPreview.empty() || mFormat != ImageFormat::Exr) loadImageModule(); // fails now, not after the render
}

void OutputOptions::toWorkingSpace(RenderSettings& rs, std::vector<std::string>& warnings) const
{
    const auto convert = [&](const char* option, Vec3d& value) {
        const Vec3d c = mInputToWorking->apply(value);
        const auto near = [](double a, double b) { return std::abs(a - b) <= 1e-5 * std::max(std::abs(b), 1e-30); };
        if (value.x == value.y && value.y == value.z) {
            // Grey stays exactly grey: the renderer composites grey media in one channel.
            if (near(c.x, value.x) && near(c.y, value.x) && near(c.z, value.x)) return;
            if (near(c.x, c.y) && near(c.z, c.y)) {
                value = Vec3d((c.x + c.y + c.z) / 3.0);
                return;
            }
        }
        value = c;
        if (c.x < 0.0 || c.y < 0.0 || c.z < 0.0) {
            warnings.push_back(std::string(option) + " lies outside the working space " + mWorkingSpace +
                               ": its negative components are taken as 0 (--input-space, --working-space)");
            value = Vec3d(std::max(c.x, 0.0), std::max(c.y, 0.0), std::max(c.z, 0.0));
        }
    };
    for (Light& light : rs.lights) convert("--light colour", light.color);
    for (PointLight& light : rs.pointLights) convert(light.spotAngle > 0.0 ? "--spot-light intensity" : "--point-light intensity", light.color);
    convert("--absorb", rs.medium.absorb);
    convert("--scatter", rs.medium.scatter);
    convert("--emission", rs.medium.emission);
    convert("--ambient", rs.ambient);
    convert("--emission-color", rs.gridEmission.color);
    // The blackbody's Rec.709 colours, and the colour grid's and the level-set shaders' input-space
    // colours: linear maps, their columns the images of the primaries.
    const auto matrixOf = [](const ColorTransform& transform) {
        Mat3d m(1.0);
        for (int c = 0; c < 3; ++c) {
            Vec3d primary(0.0);
            primary[c] = 1.0;
            m[c] = transform.apply(primary);
        }
        return m;
    };
    if (mRec709ToWorking) rs.gridEmission.rec709ToWorking = matrixOf(*mRec709ToWorking);
    rs.inputToWorking = matrixOf(*mInputToWorking);
}

Attributes OutputOptions::resolved() const
{
    Attributes a{{"ocio-config", mConfig ? mConfig->origin() : std::string()}, {"input-space", mInputSpace}, {"working-space", mWorkingSpace}};
    if (!isDisplayReferred(mFormat)) a.emplace_back("output-space", mOutputSpace);
    if (mFormat == ImageFormat::Exr) {
        a.emplace_back("exr-type", choiceName(mExr.colorType, kExrTypes));
        a.emplace_back("compression", choiceName(mExr.compression, kCompressions));
        if (mExr.compression == ExrCompression::Zip || mExr.compression == ExrCompression::Zips) a.emplace_back("zip-level", std::to_string(mExr.zipLevel));
        std::string aov;
        for (const auto& [on, name] : {std::pair{mPasses.transmittance, "transmittance"}, {mPasses.shadow, "shadow"}, {mPasses.emission, "emission"}}) {
            if (on) aov += (aov.empty() ? "" : ",") + std::string(name);
        }
        a.emplace_back("aov", aov.empty() ? "none" : aov);
        a.emplace_back("deep", mDeep ? "on" : "off");
    }
    if (!mPreview.empty() || isDisplayReferred(mFormat)) {
        a.emplace_back("display", mDisplay);
        a.emplace_back("view", mView);
    }
    return a;
}

void OutputOptions::refuseInputs(const std::string& output, const std::string& preview, std::vector<std::string> inputs) const
{
    inputs.push_back(mConfigPath);
    if (const char* env = std::getenv("OCIO")) inputs.emplace_back(env);
    for (const std::string* out : {&output, &preview}) {
        for (const std::string& in : inputs) {
            std::error_code ec;
            if (!out->empty() && !in.empty() && std::filesystem::equivalent(*out, in, ec) && !ec) {
                throw ValueError(*out + ": is the same file as the input " + in + ": refusing to write over an input");
            }
        }
    }
}

void OutputOptions::write(Frame& frame, const Camera& camera, const std::string& output, const std::string& preview,
    const Attributes& attributes) const
{
    // The main output first. The preview reads the working-space beauty, which the EXR and .hdr
    // writers convert in place: keep a copy for it.
    const Image workingBeauty = preview.empty() ? Image() : frame.beauty;
    std::optional<ColorTransform> toDisplay;
    if (!preview.empty() || isDisplayReferred(mFormat)) toDisplay = ColorTransform::toDisplay(*mConfig, mWorkingSpace, mDisplay, mView);
    if (mFormat == ImageFormat::Exr) {
        writeExrInOutputSpace(frame, camera, output, attributes);
    } else if (isDisplayReferred(mFormat)) {
        writeImage(frame.beauty, output, &*toDisplay, {mDisplaySpace, attributes});
    } else {
        ColorTransform::between(*mConfig, mWorkingSpace, mOutputSpace).applyPremultiplied(frame.beauty.rgba.data(), frame.beauty.rgba.size() / 4);
        writeImage(frame.beauty, output, nullptr, {mOutputSpace, attributes});
    }
    if (!preview.empty()) writeImage(workingBeauty, preview, &*toDisplay, {mDisplaySpace, attributes});
}

void OutputOptions::toOutputSpace(Frame& frame) const
{
    const ColorTransform toOutput = ColorTransform::between(*mConfig, mWorkingSpace, mOutputSpace);
    if (mPasses.deep) {
        // Deep samples are premultiplied by their own alpha: convert each as a pixel.
        std::vector<float> rgba(frame.deep.samples.size() * 4);
        for (std::size_t i = 0; i < frame.deep.samples.size(); ++i) {
            const DeepSample& d = frame.deep.samples[i];
            const float v[4] = {d.r, d.g, d.b, d.a};
            std::copy(v, v + 4, &rgba[4 * i]);
        }
        toOutput.applyPremultiplied(rgba.data(), frame.deep.samples.size());
        for (std::size_t i = 0; i < frame.deep.samples.size(); ++i) {
            DeepSample& d = frame.deep.samples[i];
            d.r = rgba[4 * i];
            d.g = rgba[4 * i + 1];
            d.b = rgba[4 * i + 2];
        }
        // The flat beauty too (the Python module's array; a deep file holds the samples only).
        toOutput.applyPremultiplied(frame.beauty.rgba.data(), frame.beauty.rgba.size() / 4);
        return;
    }
    const std::size_t pixels = frame.beauty.rgba.size() / 4;
    // Colour passes share the beauty's alpha; transmittance is a per-channel ratio, not a colour.
    for (std::vector<float>* pass : {&frame.shadow, &frame.emission}) {
        if (pass->empty()) continue;
        std::vector<float> rgba(pixels * 4);
        for (std::size_t i = 0; i < pixels; ++i) {
            std::copy_n(&(*pass)[3 * i], 3, &rgba[4 * i]);
            rgba[4 * i + 3] = frame.beauty.rgba[4 * i + 3];
        }
        toOutput.applyPremultiplied(rgba.data(), pixels);
        for (std::size_t i = 0; i < pixels; ++i) std::copy_n(&rgba[4 * i], 3, &(*pass)[3 * i]);
    }
    toOutput.applyPremultiplied(frame.beauty.rgba.data(), pixels);
}

void OutputOptions::writeExrInOutputSpace(Frame& frame, const Camera& camera, const std::string& output,
    const Attributes& attributes) const
{
    ExrOptions exr = mExr;
    exr.camera = &camera;
    exr.attributes = attributes;
    // The colour space by name, besides the chromaticities: OpenImageIO's attribute and the
    // Color Interop Forum's identifier (docs/output.md#colour-management-opencolorio-21).
    exr.attributes.emplace_back("oiio:ColorSpace", mOutputSpace);
    const std::string interopId = colorInteropIdOf(*mConfig, mOutputSpace);
    if (!interopId.empty()) exr.attributes.emplace_back("colorInteropID", interopId);
    toOutputSpace(frame);
    if (mPasses.deep) writeDeepExr(frame.deep, output, exr);
    else writeExr(frame, output, exr);
}

} // namespace vdb_ewa::cli
