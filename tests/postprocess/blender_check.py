# Imports sinew-export's glTF and PC2 (+ rest OBJ) into Blender headless and checks what an artist
# sees (tests/postprocess/artist_tools_test.cpp runs it):
#   blender -b --factory-startup --python-exit-code 1 -P blender_check.py -- \
#       OUT.glb REST.obj OUT.pc2 EXPECT.json
# EXPECT.json: {"fps": F, "range": [first, last] (the glTF action's frame range),
#   "positions": [[x, y, z] per results frame k] (one vertex, Blender world coordinates, m),
#   "gltf": [[n, k], ...] and "pc2": [[n, k], ...] (Blender frame n must show results frame k),
#   "color": true when the glTF has COLOR_0 (optional)}.
# Checks, for the glTF (imported with Smooth shading: Debian's Blender 3.4 importer fails with its
# default shading, a numpy >= 1.24 bug) and for the OBJ + Mesh Cache modifier (default settings:
# no axis mapping): the animation's frame range, and that Blender frame n_k shows results frame k
# at one vertex (consecutive results frames differ there, so showing a neighbouring frame fails).
# Prints one line per check; exits 1 on any failure.
import json
import sys

import bpy

argv = sys.argv[sys.argv.index("--") + 1:]
glb_path, obj_path, pc2_path, expect_path = argv
with open(expect_path) as f:
    expect = json.load(f)
failures = []


def check(ok, what):
    print(("ok      " if ok else "FAILED  ") + what)
    if not ok:
        failures.append(what)


def world_positions(obj):
    """The evaluated mesh's vertices in world coordinates (shape keys and modifiers applied)."""
    evaluated = obj.evaluated_get(bpy.context.evaluated_depsgraph_get())
    mesh = evaluated.to_mesh()
    out = [obj.matrix_world @ v.co for v in mesh.vertices]
    evaluated.to_mesh_clear()
    return out


def nearest(points, p):
    return min(range(len(points)), key=lambda i: (points[i] - p).length)


def check_mapping(obj, label, pairs):
    from mathutils import Vector
    scene = bpy.context.scene
    scene.frame_set(pairs[0][0])
    points = world_positions(obj)
    want = [Vector(p) for p in expect["positions"]]
    i = nearest(points, want[pairs[0][1]])
    for n, k in pairs:
        scene.frame_set(n)
        p = world_positions(obj)[i]
        shown = min(range(len(want)), key=lambda j: (p - want[j]).length)
        check((p - want[k]).length < 1e-6,
              f"{label}: Blender frame {n} shows results frame {k} (vertex {i}: results frame "
              f"{shown}'s position, off by {(p - want[k]).length:.2e} m)")


bpy.ops.wm.read_factory_settings(use_empty=True)  # no default cube
scene = bpy.context.scene
scene.render.fps = int(expect["fps"])
scene.render.fps_base = 1.0

# glTF: shape keys driven by an action.
bpy.ops.import_scene.gltf(filepath=glb_path, import_shading="SMOOTH")
meshes = [o for o in scene.objects if o.type == "MESH"]
check(len(meshes) == 1, f"glTF: one mesh object (got {len(meshes)})")
gltf_obj = meshes[0]
keys = gltf_obj.data.shape_keys
count = len(expect["positions"])
check(keys is not None and len(keys.key_blocks) == count + 1, f"glTF: {count} shape keys + Basis")
lo, hi = keys.animation_data.action.frame_range
first, last = expect["range"]
check(abs(lo - first) < 1e-3 and abs(hi - last) < 1e-3,
      f"glTF: action frame range {lo:g} .. {hi:g} (want {first} .. {last})")
check_mapping(gltf_obj, "glTF", expect["gltf"])
if expect.get("color"):
    names = [c.name for c in gltf_obj.data.color_attributes]
    check(names == ["Col"], f"glTF: COLOR_0 imported as the colour attribute Col (got {names})")
gltf_obj.hide_viewport = True
gltf_obj.hide_render = True

# PC2: the rest OBJ with a Mesh Cache modifier at its default settings.
bpy.ops.wm.obj_import(filepath=obj_path)
obj = bpy.context.selected_objects[0]
cache = obj.modifiers.new("sinew", "MESH_CACHE")
cache.cache_format = "PC2"
cache.filepath = pc2_path
check_mapping(obj, "PC2", expect["pc2"])

if failures:
    print(f"{len(failures)} check(s) failed")
    sys.exit(1)
print("all checks passed")
