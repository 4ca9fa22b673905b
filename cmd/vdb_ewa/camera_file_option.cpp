/// @file camera_file_option.cpp
#include "camera_file_option.h"

#include "job_file.h"
#include "option_values.h"

#include <vdb_ewa/camera_file.h>
#include <vdb_ewa/error.h>

#include <nlohmann/json.hpp>

#include <cmath>
#include <filesystem>
#include <set>
#include <utility>
#include <vector>

namespace vdb_ewa::cli {
namespace {


Vec3d vec3(const nlohmann::json& v, const std::string& where)
{
    if (!v.is_array() || v.size() != 3 || !v[0].is_number() || !v[1].is_number() || !v[2].is_number()) {
        throw ValueError(where + ": expected [x, y, z]");
    }
    return {v[0].get<double>(), v[1].get<double>(), v[2].get<double>()};
}

double number(const nlohmann::json& v, const std::string& where)
{
    if (!v.is_number()) throw ValueError(where + ": expected a number");
    return v.get<double>();
}

CameraSettings fromJson(const nlohmann::json& j, const std::string& path)
{
    static const std::set<std::string> keys = {"res", "camera", "translate", "rotate", "lookat", "up", "fov", "focal",
        "aperture", "frame", "near", "far", "worldToCamera", "screenWindowWidth"};
    for (const auto& [key, value] : j.items()) {
        if (!keys.count(key)) throw ValueError(path + ": '" + key + "' is not a camera key");
    }
    const auto at = [&](const char* key) { return path + ": " + key; };
    CameraSettings s;
    if (j.contains("res")) {
        if (!j["res"].is_string()) throw ValueError(at("res") + ": expected \"WxH\"");
        parseResolution(j["res"].get<std::string>(), s.width, s.height);
    }
    if (j.contains("camera")) {
        const std::string kind = j["camera"].is_string() ? j["camera"].get<std::string>() : "";
        if (kind.rfind("persp", 0) == 0) s.projection = Projection::Perspective;
        else if (kind.rfind("ortho", 0) == 0) s.projection = Projection::Orthographic;
        else throw ValueError(at("camera") + ": expected \"perspective\" or \"orthographic\"");
    }
    if (j.contains("aperture")) s.aperture = number(j["aperture"], at("aperture"));
    if (j.contains("focal") && j.contains("fov")) throw ValueError(path + ": give focal or fov, not both");
    if (j.contains("focal")) s.focal = number(j["focal"], at("focal"));
    if (j.contains("fov")) s.setFieldOfView(number(j["fov"], at("fov")));
    if (j.contains("frame")) s.frame = number(j["frame"], at("frame"));
    if (j.contains("near")) s.near = number(j["near"], at("near"));
    if (j.contains("far")) s.far = number(j["far"], at("far"));
    if (j.contains("worldToCamera")) {
        for (const char* key : {"translate", "rotate", "lookat", "up"}) {
            if (j.contains(key)) throw ValueError(path + ": worldToCamera sets the camera's position and rotation; '" + key + "' cannot be given with it");
        }
        const nlohmann::json& m = j["worldToCamera"];
        double w[4][4];
        for (int r = 0; r < 4; ++r) {
            if (!m.is_array() || m.size() != 4 || !m[r].is_array() || m[r].size() != 4) {
                throw ValueError(at("worldToCamera") + ": expected 4 rows of 4 numbers");
            }
            for (int c = 0; c < 4; ++c) w[r][c] = number(m[r][c], at("worldToCamera"));
        }
        // The screen window: given, or the field of view's (perspective), or the frame (orthographic).
        double window = s.projection == Projection::Perspective ? s.aperture / s.focal : s.frame;
        if (j.contains("screenWindowWidth")) window = number(j["screenWindowWidth"], at("screenWindowWidth"));
        const CameraSettings placed = cameraFromWorldToCamera(w, s.projection, window, s.width, s.height);
        s.translate = placed.translate;
        s.rotate = placed.rotate;
        s.focal = placed.focal;
        s.frame = placed.frame;
    } else {
        if (j.contains("screenWindowWidth")) throw ValueError(path + ": screenWindowWidth goes with worldToCamera (else fov or frame)");
        if (j.contains("translate")) s.translate = vec3(j["translate"], at("translate"));
        if (j.contains("rotate")) s.rotate = vec3(j["rotate"], at("rotate"));
        if (j.contains("lookat")) s.lookAt = vec3(j["lookat"], at("lookat"));
        if (j.contains("up")) s.up = vec3(j["up"], at("up"));
    }
    return s;
}

/// Keyframes {"at": frame, camera keys...}, interpolated linearly at @a frame: position,
/// rotation angles or target and up, field of view (or orthographic frame), aperture, near and
/// far. Resolution and projection are the first key's.
CameraSettings interpolated(const nlohmann::json& keys, double frame, const std::string& path)
{
    if (!keys.is_array() || keys.empty()) throw ValueError(path + ": keys: expected a list of keyframes");
    std::vector<std::pair<double, CameraSettings>> frames;
    for (const nlohmann::json& key : keys) {
        if (!key.is_object() || !key.contains("at") || !key["at"].is_number()) throw ValueError(path + ": keys: each keyframe needs \"at\": its frame");
        nlohmann::json camera = key;
        camera.erase("at");
        frames.emplace_back(key["at"].get<double>(), fromJson(camera, path));
        const CameraSettings& first = frames.front().second;
        const CameraSettings& added = frames.back().second;
        if (frames.size() > 1 && (frames.back().first <= frames[frames.size() - 2].first)) throw ValueError(path + ": keys: frames must rise");
        if (added.rotate.has_value() != first.rotate.has_value() || added.lookAt.has_value() != first.lookAt.has_value()) {
            throw ValueError(path + ": keys: every keyframe must give rotate, or every keyframe lookat");
        }
    }
    if (frame <= frames.front().first) return frames.front().second;
    if (frame >= frames.back().first) return frames.back().second;
    std::size_t k = 1;
    while (frames[k].first < frame) ++k;
    if (frames[k].first == frame) return frames[k].second; // a keyframe as given
    const CameraSettings &a = frames[k - 1].second, &b = frames[k].second;
    const double t = (frame - frames[k - 1].first) / (frames[k].first - frames[k - 1].first);
    const auto mix = [t](auto x, auto y) { return x + (y - x) * t; };
    CameraSettings s = a;
    s.translate = mix(a.translate, b.translate);
    if (a.rotate) s.rotate = mix(*a.rotate, *b.rotate);
    if (a.lookAt) s.lookAt = mix(*a.lookAt, *b.lookAt);
    s.up = mix(a.up, b.up);
    s.aperture = mix(a.aperture, b.aperture);
    s.setFieldOfView(mix(a.fieldOfView(), b.fieldOfView()));
    s.frame = mix(a.frame, b.frame);
    s.near = mix(a.near, b.near);
    s.far = mix(a.far, b.far);
    return s;
}

} // namespace

CameraSettings readCameraFile(const std::string& path, int frame)
{
    std::error_code error;
    const auto status = std::filesystem::status(path, error);
    if (!std::filesystem::exists(status)) throw IoError(path + ": no such camera file");
    if (!std::filesystem::is_regular_file(status)) throw IoError(path + ": not a regular file, so not a camera file");
    const std::string ext = std::filesystem::path(path).extension().string();
    if (ext == ".exr" || ext == ".EXR") return readExrCamera(path);
    const nlohmann::json j = readJsonObjectFile(path, "camera", "key: value");
    if (j.contains("keys")) {
        if (j.size() != 1) throw ValueError(path + ": a file of keyframes holds \"keys\" alone");
        return interpolated(j["keys"], double(frame), path);
    }
    return fromJson(j, path);
}

} // namespace vdb_ewa::cli
