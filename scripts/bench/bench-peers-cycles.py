#!/usr/bin/env python3
"""Renders a medium exported by glint (scripts/mitsuba/medium.py: an extinction
grid per mm, cell-centred) with Blender Cycles through the `bpy` wheel, for
scripts/bench/bench-peers (issue 41 item 6). Runs in its own venv (bpy needs numpy<2):

    /work/venv-bpy/bin/python scripts/bench/bench-peers-cycles.py SPEC.json

SPEC.json: density (an .npy of [i, j, k] extinction per mm), lo_mm and size_mm (the
grid's box), albedo (RGB, constant), g, environment (radiance), light (null or
{"towards": [x, y, z], "irradiance": E}), camera (glint's `derived`: eye,
focal_point, view_up, view_angle_deg), size [w, h], bounces, samples, time_limit
(seconds, 0: none), denoise (bool), seed, out (an .npy written with the linear RGB,
rows top to bottom). Prints one JSON line: {"seconds": wall time of the render call}.

The grid reaches Cycles through geometry nodes, since the wheel has no OpenVDB Python
module to write a .vdb: a point cloud of one vertex per voxel carrying the extinction,
read back by `Volume Cube` (one voxel per grid voxel, over the same box) through
`Sample Index` at the voxel under each position; Cycles interpolates the grid
trilinearly, as glint and Mitsuba do. The medium is Volume Scatter (colour = albedo,
Henyey-Greenstein g) plus Volume Absorption (colour = albedo) at the same density:
extinction = density, albedo = colour. 1 Blender unit = 1 mm. The sun's strength is its
irradiance; the world's colour the environment's radiance.
"""

import json
import math
import sys
import tempfile
import time

import bpy
import numpy as np
from mathutils import Vector


def grid_object(density, lo, size, mat):
    """An object whose geometry-nodes modifier makes the `density` volume grid, of
    material `mat`."""
    n = density.shape
    cell = [size[a] / n[a] for a in range(3)]
    # One vertex per voxel at its centre, i fastest, with the extinction as attribute.
    i, j, k = np.meshgrid(*(np.arange(m) for m in n), indexing="ij")
    pos = np.stack([lo[a] + (idx.ravel(order="F") + 0.5) * cell[a] for a, idx in enumerate((i, j, k))], 1)
    mesh = bpy.data.meshes.new("voxels")
    mesh.vertices.add(len(pos))
    mesh.vertices.foreach_set("co", pos.astype(np.float32).ravel())
    attr = mesh.attributes.new("d", "FLOAT", "POINT")
    attr.data.foreach_set("value", density.ravel(order="F").astype(np.float32))
    voxels = bpy.data.objects.new("voxels", mesh)
    bpy.context.scene.collection.objects.link(voxels)
    voxels.hide_render = True

    holder = bpy.data.objects.new("medium", bpy.data.meshes.new("medium"))
    bpy.context.scene.collection.objects.link(holder)
    tree = bpy.data.node_groups.new("grid", "GeometryNodeTree")
    tree.interface.new_socket("Geometry", in_out="OUTPUT", socket_type="NodeSocketGeometry")
    nodes, links = tree.nodes, tree.links
    out = nodes.new("NodeGroupOutput")
    info = nodes.new("GeometryNodeObjectInfo")
    info.inputs["Object"].default_value = voxels
    info.transform_space = "ORIGINAL"
    named = nodes.new("GeometryNodeInputNamedAttribute")
    named.data_type = "FLOAT"
    named.inputs["Name"].default_value = "d"
    # Index of the voxel under the position: round((p - lo) / cell - 1/2) per axis.
    position = nodes.new("GeometryNodeInputPosition")
    sep = nodes.new("ShaderNodeSeparateXYZ")
    links.new(position.outputs[0], sep.inputs[0])
    index = None
    stride = 1
    for a, name in enumerate("XYZ"):
        m = nodes.new("ShaderNodeMath")
        m.operation = "MULTIPLY_ADD"
        links.new(sep.outputs[name], m.inputs[0])
        m.inputs[1].default_value = 1.0 / cell[a]
        m.inputs[2].default_value = -lo[a] / cell[a] - 0.5
        r = nodes.new("ShaderNodeMath")
        r.operation = "ROUND"
        links.new(m.outputs[0], r.inputs[0])
        c = nodes.new("ShaderNodeClamp")
        links.new(r.outputs[0], c.inputs["Value"])
        c.inputs["Min"].default_value = 0
        c.inputs["Max"].default_value = n[a] - 1
        s = nodes.new("ShaderNodeMath")
        s.operation = "MULTIPLY"
        links.new(c.outputs[0], s.inputs[0])
        s.inputs[1].default_value = stride
        stride *= n[a]
        if index is None:
            index = s
        else:
            add = nodes.new("ShaderNodeMath")
            add.operation = "ADD"
            links.new(index.outputs[0], add.inputs[0])
            links.new(s.outputs[0], add.inputs[1])
            index = add
    sample = nodes.new("GeometryNodeSampleIndex")
    sample.data_type = "FLOAT"
    sample.domain = "POINT"
    links.new(info.outputs["Geometry"], sample.inputs["Geometry"])
    links.new(named.outputs["Attribute"], sample.inputs["Value"])
    links.new(index.outputs[0], sample.inputs["Index"])
    cube = nodes.new("GeometryNodeVolumeCube")
    links.new(sample.outputs[0], cube.inputs["Density"])
    cube.inputs["Min"].default_value = lo
    cube.inputs["Max"].default_value = [lo[a] + size[a] for a in range(3)]
    for a, name in enumerate("XYZ"):
        cube.inputs[f"Resolution {name}"].default_value = n[a]
    setmat = nodes.new("GeometryNodeSetMaterial")
    setmat.inputs["Material"].default_value = mat
    links.new(cube.outputs[0], setmat.inputs["Geometry"])
    links.new(setmat.outputs[0], out.inputs[0])
    mod = holder.modifiers.new("grid", "NODES")
    mod.node_group = tree
    return holder


def material(albedo, g):
    mat = bpy.data.materials.new("medium")
    mat.use_nodes = True
    nodes, links = mat.node_tree.nodes, mat.node_tree.links
    nodes.clear()
    out = nodes.new("ShaderNodeOutputMaterial")
    attr = nodes.new("ShaderNodeAttribute")
    attr.attribute_name = "density"
    scatter = nodes.new("ShaderNodeVolumeScatter")
    scatter.inputs["Color"].default_value = (*albedo, 1.0)
    scatter.inputs["Anisotropy"].default_value = g
    absorb = nodes.new("ShaderNodeVolumeAbsorption")
    absorb.inputs["Color"].default_value = (*albedo, 1.0)
    links.new(attr.outputs["Fac"], scatter.inputs["Density"])
    links.new(attr.outputs["Fac"], absorb.inputs["Density"])
    add = nodes.new("ShaderNodeAddShader")
    links.new(scatter.outputs[0], add.inputs[0])
    links.new(absorb.outputs[0], add.inputs[1])
    links.new(add.outputs[0], out.inputs["Volume"])
    return mat


def main() -> int:
    spec = json.load(open(sys.argv[1]))
    bpy.ops.wm.read_factory_settings(use_empty=True)
    scene = bpy.context.scene
    density = np.load(spec["density"])
    grid_object(density, spec["lo_mm"], spec["size_mm"], material(spec["albedo"], spec["g"]))

    world = bpy.data.worlds.new("env")
    bg = world.node_tree.nodes["Background"]
    bg.inputs["Color"].default_value = (1.0, 1.0, 1.0, 1.0)
    bg.inputs["Strength"].default_value = spec["environment"]
    scene.world = world
    if spec.get("light"):
        sun = bpy.data.lights.new("sun", "SUN")
        sun.energy = spec["light"]["irradiance"]
        sun.angle = 0.0
        obj = bpy.data.objects.new("sun", sun)
        obj.rotation_euler = Vector(spec["light"]["towards"]).to_track_quat("Z", "Y").to_euler()
        scene.collection.objects.link(obj)

    cam_data = bpy.data.cameras.new("cam")
    cam_data.sensor_fit = "VERTICAL"
    cam_data.angle_y = math.radians(spec["camera"]["view_angle_deg"])
    cam_data.clip_start, cam_data.clip_end = 0.01, 1e6
    cam = bpy.data.objects.new("cam", cam_data)
    eye, focal = Vector(spec["camera"]["eye"]), Vector(spec["camera"]["focal_point"])
    cam.location = eye
    cam.rotation_euler = (focal - eye).to_track_quat("-Z", "Y").to_euler()
    scene.collection.objects.link(cam)
    scene.camera = cam

    w, h = spec["size"]
    r = scene.render
    r.engine = "CYCLES"
    r.resolution_x, r.resolution_y, r.resolution_percentage = w, h, 100
    r.film_transparent = False
    r.image_settings.file_format = "OPEN_EXR"
    r.image_settings.color_depth = "32"
    scene.view_settings.view_transform = "Standard"
    c = scene.cycles
    c.device = "CPU"
    c.samples = spec["samples"]
    c.time_limit = spec.get("time_limit", 0.0)
    c.seed = spec.get("seed", 0)
    c.use_denoising = bool(spec.get("denoise"))
    c.denoiser = "OPENIMAGEDENOISE"
    c.pixel_filter_type = "BOX"
    c.filter_width = 1.0
    c.max_bounces = spec["bounces"] + 1
    c.volume_bounces = spec["bounces"]
    c.transparent_max_bounces = 64
    c.use_light_tree = True

    with tempfile.TemporaryDirectory() as tmp:
        r.filepath = f"{tmp}/out.exr"
        t = time.perf_counter()
        bpy.ops.render.render(write_still=True)
        seconds = time.perf_counter() - t
        img = bpy.data.images.load(r.filepath)
        px = np.array(img.pixels[:], dtype=np.float32).reshape(h, w, 4)[::-1, :, :3]
    np.save(spec["out"], px)
    print(json.dumps({"seconds": seconds}))
    return 0


if __name__ == "__main__":
    sys.exit(main())
