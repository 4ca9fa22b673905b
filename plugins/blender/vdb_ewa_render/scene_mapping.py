"""A Blender scene as vdb_ewa.render() options: the camera, the sun, point and spot lights, each volume object's
grid, transform and Principled Volume (docs/blender.md has the table). Pure functions of bpy
data; __init__.py renders with them."""
import math
import os

import bpy
import mathutils

FOUR_PI = 4.0 * math.pi


class Volume:
    """One volume object to render: its grid's file, grid names, transform and material options."""

    def __init__(self, name, path, object_to_world, density_grid, options, depth, motion=None, centre=(0.0, 0.0, 0.0)):
        self.name = name
        self.path = path
        self.object_to_world = object_to_world  # 4x4 nested lists, column vectors
        self.density_grid = density_grid
        self.options = options  # material options; scatter/absorb/blackbody per grid value per *world* unit
        self.depth = depth  # of its centre from the camera, to composite several front to back
        self.motion = motion  # motion blur: dict(velocity_grid, velocity_unit, velocity_scale), or None
        self.centre = centre  # its object's origin in the world, to order several from another eye


def resolution(scene):
    """The render's size in pixels: Blender's resolution times its percentage."""
    r = scene.render
    return max(1, int(r.resolution_x * r.resolution_percentage / 100)), max(1, int(r.resolution_y * r.resolution_percentage / 100))


def placement_options(world_from_camera):
    """A camera at @a world_from_camera as translate and rotate (degrees, about x then y then z:
    Blender's XYZ Euler; both cameras look down their local -z with +y up). Its scale is dropped."""
    location, rotation, _ = world_from_camera.decompose()
    return dict(translate=tuple(location), rotate=tuple(math.degrees(a) for a in rotation.to_euler('XYZ')))


def lens_options(kind, width, height, lens, sensor_width, sensor_height, sensor_fit, ortho_scale, zoom=1.0):
    """Blender's projection onto an image of @a width x @a height pixels as vdb_ewa's: focal and
    aperture (mm; aperture the horizontal film width) for 'PERSP', camera="ortho" and frame (the
    horizontal extent, scene units) for 'ORTHO'. The sensor (or orthographic scale) spans the
    image side Blender's sensor fit picks (Auto: the longer one), times @a zoom (Blender's view
    zoom: 2 in a 3D view, the camera zoom's factor through a camera)."""
    aspect = width / height
    horizontal = sensor_fit == 'HORIZONTAL' or (sensor_fit == 'AUTO' and width >= height)
    if kind == 'ORTHO':
        return dict(camera="ortho", frame=zoom * (ortho_scale if horizontal else ortho_scale * aspect))
    sensor = zoom * (sensor_width if sensor_fit != 'VERTICAL' else sensor_height)
    return dict(focal=lens, aperture=sensor if horizontal else sensor * aspect)


def camera_options(scene, warnings, camera=None, size=None, zoom=1.0):
    """A camera object (the scene camera by default) as translate, rotate, the lens and the clip
    range, on an image of @a size pixels (the scene's resolution by default) spanning @a zoom
    times its sensor (a 3D view through the camera: viewport_camera_options)."""
    cam = camera or scene.camera
    if cam is None or cam.type != 'CAMERA':
        raise ValueError("the scene has no camera")
    width, height = size or resolution(scene)
    location = cam.matrix_world.translation
    data = cam.data
    options = dict(res="%dx%d" % (width, height), near=data.clip_start, far=data.clip_end, **placement_options(cam.matrix_world))
    if data.type not in ('ORTHO', 'PERSP'):
        raise ValueError("camera %s: %s cameras are not supported (perspective and orthographic are)" % (cam.name, data.type))
    options.update(lens_options(data.type, width, height, data.lens, data.sensor_width, data.sensor_height, data.sensor_fit,
                                data.ortho_scale, zoom))
    if data.shift_x or data.shift_y:
        warnings.append("camera %s: lens shift is ignored" % cam.name)
    if scene.render.pixel_aspect_x != scene.render.pixel_aspect_y:
        warnings.append("non-square pixels are ignored")
    if data.dof.use_dof:
        # A thin lens: Blender's f-stop over its focal length in mm and scene units as metres
        # (vdb_ewa's --fstop takes them alike); the focus depth along the view axis, of the focus
        # object where there is one (Cycles focuses on a plane, as vdb_ewa does).
        if data.type != 'PERSP':
            warnings.append("camera %s: depth of field needs a perspective camera; ignored" % cam.name)
        else:
            options["fstop"] = data.dof.aperture_fstop
            focus = data.dof.focus_distance
            if data.dof.focus_object is not None:
                forward = cam.matrix_world.to_3x3() @ mathutils.Vector((0.0, 0.0, -1.0))
                focus = (data.dof.focus_object.matrix_world.translation - location).dot(forward.normalized())
            if focus > 0.0:
                options["focus_distance"] = focus
            else:
                warnings.append("camera %s: the focus lies behind the camera; focused on the point looked at" % cam.name)
    return options


# Blender's 3D view: a 36 mm sensor (Auto fit) behind the view's lens, at twice a camera's zoom
# (BKE_camera_params_from_view3d, CAMERA_PARAM_ZOOM_INIT_PERSP): 72 mm of film across the longer side.
VIEW_SENSOR = 36.0
VIEW_ZOOM = 2.0


def camera_view_zoom(view_camera_zoom):
    """The part of the camera's sensor a 3D view through it spans, from its View Camera Zoom
    (-30 to 600): 1 / Blender's BKE_screen_view3d_zoom_to_fac, (sqrt 2 + zoom / 50)^2 / 4;
    2 at zoom 0 (the camera frame half the view wide), 1 at 50 (2 - sqrt 2) = 29.3."""
    return 4.0 / (math.sqrt(2.0) + view_camera_zoom / 50.0) ** 2


def viewport_camera_options(scene, space, region_data, width, height, warnings):
    """A 3D view (its RegionView3D, the View3D space's lens and clip range) on a region of @a width
    x @a height pixels as vdb_ewa's camera keywords, the whole region as Blender draws it.
    Perspective: the view's placement, VIEW_SENSOR x VIEW_ZOOM mm of film behind the lens.
    Orthographic: Blender's scale, the view distance x VIEW_SENSOR / lens at VIEW_ZOOM, and its clip
    range, [-clip_end / 2, clip_end / 2] about the view point (the eye is moved back by half of it).
    Through the camera: camera_options at the region's size, the sensor spanned as the view's
    camera zoom draws it (camera_view_zoom); the camera frame's offset (a lens shift) is ignored,
    with a warning."""
    if region_data.view_perspective == 'CAMERA':
        camera = space.camera if space.use_local_camera and space.camera else scene.camera
        if tuple(region_data.view_camera_offset) != (0.0, 0.0):
            warnings.append("the camera frame's offset in the view is ignored: the view is rendered centred on the camera")
        return camera_options(scene, warnings, camera, (width, height), camera_view_zoom(region_data.view_camera_zoom))
    world_from_view = region_data.view_matrix.inverted()
    options = dict(res="%dx%d" % (width, height))
    if region_data.view_perspective == 'ORTHO':
        depth = 0.5 * space.clip_end
        options.update(placement_options(world_from_view @ mathutils.Matrix.Translation((0.0, 0.0, depth))))
        options.update(near=1e-6 * depth, far=2.0 * depth)
        options.update(lens_options('ORTHO', width, height, space.lens, VIEW_SENSOR, VIEW_SENSOR, 'AUTO',
                                    region_data.view_distance * VIEW_SENSOR / space.lens, VIEW_ZOOM))
    else:
        options.update(placement_options(world_from_view))
        options.update(near=space.clip_start, far=space.clip_end)
        options.update(lens_options('PERSP', width, height, space.lens, VIEW_SENSOR, VIEW_SENSOR, 'AUTO', 0.0, VIEW_ZOOM))
    return options


def motion_options(scene):
    """The scene's motion blur as vdb_ewa's shutter (frames around the frame's time, where Cycles'
    Motion Blur Position puts Blender's Shutter) and frames per second; {} when it is off."""
    r = scene.render
    if not r.use_motion_blur:
        return {}
    length = r.motion_blur_shutter
    position = getattr(scene.cycles, "motion_blur_position", "CENTER") if hasattr(scene, "cycles") else "CENTER"
    shutter = {"START": (0.0, length), "END": (-length, 0.0)}.get(position, (-0.5 * length, 0.5 * length))
    return dict(shutter="%.17g,%.17g" % shutter, fps=r.fps / r.fps_base)


def volume_motion(obj, scene, warnings):
    """A volume object's velocity grid (Blender's Velocity Grid, or its split X, Y, Z grids when
    they are named NAME.x, NAME.y, NAME.z), unit and scale, when the scene's motion blur is on;
    None for a volume that stands still."""
    if not scene.render.use_motion_blur:
        return None
    data = obj.data
    where = "volume %s" % obj.name
    if obj.animation_data is not None and obj.animation_data.action is not None:
        warnings.append("%s: its object's animation is not blurred (vdb_ewa blurs by the velocity grid only)" % where)
    name = data.velocity_grid
    motion = dict(velocity_grid=name, velocity_unit=data.velocity_unit.lower(), velocity_scale=data.velocity_scale)
    if name and grid_of(data, name) is not None:
        return motion
    split = (data.velocity_x_grid, data.velocity_y_grid, data.velocity_z_grid)
    if not any(split):
        return None  # no velocity grid: Cycles does not blur it either
    if split == tuple(name + "." + a for a in "xyz") and all(grid_of(data, g) is not None for g in split):
        return motion  # vdb_ewa joins NAME.x, NAME.y, NAME.z itself
    warnings.append("%s: split velocity grids %s are not named %s.x, .y, .z; it is not blurred" % (where, "/".join(split), name))
    return None


def _instances(depsgraph, kind):
    """The depsgraph's object instances of @a kind ('LIGHT', 'VOLUME')."""
    return (instance for instance in depsgraph.object_instances if instance.object.type == kind)


def light_options(depsgraph, warnings):
    """Sun lights as --light X,Y,Z,R,G,B: the direction towards the sun (its local +z) and colour
    x strength / 4 pi (a sun of irradiance E lights an isotropic medium as vdb_ewa's light of E / 4 pi)."""
    lights = []
    for instance in _instances(depsgraph, 'LIGHT'):
        obj = instance.object
        light = obj.data
        if light.type in ('POINT', 'SPOT'):
            continue  # point_light_options
        if light.type != 'SUN':
            warnings.append("light %s: %s lights are not supported (sun, point and spot lights are)" % (obj.name, light.type.lower()))
            continue
        m = instance.matrix_world.to_3x3()
        d = (m[0][2], m[1][2], m[2][2])
        norm = math.sqrt(sum(c * c for c in d))
        if norm == 0.0:
            continue
        scale = light.energy / FOUR_PI
        lights.append(tuple(c / norm for c in d) + tuple(c * scale for c in light.color))
    return lights


def point_light_options(depsgraph, warnings):
    """Point and spot lights as --point-light X,Y,Z,R,G,B and --spot-light X,Y,Z,TX,TY,TZ,ANGLE,
    BLEND,R,G,B: colour x power / (16 pi^2) (Cycles' radiant intensity is power / 4 pi, and an
    isotropic medium scatters 1 / 4 pi of it towards the eye, where vdb_ewa's model scatters all);
    a spot aims along its local -z, Spot Size its full cone angle, Spot Blend its blend (the same
    smoothstep as Cycles'). Their radius (Cycles' soft size) becomes point_light_radius, the
    largest one (vdb_ewa has one for all). Returns the keyword options, empty without such lights."""
    points, spots, radii = [], [], []
    for instance in _instances(depsgraph, 'LIGHT'):
        obj = instance.object
        light = obj.data
        if light.type not in ('POINT', 'SPOT'):
            continue
        m = instance.matrix_world
        position = tuple(m.translation)
        intensity = tuple(c * light.energy / (FOUR_PI * FOUR_PI) for c in light.color)
        radii.append(light.shadow_soft_size)
        if light.type == 'POINT':
            points.append(position + intensity)
        else:
            axis = m.to_3x3() @ mathutils.Vector((0.0, 0.0, -1.0))
            target = tuple(p + a for p, a in zip(position, axis))
            spots.append(position + target + (math.degrees(light.spot_size), light.spot_blend) + intensity)
    options = {}
    if points:
        options["point_light"] = points
    if spots:
        options["spot_light"] = spots
    if radii:
        options["point_light_radius"] = max(radii)
        if min(radii) != max(radii):
            warnings.append("point and spot lights of radii %g to %g: vdb_ewa gives them all the largest" % (min(radii), max(radii)))
    return options


def _principled(material):
    """The Principled Volume node feeding the material's volume output, or None."""
    if material is None or not material.use_nodes:
        return None
    for node in material.node_tree.nodes:
        if node.type == 'OUTPUT_MATERIAL' and node.is_active_output:
            links = node.inputs['Volume'].links
            if links and links[0].from_node.type == 'PRINCIPLED_VOLUME':
                return links[0].from_node
    return None


def _value(node, name, warnings, where):
    socket = node.inputs[name]
    if socket.is_linked:
        warnings.append("%s: the Principled Volume's %s is linked to other nodes; its own value is used" % (where, name))
    value = socket.default_value
    return tuple(value)[:3] if socket.type == 'RGBA' else value


MAX_ANISOTROPY = 0.999
# Octaves of multiple scattering a scene with Cycles' Volume Bounces > 0 gets (--multiple-scattering;
# their count measured against the path-traced truth: docs/lighting.md#multiple-scattering).
SCATTERING_OCTAVES = 4


def scattering_options(scene):
    """Cycles' Volume Bounces as --multiple-scattering: 0 bounces single scattering (1 octave),
    more the measured octaves, at most one per bounce after the first."""
    bounces = getattr(getattr(scene, "cycles", None), "volume_bounces", 0)
    return dict(multiple_scattering=1 if bounces <= 0 else min(1 + bounces, SCATTERING_OCTAVES))


def material_options(obj, warnings):
    """The object's Principled Volume as vdb_ewa options, per grid value per world unit (render()
    multiplies them by the voxel length): Cycles' coefficients, scattering = Color x Density,
    absorption = (1 - Color) x (1 - sqrt(Absorption Color)) x Density; blackbody from the
    Temperature Attribute with the node's Temperature as its scale. Returns (density grid, options)."""
    material = obj.active_material
    node = _principled(material)
    where = "volume %s" % obj.name
    if node is None:
        warnings.append("%s: no Principled Volume; rendered with Blender's default volume (density 1, grey 0.5)" % where)
        return "density", dict(scatter=(0.5, 0.5, 0.5), absorb=(0.5, 0.5, 0.5))
    density = _value(node, "Density", warnings, where)
    color = _value(node, "Color", warnings, where)
    absorption = _value(node, "Absorption Color", warnings, where)
    scatter = tuple(c * density for c in color)
    absorb = tuple(max(1.0 - c, 0.0) * max(1.0 - math.sqrt(max(a, 0.0)), 0.0) * density for c, a in zip(color, absorption))
    options = dict(scatter=scatter, absorb=absorb)
    grid = _value(node, "Density Attribute", warnings, where) or "density"
    color_attribute = _value(node, "Color Attribute", warnings, where)
    if color_attribute:
        if grid_of(obj.data, color_attribute) is not None:
            options["color_grid"] = color_attribute
            warnings.append("%s: the Color Attribute tints the scattering only; Cycles' absorption follows it too" % where)
        else:
            warnings.append("%s: no grid '%s' for the Color Attribute; ignored" % (where, color_attribute))
    anisotropy = _value(node, "Anisotropy", warnings, where)
    if anisotropy != 0.0:
        # vdb_ewa's --anisotropy is Henyey-Greenstein's g, as Cycles' (docs/lighting.md#scattering);
        # Cycles takes +-1, a delta, vdb_ewa the open interval.
        options["anisotropy"] = max(-MAX_ANISOTROPY, min(MAX_ANISOTROPY, anisotropy))
    if _value(node, "Emission Strength", warnings, where) > 0.0:
        warnings.append("%s: Emission Strength is ignored (Blender's emission does not follow the density; use a "
                        "temperature or flame grid)" % where)
    intensity = _value(node, "Blackbody Intensity", warnings, where)
    temperature = _value(node, "Temperature Attribute", warnings, where) or "temperature"
    if intensity > 0.0 and grid_of(obj.data, temperature) is None:
        warnings.append("%s: no grid '%s' for the Temperature Attribute; no blackbody emission" % (where, temperature))
    elif intensity > 0.0:
        options["temperature"] = temperature
        options["temperature_scale"] = _value(node, "Temperature", warnings, where)
        options["blackbody_intensity"] = intensity
        if tuple(_value(node, "Blackbody Tint", warnings, where)) != (1.0, 1.0, 1.0):
            warnings.append("%s: Blackbody Tint is ignored" % where)
        if abs(intensity - 1.0) > 1e-6:
            warnings.append("%s: Blackbody Intensity %g scales the emission; Cycles mixes 1 and T^4 by it (docs/lighting.md)"
                            % (where, intensity))
    return grid, options


def grid_of(volume, name):
    """The grid called @a name in a volume's file (Blender reads its metadata), or None."""
    volume.grids.load()
    return next((grid for grid in volume.grids if grid.name == name), None)


def half_voxel(volume, grid_name):
    """Blender's placement of a grid's voxels, in object space: Cycles (and the viewport) put voxel
    (i, j, k)'s value at the centre of the index cell [i, i + 1]^3, OpenVDB and vdb_ewa at the
    index point (i, j, k) itself: half a voxel apart along each index axis (measured against
    Cycles, docs/blender.md). Zero where the grid is not found (the render then says why)."""
    grid = grid_of(volume, grid_name)
    return mathutils.Vector((0.0, 0.0, 0.0)) if grid is None else grid.matrix_object.to_3x3() @ mathutils.Vector((0.5, 0.5, 0.5))


def volumes(depsgraph, camera_location, warnings, motion_blur=True):
    """Every visible volume object with an OpenVDB file, nearest first; without their velocity
    grids where @a motion_blur is False (the viewport)."""
    found = []
    for instance in _instances(depsgraph, 'VOLUME'):
        obj = instance.object
        data = obj.data
        path = bpy.path.abspath(data.filepath, library=data.library)
        if data.is_sequence:
            path = bpy.path.abspath(data.grids.frame_filepath, library=data.library) or path
        if not path or not os.path.isfile(path):
            warnings.append("volume %s: no OpenVDB file (%s); skipped" % (obj.name, path or "none"))
            continue
        grid, options = material_options(obj, warnings)
        m = instance.matrix_world @ mathutils.Matrix.Translation(half_voxel(data, grid))
        object_to_world = [[m[r][c] for c in range(4)] for r in range(4)]
        centre = m.translation
        depth = (centre - camera_location).length
        motion = volume_motion(obj, depsgraph.scene, warnings) if motion_blur else None
        found.append(Volume(obj.name, path, object_to_world, grid, options, depth, motion, tuple(centre)))
    found.sort(key=lambda v: v.depth)
    return found
