"""Bakes a small Mantaflow fire headless with Debian's Blender, into the OpenVDB cache Blender
writes (density, flame, temperature and a staggered velocity grid in cells per Mantaflow time
unit, clipped to the density): the cache issue 53 was found on.

    blender --factory-startup -b --python bench/bake_mantaflow_fire.py -- CACHE_DIR [RES]

A 2-unit domain of RES (64) cells, a sphere of fire and smoke at its floor, 24 frames at 24 fps:
about 40 s on two cores. The data frames are CACHE_DIR/data/fluid_data_NNNN.vdb."""
import sys

import bpy

args = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else []
cache = args[0] if args else "/tmp/mantaflow_fire"
res = int(args[1]) if len(args) > 1 else 64
scene = bpy.context.scene
for ob in list(bpy.data.objects):
    bpy.data.objects.remove(ob, do_unlink=True)
scene.render.fps, scene.render.fps_base = 24, 1.0
scene.frame_start, scene.frame_end = 1, 24

bpy.ops.mesh.primitive_cube_add(size=2, location=(0, 0, 1))
domain = bpy.context.active_object
fluid = domain.modifiers.new("Fluid", 'FLUID')
fluid.fluid_type = 'DOMAIN'
settings = fluid.domain_settings
settings.domain_type = 'GAS'
settings.resolution_max = res
settings.cache_type = 'ALL'
settings.cache_data_format = 'OPENVDB'
settings.cache_directory = cache
settings.cache_frame_start, settings.cache_frame_end = 1, 24
settings.openvdb_cache_compress_type = 'ZIP'
settings.openvdb_data_depth = '32'

bpy.ops.mesh.primitive_uv_sphere_add(radius=0.2, location=(0, 0, 0.3))
source = bpy.context.active_object
flow = source.modifiers.new("Fluid", 'FLUID')
flow.fluid_type = 'FLOW'
flow.flow_settings.flow_type = 'BOTH'
flow.flow_settings.flow_behavior = 'INFLOW'
flow.flow_settings.flow_source = 'MESH'
flow.flow_settings.surface_distance = 1.5

bpy.context.view_layer.objects.active = domain
domain.select_set(True)
source.select_set(False)
# Debian's Blender 3.4.1: evaluating a GAS domain with cache type ALL can leave a Mantaflow
# exception behind ("'NoneType' object has no attribute 'getDataPointer'"), which the next
# bpy.ops call raises as SystemError. Absorb it once, then bake (retried like that).
for attempt in range(3):
    try:
        bpy.context.view_layer.update()
    except SystemError:
        pass
    try:
        with bpy.context.temp_override(object=domain, active_object=domain, selected_objects=[domain], scene=scene):
            bpy.ops.fluid.bake_all()
        break
    except SystemError as e:
        print("bake attempt", attempt, "raised", repr(e))
print("baked into", cache)
