"""Materials of the Blender tests' scenes, made inside Blender (blender_scene.py, viewport_scene.py)."""
import bpy


def principled_volume(name, grid, density, color, absorption_color=(0.0, 0.0, 0.0), anisotropy=0.0):
    """A material of one Principled Volume reading the density from @a grid."""
    material = bpy.data.materials.new(name)
    material.use_nodes = True
    nodes = material.node_tree.nodes
    for node in list(nodes):
        if node.type != "OUTPUT_MATERIAL":
            nodes.remove(node)
    principled = nodes.new("ShaderNodeVolumePrincipled")
    principled.inputs["Density"].default_value = density
    principled.inputs["Color"].default_value = (*color, 1.0)
    principled.inputs["Absorption Color"].default_value = (*absorption_color, 1.0)
    principled.inputs["Anisotropy"].default_value = anisotropy
    principled.inputs["Density Attribute"].default_value = grid
    output = next(n for n in nodes if n.type == "OUTPUT_MATERIAL")
    material.node_tree.links.new(principled.outputs["Volume"], output.inputs["Volume"])
    return material
