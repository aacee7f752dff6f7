#!/usr/bin/python3
"""Mutation fuzzer for the sinew tools' input files (docs/development.md, "Fuzzing the readers").

Builds small valid inputs with the tools themselves (a box and a skin-block model, a short CPU run's
results and checkpoint, a sweep, the sample head's rig spec and landmarks, a voxelizer spec), makes
broken variants of them (YAML: keys removed, renamed, retyped, numbers replaced by NaN/inf/-1/0/
1e308, huge lists, wrong nesting, truncated text, binary garbage, UTF-8 oddities, alias bombs, deep
nesting, an empty file, a directory; HDF5: datasets deleted, resized, retyped, replaced by groups,
out-of-range and negative indices, NaN coordinates, attributes changed, truncated and bit-flipped
files; meshes for sinew-voxelize, scripts/fuzz_meshes.py: PLY (ASCII and binary), OFF, glTF and
STL with broken headers, counts, numbers, faces, accessors and bytes, and a 2 GB file of zeros
named .ply), runs each tool on each variant under a timeout, and classifies every run:

  error    nonzero exit with a one-line message that names the input file (the standard)
  vague    nonzero exit whose message does not name the file (reported, not a failure)
  unstable exit 3: a run that blew up on a damaged but readable input (sinew-simulate, -sweep)
  ok       exit 0 (fine when the variant is still valid)
  crash    killed by a signal, an abort, "terminate called", a sanitizer report
  hang     still running at the timeout
  partial  a failed run left an output under its final name, or any run left a .tmp- file
  silent   a restart from a checkpoint whose state had one bit flipped (in /u, /u_prev,
           /sliding_triangle, or the step, time or dt attribute) exited 0: damage went unnoticed

and, as target live_origin, sends sinew-live --play requests of a hostile web page (foreign Origins
and Hosts: scripts/fuzz_live.py), each refused, accepted, hang or crash, then checks that the
user's own page still gets in (own, or locked_out).

Exit status: 0 when no crash, hang, partial, silent, accepted or locked_out was found, 1 otherwise. The seed makes the variants
reproducible: `--seed 1 --variants 40` gives the same files on every machine.

  scripts/fuzz_inputs.py --build build/dev --work /tmp/sinew-fuzz --variants 40
  scripts/fuzz_inputs.py --build build/dev --targets inspect,export_glb --variants 200 --keep
  scripts/fuzz_inputs.py --build build/dev --targets voxelize_mesh --mesh-variants 500
"""
import argparse
import collections
import copy
import json
import os
import random
import re
import resource
import shutil
import signal
import subprocess
import sys
import time

import fuzz_live  # scripts/fuzz_live.py: hostile pages' requests to sinew-live
import fuzz_meshes  # scripts/fuzz_meshes.py: the mesh seeds and mutations

try:
    import h5py
    import numpy as np
    import yaml
except ImportError as e:  # ctest's fuzz_tool_inputs skips on 77 (install-deps installs them)
    print(f"fuzz_inputs: skipped: {e} (python3-h5py and python3-yaml, scripts/install-deps)")
    sys.exit(77)

REPO = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))

# ----------------------------------------------------------------------------------------------
# Seeds: small valid inputs, made by the tools under test.

SCENE = """title: fuzz seed
model: model.h5
effects: [elasticity, hourglass, damping, loads]
duration: 0.002
damping: 2000
boundary_conditions:
  - {type: fixed, set: z_min}
  - {type: force, set: press, value: [0, 0, -0.5], curve: {ramp: 0.001, hold: 0.0005, release: 0.0005}}
output:
  interval: 0.0005
  fields: [stress, J, surfaces]
  probe_interval: 0.0002
probes:
  - {name: top_centre, type: displacement, point: [0.003, 0.003, 0.004]}
  - {name: base_reaction, type: reaction, set: z_min}
"""

HEAD_SCENE = """title: fuzz sliding seed
model: head.h5
effects: [elasticity, hourglass, damping, muscles, sliding]
duration: 0.004
mass_scaling: 36
damping: 50
muscles:
  frontalis_left: {ramp: 0.002, peak: 0.5}
output:
  interval: 0.002
  fields: [surfaces]
"""

SWEEP = """version: 1
title: fuzz seed sweep
scene: scene.yaml
grid:
  damping: [1000, 2000]
  boundary_conditions[1].value: [[0, 0, -0.5], [0, 0, -0.25]]
figures:
  - {name: top_end, probe: top_centre, value: uz}
  - {name: top_at, probe: top_centre, value: uz, at: 0.001}
  - {name: base_max, probe: base_reaction, value: fz, stat: max_abs}
  - {name: kinetic_end, energy: kinetic}
  - {name: dt, summary: dt_s}
run: {device: cpu}
"""


# The voxelize_mesh target's spec: the mesh (an icosphere of radius 10 mm) as the skin, coarse voxels
# so that a mesh that still reads runs in a fraction of a second.
MESH_SPEC = """units: mm
resolution: {{voxel_size: 4}}
outer: {mesh}
materials: {{preset: warburton2013}}
layers: [{{material: dermis}}]
"""


def tool(build, folder, name):
    path = os.path.join(build, folder, name)
    if not os.path.exists(path):
        sys.exit(f"fuzz_inputs: {path} is missing: build it first (docs/development.md)")
    return path


def check_call(argv, cwd):
    r = subprocess.run(argv, cwd=cwd, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    if r.returncode != 0:
        sys.exit(f"fuzz_inputs: seed step failed: {' '.join(argv)}\n{r.stdout}")


def write_mesh_seeds(seed_dir):
    """One mesh of each format (fuzz_meshes.py), voxelized by MESH_SPEC."""
    os.makedirs(os.path.join(seed_dir, "meshes"), exist_ok=True)
    for name, (ext, data) in fuzz_meshes.seeds().items():
        with open(os.path.join(seed_dir, "meshes", name + ext), "wb") as f:
            f.write(data)


def make_seeds(build, seed_dir, with_voxelizer, meshes_only=False):
    os.makedirs(seed_dir, exist_ok=True)
    if meshes_only:  # the voxelize_mesh target alone needs only sinew-voxelize
        write_mesh_seeds(seed_dir)
        return
    check_call([tool(build, "formats", "sinew-generate"), "box", "--dims", "3", "3", "3",
                "--voxel-size", "0.005", "--material", "soft:3000:0.45:1000", "-o", "box.h5"],
               seed_dir)
    check_call([tool(build, "simulator", "sinew-sample-model"), "skin-block", "--dims", "6", "6",
                "4", "--voxel-size", "0.001", "-q", "-o", "model.h5"], seed_dir)
    with open(os.path.join(seed_dir, "scene.yaml"), "w") as f:
        f.write(SCENE)
    with open(os.path.join(seed_dir, "sweep.yaml"), "w") as f:
        f.write(SWEEP)
    check_call([tool(build, "simulator", "sinew-simulate"), "scene.yaml", "-o", "run", "-q",
                "--threads", "1", "--checkpoint-every", "100"], seed_dir)
    shutil.copy(os.path.join(seed_dir, "run", "results.h5"), os.path.join(seed_dir, "results.h5"))
    shutil.copy(os.path.join(seed_dir, "run", "checkpoint.h5"),
                os.path.join(seed_dir, "checkpoint.h5"))
    if with_voxelizer:
        check_call([tool(build, "voxelizer", "sinew-head"), "-o", "head"], seed_dir)
        with open(os.path.join(REPO, "data", "specs", "sample_head_3mm.yaml")) as f:
            spec = f.read().replace("../meshes/head/", "head/")
        spec = spec.replace("../landmarks/sample_head.yaml", "landmarks.yaml")
        with open(os.path.join(seed_dir, "rig_spec.yaml"), "w") as f:
            f.write(spec)
        shutil.copy(os.path.join(REPO, "data", "landmarks", "sample_head.yaml"),
                    os.path.join(seed_dir, "landmarks.yaml"))
        # The sample head at 3 mm: sliding nodes on the skull, so that a checkpoint carries
        # sliding triangle ids (the box models have none).
        check_call([tool(build, "voxelizer", "sinew-voxelize"), "rig_spec.yaml", "-o", "head.h5",
                    "-q"], seed_dir)
        with open(os.path.join(seed_dir, "head_scene.yaml"), "w") as f:
            f.write(HEAD_SCENE)
        check_call([tool(build, "simulator", "sinew-simulate"), "head_scene.yaml", "-o", "hrun",
                    "-q", "--checkpoint-every", "20"], seed_dir)
        shutil.copy(os.path.join(seed_dir, "hrun", "checkpoint.h5"),
                    os.path.join(seed_dir, "head_checkpoint.h5"))
        with open(os.path.join(REPO, "data", "specs", "demo_layered_block.yaml")) as f:
            spec = f.read().replace("voxel_size: 1.0", "voxel_size: 2.0")
        with open(os.path.join(seed_dir, "vox_spec.yaml"), "w") as f:
            f.write(spec)
        write_mesh_seeds(seed_dir)


# ----------------------------------------------------------------------------------------------
# YAML mutations. Each takes (rng, text) and returns bytes, or None when it does not apply.

SPECIAL_NUMBERS = [float("nan"), float("inf"), float("-inf"), -1, 0, 1e308, -1e308, 1e-308,
                   2**31, 2**63, -(2**63), 4294967297, 0.5, 1e-30]
ODD_VALUES = ["abc", "", [1, 2], {"a": 1}, None, True, [], {}, "../../../../dev/zero",
              "/dev/null", "/", "\u202e\u0000x", "é" * 3, "x" * 100000, [[[]]], -0.0]


def yaml_paths(node, prefix=()):
    """Every (path, value) pair of a loaded YAML document, containers included."""
    out = [(prefix, node)]
    if isinstance(node, dict):
        for k, v in node.items():
            out += yaml_paths(v, prefix + (k,))
    elif isinstance(node, list):
        for i, v in enumerate(node):
            out += yaml_paths(v, prefix + (i,))
    return out


def set_at(doc, path, value):
    if not path:
        return value
    node = doc
    for p in path[:-1]:
        node = node[p]
    node[path[-1]] = value
    return doc


def dump(doc):
    return yaml.safe_dump(doc, default_flow_style=None, allow_unicode=True, width=100).encode()


def structured(fn):
    def mutate(rng, text):
        try:
            doc = yaml.safe_load(text)
        except yaml.YAMLError:
            return None
        if not isinstance(doc, (dict, list)):
            return None
        return fn(rng, doc)
    mutate.__name__ = fn.__name__
    return mutate


@structured
def remove_key(rng, doc):
    dicts = [(p, v) for p, v in yaml_paths(doc) if isinstance(v, dict) and v]
    path, d = rng.choice(dicts)
    del d[rng.choice(list(d))]
    return dump(doc)


@structured
def rename_key(rng, doc):
    dicts = [(p, v) for p, v in yaml_paths(doc) if isinstance(v, dict) and v]
    path, d = rng.choice(dicts)
    k = rng.choice(list(d))
    d[str(k) + rng.choice(["_x", "s", "X"])] = d.pop(k)
    return dump(doc)


@structured
def retype_value(rng, doc):
    path, _ = rng.choice(yaml_paths(doc)[1:])
    return dump(set_at(doc, path, copy.deepcopy(rng.choice(ODD_VALUES))))


@structured
def special_number(rng, doc):
    nums = [p for p, v in yaml_paths(doc) if isinstance(v, (int, float)) and not isinstance(v, bool)]
    if not nums:
        return None
    for _ in range(rng.choice([1, 1, 1, 3])):
        set_at(doc, rng.choice(nums), rng.choice(SPECIAL_NUMBERS))
    return dump(doc)


@structured
def huge_list(rng, doc):
    lists = [(p, v) for p, v in yaml_paths(doc) if isinstance(v, list) and v]
    if not lists:
        return None
    path, v = rng.choice(lists)
    n = rng.choice([1000, 100000])
    set_at(doc, path, [copy.deepcopy(v[0]) for _ in range(n)])
    return dump(doc)


@structured
def wrong_nesting(rng, doc):
    path, v = rng.choice(yaml_paths(doc)[1:])
    wrapped = rng.choice([[v], {"value": v}, [[v]]])
    return dump(set_at(doc, path, wrapped))


@structured
def duplicate_entry(rng, doc):
    lists = [(p, v) for p, v in yaml_paths(doc) if isinstance(v, list) and v]
    if not lists:
        return None
    _, v = rng.choice(lists)
    v.append(copy.deepcopy(rng.choice(v)))
    return dump(doc)


def truncate(rng, text):
    return text[: rng.randrange(0, max(1, len(text)))]


def garbage(rng, text):
    return bytes(rng.randrange(256) for _ in range(rng.choice([16, 1000, 70000])))


def splice_garbage(rng, text):
    at = rng.randrange(len(text) + 1)
    return text[:at] + bytes(rng.randrange(256) for _ in range(rng.randrange(1, 40))) + text[at:]


def utf8_oddity(rng, text):
    odd = rng.choice([b"\xef\xbb\xbf", b"\xff\xfe", b"\x00", b"\xc3\x28", b"\xe2\x80\xae",
                      b"\xf0\x9f\x98\x80", b"\xed\xa0\x80", b"\r", b"\t"])
    if rng.random() < 0.3:
        return odd + text
    at = rng.randrange(len(text) + 1)
    return text[:at] + odd + text[at:]


def alias_bomb(rng, text):
    lines = ["a: &a [x, x, x, x, x, x, x, x, x, x]"]
    for i in range(1, 9):
        prev = chr(ord("a") + i - 1)
        cur = chr(ord("a") + i)
        lines.append(f"{cur}: &{cur} [*{prev}, *{prev}, *{prev}, *{prev}, *{prev}, *{prev}, *{prev},"
                     f" *{prev}, *{prev}, *{prev}]")
    return text + ("\n".join(lines) + "\n").encode()


def deep_nesting(rng, text):
    depth = rng.choice([1000, 100000])
    key = rng.choice([b"title", b"effects", b"grid", b"landmarks", b"zzz"])
    return text + b"\n" + key + b": " + b"[" * depth + b"]" * depth + b"\n"


def duplicate_key(rng, text):
    lines = text.splitlines(keepends=True)
    top = [l for l in lines if re.match(rb"^[a-z_]+:", l)]
    return text + b"\n" + rng.choice(top) if top else None


def empty(rng, text):
    return b""


def only_comment(rng, text):
    return b"# nothing here\n"


def scalar_document(rng, text):
    return rng.choice([b"42\n", b"- 1\n- 2\n", b"~\n", b"---\n---\n", b"...\n"])


YAML_MUTATIONS = [remove_key, rename_key, retype_value, special_number, special_number,
                  huge_list, wrong_nesting, duplicate_entry, truncate, garbage, splice_garbage,
                  utf8_oddity, alias_bomb, deep_nesting, duplicate_key, empty, only_comment,
                  scalar_document]


# ----------------------------------------------------------------------------------------------
# HDF5 mutations, on a copy of the seed file (h5py). Each takes (rng, path) and returns a label.

def datasets(f):
    out = []
    f.visititems(lambda n, o: out.append(n) if isinstance(o, h5py.Dataset) else None)
    return out


def groups(f):
    out = []
    f.visititems(lambda n, o: out.append(n) if isinstance(o, h5py.Group) else None)
    return out


def replace(f, name, data):
    attrs = dict(f[name].attrs)
    del f[name]
    d = f.create_dataset(name, data=data)
    for k, v in attrs.items():
        d.attrs[k] = v


def pick(rng, names, prefer=None):
    if prefer:
        good = [n for n in names if prefer(n)]
        if good and rng.random() < 0.7:
            return rng.choice(good)
    return rng.choice(names)


def h5_delete(rng, f):
    name = pick(rng, datasets(f) + groups(f))
    del f[name]
    return name


def h5_resize(rng, f):
    name = pick(rng, datasets(f))
    a = f[name][()]
    if a.ndim == 0:
        a = np.array([a, a])
    elif a.shape[0] == 0:
        a = np.zeros((3,) + a.shape[1:], dtype=a.dtype)
    else:
        n = rng.choice([0, 1, a.shape[0] - 1, a.shape[0] + 1, a.shape[0] * 2])
        idx = np.arange(n) % a.shape[0]
        a = a[idx]
    replace(f, name, a)
    return name


def h5_retype(rng, f):
    name = pick(rng, datasets(f))
    a = f[name][()]
    choice = "numbers"
    if isinstance(a, (bytes, str)) or (hasattr(a, "dtype") and a.dtype.kind in "OSU"):
        new = np.array([1.5, 2.5])
    else:
        a = np.asarray(a)
        choice = rng.choice(["float", "int8", "uint64", "string", "scalar", "bool"])
        if choice == "float":
            new = a.astype(np.float32) + 0.5
        elif choice == "int8":
            new = a.astype(np.int8)
        elif choice == "uint64":
            new = np.abs(a).astype(np.uint64)
        elif choice == "bool":
            new = a.astype(bool)
        elif choice == "string":
            new = np.array(["abc"] * max(1, a.size), dtype=h5py.string_dtype())
        else:
            new = np.float64(7)
    replace(f, name, new)
    return f"{name} {choice}"


def h5_bad_index(rng, f):
    ints = [n for n in datasets(f) if f[n].dtype.kind in "iu" and f[n].size > 0]
    if not ints:
        return None
    name = rng.choice(ints)
    a = f[name][()].copy()
    flat = a.reshape(-1)
    k = rng.randrange(flat.size)
    flat[k] = rng.choice([int(flat.max()) + 1, 100000, -1, -(2**31), 2**31 - 1, 0])
    replace(f, name, a)
    return f"{name}[{k}]={flat[k]}"


def h5_nan(rng, f):
    floats = [n for n in datasets(f) if f[n].dtype.kind == "f" and f[n].size > 0]
    if not floats:
        return None
    name = rng.choice(floats)
    a = f[name][()].copy()
    flat = np.asarray(a).reshape(-1)
    values = []
    for _ in range(rng.choice([1, 1, 5])):
        values.append(rng.choice([np.nan, np.inf, -np.inf, 1e308, -1.0, 0.0]))
        flat[rng.randrange(flat.size)] = values[-1]
    replace(f, name, flat.reshape(np.shape(a)))
    return f"{name}={','.join(str(v) for v in values)}"


def h5_shape(rng, f):
    multi = [n for n in datasets(f) if f[n].ndim >= 1 and f[n].size > 0]
    name = rng.choice(multi)
    a = f[name][()]
    choice = rng.choice(["transpose", "flatten", "column", "add_axis"])
    if choice == "transpose" and a.ndim >= 2:
        a = a.T.copy()
    elif choice == "column" and a.ndim >= 2:
        a = a[..., :-1].copy()
    elif choice == "add_axis":
        a = a[..., None].copy()
    else:
        a = a.reshape(-1)
        a = np.concatenate([a, a[:1]])
    replace(f, name, a)
    return f"{name} {choice}"


def h5_group_for_dataset(rng, f):
    name = pick(rng, datasets(f))
    del f[name]
    f.create_group(name)
    return name


def h5_attr(rng, f):
    holders = [f] + [f[n] for n in datasets(f) + groups(f) if len(f[n].attrs)]
    obj = rng.choice(holders)
    if not len(obj.attrs):
        return None
    key = rng.choice(list(obj.attrs))
    choice = rng.choice(["delete", "number", "string", "big", "array"])
    if choice == "delete":
        del obj.attrs[key]
    elif choice == "number":
        obj.attrs[key] = rng.choice([-1, 0, 99, 2**40])
    elif choice == "string":
        obj.attrs[key] = rng.choice(["", "sinew-model", "sinew-results", "x" * 5000])
    elif choice == "big":
        obj.attrs[key] = np.float64(np.nan)
    else:
        obj.attrs[key] = np.arange(4)
    return f"{obj.name}@{key}"


H5_STRUCTURAL = [h5_delete, h5_resize, h5_retype, h5_bad_index, h5_bad_index, h5_nan, h5_nan,
                 h5_shape, h5_group_for_dataset, h5_attr]


def h5_truncate(rng, data):
    return data[: rng.randrange(0, len(data))]


def h5_bitflip(rng, data):
    b = bytearray(data)
    for _ in range(rng.choice([1, 8, 64])):
        b[rng.randrange(len(b))] ^= 1 << rng.randrange(8)
    return bytes(b)


def h5_garbage(rng, data):
    return bytes(rng.randrange(256) for _ in range(rng.choice([0, 8, 4096])))


H5_BYTES = [h5_truncate, h5_bitflip, h5_garbage]


def state_flip(rng, f):
    """One bit of a checkpoint's state flipped in place, keeping every attribute (its digests):
    what a bad sector does. A restart must refuse it (issue 33: it restarted with exit 0)."""
    names = [n for n in ("u", "u_prev", "sliding_triangle") if n in f and f[n].size]
    if rng.random() < 0.25 or not names:
        key = rng.choice(["step", "time", "dt"])
        value = np.array(f.attrs[key])
        raw = value.view(np.uint64 if value.dtype.itemsize == 8 else np.uint32).copy()
        raw ^= raw.dtype.type(1) << raw.dtype.type(rng.randrange(8 * value.dtype.itemsize))
        f.attrs.modify(key, raw.view(value.dtype))
        return f"@{key}"
    name = rng.choice(names)
    data = f[name][...]
    flat = data.reshape(-1).view(np.uint64 if data.dtype.itemsize == 8 else np.uint32)
    i = rng.randrange(flat.size)
    flat[i] ^= flat.dtype.type(1) << flat.dtype.type(rng.randrange(8 * data.dtype.itemsize))
    f[name][...] = data
    return f"/{name}[{i}]"


def make_h5_variant(rng, seed_path, out_path, state_flips=False):
    if state_flips and rng.random() < 0.3:
        shutil.copy(seed_path, out_path)
        with h5py.File(out_path, "r+") as f:
            return f"state_flip {state_flip(rng, f)}"
    if rng.random() < 0.22:
        fn = rng.choice(H5_BYTES)
        with open(seed_path, "rb") as f:
            data = f.read()
        with open(out_path, "wb") as f:
            f.write(fn(rng, data))
        return fn.__name__
    for _ in range(10):
        shutil.copy(seed_path, out_path)
        fn = rng.choice(H5_STRUCTURAL)
        try:
            with h5py.File(out_path, "r+") as f:
                what = fn(rng, f)
        except Exception:  # a mutation that does not apply to this dataset: draw another
            what = None
        if what is not None:
            return f"{fn.__name__} {what}"
    return "copy"


def make_yaml_variant(rng, seed_path, out_path):
    with open(seed_path, "rb") as f:
        text = f.read()
    for _ in range(10):
        fn = rng.choice(YAML_MUTATIONS)
        data = fn(rng, text)
        if data is not None:
            with open(out_path, "wb") as f:
                f.write(data)
            return fn.__name__
    shutil.copy(seed_path, out_path)
    return "copy"


def make_mesh_variant(rng, seed_dir, i, run_dir, special):
    """The voxelize_mesh target's input: the i-th format's seed mutated (or a special input named
    like a PLY), and the spec that reads it. Returns (variant file name, label)."""
    names = sorted(fuzz_meshes.FORMATS)
    fmt = names[i % len(names)]
    ext = fuzz_meshes.FORMATS[fmt][0]
    variant = "mesh.ply" if special else "mesh" + ext
    with open(os.path.join(run_dir, "mesh_spec.yaml"), "w") as f:
        f.write(MESH_SPEC.format(mesh=variant))
    path = os.path.join(run_dir, variant)
    if special:
        return variant, make_special_variant(special, path)
    with open(os.path.join(seed_dir, "meshes", fmt + ext), "rb") as f:
        data, label = fuzz_meshes.mutate(rng, f.read(), fmt)
    with open(path, "wb") as f:
        f.write(data)
    return variant, f"{fmt} {label}"


def make_special_variant(kind, out_path):
    """An input that is not a file: a folder, a missing file, a FIFO nobody writes (a reader that
    blocks on it hangs), a character device; for meshes also a 2 GiB file of zeros (sparse: it
    costs no disk; assimp 5.2 died of SIGBUS on one named .ply)."""
    if kind == "zeros_2g":
        with open(out_path, "wb") as f:
            f.truncate(2 << 30)
    elif kind == "directory":
        os.makedirs(out_path)
    elif kind == "missing":
        pass
    elif kind == "fifo":
        os.mkfifo(out_path)
    elif kind == "dev_zero":
        os.symlink("/dev/zero", out_path)
    return kind


SPECIALS = ["directory", "missing", "fifo", "dev_zero"]
MESH_SPECIALS = SPECIALS + ["zeros_2g"]

# ----------------------------------------------------------------------------------------------
# Targets: a tool, the seed it mutates, where the variant goes and the command line.


class Target:
    def __init__(self, name, kind, seed, variant_name, argv, outputs, extra=(), live=False,
                 failure_keeps=(), state_flips=False):
        self.name, self.kind, self.seed = name, kind, seed
        self.variant_name = variant_name  # the variant's file name inside its run folder
        self.argv = argv                  # (build, run_dir) -> argv; the run folder is the cwd
        self.outputs = outputs            # outputs (relative) that a failed run must not leave
        self.extra = extra                # seed files copied into the run folder
        self.live = live                  # a server: success is its "open http" line
        self.failure_keeps = failure_keeps  # outputs a failed run may keep if valid HDF5
        self.state_flips = state_flips    # a checkpoint: some variants flip one bit of its state


def targets(build, with_voxelizer, live_three):
    T = []
    sim = lambda b: tool(b, "simulator", "sinew-simulate")
    T.append(Target("inspect", "h5", "model.h5", "model.h5",
                    lambda b: [tool(b, "formats", "sinew-inspect"), "model.h5"], []))
    T.append(Target("inspect_box", "h5", "box.h5", "model.h5",
                    lambda b: [tool(b, "formats", "sinew-inspect"), "--json", "model.h5"], []))
    T.append(Target("simulate_model", "h5", "model.h5", "model.h5",
                    lambda b: [sim(b), "scene.yaml", "-o", "out", "--threads", "1"],
                    [], extra=["scene.yaml"],
                    failure_keeps=["out/results.h5"]))
    T.append(Target("simulate_scene", "yaml", "scene.yaml", "scene.yaml",
                    lambda b: [sim(b), "scene.yaml", "-o", "out", "--threads", "1"],
                    [], extra=["model.h5"], failure_keeps=["out/results.h5"]))
    T.append(Target("simulate_explain", "yaml", "scene.yaml", "scene.yaml",
                    lambda b: [sim(b), "scene.yaml", "--explain"], [], extra=["model.h5"]))
    T.append(Target("simulate_restart", "h5", "checkpoint.h5", "ckpt.h5",
                    lambda b: [sim(b), "scene.yaml", "-o", "run", "--threads", "1", "--restart",
                               "ckpt.h5"],
                    [], extra=["scene.yaml", "model.h5", "run"], failure_keeps=["run/results.h5"],
                    state_flips=True))
    T.append(Target("export_glb", "h5", "results.h5", "results.h5",
                    lambda b: [tool(b, "postprocess", "sinew-export"), "results.h5", "--glb",
                               "out.glb"], ["out.glb"]))
    T.append(Target("export_pc2", "h5", "results.h5", "results.h5",
                    lambda b: [tool(b, "postprocess", "sinew-export"), "results.h5", "--pc2",
                               "out.pc2", "--rest-obj", "rest.obj", "--obj-sequence", "seq"],
                    ["out.pc2", "rest.obj"]))
    T.append(Target("render", "h5", "results.h5", "results.h5",
                    lambda b: [tool(b, "postprocess", "sinew-render"), "results.h5", "--frame",
                               "2", "--size", "64x48", "-o", "out.png", "--contact-sheet",
                               "sheet.png"], ["out.png", "sheet.png"]))
    T.append(Target("render_model", "h5", "model.h5", "model.h5",
                    lambda b: [tool(b, "postprocess", "sinew-render"), "model.h5", "--size",
                               "64x48", "-o", "out.png"], ["out.png"]))
    T.append(Target("wrinkles", "h5", "results.h5", "results.h5",
                    lambda b: [tool(b, "postprocess", "sinew-wrinkles"), "results.h5", "--json",
                               "out.json", "--csv", "out.csv", "-q"], ["out.json", "out.csv"]))
    T.append(Target("sweep", "yaml", "sweep.yaml", "sweep.yaml",
                    lambda b: [tool(b, "sweep", "sinew-sweep"), "sweep.yaml", "-o", "out",
                               "--threads", "1", "-q"], [],
                    extra=["scene.yaml", "model.h5"]))
    if not os.path.isdir(live_three):
        print(f"fuzz_inputs: live_play skipped: no three.js at {live_three} (install-deps)")
    else:
        T.append(Target("live_play", "h5", "results.h5", "results.h5",
                        lambda b: [tool(b, "live", "sinew-live"), "--play", "results.h5",
                                   "--port", "0", "--three", live_three], [],
                        extra=["scene.yaml", "model.h5"], live=True))
    if with_voxelizer:
        T.append(Target("rig_spec", "yaml", "rig_spec.yaml", "rig_spec.yaml",
                        lambda b: [tool(b, "voxelizer", "sinew-rig"), "rig_spec.yaml", "-o",
                                   "out"], [], extra=["head", "landmarks.yaml"]))
        T.append(Target("rig_landmarks", "yaml", "landmarks.yaml", "landmarks.yaml",
                        lambda b: [tool(b, "voxelizer", "sinew-rig"), "rig_spec.yaml", "-o",
                                   "out"], [], extra=["head", "rig_spec.yaml"]))
        T.append(Target("simulate_head_model", "h5", "head.h5", "head.h5",
                        lambda b: [sim(b), "head_scene.yaml", "-o", "out", "-q"], [],
                        extra=["head_scene.yaml"], failure_keeps=["out/results.h5"]))
        T.append(Target("simulate_head_restart", "h5", "head_checkpoint.h5", "ckpt.h5",
                        lambda b: [sim(b), "head_scene.yaml", "-o", "hrun", "-q", "--restart",
                                   "ckpt.h5"], [], extra=["head_scene.yaml", "head.h5", "hrun"],
                        failure_keeps=["hrun/results.h5"], state_flips=True))
        T.append(Target("voxelize", "yaml", "vox_spec.yaml", "vox_spec.yaml",
                        lambda b: [tool(b, "voxelizer", "sinew-voxelize"), "vox_spec.yaml", "-o",
                                   "out.h5", "-q", "--threads", "1"], ["out.h5"]))
        # The variant is a mesh of one of fuzz_meshes.FORMATS (named per run, make_mesh_variant).
        T.append(Target("voxelize_mesh", "mesh", None, None,
                        lambda b: [tool(b, "voxelizer", "sinew-voxelize"), "mesh_spec.yaml", "-o",
                                   "out.h5", "-q", "--threads", "1"], ["out.h5"]))
    return T


# ----------------------------------------------------------------------------------------------
# Running and classifying.

CRASH_TEXT = re.compile(r"terminate called|Segmentation fault|core dumped|AddressSanitizer|"
                        r"UndefinedBehaviorSanitizer|runtime error:|LeakSanitizer|"
                        r"Assertion .* failed|stack smashing|double free|HDF5-DIAG")


def valid_h5(path):
    try:
        with h5py.File(path, "r"):
            return True
    except Exception:
        return False


def memory_cap(gib):
    """A limit on the tool's data segment, so that a reader filling memory (from /dev/zero, say)
    fails there rather than pushing the machine into its OOM killer. None: no limit (sanitizer
    builds reserve terabytes of shadow memory)."""
    if not gib:
        return None
    limit = int(gib * 2**30)
    return lambda: resource.setrlimit(resource.RLIMIT_DATA, (limit, limit))


def run_one(target, build, run_dir, variant_file, timeout, memory_gib, label=""):
    argv = target.argv(build)
    start = time.time()
    # The voxelizer's mesh import stops well before the run's timeout: a mesh assimp hangs on
    # must be a clean error, not a hang of the tool (docs/voxelizer.md, "Broken mesh files").
    env = dict(os.environ, SINEW_MESH_IMPORT_TIMEOUT=str(max(1.0, timeout / 4)))
    proc = subprocess.Popen(argv, cwd=run_dir, stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                            start_new_session=True, preexec_fn=memory_cap(memory_gib), env=env)
    out = b""
    hung = False
    if target.live:
        # A server: wait for its "open http" line, then stop it with SIGTERM.
        deadline = start + timeout
        os.set_blocking(proc.stdout.fileno(), False)
        while time.time() < deadline and proc.poll() is None:
            chunk = proc.stdout.read() or b""
            out += chunk
            if b"open http" in out:
                break
            time.sleep(0.05)
        served = b"open http" in out
        if proc.poll() is None:
            hung = fuzz_live.stop(proc) or not served
        os.set_blocking(proc.stdout.fileno(), True)
        out += proc.stdout.read() or b""
        rc = 0 if served and not hung else proc.returncode
    else:
        try:
            out, _ = proc.communicate(timeout=timeout)
        except subprocess.TimeoutExpired:
            os.killpg(proc.pid, signal.SIGKILL)
            out, _ = proc.communicate()
            hung = True
        rc = proc.returncode
    text = out.decode("utf-8", "replace")
    elapsed = time.time() - start

    leftovers = []
    for root, dirs, files in os.walk(run_dir):
        leftovers += [os.path.join(root, n) for n in files + dirs if ".tmp-" in n]
    if hung:
        cls = "hang"
    elif rc is not None and rc < 0 or CRASH_TEXT.search(text) or rc in (134, 139):
        cls = "crash"
    elif leftovers:
        cls = "partial"
    elif rc == 3:
        cls = "unstable"  # sinew-simulate's and sinew-sweep's status for a run that blew up
    elif rc != 0:
        bad = [o for o in target.outputs if os.path.exists(os.path.join(run_dir, o))]
        bad += [o for o in target.failure_keeps
                if os.path.exists(os.path.join(run_dir, o))
                and not valid_h5(os.path.join(run_dir, o))]
        if bad:
            cls, text = "partial", text + f"\n(left: {bad})"
        else:
            base = os.path.basename(variant_file)
            cls = "error" if base in text or variant_file in text else "vague"
    elif label.startswith("state_flip"):
        cls = "silent"  # a damaged state restarted as if whole
    else:
        cls = "ok"
    return cls, rc, elapsed, text


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--build", default=os.path.join(REPO, "build", "dev"),
                    help="the CMake build folder with the tools (default build/dev)")
    ap.add_argument("--work", default="/tmp/sinew-fuzz", help="scratch folder (emptied first)")
    ap.add_argument("--seed", type=int, default=1, help="random seed of the mutations")
    ap.add_argument("--variants", type=int, default=40, help="variants per target")
    ap.add_argument("--mesh-variants", type=int, default=None,
                    help="variants of the voxelize_mesh target (default 3 x --variants: six "
                         "formats share it)")
    ap.add_argument("--timeout", type=float, default=20, help="seconds before a run is a hang")
    ap.add_argument("--memory", type=float, default=4,
                    help="GiB of data segment per tool run (RLIMIT_DATA; 0: none, for ASan)")
    ap.add_argument("--targets", default="", help="comma-separated target names (default all)")
    ap.add_argument("--no-voxelizer", action="store_true", help="skip sinew-rig/-voxelize")
    ap.add_argument("--no-specials", action="store_true",
                    help="skip the folder, missing file, FIFO and /dev/zero inputs")
    ap.add_argument("--three", default=os.path.join(REPO, ".cache", "three", "node_modules", "three"),
                    help="three.js for sinew-live (the live_play target is skipped without it)")
    ap.add_argument("--keep", action="store_true", help="keep the folder of every run")
    ap.add_argument("--json", default="", help="write every run's record to this JSON file")
    args = ap.parse_args()

    build = os.path.abspath(args.build)
    with_vox = not args.no_voxelizer and os.path.exists(
        os.path.join(build, "voxelizer", "sinew-voxelize"))
    work = os.path.abspath(args.work)
    shutil.rmtree(work, ignore_errors=True)
    seed_dir = os.path.join(work, "seed")
    chosen = set(filter(None, args.targets.split(",")))
    make_seeds(build, seed_dir, with_vox, meshes_only=with_vox and chosen == {"voxelize_mesh"})

    all_targets = targets(build, with_vox, args.three)
    known = {t.name for t in all_targets} | {"live_origin"}
    if chosen - known:
        sys.exit(f"fuzz_inputs: unknown targets {sorted(chosen - known)}")
    records = []
    counts = collections.OrderedDict()
    for target in all_targets:
        if chosen and target.name not in chosen:
            continue
        rng = random.Random(f"{args.seed}:{target.name}")
        counts[target.name] = collections.Counter()
        mesh = target.kind == "mesh"
        n = args.variants
        if mesh:
            n = 3 * args.variants if args.mesh_variants is None else args.mesh_variants
        kinds = ([] if args.no_specials else MESH_SPECIALS if mesh else SPECIALS) + [None] * n
        for i, special in enumerate(kinds):
            run_dir = os.path.join(work, target.name, f"{i:04d}")
            os.makedirs(run_dir)
            for e in target.extra:
                src = os.path.join(seed_dir, e)
                dst = os.path.join(run_dir, e)
                (shutil.copytree if os.path.isdir(src) else shutil.copy)(src, dst)
            variant_name = target.variant_name
            if mesh:
                variant_name, label = make_mesh_variant(rng, seed_dir, i, run_dir, special)
            else:
                variant = os.path.join(run_dir, variant_name)
                seed_path = os.path.join(seed_dir, target.seed)
                if special:
                    label = make_special_variant(special, variant)
                elif target.kind == "h5":
                    label = make_h5_variant(rng, seed_path, variant, target.state_flips)
                else:
                    label = make_yaml_variant(rng, seed_path, variant)
            cls, rc, elapsed, text = run_one(target, build, run_dir, variant_name,
                                             args.timeout, args.memory, label)
            counts[target.name][cls] += 1
            last = [l for l in text.strip().splitlines() if l.strip()][-1:] or [""]
            records.append({"target": target.name, "variant": i, "mutation": label, "class": cls,
                            "rc": rc, "seconds": round(elapsed, 2), "message": last[0][:300]})
            if cls in ("crash", "hang", "partial", "silent"):
                print(f"[{cls}] {target.name} #{i} ({label}) rc={rc}: {text.strip()[-600:]}",
                      flush=True)
            elif not args.keep:
                shutil.rmtree(run_dir, ignore_errors=True)
        print(f"{target.name}: {len(kinds)} variants: " +
              ", ".join(f"{k} {v}" for k, v in sorted(counts[target.name].items())), flush=True)
    if (not chosen or "live_origin" in chosen) and os.path.isdir(args.three):
        run_dir = os.path.join(work, "live_origin")
        os.makedirs(run_dir)
        for e in ("results.h5", "scene.yaml", "model.h5"):
            shutil.copy(os.path.join(seed_dir, e), os.path.join(run_dir, e))
        argv = [tool(build, "live", "sinew-live"), "--play", "results.h5", "--port", "0",
                "--three", args.three]
        found, live_records, text = fuzz_live.campaign(argv, run_dir, args.variants, args.seed,
                                                       args.timeout)
        counts["live_origin"] = collections.Counter(found)
        records += live_records
        for r in live_records:
            if r["class"] in fuzz_live.FAILURES:
                print(f"[{r['class']}] live_origin ({r['mutation']}) status {r['status']}: "
                      f"{text.strip()[-600:]}", flush=True)
        print("live_origin: " + ", ".join(f"{k} {v}" for k, v in sorted(found.items())),
              flush=True)
    if args.json:
        with open(args.json, "w") as f:
            json.dump(records, f, indent=1)
    total = collections.Counter()
    for c in counts.values():
        total.update(c)
    print("total: " + ", ".join(f"{k} {v}" for k, v in sorted(total.items())))
    failures = ("crash", "hang", "partial", "silent") + fuzz_live.FAILURES
    return 1 if any(total[k] for k in failures) else 0


if __name__ == "__main__":
    sys.exit(main())
