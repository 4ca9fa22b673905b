"""Run inside Blender (blender -b --factory-startup --python blender_scene.py -- PARAMS.json): build
the test scene from PARAMS (two interpenetrating volume objects loading a .vdb file, each with a
transform and a Principled Volume of its own, the first moving by its velocity grid under the scene's
motion blur; a camera with depth of field aimed at a point; a sun and a spot light), render it with PARAMS["engine"] and save Blender's own
render result as a float EXR and as a PNG (Standard view)."""
import json
import math
import os
import sys
import time

import bpy
import mathutils

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from blender_materials import principled_volume  # noqa: E402

params = json.load(open(sys.argv[sys.argv.index("--") + 1]))

bpy.ops.wm.read_factory_settings(use_empty=True)
scene = bpy.context.scene
if params["engine"] == "VDB_EWA":
    sys.path.insert(0, params["addon_dir"])
    import vdb_ewa_render
    vdb_ewa_render.register()
    # The panel's Options field: items split at the commas before a keyword=.
    parsed = vdb_ewa_render.parse_extra_options("lod=0, ambient=0.1,0.1,0.1, deep=true, aov=shadow,emission, slab=0.5")
    assert parsed == dict(lod=0, ambient="0.1,0.1,0.1", deep=True, aov="shadow,emission", slab=0.5), parsed
    scene.vdb_ewa.quality = params.get("quality", "default")
scene.render.engine = params["engine"]
scene.render.resolution_x, scene.render.resolution_y = params["res"]
scene.render.resolution_percentage = 100
scene.render.film_transparent = True
scene.view_settings.view_transform = "Standard"
scene.view_settings.look = "None"
if params["engine"] == "CYCLES":
    scene.cycles.samples = params["cycles_samples"]
    scene.cycles.seed = params.get("cycles_seed", 0)
    scene.cycles.use_denoising = False
    scene.cycles.volume_bounces = 0  # single scattering, as vdb_ewa's
else:
    scene.cycles.volume_bounces = params["volume_bounces"]  # --multiple-scattering (docs/blender.md)
    scene.cycles.volume_step_rate = params.get("cycles_step_rate", 1.0)
    scene.cycles.device = "CPU"
    scene.render.threads_mode = "FIXED"
    scene.render.threads = 2

# The first object moves: its file holds a velocity grid (Blender's default name), in world units
# per second of its object space, scaled; the scene's motion blur is on (Cycles' default shutter).
moving = bpy.data.volumes.new("moving")
moving.filepath = params["moving_asset"]
moving.velocity_grid = "velocity"
moving.velocity_unit = "SECOND"
moving.velocity_scale = params["velocity_scale"]
scene.render.use_motion_blur = True
scene.render.motion_blur_shutter = params["shutter"]
scene.render.fps, scene.render.fps_base = params["fps"], 1.0
obj = bpy.data.objects.new("asset", moving)
scene.collection.objects.link(obj)
obj.matrix_world = mathutils.Matrix(params["object_to_world"])
# A second volume object of the same asset, still, interpenetrating the first, with a material
# of its own.
volume = bpy.data.volumes.new("asset")
volume.filepath = params["asset"]
second = bpy.data.objects.new("asset.second", volume)
scene.collection.objects.link(second)
second.matrix_world = mathutils.Matrix(params["second_object_to_world"])
volume.materials.append(principled_volume("volume.second", params["grid"], params["second_density"], params["second_color"], params["second_absorption_color"],
                                          params["anisotropy"]))
moving.materials.append(principled_volume("volume", params["grid"], params["density"], params["color"], params["absorption_color"], params["anisotropy"]))

camera_data = bpy.data.cameras.new("camera")
camera_data.lens = params["focal"]
camera_data.sensor_width = params["sensor"]
camera_data.clip_start, camera_data.clip_end = params["clip"]
camera = bpy.data.objects.new("camera", camera_data)
scene.collection.objects.link(camera)
eye, target = mathutils.Vector(params["eye"]), mathutils.Vector(params["target"])
camera.matrix_world = mathutils.Matrix.LocRotScale(eye, (target - eye).to_track_quat("-Z", "Y"), None)
scene.camera = camera
camera_data.dof.use_dof = True
camera_data.dof.aperture_fstop = params["fstop"]
camera_data.dof.focus_distance = params["focus_distance"]

sun_data = bpy.data.lights.new("sun", "SUN")
sun_data.energy = params["sun_strength"]
sun_data.color = params["sun_color"]
sun = bpy.data.objects.new("sun", sun_data)
scene.collection.objects.link(sun)
sun.matrix_world = mathutils.Matrix.LocRotScale(None, mathutils.Vector(params["sun_direction"]).to_track_quat("Z", "Y"), None)

spot_data = bpy.data.lights.new("spot", "SPOT")
spot_data.energy = params["spot_power"]
spot_data.color = params["spot_color"]
spot_data.spot_size = math.radians(params["spot_angle"])
spot_data.spot_blend = params["spot_blend"]
spot_data.shadow_soft_size = params["spot_radius"]
spot = bpy.data.objects.new("spot", spot_data)
scene.collection.objects.link(spot)
spot_at, spot_to = mathutils.Vector(params["spot_position"]), mathutils.Vector(params["target"])
spot.matrix_world = mathutils.Matrix.LocRotScale(spot_at, (spot_to - spot_at).to_track_quat("-Z", "Y"), None)

t0 = time.monotonic()
bpy.ops.render.render()
print("blender_scene: %s rendered in %.3f s" % (params["engine"], time.monotonic() - t0))
result = bpy.data.images["Render Result"]
settings = scene.render.image_settings
settings.file_format, settings.color_depth, settings.color_mode = "OPEN_EXR", "32", "RGBA"
result.save_render(params["exr"])
settings.file_format, settings.color_depth, settings.color_mode = "PNG", "8", "RGBA"
result.save_render(params["png"])

if params["engine"] == "VDB_EWA":
    # Progress and Esc: an engine whose test_break() turns true after its second progress report
    # (Esc in the UI) must stop the render at once; the reports must rise.
    # The add-on's render functions on an engine of its own (a subclass of a registered engine
    # would take over its RNA type).
    class CancellingEngine(bpy.types.RenderEngine):
        bl_idname = "VDB_EWA_CANCEL_TEST"
        bl_label = "vdb_ewa (cancel test)"
        render = vdb_ewa_render.VdbEwaRenderEngine.render
        report_frame = vdb_ewa_render.VdbEwaRenderEngine.report_frame
        reports = []

        def report_progress(self, value):  # RNA's update_progress cannot be overridden
            CancellingEngine.reports.append(value)
            self.update_progress(value)

        def cancel_requested(self):
            return len(CancellingEngine.reports) >= 2

    bpy.utils.register_class(CancellingEngine)
    scene.render.engine = "VDB_EWA_CANCEL_TEST"
    scene.vdb_ewa.quality = "final"  # long enough to be cancelled midway
    t0 = time.monotonic()
    bpy.ops.render.render()
    cancelled_seconds = time.monotonic() - t0
    scene.vdb_ewa.quality = "default"
    scene.render.engine = "VDB_EWA"
    t0 = time.monotonic()
    bpy.ops.render.render()
    full_seconds = time.monotonic() - t0
    with open(params["exr"] + ".progress.json", "w") as f:
        json.dump(dict(cancelled_reports=CancellingEngine.reports, cancelled_seconds=cancelled_seconds, full_seconds=full_seconds), f)
