"""vdb_ewa as a Blender render engine: the scene's OpenVDB volume objects rendered in-process by
vdb_ewa's library (its Python module), from the scene camera at the scene's resolution, lit by
its sun lights. docs/blender.md."""
bl_info = {
    "name": "vdb_ewa",
    "author": "vdb_ewa",
    "version": (0, 1, 0),
    "blender": (3, 4, 0),
    "location": "Render Properties > Render Engine > vdb_ewa",
    "description": "EWA volume splatting of OpenVDB volume objects (vdb_ewa's library, in-process)",
    "category": "Render",
}

import os
import re
import sys

import bpy
import mathutils
import numpy as np

from . import scene_mapping, viewport

# Cycles' and EEVEE's panels that apply to vdb_ewa too: the output size, the camera, lights, volumes.
_SHARED_PANELS = ("RENDER_PT_format", "RENDER_PT_frame_range", "DATA_PT_lens", "DATA_PT_camera", "DATA_PT_light",
                  "DATA_PT_EEVEE_light", "DATA_PT_volume_file", "DATA_PT_volume_grids", "EEVEE_MATERIAL_PT_volume")


def import_vdb_ewa():
    """The vdb_ewa module: from $VDB_EWA_PYTHONPATH, the add-on's preference, or Python's path."""
    for folder in (os.environ.get("VDB_EWA_PYTHONPATH", ""), _preferences().module_path if _preferences() else ""):
        if folder and folder not in sys.path:
            sys.path.insert(0, bpy.path.abspath(folder))
    import vdb_ewa
    return vdb_ewa


def _preferences():
    addon = bpy.context.preferences.addons.get(__name__)
    return addon.preferences if addon else None


class VdbEwaPreferences(bpy.types.AddonPreferences):
    bl_idname = __name__
    module_path: bpy.props.StringProperty(
        name="vdb_ewa module folder", subtype='DIR_PATH',
        description="Folder holding the vdb_ewa Python module (empty: Python's path, where scripts/setup.sh "
                    "and the Debian package install it: /usr/local/lib/python3.11/dist-packages, "
                    "/usr/lib/python3/dist-packages)")

    def draw(self, context):
        self.layout.prop(self, "module_path")


def _settings_changed(settings, context):
    """A depsgraph update of the settings' scene, so the Rendered viewport's view_update sees them
    (a property of an add-on's own tags nothing)."""
    settings.id_data.update_tag()


class VdbEwaSettings(bpy.types.PropertyGroup):
    quality: bpy.props.EnumProperty(
        name="Quality", default='default', update=_settings_changed,
        items=[('draft', "Draft", "vdb_ewa --quality draft"), ('default', "Default", "vdb_ewa's defaults"),
               ('high', "High", "vdb_ewa --quality high"), ('final', "Final", "vdb_ewa --quality final: refined kernels")])
    extra_options: bpy.props.StringProperty(
        name="Options", update=_settings_changed,
        description="More vdb_ewa render options as keyword=value, comma-separated "
                    "(lod=0, refine=2, ambient=0.1,0.1,0.1); they override the scene's; help(vdb_ewa.render) lists them")


class RENDER_PT_vdb_ewa(bpy.types.Panel):
    bl_label = "vdb_ewa"
    bl_space_type = 'PROPERTIES'
    bl_region_type = 'WINDOW'
    bl_context = "render"
    COMPAT_ENGINES = {"VDB_EWA"}

    @classmethod
    def poll(cls, context):
        return context.engine in cls.COMPAT_ENGINES

    def draw(self, context):
        settings = context.scene.vdb_ewa
        self.layout.prop(settings, "quality")
        self.layout.prop(settings, "extra_options")


def parse_extra_options(text):
    """'lod=0, refine=2, ambient=0.1,0.1,0.1, deep=true' as keyword arguments: items split at the
    commas before a keyword=, numbers where they parse, true/false as booleans, the rest strings
    (X,Y,Z values stay strings, as on the command line)."""
    options = {}
    for item in filter(None, (part.strip() for part in re.split(r",(?=\s*[A-Za-z_]+\s*=)", text))):
        key, sep, value = item.partition("=")
        if not sep:
            raise ValueError("vdb_ewa options: expected keyword=value, got '%s'" % item)
        key, value = key.strip(), value.strip()
        if value.lower() in ("true", "false"):
            options[key] = value.lower() == "true"
            continue
        try:
            options[key] = float(value) if any(c in value for c in ".eE") else int(value)
        except ValueError:
            options[key] = value
    return options


def shading_options(depsgraph, warnings):
    """The options every render of the scene shares, F12's and the viewport's: lights, shadows,
    colour spaces, quality."""
    scene = depsgraph.scene
    options = dict(light=scene_mapping.light_options(depsgraph, warnings) or [(0.0, 0.0, 1.0, 0.0, 0.0, 0.0)])
    options.update(scene_mapping.point_light_options(depsgraph, warnings))
    options.update(scene_mapping.scattering_options(scene))
    # Blender's scene-linear space is linear Rec.709; render and return it there.
    # Cycles' attenuation: shadows fall as exp(-optical depth), without vdb_render's --gain.
    options["gain"] = 0.0
    options["working_space"] = "lin_rec709"
    options["output_space"] = "lin_rec709"
    options["quality"] = scene.vdb_ewa.quality
    return options


def render_options(depsgraph, warnings):
    """The options every volume of an F12 frame shares: the scene camera, its motion blur and the
    shading."""
    scene = depsgraph.scene
    options = scene_mapping.camera_options(scene, warnings)
    options.update(shading_options(depsgraph, warnings))
    options.update(scene_mapping.motion_options(scene))
    return options


def volume_options(vdb_ewa, volume):
    """The grid of @a volume, moved by its object's transform (with its velocity grid, which moves
    with it), and its material per voxel length."""
    grid = vdb_ewa.open(volume.path, volume.density_grid).transformed(volume.object_to_world)
    if volume.motion:
        grid = grid.with_velocity_grid(volume.motion["velocity_grid"])
    length = grid.voxel_length
    options = dict(volume.options)
    options["scatter"] = tuple(c * length for c in options["scatter"])
    options["absorb"] = tuple(c * length for c in options["absorb"])
    if "color_grid" in options:
        options["color"] = options.pop("color_grid")
    if "blackbody_intensity" in options:
        options["blackbody_intensity"] *= length
    if volume.motion:
        options.update(velocity_unit=volume.motion["velocity_unit"], velocity_scale=volume.motion["velocity_scale"])
    return grid, options


BLACKBODY_OPTIONS = ("temperature_scale", "blackbody_intensity")


def mergeable(volumes):
    """Volume objects that one field can hold, each with its own material (Grid.with_added_volume's
    absorb and scatter, its colour and temperature grids attached to it): the moving ones'
    velocities in the same unit and scale (the sum moves with their velocities weighted by their
    densities), and the blackbody options of those with a temperature grid the same per voxel
    length (the frame has one Temperature and Blackbody Intensity)."""
    motions = {(m["velocity_unit"], m["velocity_scale"]) for m in (v.motion for v in volumes) if m}
    return len(motions) <= 1


class MergedVolumes:
    """Volume objects in one field (Grid.with_added_volume), each with its own material where it
    differs from the first's: one front-to-back sweep, so they hide and shadow each other where
    they interpenetrate."""

    def __init__(self, volumes):
        self.volumes = volumes
        self.name = "+".join(v.name for v in volumes)
        self.path = volumes[0].path
        self.object_to_world = "each its own"
        self.centre = volumes[0].centre

    def render_input(self, vdb_ewa):
        """The summed grid on the finest volume's voxels, and the first volume's material per its
        voxel length; the others' materials go with their grids. None where two blackbody
        volumes' options differ per voxel length (they cannot share the frame's): each is then
        rendered alone and composited."""
        inputs = sorted((volume_options(vdb_ewa, v) for v in self.volumes), key=lambda gm: gm[0].voxel_length)
        grid, material = inputs[0]
        material = dict(material)
        for other, own in inputs[1:]:
            for key in ("velocity_unit", "velocity_scale"):  # a moving volume's, where the first stands still
                if key in own:
                    material.setdefault(key, own[key])
            if "temperature" in own:
                blackbody = {k: own[k] for k in BLACKBODY_OPTIONS}
                if "temperature" in material and any(abs(material[k] - v) > 1e-9 * abs(v) for k, v in blackbody.items()):
                    return None
                material.update(blackbody)
            shared = all(own[k] == material[k] for k in ("absorb", "scatter")) and "color" not in own and "temperature" not in own
            if shared:
                grid = grid.with_added_volume(other)  # with its velocities (volume_options attached them)
                continue
            if "color" in own:
                other = other.with_color_grid(own["color"])
            if "temperature" in own:
                other = other.with_temperature_grid(own["temperature"])
            grid = grid.with_added_volume(other, absorb=own["absorb"], scatter=own["scatter"], emission=0.0)
        return grid, material


def render_inputs(vdb_ewa, volumes, warnings):
    """What to render for @a volumes (nearest first): [(volume, grid, material)], one summed field
    (MergedVolumes) where they can share one, else each alone, nearest first, to composite with
    over(). Raises ValueError naming the volume where its grid cannot be read."""
    try:
        if len(volumes) > 1 and mergeable(volumes):
            merged = MergedVolumes(volumes)
            summed = merged.render_input(vdb_ewa)
            if summed is not None:
                return [(merged, *summed)]
    except vdb_ewa.Error as e:
        raise ValueError(str(e)) from e
    if len(volumes) > 1:
        warnings.append("volumes moving in different velocity units or scales, or glowing with different Temperature or "
                        "Blackbody Intensity per voxel, are composited one over the other: wrong where they interpenetrate")
    inputs = []
    for volume in volumes:
        try:
            inputs.append((volume, *volume_options(vdb_ewa, volume)))
        except vdb_ewa.Error as e:
            raise ValueError("volume %s: %s" % (volume.name, e)) from e
    return inputs


def over(front, back):
    """Premultiplied front over back."""
    return front + back * (1.0 - front[..., 3:4])


def viewport_scenes(vdb_ewa, volumes, grid_keywords):
    """A vdb_ewa.Scene for each render input of @a volumes, made with its material and the grid
    keywords of the panel's Options: [(centre, Scene)]. Raises ValueError, vdb_ewa.Error."""
    return [(volume.centre, vdb_ewa.Scene(grid, **{**material, **grid_keywords}))  # Options override, as for F12
            for volume, grid, material in render_inputs(vdb_ewa, volumes, [])]


class VdbEwaRenderEngine(bpy.types.RenderEngine):
    bl_idname = "VDB_EWA"
    bl_label = "vdb_ewa"
    bl_use_preview = False
    bl_use_eevee_viewport = False  # Rendered shading: view_update and view_draw below
    bl_use_postprocess = True

    def __init__(self):
        self._viewport = None  # viewport.Session of the 3D view this engine draws, made by view_update
        self._scene_key = None  # what the session's scenes were made of
        self._shading = {}  # per-render keywords from the scene: lights, quality
        self._extra = {}  # the panel's Options, but the grid keywords (they go to the scenes)
        self._error = None  # what the view shows instead of an image
        self._shown = None  # the text the view shows (update_stats), to set it once
        self._warned = set()  # the scene mapping's warnings printed, each once

    def __del__(self):
        if getattr(self, "_viewport", None) is not None:
            self._viewport.stop()

    def render(self, depsgraph):
        scene = depsgraph.scene
        width, height = scene_mapping.resolution(scene)
        result = self.begin_result(0, 0, width, height)
        try:
            self.report_frame(depsgraph, result, width, height)
        finally:
            self.end_result(result)

    def report_progress(self, value):
        """Blender's progress bar (the status bar), 0 to 1."""
        self.update_progress(value)

    def cancel_requested(self):
        """Esc: Blender's test_break()."""
        return self.test_break()

    def view_update(self, context, depsgraph):
        """The scene changed (and the view was switched to Rendered): the per-render keywords
        anew; the scenes anew where the volumes, their data or materials changed (a key of what
        they are made of), the session's light maps kept otherwise. Runs on the main thread."""
        self._error = None
        try:
            vdb_ewa = import_vdb_ewa()
        except ImportError as e:
            self._error = "the Python module is not found (%s): set the add-on's module folder" % e
            return
        warnings = []
        try:
            scene = depsgraph.scene
            shading = shading_options(depsgraph, warnings)
            grid_keywords, extra = viewport.split_grid_keywords(parse_extra_options(scene.vdb_ewa.extra_options))
            # No motion blur in the viewport, as in Cycles'; each render orders several volumes from its own eye.
            volumes = scene_mapping.volumes(depsgraph, mathutils.Vector(), warnings, motion_blur=False)
        except ValueError as e:
            self._error = str(e)
            return
        if not volumes:
            self._error = "no volume object with an OpenVDB file to render"
            return
        if self._viewport is None:
            self._viewport = viewport.Session(vdb_ewa, over)
        key = repr([(v.path, v.density_grid, v.object_to_world, sorted(v.options.items())) for v in volumes]
                   + sorted(grid_keywords.items()))
        if key != self._scene_key:
            self._scene_key = key
            self._viewport.set_scene(lambda: viewport_scenes(vdb_ewa, volumes, grid_keywords))
        self._shading, self._extra = shading, extra
        self.warn(warnings)

    def view_draw(self, context, depsgraph):
        """Draw the newest image of the view and, where the view changed, ask for one of the new
        view (the running render of the old one is cancelled). Runs on the main thread."""
        region = context.region
        error = self._error
        if error is None and self._viewport is not None:
            warnings = []
            try:
                camera = scene_mapping.viewport_camera_options(depsgraph.scene, context.space_data, context.region_data,
                                                               region.width, region.height, warnings)
                self._viewport.request({**self._shading, **camera, **self._extra}, camera["translate"])
            except ValueError as e:
                error = str(e)
            self.warn(warnings)
        image, render_error = self._viewport.take() if self._viewport is not None else (None, None)
        error = error or render_error
        if error is None and image is not None:
            image.draw(self, depsgraph.scene, region.width, region.height)
            image.record()
        self.show("vdb_ewa: " + error if error else "")

    def warn(self, warnings):
        """The scene mapping's warnings on the console, each once."""
        for w in warnings:
            if w not in self._warned:
                self._warned.add(w)
                print("vdb_ewa warning: " + w, flush=True)

    def show(self, text):
        """@a text in the view's corner (update_stats) and once on the console."""
        if text != self._shown:
            self._shown = text
            self.update_stats("", text)
            if text:
                print(text, flush=True)

    def report_frame(self, depsgraph, result, width, height):
        try:
            vdb_ewa = import_vdb_ewa()
        except ImportError as e:
            self.report({'ERROR'}, "vdb_ewa: the Python module is not found (%s): set the add-on's module folder" % e)
            return
        warnings = []
        try:
            options = render_options(depsgraph, warnings)
            extra = parse_extra_options(depsgraph.scene.vdb_ewa.extra_options)
            volumes = scene_mapping.volumes(depsgraph, depsgraph.scene.camera.matrix_world.translation, warnings)
            inputs = render_inputs(vdb_ewa, volumes, warnings)
        except ValueError as e:
            self.report({'ERROR'}, "vdb_ewa: %s" % e)
            return
        image = np.zeros((height, width, 4), np.float32)
        for index, (volume, grid, material) in enumerate(inputs):
            self.update_stats("vdb_ewa", "volume %s (%d of %d)" % (volume.name, index + 1, len(inputs)))

            def progress(percent, index=index):
                self.report_progress((index + percent / 100.0) / len(inputs))
                return self.cancel_requested()

            try:
                call = {**options, **material, **extra}  # the panel's Options override the scene's
                if os.environ.get("VDB_EWA_VERBOSE"):
                    print("vdb_ewa: volume %s: %s moved by %s: %s" % (volume.name, volume.path, volume.object_to_world, call))
                frame = vdb_ewa.render(grid, progress=progress, **call)
            except vdb_ewa.Cancelled:
                return
            except vdb_ewa.Error as e:
                self.report({'ERROR'}, "vdb_ewa: volume %s: %s" % (volume.name, e))
                return
            warnings.extend(frame.warnings)
            image = over(image, frame.beauty)  # nearest first (by their centres)
        for w in warnings:
            self.report({'WARNING'}, "vdb_ewa: " + w)
        # Blender's rows run bottom to top.
        result.layers[0].passes["Combined"].rect = image[::-1].reshape(-1, 4)


def _panels(add):
    for name in _SHARED_PANELS:
        panel = getattr(bpy.types, name, None)
        if panel is not None and hasattr(panel, "COMPAT_ENGINES"):
            (panel.COMPAT_ENGINES.add if add else panel.COMPAT_ENGINES.discard)("VDB_EWA")


_CLASSES = (VdbEwaPreferences, VdbEwaSettings, RENDER_PT_vdb_ewa, VdbEwaRenderEngine)


def register():
    for cls in _CLASSES:
        bpy.utils.register_class(cls)
    bpy.types.Scene.vdb_ewa = bpy.props.PointerProperty(type=VdbEwaSettings)
    _panels(True)


def unregister():
    viewport.stop_all()
    _panels(False)
    del bpy.types.Scene.vdb_ewa
    for cls in reversed(_CLASSES):
        bpy.utils.unregister_class(cls)
