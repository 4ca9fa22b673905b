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
import numpy as np

from . import scene_mapping

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


class VdbEwaSettings(bpy.types.PropertyGroup):
    quality: bpy.props.EnumProperty(
        name="Quality", default='default',
        items=[('draft', "Draft", "vdb_ewa --quality draft"), ('default', "Default", "vdb_ewa's defaults"),
               ('high', "High", "vdb_ewa --quality high"), ('final', "Final", "vdb_ewa --quality final: refined kernels")])
    extra_options: bpy.props.StringProperty(
        name="Options", description="More vdb_ewa render options as keyword=value, comma-separated "
                                    "(lod=0, refine=2, ambient=0.1,0.1,0.1); they override the scene's; "
                                    "help(vdb_ewa.render) lists them")


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


def render_options(depsgraph, warnings):
    """The options every volume of the frame shares: camera, lights, colour spaces, quality."""
    scene = depsgraph.scene
    options = scene_mapping.camera_options(scene, warnings)
    options["light"] = scene_mapping.light_options(depsgraph, warnings) or [(0.0, 0.0, 1.0, 0.0, 0.0, 0.0)]
    options.update(scene_mapping.point_light_options(depsgraph, warnings))
    options.update(scene_mapping.motion_options(scene))
    # Blender's scene-linear space is linear Rec.709; render and return it there.
    # Cycles' attenuation: shadows fall as exp(-optical depth), without vdb_render's --gain.
    options["gain"] = 0.0
    options["working_space"] = "lin_rec709"
    options["output_space"] = "lin_rec709"
    options["quality"] = scene.vdb_ewa.quality
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


def over(front, back):
    """Premultiplied front over back."""
    return front + back * (1.0 - front[..., 3:4])


class VdbEwaRenderEngine(bpy.types.RenderEngine):
    bl_idname = "VDB_EWA"
    bl_label = "vdb_ewa"
    bl_use_preview = False
    bl_use_eevee_viewport = True
    bl_use_postprocess = True

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
        except ValueError as e:
            self.report({'ERROR'}, "vdb_ewa: %s" % e)
            return
        image = np.zeros((height, width, 4), np.float32)
        merged = None
        if len(volumes) > 1 and mergeable(volumes):
            try:
                merged = MergedVolumes(volumes).render_input(vdb_ewa)
            except vdb_ewa.Error as e:
                self.report({'ERROR'}, "vdb_ewa: %s" % e)
                return
            if merged is not None:
                volumes = [MergedVolumes(volumes)]
        if len(volumes) > 1:
            warnings.append("volumes moving in different velocity units or scales, or glowing with different Temperature or "
                            "Blackbody Intensity per voxel, are composited one over the other: wrong where they interpenetrate")
        for index, volume in enumerate(volumes):
            self.update_stats("vdb_ewa", "volume %s (%d of %d)" % (volume.name, index + 1, len(volumes)))

            def progress(percent, index=index):
                self.report_progress((index + percent / 100.0) / len(volumes))
                return self.cancel_requested()

            try:
                grid, material = merged if isinstance(volume, MergedVolumes) else volume_options(vdb_ewa, volume)
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
    _panels(False)
    del bpy.types.Scene.vdb_ewa
    for cls in reversed(_CLASSES):
        bpy.utils.unregister_class(cls)
