"""Blender side of benches/blender.sh's outdoor rows: the kind of scene `scripts/outdoor.rhai`
renders, timed per image/depth pair.

Run inside Blender (benches/blender.sh does; EEVEE needs an OpenGL context, which
`xvfb-run -a` gives with Mesa's software rasteriser):

    blender -b --factory-startup -noaudio --python python/bench/blender_outdoor.py -- \
        --engine CYCLES --spp 16 --views 4 --out /tmp/blender-outdoor

The scene: a 3 m beam, 0.3 x 0.4 m, on two concrete abutments standing on a 200 m ground
plane; a sun of 0.53 degrees (soft shadows) at 45 degrees elevation and a Nishita sky (its own
sun disc off: the sun lamp is the sun); cameras around the beam pitched 15 degrees down, framed
as shmgen's "frame" (vertical field of view pi/3, 960 x 960). Cycles on the CPU without
denoising or adaptive sampling, or EEVEE with soft shadows and ambient occlusion; RGB to PNG
and the Z pass to a float32 ZIP OpenEXR through the compositor. Prints `pair <seconds>` per
pair, then `median <seconds>`.
"""

import argparse
import math
import os
import statistics
import sys
import time

import bpy
from mathutils import Vector

CENTRE = Vector((0.0, 0.0, 0.9))
RADIUS = 1.8  # bounding sphere of the beam and its abutments


def options():
    argv = sys.argv[sys.argv.index("--") + 1 :] if "--" in sys.argv else []
    parser = argparse.ArgumentParser()
    parser.add_argument("--engine", choices=["CYCLES", "BLENDER_EEVEE"], default="CYCLES")
    parser.add_argument("--spp", type=int, default=1)
    parser.add_argument("--views", type=int, default=4)
    parser.add_argument("--size", type=int, default=960)
    parser.add_argument("--out", default="/tmp/blender-outdoor")
    return parser.parse_args(argv)


def diffuse(name, colour):
    material = bpy.data.materials.new(name)
    material.use_nodes = True
    material.node_tree.nodes["Principled BSDF"].inputs["Base Color"].default_value = (*colour, 1.0)
    return material


def solid(centre, size, material):
    bpy.ops.mesh.primitive_cube_add(size=1.0, location=centre)
    cube = bpy.context.active_object
    cube.scale = size
    cube.data.materials.append(material)


def build_scene():
    for thing in list(bpy.data.objects):
        bpy.data.objects.remove(thing, do_unlink=True)
    bpy.ops.mesh.primitive_plane_add(size=200.0)
    bpy.context.active_object.data.materials.append(diffuse("grass", (0.12, 0.22, 0.05)))
    concrete = diffuse("concrete", (0.45, 0.44, 0.42))
    for x in (-1.35, 1.35):
        solid((x, 0.0, 0.5), (0.5, 0.8, 1.0), concrete)
    solid((0.0, 0.0, 1.2), (3.0, 0.3, 0.4), diffuse("steel", (0.35, 0.25, 0.2)))


def daylight():
    sun = bpy.data.objects.new("sun", bpy.data.lights.new("sun", "SUN"))
    sun.data.angle = math.radians(0.53)
    sun.data.energy = 4.0
    sun.rotation_euler = (math.radians(45.0), 0.0, math.radians(30.0))
    bpy.context.scene.collection.objects.link(sun)
    world = bpy.data.worlds.new("sky")
    world.use_nodes = True
    sky = world.node_tree.nodes.new("ShaderNodeTexSky")
    sky.sky_type = "NISHITA"
    sky.sun_disc = False
    sky.sun_elevation = math.radians(45.0)
    background = world.node_tree.nodes["Background"]
    background.inputs["Strength"].default_value = 0.3
    world.node_tree.links.new(sky.outputs["Color"], background.inputs["Color"])
    bpy.context.scene.world = world


def renderer(opts):
    scene = bpy.context.scene
    scene.render.engine = opts.engine
    if opts.engine == "CYCLES":
        scene.cycles.device = "CPU"
        scene.cycles.samples = opts.spp
        scene.cycles.use_adaptive_sampling = False
        scene.cycles.use_denoising = False
    else:
        scene.eevee.taa_render_samples = opts.spp
        scene.eevee.use_soft_shadows = True
        scene.eevee.use_gtao = True
    scene.render.resolution_x = scene.render.resolution_y = opts.size
    scene.render.resolution_percentage = 100
    # Keeps the scene (and the sky's importance map) between the views, as the beams' script.
    scene.render.use_persistent_data = True
    scene.render.image_settings.file_format = "PNG"
    scene.view_layers[0].use_pass_z = True
    scene.use_nodes = True
    tree = scene.node_tree
    z = tree.nodes.new("CompositorNodeOutputFile")
    z.base_path = os.path.join(opts.out, "depth")
    z.format.file_format = "OPEN_EXR"
    z.format.color_depth = "32"
    z.format.exr_codec = "ZIP"
    tree.links.new(tree.nodes["Render Layers"].outputs["Depth"], z.inputs[0])
    data = bpy.data.cameras.new("camera")
    data.sensor_fit = "VERTICAL"
    data.angle_y = math.pi / 3.0
    camera = bpy.data.objects.new("camera", data)
    scene.collection.objects.link(camera)
    scene.camera = camera
    return camera


def place(camera, view, views):
    yaw = 2.0 * math.pi * (view + 0.5) / views
    pitch = math.radians(15.0)
    towards = Vector((math.cos(pitch) * math.cos(yaw), math.cos(pitch) * math.sin(yaw), math.sin(pitch)))
    camera.location = CENTRE + 1.05 * RADIUS / math.sin(math.pi / 6.0) * towards
    camera.rotation_euler = (-towards).to_track_quat("-Z", "Y").to_euler()


def main():
    opts = options()
    build_scene()
    daylight()
    camera = renderer(opts)
    seconds = []
    for view in range(opts.views):
        place(camera, view, opts.views)
        bpy.context.scene.frame_current = view
        bpy.context.scene.render.filepath = os.path.join(opts.out, f"rgb_{view:04d}.png")
        start = time.perf_counter()
        bpy.ops.render.render(write_still=True)
        seconds.append(time.perf_counter() - start)
        print(f"pair {seconds[-1]:.4f}", flush=True)
    print(f"median {statistics.median(seconds):.4f}", flush=True)


main()
