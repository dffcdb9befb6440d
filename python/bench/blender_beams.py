"""Blender Cycles side of benches/blender.sh: renders 3DGEN A1 beams the way shmgen does and
times each image/depth pair.

Run inside Blender (benches/blender.sh does):

    blender -b --factory-startup -noaudio --python python/bench/blender_beams.py -- \
        --spp 1 --beams 3 --views 5 --out /tmp/blender-beams

The scene matches `scripts/a1_beams.rhai --set paper_mesh=true`: boxes of length 1 m with the
paper's width and height ratios, every face split into a 32 × 32 grid (6,144 quads = the
paper's 12,288 triangles), bent by the paper's mapping (v(x) added to z; a simply supported
beam under a mid-span load, peak 2 % of the span); a procedural noise texture; a key and a fill
light fixed to the camera on a black world, as shmgen's studio light; cameras on a sphere at
960 × 960 with a vertical field of view of pi/3, framed so the bounding sphere fits (margin
1.05). Cycles on the CPU, no denoising, no adaptive sampling; RGB to PNG and the Z pass to a
float32 ZIP OpenEXR through the compositor. Prints one line per pair: `pair <seconds>`, then
`median <seconds>`.
"""

import argparse
import math
import os
import statistics
import sys
import time

import bpy
from mathutils import Vector


def arguments():
    argv = sys.argv[sys.argv.index("--") + 1 :] if "--" in sys.argv else []
    parser = argparse.ArgumentParser()
    parser.add_argument("--spp", type=int, default=1)
    parser.add_argument("--beams", type=int, default=3)
    parser.add_argument("--views", type=int, default=5)
    parser.add_argument("--threads", type=int, default=0, help="0: every core")
    parser.add_argument("--out", default="/tmp/blender-beams")
    return parser.parse_args(argv)


def clear_scene():
    for thing in list(bpy.data.objects):
        bpy.data.objects.remove(thing, do_unlink=True)
    for mesh in list(bpy.data.meshes):
        bpy.data.meshes.remove(mesh)


def paper_ratios(i, j, count=20):
    """The 3DGEN grid (stdlib/beam.rhai): width ratio i and height/width ratio j of 20."""
    width = 0.25 - (i / (count - 1)) ** 0.85 * (0.25 - 0.02)
    return width, width * (0.05 + j / (count - 1) * (1.5 - 0.05))


def beam(length, width, height, material):
    """A 1 m box, each face a 32 x 32 grid, bent by v(x) added to z (peak 0.02 L)."""
    bpy.ops.mesh.primitive_cube_add(size=1.0)
    box = bpy.context.active_object
    bpy.ops.object.mode_set(mode="EDIT")
    bpy.ops.mesh.subdivide(number_cuts=31)
    bpy.ops.object.mode_set(mode="OBJECT")
    box.scale = (length, width, height)
    bpy.ops.object.transform_apply(scale=True)
    peak = 0.02 * length
    for vertex in box.data.vertices:
        x = vertex.co.x / length + 0.5  # 0 .. 1 along the span
        # Simply supported, load at mid-span: v(x) = peak * (3x - 4x^3) / 1 for x <= 1/2.
        s = x if x <= 0.5 else 1.0 - x
        vertex.co.z -= peak * (3.0 * s - 4.0 * s**3)
    box.data.materials.append(material)
    return box


def noise_material():
    material = bpy.data.materials.new("procedural")
    material.use_nodes = True
    nodes, links = material.node_tree.nodes, material.node_tree.links
    bsdf = nodes["Principled BSDF"]
    noise = nodes.new("ShaderNodeTexNoise")
    noise.inputs["Scale"].default_value = 40.0
    ramp = nodes.new("ShaderNodeValToRGB")
    ramp.color_ramp.elements[0].color = (0.25, 0.12, 0.05, 1.0)
    ramp.color_ramp.elements[1].color = (0.55, 0.50, 0.45, 1.0)
    links.new(noise.outputs["Fac"], ramp.inputs["Fac"])
    links.new(ramp.outputs["Color"], bsdf.inputs["Base Color"])
    bsdf.inputs["Roughness"].default_value = 0.6
    return material


def camera_rig():
    data = bpy.data.cameras.new("camera")
    data.sensor_fit = "VERTICAL"
    data.angle_y = math.pi / 3.0
    camera = bpy.data.objects.new("camera", data)
    bpy.context.scene.collection.objects.link(camera)
    bpy.context.scene.camera = camera
    for name, energy, offset in (("key", 3.0, (1.5, 1.0, 0.5)), ("fill", 1.0, (-1.5, -0.5, 0.5))):
        light = bpy.data.objects.new(name, bpy.data.lights.new(name, "SUN"))
        light.data.energy = energy
        light.parent = camera  # fixed to the camera, as shmgen's studio lights
        light.rotation_euler = offset
        bpy.context.scene.collection.objects.link(light)
    return camera


def aim(camera, centre, radius, view, views):
    """Camera `view` of `views` on the sphere around the beam, framed as shmgen's "frame"."""
    distance = 1.05 * radius / math.sin(math.pi / 6.0)
    yaw = 2.0 * math.pi * (view + 0.5) / views
    pitch = math.asin(-1.0 + 2.0 * ((view * 0.618034) % 1.0)) * 0.9
    direction = Vector((math.cos(pitch) * math.cos(yaw), math.cos(pitch) * math.sin(yaw), math.sin(pitch)))
    camera.location = centre + distance * direction
    camera.rotation_euler = (-direction).to_track_quat("-Z", "Y").to_euler()


def setup_render(args):
    scene = bpy.context.scene
    scene.render.engine = "CYCLES"
    scene.cycles.device = "CPU"
    scene.cycles.samples = args.spp
    scene.cycles.use_adaptive_sampling = False
    scene.cycles.use_denoising = False
    scene.render.resolution_x = scene.render.resolution_y = 960
    scene.render.resolution_percentage = 100
    scene.render.use_persistent_data = True
    if args.threads:
        scene.render.threads_mode = "FIXED"
        scene.render.threads = args.threads
    scene.world = bpy.data.worlds.new("black")
    scene.world.color = (0.0, 0.0, 0.0)
    scene.render.image_settings.file_format = "PNG"
    scene.view_layers[0].use_pass_z = True
    scene.use_nodes = True
    tree = scene.node_tree
    layers = tree.nodes["Render Layers"]
    depth = tree.nodes.new("CompositorNodeOutputFile")
    depth.base_path = os.path.join(args.out, "depth")
    depth.format.file_format = "OPEN_EXR"
    depth.format.color_depth = "32"
    depth.format.exr_codec = "ZIP"
    tree.links.new(layers.outputs["Depth"], depth.inputs[0])


def main():
    args = arguments()
    clear_scene()
    setup_render(args)
    camera = camera_rig()
    material = noise_material()
    times = []
    pair = 0
    for b in range(args.beams):
        width, height = paper_ratios((7 * b + 3) % 20, (11 * b + 5) % 20)
        box = beam(1.0, width, height, material)
        radius = 0.5 * Vector((1.0, width, height + 0.02)).length
        for view in range(args.views):
            aim(camera, Vector((0.0, 0.0, -0.01)), radius, view, args.views)
            bpy.context.scene.frame_current = pair
            bpy.context.scene.render.filepath = os.path.join(args.out, f"rgb_{pair:04d}.png")
            start = time.perf_counter()
            bpy.ops.render.render(write_still=True)
            times.append(time.perf_counter() - start)
            print(f"pair {times[-1]:.4f}", flush=True)
            pair += 1
        bpy.data.objects.remove(box, do_unlink=True)
    # The first render of each beam builds Cycles' scene; the median is of every pair.
    print(f"median {statistics.median(times):.4f}", flush=True)


main()
