"""Run inside Blender with a window (xvfb-run blender --factory-startup --python viewport_scene.py --
PARAMS.json; not -b): the add-on's Rendered viewport. Builds a scene (a volume object of PARAMS'
asset with a Principled Volume, a camera aimed at it, a sun), leaves one 3D view of PARAMS["region"]
pixels (no overlays, no header), switches it to Rendered shading, then from bpy.app.timers orbits
the view PARAMS["orbits"] times, makes it orthographic, looks through the camera, and F12-renders the camera's view at the
region's size. After each view's refined image it takes a screenshot. Writes PARAMS["out"]/viewport.json:
the engine's records (viewport.RECORDS: every image drawn, coarse and refined, with its times), the
times of the view changes, the screenshots and the 3D view's rectangle in them; exits 1 on a timeout."""
import json
import math
import os
import sys
import time
import traceback

import bpy
import mathutils

params = json.load(open(sys.argv[sys.argv.index("--") + 1]))
out = lambda name: os.path.join(params["out"], name)
WAIT_SECONDS = params.get("wait_seconds", 30.0)

bpy.ops.wm.read_factory_settings(use_empty=True)
bpy.context.preferences.view.show_splash = False  # it would cover the view (read after this script)
# A plain background (the theme's radial gradient otherwise), to composite F12's image over.
bpy.context.preferences.themes[0].view_3d.space.gradients.background_type = 'SINGLE_COLOR'
sys.path.insert(0, params["addon_dir"])
sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import vdb_ewa_render  # noqa: E402
from blender_materials import principled_volume  # noqa: E402
vdb_ewa_render.register()
RECORDS = vdb_ewa_render.viewport.RECORDS

scene = bpy.context.scene
scene.render.engine = "VDB_EWA"
scene.vdb_ewa.quality = params["quality"]
scene.render.resolution_percentage = 100
scene.render.film_transparent = False  # the view's background plain (a checker board otherwise)
scene.render.dither_intensity = 0.0
scene.view_settings.view_transform = "Standard"
scene.view_settings.look = "None"

data = bpy.data.volumes.new("pyro")
data.filepath = params["asset"]
volume = bpy.data.objects.new("pyro", data)
scene.collection.objects.link(volume)
data.materials.append(principled_volume("smoke", params["grid"], params["density"], params["color"]))

sun_data = bpy.data.lights.new("sun", "SUN")
sun_data.energy = params["sun_strength"]
sun = bpy.data.objects.new("sun", sun_data)
scene.collection.objects.link(sun)
sun.matrix_world = mathutils.Matrix.LocRotScale(None, mathutils.Vector(params["sun_direction"]).to_track_quat("Z", "Y"), None)

# The volume's bounds (Blender's, in the world) frame the camera and the view.
bpy.context.view_layer.update()
corners = [volume.matrix_world @ mathutils.Vector(c) for c in volume.evaluated_get(bpy.context.evaluated_depsgraph_get()).bound_box]
centre = sum(corners, mathutils.Vector()) / 8.0
extent = (max(corners, key=lambda c: (c - centre).length) - centre).length * 2.0
camera_data = bpy.data.cameras.new("camera")
camera_data.lens = params["focal"]
camera_data.clip_start, camera_data.clip_end = 0.01 * extent, 100.0 * extent
camera = bpy.data.objects.new("camera", camera_data)
scene.collection.objects.link(camera)
eye = centre + extent * mathutils.Vector(params["eye_direction"])
camera.matrix_world = mathutils.Matrix.LocRotScale(eye, (centre - eye).to_track_quat("-Z", "Y"), None)
scene.camera = camera

state = dict(step="layout", since=time.monotonic(), shots=[], changes=[], log=[])


def window():
    return bpy.context.window_manager.windows[0]


def views():
    return [a for a in window().screen.areas if a.type == 'VIEW_3D']


def region_of(area):
    return next(r for r in area.regions if r.type == 'WINDOW')


def the_view():
    return min(views(), key=lambda a: abs(region_of(a).width - params["region"][0]) + abs(region_of(a).height - params["region"][1]))


def refined_since(t):
    return next((r for r in RECORDS if r["requested"] >= t and not r["coarse"]), None)


def first_since(t, coarse):
    return next((r for r in RECORDS if r["requested"] >= t and r["coarse"] == coarse), None)


def screenshot(name):
    path = out(name)
    with bpy.context.temp_override(window=window()):
        bpy.ops.screen.screenshot(filepath=path, check_existing=False)
    state["shots"].append(path)
    return path


def finish(failure=None):
    area = the_view()
    r = region_of(area)
    win = window()
    result = dict(records=RECORDS, changes=state["changes"], shots=state["shots"], failure=failure,
                  window=[win.width, win.height], region=[r.x, r.y, r.width, r.height], centre=list(centre), extent=extent,
                  switch=state.get("switch"), settled=state.get("settled"), f12=state.get("f12"), f12_seconds=state.get("f12_seconds"))
    with open(out("viewport.json"), "w") as f:
        json.dump(result, f, indent=1)
    print("viewport_scene: %s" % (failure or "done"), flush=True)
    bpy.ops.wm.quit_blender()
    return None


def mapping():
    """The add-on's camera keywords for the view against Blender's own projection and view matrices:
    (2 focal / aperture or 2 / frame, window_matrix[0][0]) and the largest difference of the
    camera-to-world rotations (and of the eyes, but orthographic's, moved back on purpose)."""
    area = the_view()
    space = area.spaces.active
    rv3d = space.region_3d
    r = region_of(area)
    o = vdb_ewa_render.scene_mapping.viewport_camera_options(scene, space, rv3d, r.width, r.height, [])
    ours = 2.0 * o["focal"] / o["aperture"] if "focal" in o else 2.0 / o["frame"]
    world_from_view = rv3d.view_matrix.inverted()
    rotation = mathutils.Euler([math.radians(a) for a in o["rotate"]], 'XYZ').to_matrix()
    blender = world_from_view.to_3x3().normalized()
    eye = 0.0 if rv3d.view_perspective == 'ORTHO' else (mathutils.Vector(o["translate"]) - world_from_view.translation).length / extent
    return dict(projection=[ours, rv3d.window_matrix[0][0]], rotation=max(abs(a - b) for ra, rb in zip(rotation, blender) for a, b in zip(ra, rb)),
                eye=eye)


def change_view(what):
    """Apply @a what to the view and note when."""
    area = the_view()
    rv3d = area.spaces.active.region_3d
    if what[0] == "orbit":
        rv3d.view_rotation = mathutils.Quaternion((0.0, 0.0, 1.0), math.radians(what[1])) @ rv3d.view_rotation
    elif what[0] == "ortho":
        rv3d.view_perspective = 'ORTHO'
    else:
        rv3d.view_perspective = 'CAMERA'
        rv3d.view_camera_zoom = 50.0 * (2.0 - math.sqrt(2.0))  # the camera's frame spans the region
        rv3d.view_camera_offset = (0.0, 0.0)
    area.tag_redraw()
    state["changes"].append(dict(what=what[0], t=time.monotonic()))


def step():
    """The test's steps, each a call of this timer; returns the seconds to the next."""
    try:
        return _step()
    except Exception:
        traceback.print_exc()
        return finish("viewport_scene: " + traceback.format_exc().splitlines()[-1])


def _step():
    s = state["step"]
    win = window()
    if time.monotonic() - state["since"] > WAIT_SECONDS:
        return finish("timed out at step %s after %.0f s" % (s, WAIT_SECONDS))
    if s == "layout":  # one 3D view over the window; its header and side regions hidden
        for area in list(win.screen.areas):
            if area.type != 'VIEW_3D':
                with bpy.context.temp_override(window=win, screen=win.screen, area=area):
                    bpy.ops.screen.area_close()
        state["step"] = "regions"
        return 0.2
    if s == "regions":
        space = views()[0].spaces.active
        space.show_region_header = space.show_region_tool_header = space.show_region_toolbar = space.show_region_ui = False
        state["step"] = "split"
        return 0.2
    if s == "split":  # split off a region of the asked size (width, then height)
        area = views()[0]
        with bpy.context.temp_override(window=win, screen=win.screen, area=area):
            bpy.ops.screen.area_split(direction='VERTICAL', factor=params["region"][0] / area.width)
        state["step"] = "split2"
        return 0.2
    if s == "split2":
        area = min(views(), key=lambda a: abs(a.width - params["region"][0]))
        with bpy.context.temp_override(window=win, screen=win.screen, area=area):
            bpy.ops.screen.area_split(direction='HORIZONTAL', factor=params["region"][1] / area.height)
        state["step"] = "view"
        return 0.2
    if s == "view":
        area = the_view()
        for other in views():
            if other != area:
                other.type = 'TEXT_EDITOR'  # no other 3D view drawing
        space = area.spaces.active
        space.overlay.show_overlays = False
        space.show_gizmo = False
        space.lens = params["view_lens"]
        space.clip_start, space.clip_end = 0.01 * extent, 100.0 * extent
        rv3d = space.region_3d
        rv3d.view_perspective = 'PERSP'
        rv3d.view_location = centre
        rv3d.view_distance = params["view_distance"] * extent
        rv3d.view_rotation = (mathutils.Vector(params["eye_direction"])).to_track_quat("Z", "Y")
        r = region_of(area)
        scene.render.resolution_x, scene.render.resolution_y = r.width, r.height  # F12 at the region's size
        state.update(step="settle", cpu=time.process_time(), since=time.monotonic())
        return 0.5
    if s == "settle":  # Blender compiles its shaders (llvmpipe) for seconds after it starts: wait for it to idle
        cpu, state["cpu"] = time.process_time() - state["cpu"], time.process_time()
        if cpu > 0.05 and time.monotonic() - state["since"] < params["settle_seconds"]:
            return 0.5
        state["settled"] = time.monotonic() - state["since"]
        state["step"] = "rendered"
        return 0.01
    if s == "rendered":
        the_view().spaces.active.shading.type = params.get("shading", "RENDERED")
        state["switch"] = dict(t=time.monotonic())
        state.update(step="first", since=time.monotonic())
        return 0.01
    if s == "first":
        done = refined_since(state["switch"]["t"])
        if done is None:
            return 0.01
        coarse = first_since(state["switch"]["t"], True)
        state["switch"].update(refined=done["drawn"] - state["switch"]["t"], coarse=coarse and coarse["drawn"] - state["switch"]["t"])
        state.update(step="shot", since=time.monotonic(), index=0)
        return 0.05
    if s == "shot":  # the refined image of the last change is drawn: its screenshot, then the next change
        index = state["index"]
        screenshot("view%d.png" % index)
        plan = [("orbit", params["orbit_degrees"])] * params["orbits"] + [("ortho",), ("camera",)]
        if index >= len(plan):
            state.update(step="f12", since=time.monotonic())
            return 0.05
        change_view(plan[index])
        state.update(step="wait", since=time.monotonic(), index=index + 1)
        return 0.01
    if s == "wait":
        change = state["changes"][-1]
        done = refined_since(change["t"])
        if done is None:
            return 0.01
        coarse = first_since(change["t"], True)
        change.update(mapping(), refined=done["drawn"] - change["t"], coarse=coarse and coarse["drawn"] - change["t"],
                      refined_line=done["line"], coarse_line=coarse and coarse["line"])
        state.update(step="shot", since=time.monotonic())
        return 0.05
    if s == "f12":  # the camera's view at the region's size, rendered by F12
        t0 = time.monotonic()
        bpy.ops.render.render()
        state["f12_seconds"] = time.monotonic() - t0
        result = bpy.data.images["Render Result"]
        settings = scene.render.image_settings
        settings.file_format, settings.color_depth, settings.color_mode = "OPEN_EXR", "32", "RGBA"
        result.save_render(out("f12.exr"))
        state["f12"] = out("f12.exr")
        # A bad option: the view shows the error (and the console prints it once), then recovers.
        scene.vdb_ewa.extra_options = "bogus=1"
        state.update(step="error", since=time.monotonic(), error_t=time.monotonic())
        return 1.0
    if s == "error":
        scene.vdb_ewa.extra_options = ""
        state["changes"].append(dict(what="recover", t=time.monotonic()))
        state.update(step="recover", since=time.monotonic())
        return 0.01
    if s == "recover":
        if refined_since(state["changes"][-1]["t"]) is None:
            return 0.01
        return finish()
    return finish("unknown step " + s)


bpy.app.timers.register(step, first_interval=1.0)
