# Imports sinew-export's glTF and rest OBJ into Blender headless and checks their UV maps
# (tests/postprocess/texture_coordinates_test.cpp runs it):
#   blender -b --factory-startup --python-exit-code 1 -P blender_uv_check.py -- \
#       OUT.glb REST.obj EXPECT.json
# EXPECT.json: every triangle corner as [x, y, z, u, v]: the position in Blender's world
# coordinates in µm and the texture coordinates (v up, Blender's and OBJ's convention) in 1e-6,
# rounded to integers. For each file the set of (position, UV) pairs of the imported mesh's
# face corners (loops) must equal the expected set, compared at 10 µm and 1e-5. The glTF is
# imported with Smooth shading (Debian's Blender 3.4 importer fails with its default: numpy >= 1.24),
# the OBJ with the importer's defaults. Prints one line per check; exits 1 on any failure.
import json
import sys

import bpy

argv = sys.argv[sys.argv.index("--") + 1:]
glb_path, obj_path, expect_path = argv
with open(expect_path) as f:
    expect = {tuple(round(c / 10) for c in corner) for corner in json.load(f)}
failures = []


def check(ok, what):
    print(("ok      " if ok else "FAILED  ") + what)
    if not ok:
        failures.append(what)


def corners(obj):
    mesh = obj.data
    uv = mesh.uv_layers.active
    if uv is None:
        return set()
    out = set()
    for loop in mesh.loops:
        p = obj.matrix_world @ mesh.vertices[loop.vertex_index].co
        w = uv.data[loop.index].uv
        out.add((round(p.x * 1e5), round(p.y * 1e5), round(p.z * 1e5), round(w.x * 1e5),
                 round(w.y * 1e5)))
    return out


def import_and_check(label, do_import):
    bpy.ops.wm.read_factory_settings(use_empty=True)
    do_import()
    meshes = [o for o in bpy.context.scene.objects if o.type == "MESH"]
    check(len(meshes) == 1, f"{label}: one mesh object (got {len(meshes)})")
    if not meshes:
        return
    obj = meshes[0]
    check(len(obj.data.uv_layers) >= 1,
          f"{label}: has a UV map ({[layer.name for layer in obj.data.uv_layers]})")
    got = corners(obj)
    check(got == expect,
          f"{label}: {len(got)} (position, UV) corners, {len(expect)} expected, "
          f"{len(got - expect)} unexpected, {len(expect - got)} missing")


import_and_check("glTF",
                 lambda: bpy.ops.import_scene.gltf(filepath=glb_path, import_shading="SMOOTH"))
if hasattr(bpy.ops.wm, "obj_import"):  # Blender >= 3.2's OBJ importer
    import_and_check("OBJ", lambda: bpy.ops.wm.obj_import(filepath=obj_path))
else:
    import_and_check("OBJ", lambda: bpy.ops.import_scene.obj(filepath=obj_path))
sys.exit(1 if failures else 0)
