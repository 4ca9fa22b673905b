/// @file camera_file.cpp
/// @brief Cameras from EXR headers and vdb_ewa's exact camera record.
#include <vdb_ewa/camera_file.h>

#include <vdb_ewa/error.h>

#include <OpenEXR/ImfHeader.h>
#include <OpenEXR/ImfInputFile.h>
#include <OpenEXR/ImfStandardAttributes.h>
#include <OpenEXR/ImfStringAttribute.h>

#include <glm/glm.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <map>
#include <sstream>
#include <vector>

namespace vdb_ewa {
namespace {

constexpr double kPi = 3.14159265358979323846;

std::string exact(double v)
{
    char text[40];
    std::snprintf(text, sizeof text, "%.17g", v);
    return text;
}

std::string exact3(const Vec3d& v) { return exact(v.x) + "," + exact(v.y) + "," + exact(v.z); }

std::vector<double> numbers(const std::string& key, const std::string& text, std::size_t count)
{
    std::vector<double> out;
    std::stringstream ss(text);
    std::string item;
    while (std::getline(ss, item, ',')) {
        char* end = nullptr;
        const double v = std::strtod(item.c_str(), &end);
        if (item.empty() || *end != '\0') throw ValueError("camera record: " + key + " '" + text + "' is not a list of numbers");
        out.push_back(v);
    }
    if (out.size() != count) throw ValueError("camera record: " + key + " needs " + std::to_string(count) + " numbers, got '" + text + "'");
    return out;
}

Vec3d vec3(const std::string& key, const std::string& text)
{
    const std::vector<double> v = numbers(key, text, 3);
    return {v[0], v[1], v[2]};
}

} // namespace

std::string cameraRecord(const CameraSettings& s)
{
    if (!s.rotate && !s.lookAt) throw ValueError("camera record: the camera needs --rotate or --lookat, not a grid's default target");
    std::string r = "projection=" + std::string(s.projection == Projection::Perspective ? "perspective" : "orthographic") +
                    ";res=" + std::to_string(s.width) + "x" + std::to_string(s.height) + ";translate=" + exact3(s.translate);
    if (s.rotate) r += ";rotate=" + exact3(*s.rotate);
    if (s.lookAt) r += ";lookat=" + exact3(*s.lookAt) + ";up=" + exact3(s.up);
    return r + ";focal=" + exact(s.focal) + ";aperture=" + exact(s.aperture) + ";frame=" + exact(s.frame) + ";near=" + exact(s.near) +
           ";far=" + exact(s.far);
}

CameraSettings cameraFromRecord(const std::string& record)
{
    std::map<std::string, std::string> fields;
    std::stringstream ss(record);
    std::string item;
    while (std::getline(ss, item, ';')) {
        const std::size_t eq = item.find('=');
        if (eq == std::string::npos) throw ValueError("camera record: '" + item + "' is not key=value");
        fields[item.substr(0, eq)] = item.substr(eq + 1);
    }
    for (const char* key : {"projection", "res", "translate", "focal", "aperture", "frame", "near", "far"}) {
        if (!fields.count(key)) throw ValueError(std::string("camera record: no ") + key);
    }
    CameraSettings s;
    const std::string& projection = fields["projection"];
    if (projection != "perspective" && projection != "orthographic") throw ValueError("camera record: projection '" + projection + "'");
    s.projection = projection == "perspective" ? Projection::Perspective : Projection::Orthographic;
    int w = 0, h = 0;
    char tail = 0;
    if (std::sscanf(fields["res"].c_str(), "%dx%d%c", &w, &h, &tail) != 2) throw ValueError("camera record: res '" + fields["res"] + "'");
    s.width = w;
    s.height = h;
    s.translate = vec3("translate", fields["translate"]);
    if (fields.count("rotate")) s.rotate = vec3("rotate", fields["rotate"]);
    if (fields.count("lookat")) s.lookAt = vec3("lookat", fields["lookat"]);
    if (fields.count("up")) s.up = vec3("up", fields["up"]);
    s.focal = numbers("focal", fields["focal"], 1)[0];
    s.aperture = numbers("aperture", fields["aperture"], 1)[0];
    s.frame = numbers("frame", fields["frame"], 1)[0];
    s.near = numbers("near", fields["near"], 1)[0];
    s.far = numbers("far", fields["far"], 1)[0];
    const Camera check(s, Vec3d(0.0)); // an impossible camera fails here, naming the problem
    return s;
}

CameraSettings cameraFromWorldToCamera(const double m[4][4], Projection projection, double screenWindowWidth, int width, int height)
{
    // Rows of the camera's 3x3 in world space (p_camera = p_world M): column j of M is camera
    // axis j. OpenEXR: x right, y up, z forward.
    Vec3d axis[3];
    for (int j = 0; j < 3; ++j) {
        const Vec3d a(m[0][j], m[1][j], m[2][j]);
        const double len = glm::length(a);
        if (!(len > 0.0) || !std::isfinite(len)) throw ValueError("worldToCamera holds no rotation (a zero or non-finite axis)");
        axis[j] = a / len;
    }
    const Vec3d right = axis[0], up = axis[1], back = -axis[2];
    // The eye: t_j = -axis_j . eye for the camera's translation row.
    Vec3d eye(0.0);
    for (int j = 0; j < 3; ++j) eye -= m[3][j] / glm::length(Vec3d(m[0][j], m[1][j], m[2][j])) * axis[j];
    // localToWorld = Rz Ry Rx with columns right, up, back (Camera's --rotate): its Euler angles.
    const double M[3][3] = {{right.x, up.x, back.x}, {right.y, up.y, back.y}, {right.z, up.z, back.z}}; // [row][column]
    const double sy = std::clamp(-M[2][0], -1.0, 1.0);
    double x, y = std::asin(sy), z;
    if (std::abs(sy) < 1.0 - 1e-12) {
        x = std::atan2(M[2][1], M[2][2]);
        z = std::atan2(M[1][0], M[0][0]);
    } else { // gimbal lock: x and z turn about the same axis
        x = 0.0;
        z = std::atan2(-M[0][1], M[1][1]);
    }
    CameraSettings s;
    s.projection = projection;
    s.width = width;
    s.height = height;
    s.translate = eye;
    s.rotate = Vec3d(x, y, z) * (180.0 / kPi);
    if (!(screenWindowWidth > 0.0) || !std::isfinite(screenWindowWidth)) throw ValueError("screenWindowWidth must be > 0");
    if (projection == Projection::Perspective) s.focal = s.aperture / screenWindowWidth;
    else s.frame = screenWindowWidth;
    return s;
}

CameraSettings readExrCamera(const std::string& path)
{
    try {
        Imf::InputFile file(path.c_str());
        const Imf::Header& header = file.header();
        if (const auto* record = header.findTypedAttribute<Imf::StringAttribute>("vdb_ewa/camera-record")) {
            return cameraFromRecord(record->value());
        }
        if (!Imf::hasWorldToCamera(header)) throw ValueError(path + ": the file holds no camera (no worldToCamera attribute)");
        const Imath::M44f& w = Imf::worldToCameraAttribute(header).value();
        double m[4][4];
        for (int i = 0; i < 4; ++i)
            for (int j = 0; j < 4; ++j) m[i][j] = double(w[i][j]);
        // worldToNDC divides by depth (a perspective camera) where its last column is not (0, 0, 0, 1).
        Projection projection = Projection::Perspective;
        if (Imf::hasWorldToNDC(header)) {
            const Imath::M44f& n = Imf::worldToNDCAttribute(header).value();
            const bool affine = n[0][3] == 0.0f && n[1][3] == 0.0f && n[2][3] == 0.0f;
            projection = affine ? Projection::Orthographic : Projection::Perspective;
        }
        const Imath::Box2i display = header.displayWindow();
        return cameraFromWorldToCamera(m, projection, double(header.screenWindowWidth()), display.max.x - display.min.x + 1,
            display.max.y - display.min.y + 1);
    } catch (const Error& e) {
        if (dynamic_cast<const ValueError*>(&e)) {
            const std::string what = e.what();
            throw ValueError(what.rfind(path, 0) == 0 ? what : path + ": " + what);
        }
        throw;
    } catch (const std::exception& e) {
        throw IoError(path + ": cannot read the camera (" + std::string(e.what()) + ")");
    }
}

} // namespace vdb_ewa
