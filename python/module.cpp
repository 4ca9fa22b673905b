/// @file module.cpp
/// @brief The Python module vdb_ewa (pybind11): grids from .vdb files or numpy arrays, render()
///        with vdb_ewa render's options as keyword arguments, frames as numpy arrays, EXR output
///        through the library, and the library's exceptions as Python exceptions. docs/python.md.
#include "array_grid.h"
#include "error_messages.h"
#include "render_call.h"

#include <vdb_ewa/vdb_ewa.h>

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <sstream>
#include <tuple>

namespace py = pybind11;
using namespace vdb_ewa;
using namespace vdb_ewa::python;

namespace {

/// The module's exception classes (owned by the module's dict).
struct ExceptionTypes
{
    PyObject* error = nullptr;
    PyObject* ioError = nullptr;
    PyObject* inputError = nullptr;
    PyObject* valueError = nullptr;
    PyObject* budgetError = nullptr;
    PyObject* cancelled = nullptr;
} gTypes;

PyObject* addException(py::module_& m, const char* name, py::tuple bases, const char* doc)
{
    const std::string qualified = std::string("vdb_ewa.") + name;
    PyObject* type = PyErr_NewExceptionWithDoc(qualified.c_str(), doc, bases.ptr(), nullptr);
    if (!type) throw py::error_already_set();
    m.add_object(name, py::handle(type)); // the module keeps the reference
    return type;
}

void registerExceptions(py::module_& m)
{
    const py::handle error = gTypes.error = addException(m, "Error", py::make_tuple(py::handle(PyExc_RuntimeError)),
        "Base of every error vdb_ewa raises; the message is the one line the CLI prints after 'vdb_ewa: '.");
    gTypes.ioError = addException(m, "IoError", py::make_tuple(error, py::handle(PyExc_OSError)),
        "A file could not be read or written (missing, unreadable, truncated, unwritable).");
    gTypes.inputError = addException(m, "InputError", py::make_tuple(error),
        "The input is readable but unusable (no such grid, unsupported grid type).");
    gTypes.valueError = addException(m, "ValueError", py::make_tuple(error, py::handle(PyExc_ValueError)),
        "An argument or option is out of range or inconsistent (unknown keyword, impossible camera...).");
    gTypes.budgetError = addException(m, "BudgetError", py::make_tuple(error, py::handle(PyExc_MemoryError)),
        "The render would need more memory than max_memory allows (found before anything is allocated).");
    gTypes.cancelled = addException(m, "Cancelled", py::make_tuple(error),
        "The render was cancelled (CancelToken.cancel, progress returning True, or Ctrl+C); nothing was written.");
    py::register_exception_translator([](std::exception_ptr p) {
        const auto raise = [](PyObject* type, const std::exception& e) { PyErr_SetString(type, cli::errorLine(e.what()).c_str()); };
        try {
            if (p) std::rethrow_exception(p);
        } catch (const Cancelled& e) {
            raise(gTypes.cancelled, e);
        } catch (const vdb_ewa::ValueError& e) {
            raise(gTypes.valueError, e);
        } catch (const BudgetError& e) {
            raise(gTypes.budgetError, e);
        } catch (const IoError& e) {
            raise(gTypes.ioError, e);
        } catch (const InputError& e) {
            raise(gTypes.inputError, e);
        } catch (const vdb_ewa::Error& e) {
            raise(gTypes.error, e);
        }
    });
}

/// A read-only (rows, columns[, channels]) float32 view of @a data, keeping @a owner alive.
py::object view(const std::vector<float>& data, int width, int height, int channels, const py::object& owner)
{
    if (data.empty()) return py::none();
    std::vector<py::ssize_t> shape{height, width}, strides{py::ssize_t(width) * channels * 4, py::ssize_t(channels) * 4};
    if (channels > 1) {
        shape.push_back(channels);
        strides.push_back(4);
    }
    py::array a(py::dtype::of<float>(), shape, strides, data.data(), owner);
    py::detail::array_proxy(a.ptr())->flags &= ~py::detail::npy_api::NPY_ARRAY_WRITEABLE_;
    return a;
}

py::dict aovs(const py::object& self)
{
    const auto& f = self.cast<const RenderedFrame&>().output;
    const int w = f.beauty.width, h = f.beauty.height;
    py::dict d;
    if (!f.depth.empty()) d["depth"] = view(f.depth, w, h, 1, self);
    if (!f.transmittance.empty()) d["transmittance"] = view(f.transmittance, w, h, 3, self);
    if (!f.shadow.empty()) d["shadow"] = view(f.shadow, w, h, 3, self);
    if (!f.emission.empty()) d["emission"] = view(f.emission, w, h, 3, self);
    return d;
}

/// A render's cancel= keyword: a CancelToken or None.
std::shared_ptr<CancelToken> cancelToken(const py::object& cancel)
{
    if (cancel.is_none()) return nullptr;
    if (!py::isinstance<CancelToken>(cancel)) throw vdb_ewa::ValueError("cancel: expected a vdb_ewa.CancelToken or None");
    return cancel.cast<std::shared_ptr<CancelToken>>();
}

/// A render's warnings as Python warnings (vdb_ewa.RenderWarning), attributed to the caller.
void warnAll(const std::vector<std::string>& warnings)
{
    const py::object warn = py::module_::import("warnings").attr("warn");
    const py::object category = py::module_::import("vdb_ewa").attr("RenderWarning");
    for (const std::string& w : warnings) warn(w, category, 1); // this C function has no frame: 1 is the caller
}

py::dict statsOf(const RenderStats& s)
{
    py::dict d;
    d["kernel_seconds"] = s.kernelSeconds;
    d["shadow_seconds"] = s.shadowSeconds;
    d["project_seconds"] = s.projectSeconds;
    d["raster_seconds"] = s.rasterSeconds;
    d["active_voxels"] = s.activeVoxels;
    d["active_tiles"] = s.activeTiles;
    d["kernels"] = s.kernels;
    d["halo_kernels"] = s.haloKernels;
    d["emitter_kernels"] = s.emitterKernels;
    d["refined_voxels"] = s.refinedVoxels;
    d["moving_kernels"] = s.movingKernels;
    d["motion_sub_kernels"] = s.motionSubKernels;
    d["kernels_skipped"] = s.kernelsSkipped;
    d["voxels_merged"] = s.voxelsMerged;
    d["merged_kernels"] = s.mergedKernels;
    d["kernels_culled"] = s.kernelsCulled;
    d["splats"] = s.splats;
    d["splat_tile_pairs"] = s.splatTilePairs;
    d["splat_tile_pairs_skipped"] = s.splatTilePairsSkipped;
    d["footprint_samples"] = s.footprintSamples;
    d["footprint_samples_by_level"] = py::make_tuple(s.footprintSamplesAtLevel[0], s.footprintSamplesAtLevel[1], s.footprintSamplesAtLevel[2], s.footprintSamplesAtLevel[3]);
    d["slab_composites_by_level"] = py::make_tuple(s.slabCompositesAtLevel[0], s.slabCompositesAtLevel[1], s.slabCompositesAtLevel[2], s.slabCompositesAtLevel[3]);
    d["streamed"] = s.streamed;
    d["bricks"] = s.bricks;
    d["bricks_expanded"] = s.bricksExpanded;
    d["bricks_hidden"] = s.bricksHidden;
    d["bricks_outside"] = s.bricksOutside;
    d["depth_windows"] = s.windows;
    d["splats_in_flight"] = s.splatsInFlight;
    d["light_rays"] = s.lightRays;
    d["light_rays_marched"] = s.lightRaysMarched;
    d["light_maps_reused"] = s.lightMapsReused;
    d["light_rays_reused"] = s.lightRaysReused;
    d["coarse_scale"] = s.coarseScale;
    d["supersample"] = s.supersample;
    d["pixel_size"] = s.pixelSize;
    d["voxel_pixels"] = s.voxelPixels;
    d["peak_resident_bytes"] = s.peakResidentBytes;
    d["raster_backend"] = s.rasterBackend;
    return d;
}

/// render()'s docstring: the calling convention, then every option with --help's text.
std::string renderDoc()
{
    std::ostringstream doc;
    doc << "Render a grid with EWA volume splatting, as `vdb_ewa render` would.\n\n"
           "The options are vdb_ewa render's long options with - spelled _ (refine_emission=4), with the same\n"
           "defaults, checks and error messages; None leaves an option at its default. Values: numbers, strings,\n"
           "True/False (flags and on/off switches), sequences for X,Y,Z options (translate=(0, 0, 5)), a sequence\n"
           "of sequences to repeat an option (light=[(1, 1, 0), (-1, 0.5, 0, 0.2, 0.3, 0.6)]).\n\n"
           "Args:\n"
           "    grid: a vdb_ewa.Grid (vdb_ewa.open, vdb_ewa.from_array), or the path of a .vdb file, whose grids\n"
           "        name, color, emission_grid and temperature then pick.\n"
           "    progress: None, or a callable f(percent) called on this thread as the render advances (0 to 100,\n"
           "        rising; 100 when done). Returning True cancels; an exception it raises cancels and propagates.\n"
           "    cancel: None, or a vdb_ewa.CancelToken: token.cancel() from any thread stops the render.\n"
           "    **options: see below.\n\n"
           "The GIL is released while rendering; Ctrl+C cancels. Warnings (clamped settings, fallbacks) are\n"
           "issued as vdb_ewa.RenderWarning and kept in Frame.warnings.\n\n"
           "Returns:\n"
           "    A vdb_ewa.Frame: beauty, a (height, width, 4) float32 array (premultiplied RGBA in output_space,\n"
           "    what the EXR holds); aovs: depth, and the passes asked for by aov=; write(path).\n\n"
           "Raises:\n"
           "    vdb_ewa.ValueError (options), vdb_ewa.IoError, vdb_ewa.InputError (the grid), vdb_ewa.BudgetError\n"
           "    (max_memory), vdb_ewa.Cancelled.\n\n"
           "Options:\n";
    for (const KeywordInfo& k : renderKeywords()) doc << "    " << k.keyword << " (" << k.type << "): " << k.description << "\n";
    return doc.str();
}

} // namespace

PYBIND11_MODULE(vdb_ewa, m)
{
    m.doc() = "EWA volume splatting of OpenVDB grids (Zwicker et al. 2002): vdb_ewa's library in Python.\n\n"
              "    import vdb_ewa\n"
              "    grid = vdb_ewa.open('smoke.vdb')                  # or vdb_ewa.from_array(array, index_to_world)\n"
              "    frame = vdb_ewa.render(grid, res='960x540', translate=(0, 0, 5), quality='high')\n"
              "    frame.beauty                                      # (540, 960, 4) float32\n"
              "    frame.write('smoke.exr')\n\n"
              "help(vdb_ewa.render) lists every option (vdb_ewa render's, - spelled _). docs/python.md.";
    // PEP 440: the version alone ("0.1.0"); versionString() adds the commit ("0.1.0 (git 657cd57)").
    const std::string version = versionString();
    m.attr("__version__") = version.substr(0, version.find(' '));
    registerExceptions(m);
    m.attr("RenderWarning") = py::reinterpret_steal<py::object>(
        PyErr_NewExceptionWithDoc("vdb_ewa.RenderWarning", "A setting was clamped or a fallback taken (the CLI's 'warning:' lines).",
            PyExc_UserWarning, nullptr));

    py::class_<GridSource> grid(m, "Grid",
        "A scalar volume to render: a fog volume or a level set, from a .vdb file (vdb_ewa.open) or a numpy array "
        "(vdb_ewa.from_array).");
    grid.def_property_readonly("name", &GridSource::name, "The grid's name.")
        .def_property_readonly("path", &GridSource::path, "The file the grid came from; '' for an array.")
        .def_property_readonly("stored_type", &GridSource::storedType, "'float' or 'double': the value type in the file.")
        .def_property_readonly("is_level_set", &GridSource::isLevelSet, "True for a level set (rendered as its iso-surface).")
        .def_property_readonly("active_voxel_count", &GridSource::activeVoxelCount, "Active voxels.")
        .def_property_readonly("active_tile_count", &GridSource::activeTileCount, "Active tiles.")
        .def_property_readonly("world_centre", [](const GridSource& g) {
            const Vec3d c = g.worldCentre();
            return py::make_tuple(c.x, c.y, c.z);
        }, "Centre of the active voxels' bounding box in world space: the camera's default target.")
        .def_property_readonly("voxel_length", &GridSource::voxelLength,
            "The length densities are per (absorb, scatter, emission): cbrt |det| of the index-to-world map's linear "
            "part, in world units.")
        .def("transformed", [](const GridSource& g, const py::object& matrix) {
            const Mat4d m = objectToWorld(matrix);
            py::gil_scoped_release release; // the moved grids are scanned again (the field's values)
            return g.transformed(m);
        },
            py::arg("object_to_world"),
            "The same grid moved by a 4x4 object-to-world matrix, column vectors: world = M @ (x, y, z, 1) (Blender's\n"
            "matrix_world); its colour and emission grids move with it, also those the render attaches by name.\n"
            "Raises vdb_ewa.ValueError for a matrix that is not 4x4, finite, affine and invertible.")
        .def("with_added_volume", [](const GridSource& g, const GridSource& other, const py::object& absorb, const py::object& scatter,
                                         const py::object& emission) {
            if (absorb.is_none() && scatter.is_none() && emission.is_none()) {
                py::gil_scoped_release release; // resamples and sums the fields
                return g.withAddedVolume(other);
            }
            Medium medium;
            for (const auto& [value, name, out] : {std::tuple{&absorb, "absorb", &medium.absorb}, {&scatter, "scatter", &medium.scatter},
                     {&emission, "emission", &medium.emission}}) {
                if (value->is_none()) continue;
                std::vector<double> v;
                try {
                    v = py::isinstance<py::sequence>(*value) ? value->cast<std::vector<double>>() : std::vector<double>{value->cast<double>()};
                } catch (const py::cast_error&) {
                    throw ValueError(std::string("with_added_volume: ") + name + ": expected a number or (R, G, B)");
                }
                if (v.size() != 1 && v.size() != 3) throw ValueError(std::string("with_added_volume: ") + name + ": expected a number or (R, G, B)");
                *out = v.size() == 1 ? Vec3d(v[0]) : Vec3d(v[0], v[1], v[2]);
            }
            py::gil_scoped_release release;
            return g.withAddedVolume(other, medium);
        },
            py::arg("other"), py::kw_only(), py::arg("absorb") = py::none(), py::arg("scatter") = py::none(), py::arg("emission") = py::none(),
            "This fog volume and another in one field, their densities summed (render's add_volume): both go through\n"
            "one front-to-back sweep, so where they interpenetrate each hides and shadows the other. other is resampled\n"
            "onto this grid's voxels where its transform differs (put the finest volume first), its densities scaled by\n"
            "the voxel lengths' ratio (densities are per voxel length). Velocities attached before (with_velocity_grid) are\n"
            "summed too: the sum moves with both volumes' velocities weighted by their densities (a volume without one\n"
            "stands still). Colours and emission are this grid's.\n"
            "With absorb, scatter or emission (a number or (R, G, B), per unit of other's density per voxel length; those\n"
            "not given take vdb_render's defaults), other has an optical model of its own, and its own colour, emission\n"
            "and temperature grids (attached to it before): each render mixes them voxel by voxel with its own medium as\n"
            "this grid's (render's add_volume_material). Raises vdb_ewa.InputError where either is a level set,\n"
            "vdb_ewa.ValueError for a negative or non-finite coefficient.")
        .def("__repr__", [](const GridSource& g) {
            return "<vdb_ewa.Grid '" + g.name() + "'" + (g.path().empty() ? std::string(" (array)") : " from " + g.path()) + ", " +
                   std::to_string(g.activeVoxelCount()) + " active voxels" + (g.isLevelSet() ? ", level set>" : ">");
        });
    // The grids of a volume's own file attached by name: each reads the file.
    using Attach = GridSource (GridSource::*)(const std::string&) const;
    const std::tuple<const char*, Attach, const char*> attachers[] = {
        {"with_velocity_grid", &GridSource::withVelocityGrid,
            "The same grid with motion blur from the velocity grid name of its file (render's velocity_grid, which\n"
            "attaches it to the input instead): a vec3s or vec3d grid, or the float grids name.x, .y, .z. Attach it\n"
            "before with_added_volume so that each volume keeps its own motion; velocity_unit, velocity_scale, fps\n"
            "and shutter still apply. Raises vdb_ewa.IoError or vdb_ewa.InputError (no such grid, wrong type)."},
        {"with_color_grid", &GridSource::withColorGrid,
            "The same grid with material colours from the vec3s grid name of its file (render's color attaches it to\n"
            "the input instead): attach it to a volume before with_added_volume(other, absorb=..., scatter=...) to give\n"
            "that volume its own colours. Raises vdb_ewa.IoError or vdb_ewa.InputError (no such grid, wrong type)."},
        {"with_emission_grid", &GridSource::withEmissionGrid,
            "The same grid with emission from the float grid name of its file (render's emission_grid, for the\n"
            "input), for a volume added with an optical model of its own. Raises vdb_ewa.IoError or vdb_ewa.InputError."},
        {"with_temperature_grid", &GridSource::withTemperatureGrid,
            "The same grid with blackbody emission from the float grid name of its file (render's temperature, for\n"
            "the input), for a volume added with an optical model of its own; the render's temperature_scale,\n"
            "temperature_offset and blackbody_intensity apply. Raises vdb_ewa.IoError or vdb_ewa.InputError."}};
    for (const auto& [name, attach, doc] : attachers) {
        grid.def(name, [attach = attach](const GridSource& g, const std::string& gridName) {
            py::gil_scoped_release release;
            return (g.*attach)(gridName);
        }, py::arg("name"), doc);
    }

    m.def("open", [](const py::object& path, const std::string& name) {
        const std::string p = py::module_::import("os").attr("fspath")(path).cast<std::string>();
        py::gil_scoped_release release;
        return GridSource::open(p, name);
    }, py::arg("path"), py::arg("name") = "",
        "Open the grid called name in the .vdb file path (default: the first scalar float or double grid, as\n"
        "vdb_render). Raises vdb_ewa.IoError (missing, unreadable, truncated file) or vdb_ewa.InputError (no such\n"
        "grid, not a scalar floating-point grid).");
    m.def("from_array", [](const py::array& array, const py::object& indexToWorld, const std::string& name, const py::object& emission,
              const py::object& temperature, const py::object& velocity) {
        GridSource grid = gridFromArray(array, indexToWorld, name);
        for (const auto& [values, kind] : {std::pair{&emission, "emission"}, {&temperature, "temperature"}}) {
            if (values->is_none()) continue;
            const py::array a = py::array::ensure(*values);
            if (!a || a.ndim() != array.ndim() || !std::equal(a.shape(), a.shape() + a.ndim(), array.shape())) {
                throw vdb_ewa::ValueError(std::string(kind) + ": expected an array of the density's shape");
            }
            grid = withArrayEmitter(grid, a, indexToWorld, kind);
        }
        if (!velocity.is_none()) {
            const py::array v = py::array::ensure(velocity);
            if (!v || v.ndim() != 4 || !std::equal(array.shape(), array.shape() + array.ndim(), v.shape()) || v.shape(3) != 3) {
                throw vdb_ewa::ValueError("velocity: expected an array of the density's shape and 3 components, [i, j, k, xyz]");
            }
            grid = withArrayVelocity(grid, v, indexToWorld);
        }
        return grid;
    }, py::arg("array"), py::arg("index_to_world") = py::none(), py::arg("name") = "density", py::kw_only(),
        py::arg("emission") = py::none(), py::arg("temperature") = py::none(), py::arg("velocity") = py::none(),
        "A fog volume from a 3D numpy array: voxel (i, j, k) holds array[i, j, k] (pyopenvdb's copyFromArray\n"
        "layout); values equal to 0 are inactive.\n\n"
        "Args:\n"
        "    array: 3D array of numbers (converted to float32).\n"
        "    index_to_world: 4x4 matrix, column vectors: world = M @ (i, j, k, 1) (numpy's and Blender's\n"
        "        convention; OpenVDB's row-vector matrix is its transpose); affine and invertible. None: identity.\n"
        "    name: the grid's name.\n"
        "    emission: None, or an array of the same layout: an emission grid (render's emission_color and\n"
        "        emission_intensity), as --emission-grid.\n"
        "    temperature: None, or an array of temperatures: blackbody emission, as --temperature.\n"
        "    velocity: None, or an array of the density's shape and 3 components ([i, j, k, xyz]): motion blur, the\n"
        "        vectors in world units per second or frame (render's velocity_unit), as --velocity-grid.\n\n"
        "Raises vdb_ewa.ValueError for a wrong shape or matrix.");

    py::class_<CancelToken, std::shared_ptr<CancelToken>>(m, "CancelToken",
        "Cancels a render from any thread: pass it as render(..., cancel=token), call token.cancel().")
        .def(py::init<>())
        .def("cancel", [](CancelToken& t) { t.cancelled.store(true); }, "Stop the render that holds this token (any thread).")
        .def("reset", [](CancelToken& t) { t.cancelled.store(false); }, "Clear the cancellation, to use the token again.")
        .def_property_readonly("cancelled", [](const CancelToken& t) { return t.cancelled.load(); }, "True once cancel() was called.");

    py::class_<RenderedFrame, std::shared_ptr<RenderedFrame>>(m, "Frame",
        "A rendered frame. Arrays are read-only float32 views in output_space, as the EXR holds them (at float "
        "precision: exr_type only affects write()).")
        .def_property_readonly("width", [](const RenderedFrame& f) { return f.output.beauty.width; })
        .def_property_readonly("height", [](const RenderedFrame& f) { return f.output.beauty.height; })
        .def_property_readonly("beauty", [](const py::object& self) {
            const auto& f = self.cast<const RenderedFrame&>().output.beauty;
            return view(f.rgba, f.width, f.height, 4, self);
        }, "(height, width, 4) float32: premultiplied RGBA, row 0 at the top, black background.")
        .def_property_readonly("aovs", &aovs,
            "Dict of the passes by name: 'depth' (height, width): camera depth where alpha reaches 0.5, inf where it "
            "never does; 'transmittance', 'shadow', 'emission' (height, width, 3) when asked for by aov= "
            "(docs/output.md).")
        .def("aov", [](const py::object& self, const std::string& name) {
            const py::dict d = aovs(self);
            if (!d.contains(name)) {
                std::string names;
                for (const auto& [k, v] : d) names += (names.empty() ? "" : ", ") + k.cast<std::string>();
                throw vdb_ewa::ValueError("aov: '" + name + "' was not rendered (this frame has " + names + "; aov= asks for passes)");
            }
            return py::object(d[py::str(name)]); // not the accessor: it would outlive d
        }, py::arg("name"), "The pass called name (see aovs); vdb_ewa.ValueError if it was not rendered.")
        .def_property_readonly("stats", [](const RenderedFrame& f) { return statsOf(f.stats); }, "Counts and stage timings (seconds).")
        .def_property_readonly("coarse", [](const RenderedFrame& f) { return f.stats.coarseScale > 1; },
            "True for a progressive render's coarse image (Scene.render(progressive=...)): draft's knobs at one sample an\n"
            "n x n block of pixels (stats['coarse_scale'] = n), interpolated back to the frame's width and height.")
        .def_property_readonly("warnings", [](const RenderedFrame& f) { return f.warnings; }, "The render's warnings, one line each.")
        .def_property_readonly("render_seconds", [](const RenderedFrame& f) { return f.seconds; }, "From the call to the frame, seconds.")
        .def_property_readonly("metadata", [](const RenderedFrame& f) {
            py::dict d;
            for (const auto& [k, v] : f.metadata()) d[py::str(k)] = v;
            return d;
        }, "The EXR header's attributes: every resolved option as vdb_ewa/NAME, the camera record, the software.")
        .def("write", [](const RenderedFrame& f, const py::object& path) {
            const std::string p = py::module_::import("os").attr("fspath")(path).cast<std::string>();
            py::gil_scoped_release release;
            f.write(p);
        }, py::arg("path"),
            "Write the frame as vdb_ewa render would: the format by the extension (.exr with Z and the passes, .png,\n"
            ".jpg, .tif, .ppm through display and view, .hdr), exr_type, compression and preview from the render's\n"
            "options, the same header; written whole or not at all. Raises vdb_ewa.IoError or vdb_ewa.ValueError.")
        .def("__repr__", [](const RenderedFrame& f) {
            return "<vdb_ewa.Frame " + std::to_string(f.output.beauty.width) + "x" + std::to_string(f.output.beauty.height) + ">";
        });

    m.def("render", [](const py::object& grid, const py::object& progress, const py::object& cancel, const py::kwargs& kwargs) {
        std::shared_ptr<RenderedFrame> frame = render(grid, progress, cancelToken(cancel), kwargs);
        warnAll(frame->warnings);
        return frame;
    }, py::arg("grid"), py::kw_only(), py::arg("progress") = py::none(), py::arg("cancel") = py::none(), renderDoc().c_str());

    py::class_<SceneCall, std::shared_ptr<SceneCall>>(m, "Scene",
        "A grid that stays loaded, rendered from camera after camera (a viewport, a turntable): Scene(grid, **options)\n"
        "takes a Grid or a path and render()'s keywords; render(**options) overrides them for one render. What\n"
        "the renders can share they share (today the light maps, with the rays marched: Frame.stats says\n"
        "light_maps_reused and light_rays_reused); each frame is the frame render() makes with the same\n"
        "keywords, bit for bit (docs/api.md#scenes-what-a-render-reuses). One render at a time per scene.")
        .def(py::init([](const py::object& grid, const py::kwargs& kwargs) { return std::make_shared<SceneCall>(grid, kwargs); }),
            py::arg("grid"), "Open the grid (a path with name=, color=, emission_grid=, temperature=, velocity_grid=, or a Grid)\n"
            "and keep render()'s keywords. Raises vdb_ewa.ValueError, vdb_ewa.IoError as render().")
        .def("render", [](SceneCall& scene, const py::object& progress, const py::object& cancel, const py::object& progressive,
                           const py::kwargs& kwargs) {
            std::shared_ptr<RenderedFrame> frame = scene.render(progress, cancelToken(cancel), progressive, kwargs);
            warnAll(frame->warnings);
            return frame;
        }, py::kw_only(), py::arg("progress") = py::none(), py::arg("cancel") = py::none(), py::arg("progressive") = py::none(),
            "Render with the scene's keywords, updated by these (camera, quality, lights...; not the grid keywords):\n"
            "a Frame, as vdb_ewa.render() returns. progress and cancel as render()'s.\n"
            "progressive: None, or a callable f(frame) called on this thread with a coarse Frame first (frame.coarse:\n"
            "draft's knobs at one sample a 4x4 block of pixels, interpolated to the full size; images under 32 pixels a\n"
            "side have none), then with the Frame render() returns: what a viewport draws while the user drags. f\n"
            "returning True for the coarse image cancels the rest (vdb_ewa.Cancelled), as cancel= does at any time.\n"
            "progress then runs over both: the coarse image is its first 10 percent.")
        .def("clear", [](SceneCall& scene) {
            py::gil_scoped_release release; // waits for a render of the scene on another thread
            scene.scene->clear();
        }, "Let go of what the renders kept: the next render starts cold.")
        .def_property_readonly("options", [](const SceneCall& scene) { return py::dict(scene.options); },
            "The keywords the scene was made with.")
        .def("__repr__", [](const SceneCall& scene) {
            return "<vdb_ewa.Scene of " + (scene.input.empty() ? scene.grid->name() : scene.input) + ">";
        });

    m.def("set_exr_threads", &setExrThreadsProcessWide, py::arg("threads") = 0,
        "Let OpenEXR compress written files with this many threads (0: all cores), as the CLI does. Process-wide\n"
        "(OpenEXR's global thread pool): for standalone scripts, not inside a DCC whose own EXR I/O shares it.\n"
        "Without it, Frame.write() compresses on OpenEXR's default pool (none: one thread).");
    m.def("_keywords", [] {
        py::list out;
        for (const KeywordInfo& k : renderKeywords()) out.append(py::make_tuple(k.keyword, k.option, k.type, k.description));
        return out;
    }, "render()'s option keywords as (keyword, option, type, description): python/make_stub.py writes vdb_ewa.pyi from them.");
}
