"""Renders a grainline glb with Blender (the `bpy` module) as tests/blender.rs needs it.

    python render.py JOB.json

JOB.json: {"glb": path, "size": 384, "samples": 16, "threads": 2, "raw": out path,
           "blend": out path (optional: the scene as rendered, to open in Blender)}

- Blender's own glTF importer reads the file (io_import_scene_gltf2, with its defaults);
- the Tangent node and the Anisotropic Rotation chain its importer makes from the
  anisotropyTexture are kept; the lobe is set strongly anisotropic: Anisotropic 1 (the link
  from the texture's B channel removed), Roughness 0.3 (issue 33: Blender's lobe cannot take
  KHR_materials_anisotropy's shape, but a stretched lobe puts its ridge on the highlight curve);
- Cycles on the CPU renders size x size with the file's camera and its key light alone (a black
  world), film transparent, no denoising;
- "raw": linear RGBA float32 little-endian, rows top to bottom.

Prints one JSON line: what the importer linked, the material's settings and the timings.
"""
import json
import os
import struct
import sys
import time

import bpy


def principled(mat):
    for n in mat.node_tree.nodes:
        if n.type == "BSDF_PRINCIPLED":
            return n
    raise SystemExit(f"no Principled BSDF in material {mat.name}")


def linked_from(bsdf, socket):
    s = bsdf.inputs[socket]
    return [l.from_node.bl_idname for l in s.links]


def main():
    job = json.load(open(sys.argv[1]))
    t0 = time.time()
    bpy.ops.wm.read_factory_settings(use_empty=True)
    bpy.ops.import_scene.gltf(filepath=job["glb"])
    t_import = time.time() - t0
    scene = bpy.context.scene
    parts = [o for o in scene.objects if o.type == "MESH" and o.data.materials]
    part = next(o for o in parts if o.name != "strokes")
    mat = part.data.materials[0]
    bsdf = principled(mat)
    info = {
        "uv_layers": [uv.name for uv in part.data.uv_layers],
        "tangent_from": linked_from(bsdf, "Tangent"),
        "rotation_from": linked_from(bsdf, "Anisotropic Rotation"),
        "anisotropic_from": linked_from(bsdf, "Anisotropic"),
        "imported_roughness": bsdf.inputs["Roughness"].default_value,
    }
    tangent_nodes = [n for n in mat.node_tree.nodes if n.type == "TANGENT"]
    info["tangent_nodes"] = [(n.direction_type, n.uv_map) for n in tangent_nodes]
    for l in list(bsdf.inputs["Anisotropic"].links):
        mat.node_tree.links.remove(l)
    bsdf.inputs["Anisotropic"].default_value = 1.0
    for l in list(bsdf.inputs["Roughness"].links):
        mat.node_tree.links.remove(l)
    bsdf.inputs["Roughness"].default_value = 0.3
    cams = [o for o in scene.objects if o.type == "CAMERA"]
    suns = [o for o in scene.objects if o.type == "LIGHT"]
    info["cameras"] = len(cams)
    info["lights"] = [(o.data.type, o.data.energy) for o in suns]
    scene.camera = cams[0]
    for o in suns:
        o.data.angle = 0.0
    world = bpy.data.worlds.new("black")
    world.use_nodes = True
    world.node_tree.nodes["Background"].inputs["Strength"].default_value = 0.0
    scene.world = world
    scene.render.engine = "CYCLES"
    scene.cycles.device = "CPU"
    scene.cycles.samples = int(job.get("samples", 16))
    scene.cycles.use_adaptive_sampling = False
    scene.cycles.use_denoising = False
    scene.cycles.seed = 1
    scene.cycles.max_bounces = 1
    scene.render.threads_mode = "FIXED"
    scene.render.threads = int(job.get("threads", 2))
    scene.render.film_transparent = True
    size = int(job["size"])
    scene.render.resolution_x = size
    scene.render.resolution_y = size
    scene.render.resolution_percentage = 100
    scene.render.image_settings.file_format = "OPEN_EXR"
    scene.render.image_settings.color_depth = "32"
    exr = job["raw"] + ".exr"
    scene.render.filepath = exr
    t1 = time.time()
    bpy.ops.render.render(write_still=True)
    t_render = time.time() - t1
    img = bpy.data.images.load(exr)
    px = list(img.pixels)  # RGBA float, rows bottom to top
    with open(job["raw"], "wb") as f:
        for y in range(size - 1, -1, -1):
            row = px[4 * size * y: 4 * size * (y + 1)]
            f.write(struct.pack(f"<{4 * size}f", *row))
    if job.get("blend"):
        bpy.ops.wm.save_as_mainfile(filepath=job["blend"])
    info["seconds"] = {"import": round(t_import, 2), "render": round(t_render, 2)}
    print(json.dumps({"ok": True, "info": info}))


main()
sys.stdout.flush()
sys.stderr.flush()
# bpy 4.2 can crash in the interpreter's teardown after a Cycles render (exit 139 with every
# output written): leave without it.
os._exit(0)
