"""Mesh files for scripts/fuzz_inputs.py's `voxelize_mesh` target (docs/development.md, "Fuzzing
the tools"): a small closed icosphere written as ASCII and binary PLY, OFF, glTF (one .gltf with
its buffer as a data URI), binary and ASCII STL, and the mutations that broke assimp 5.2.5 in
issue 33's campaign: header counts and types changed, `end_header` removed, numbers replaced by
NaN, infinity or huge values, face sizes and indices out of range, glTF accessors, buffer views
and node trees made inconsistent, and bytes truncated, flipped or spliced.

Each mutation takes (rng, data: bytes, fmt: str) and returns bytes, or None when it does not
apply to that format. Only the standard library: the fuzzer's seeds must not depend on assimp.
"""
import base64
import json
import math
import re
import struct

# ----------------------------------------------------------------------------------------------
# The seed mesh: an icosphere of radius 10 (the spec's units, mm), one subdivision: 42 vertices,
# 80 triangles, outward.


def icosphere(radius=10.0, subdivisions=1):
    t = (1 + math.sqrt(5)) / 2
    v = [(-1, t, 0), (1, t, 0), (-1, -t, 0), (1, -t, 0), (0, -1, t), (0, 1, t), (0, -1, -t),
         (0, 1, -t), (t, 0, -1), (t, 0, 1), (-t, 0, -1), (-t, 0, 1)]
    f = [(0, 11, 5), (0, 5, 1), (0, 1, 7), (0, 7, 10), (0, 10, 11), (1, 5, 9), (5, 11, 4),
         (11, 10, 2), (10, 7, 6), (7, 1, 8), (3, 9, 4), (3, 4, 2), (3, 2, 6), (3, 6, 8),
         (3, 8, 9), (4, 9, 5), (2, 4, 11), (6, 2, 10), (8, 6, 7), (9, 8, 1)]
    v = [tuple(c / math.sqrt(sum(x * x for x in p)) for c in p) for p in v]
    for _ in range(subdivisions):
        mid = {}

        def m(a, b):
            key = (min(a, b), max(a, b))
            if key not in mid:
                p = [(x + y) / 2 for x, y in zip(v[a], v[b])]
                n = math.sqrt(sum(x * x for x in p))
                v.append(tuple(c / n for c in p))
                mid[key] = len(v) - 1
            return mid[key]

        g = []
        for a, b, c in f:
            ab, bc, ca = m(a, b), m(b, c), m(c, a)
            g += [(a, ab, ca), (b, bc, ab), (c, ca, bc), (ab, bc, ca)]
        f = g
    return [tuple(radius * c for c in p) for p in v], f


def ply_ascii(v, f):
    head = (f"ply\nformat ascii 1.0\ncomment sinew fuzz seed\nelement vertex {len(v)}\n"
            "property float x\nproperty float y\nproperty float z\n"
            f"element face {len(f)}\nproperty list uchar int vertex_indices\nend_header\n")
    body = "".join(f"{x:.6f} {y:.6f} {z:.6f}\n" for x, y, z in v)
    body += "".join(f"3 {a} {b} {c}\n" for a, b, c in f)
    return (head + body).encode()


def ply_binary(v, f):
    head = (f"ply\nformat binary_little_endian 1.0\nelement vertex {len(v)}\n"
            "property float x\nproperty float y\nproperty float z\n"
            f"element face {len(f)}\nproperty list uchar int vertex_indices\nend_header\n")
    body = b"".join(struct.pack("<3f", *p) for p in v)
    body += b"".join(struct.pack("<B3i", 3, *t) for t in f)
    return head.encode() + body


def off(v, f):
    text = f"OFF\n# sinew fuzz seed\n{len(v)} {len(f)} 0\n"
    text += "".join(f"{x:.6f} {y:.6f} {z:.6f}\n" for x, y, z in v)
    text += "".join(f"3 {a} {b} {c}\n" for a, b, c in f)
    return text.encode()


def normal(v, t):
    a, b, c = (v[i] for i in t)
    u = [b[k] - a[k] for k in range(3)]
    w = [c[k] - a[k] for k in range(3)]
    n = [u[1] * w[2] - u[2] * w[1], u[2] * w[0] - u[0] * w[2], u[0] * w[1] - u[1] * w[0]]
    s = math.sqrt(sum(x * x for x in n)) or 1
    return [x / s for x in n]


def stl_binary(v, f):
    out = b"sinew fuzz seed".ljust(80, b" ") + struct.pack("<I", len(f))
    for t in f:
        out += struct.pack("<12fH", *normal(v, t), *v[t[0]], *v[t[1]], *v[t[2]], 0)
    return out


def stl_ascii(v, f):
    lines = ["solid seed"]
    for t in f:
        lines.append(" facet normal {:.6f} {:.6f} {:.6f}".format(*normal(v, t)))
        lines.append("  outer loop")
        for i in t:
            lines.append("   vertex {:.6f} {:.6f} {:.6f}".format(*v[i]))
        lines.append("  endloop")
        lines.append(" endfacet")
    lines.append("endsolid seed")
    return ("\n".join(lines) + "\n").encode()


def gltf(v, f):
    positions = b"".join(struct.pack("<3f", *p) for p in v)
    indices = b"".join(struct.pack("<3I", *t) for t in f)
    data = positions + indices
    lo = [min(p[k] for p in v) for k in range(3)]
    hi = [max(p[k] for p in v) for k in range(3)]
    doc = {
        "asset": {"version": "2.0"},
        "scene": 0,
        "scenes": [{"nodes": [0]}],
        "nodes": [{"mesh": 0, "children": [1]}, {"mesh": 0, "translation": [0, 0, 0]}],
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0}, "indices": 1, "mode": 4}]}],
        "buffers": [{"byteLength": len(data), "uri": "data:application/octet-stream;base64," +
                     base64.b64encode(data).decode()}],
        "bufferViews": [
            {"buffer": 0, "byteOffset": 0, "byteLength": len(positions), "target": 34962},
            {"buffer": 0, "byteOffset": len(positions), "byteLength": len(indices),
             "target": 34963}],
        "accessors": [
            {"bufferView": 0, "componentType": 5126, "count": len(v), "type": "VEC3",
             "min": lo, "max": hi},
            {"bufferView": 1, "componentType": 5125, "count": 3 * len(f), "type": "SCALAR"}],
    }
    return json.dumps(doc, indent=1).encode()


# Format name -> (file extension, writer). The fuzzer writes one seed of each.
FORMATS = {
    "ply": (".ply", ply_ascii),
    "ply_binary": (".ply", ply_binary),
    "off": (".off", off),
    "gltf": (".gltf", gltf),
    "stl": (".stl", stl_binary),
    "stl_ascii": (".stl", stl_ascii),
}
TEXT = {"ply", "off", "stl_ascii"}


def seeds():
    v, f = icosphere()
    return {name: (ext, write(v, f)) for name, (ext, write) in FORMATS.items()}


# ----------------------------------------------------------------------------------------------
# Mutations.

ODD_NUMBERS = [b"nan", b"-nan", b"NaN", b"inf", b"-inf", b"Infinity", b"1e999", b"-1e999",
               b"3.4e38", b"1e-45", b"4294967295", b"2147483648", b"-1", b"0",
               b"99999999999999999999", b"", b"x", b"1.2.3", b"0x10"]
HUGE_COUNTS = [0, 1, 2, 3, 255, 65535, 2**31 - 1, 2**31, 2**32 - 1, 2**32, 2**63, 2**64 - 1]
NUMBER = re.compile(rb"-?\d+(\.\d+)?(e-?\d+)?")


def ply_header_end(data):
    at = data.find(b"end_header")
    return -1 if at < 0 else data.find(b"\n", at) + 1


def text_number(rng, data, fmt):
    if fmt not in TEXT:
        return None
    start = max(0, ply_header_end(data)) if fmt == "ply" else 0
    hits = [m.span() for m in NUMBER.finditer(data, start)]
    if not hits:
        return None
    for _ in range(rng.choice([1, 1, 3])):
        a, b = rng.choice(hits)
        data = data[:a] + rng.choice(ODD_NUMBERS) + data[b:]
        hits = [m.span() for m in NUMBER.finditer(data, start)]
    return data


def text_lines(rng, data, fmt):
    if fmt not in TEXT:
        return None
    lines = data.split(b"\n")
    i = rng.randrange(len(lines))
    choice = rng.choice(["delete", "duplicate", "swap", "repeat"])
    if choice == "delete":
        del lines[i]
    elif choice == "duplicate":
        lines.insert(i, lines[i])
    elif choice == "swap":
        j = rng.randrange(len(lines))
        lines[i], lines[j] = lines[j], lines[i]
    else:
        lines[i:i + 1] = [lines[i]] * rng.choice([100, 10000])
    return b"\n".join(lines)


def ply_header(rng, data, fmt):
    if not fmt.startswith("ply"):
        return None
    end = ply_header_end(data)
    head, body = data[:end], data[end:]
    choice = rng.choice(["count", "count", "type", "list", "format", "no_end", "drop_property",
                         "extra_element", "element_name"])
    if choice == "count":
        name = rng.choice([b"vertex", b"face"])
        head = re.sub(rb"element " + name + rb" \d+",
                      b"element " + name + b" " + str(rng.choice(HUGE_COUNTS + [41, 43, 79, 81])
                                                      ).encode(), head)
    elif choice == "type":
        head = re.sub(rb"property float " + rng.choice([b"x", b"y", b"z"]),
                      b"property " + rng.choice([b"double", b"uchar", b"int", b"short", b"foo",
                                                  b"list uchar float"]) + b" x", head)
    elif choice == "list":
        head = head.replace(b"list uchar int", b"list " + rng.choice(
            [b"int int", b"uchar uchar", b"uint float", b"double int", b"char int"]))
    elif choice == "format":
        head = re.sub(rb"format \S+ \S+", b"format " + rng.choice(
            [b"ascii", b"binary_little_endian", b"binary_big_endian", b"binary"]) + b" " +
            rng.choice([b"1.0", b"2.0", b""]), head)
    elif choice == "no_end":
        head = head.replace(b"end_header\n", b"")
    elif choice == "drop_property":
        lines = head.split(b"\n")
        props = [k for k, l in enumerate(lines) if l.startswith(b"property")]
        del lines[rng.choice(props)]
        head = b"\n".join(lines)
    elif choice == "extra_element":
        head = head.replace(b"end_header", b"element edge " + str(rng.choice(HUGE_COUNTS)).encode()
                            + b"\nproperty int vertex1\nend_header")
    else:
        head = head.replace(b"element vertex", b"element " + rng.choice([b"vert", b"face"]))
    return head + body


def face_sizes(rng, data, fmt):
    """A face's corner count or an index changed (PLY, OFF)."""
    if fmt not in ("ply", "off", "ply_binary"):
        return None
    if fmt == "ply_binary":
        end = ply_header_end(data)
        b = bytearray(data)
        faces = end + 42 * 12
        k = rng.randrange(80)
        at = faces + 13 * k
        if rng.random() < 0.5:
            b[at] = rng.choice([0, 1, 2, 4, 255])
        else:
            struct.pack_into("<i", b, at + 1 + 4 * rng.randrange(3),
                             rng.choice([-1, 42, 2**31 - 1, -2**31, 1000000]))
        return bytes(b)
    lines = data.split(b"\n")
    faces = [k for k, l in enumerate(lines) if l.startswith(b"3 ")]
    k = rng.choice(faces)
    parts = lines[k].split(b" ")
    if rng.random() < 0.5:
        parts[0] = rng.choice([b"0", b"1", b"2", b"4", b"255", b"-1", b"100000"])
    else:
        parts[1 + rng.randrange(3)] = rng.choice([b"-1", b"42", b"2147483647", b"4294967295",
                                                   b"1000000"])
    lines[k] = b" ".join(parts)
    return b"\n".join(lines)


def off_header(rng, data, fmt):
    if fmt != "off":
        return None
    return re.sub(rb"\n42 80 0\n", b"\n" + b" ".join(
        str(rng.choice(HUGE_COUNTS + [41, 43, 79, 81, -1])).encode() for _ in range(3)) + b"\n",
        data)


def stl_count(rng, data, fmt):
    if fmt != "stl":
        return None
    b = bytearray(data)
    struct.pack_into("<I", b, 80, rng.choice([0, 1, 79, 81, 2**31, 2**32 - 1]))
    if rng.random() < 0.3:
        b[:5] = b"solid"  # a binary STL that claims to be ASCII
    return bytes(b)


def stl_ascii_structure(rng, data, fmt):
    if fmt != "stl_ascii":
        return None
    word = rng.choice([b"endloop", b"endfacet", b"outer loop", b"vertex", b"facet normal",
                       b"endsolid"])
    at = [m.start() for m in re.finditer(word, data)]
    if not at:
        return None
    k = rng.choice(at)
    end = data.find(b"\n", k)
    return data[:k] + data[end + 1:] if rng.random() < 0.7 else data[:k] + data[k:end] * 2 + \
        data[end:]


GLTF_EDITS = [
    ("accessors", 0, "count", [0, 1, 41, 43, 1000000, 2**32 - 1, -1]),
    ("accessors", 1, "count", [0, 1, 2, 239, 241, 1000000, 2**31, -1]),
    ("accessors", 0, "componentType", [5120, 5121, 5123, 5125, 9999]),
    ("accessors", 1, "componentType", [5120, 5121, 5123, 5126, 9999]),
    ("accessors", 0, "type", ["SCALAR", "VEC2", "VEC4", "MAT4", "X"]),
    ("accessors", 1, "type", ["VEC3", "VEC2", "MAT4"]),
    ("accessors", 0, "bufferView", [1, 2, -1, 99]),
    ("accessors", 1, "bufferView", [0, 2, -1, 99]),
    ("accessors", 1, "byteOffset", [4, 959, 10000, -4]),
    ("bufferViews", 0, "byteOffset", [4, 503, 10000, 2**32]),
    ("bufferViews", 1, "byteLength", [0, 4, 959, 100000]),
    ("bufferViews", 0, "byteStride", [0, 4, 13, 252, 256]),
    ("bufferViews", 1, "buffer", [1, -1]),
    ("buffers", 0, "byteLength", [0, 1, 10**9]),
    ("buffers", 0, "uri", ["", "missing.bin", "data:application/octet-stream;base64,AAAA",
                           "/dev/zero", "data:;base64,!!!!"]),
    ("nodes", 0, "mesh", [1, -1, 99]),
    ("nodes", 0, "children", [[0], [1, 1], [99], [-1], []]),
    ("nodes", 1, "children", [[0], [1]]),
    ("nodes", 1, "matrix", [[0] * 16, [1e38] * 16, [float("nan")] * 16, [1, 2]]),
    ("scenes", 0, "nodes", [[1, 0], [99], [], [-1]]),
    ("meshes", 0, "primitives", [[], [{}], [{"attributes": {}}]]),
]


def gltf_structure(rng, data, fmt):
    if fmt != "gltf":
        return None
    doc = json.loads(data)
    for _ in range(rng.choice([1, 1, 2])):
        key, i, field, values = rng.choice(GLTF_EDITS)
        if rng.random() < 0.15:
            doc[key][i].pop(field, None)
        else:
            doc[key][i][field] = rng.choice(values)
    if rng.random() < 0.2:
        prim = doc["meshes"][0]["primitives"]
        if prim:
            prim[0]["mode"] = rng.choice([0, 1, 2, 3, 5, 6, 99])
    return json.dumps(doc).encode()


def truncate(rng, data, fmt):
    return data[: rng.randrange(0, max(1, len(data)))]


def bitflip(rng, data, fmt):
    b = bytearray(data)
    start = ply_header_end(data) if fmt == "ply_binary" and rng.random() < 0.5 else 0
    for _ in range(rng.choice([1, 8, 64])):
        b[rng.randrange(max(0, start), len(b))] ^= 1 << rng.randrange(8)
    return bytes(b)


def splice(rng, data, fmt):
    at = rng.randrange(len(data) + 1)
    choice = rng.random()
    if choice < 0.4:
        return data[:at] + bytes(rng.randrange(256) for _ in range(rng.randrange(1, 40))) + data[at:]
    if choice < 0.7:  # a block copied elsewhere
        a = rng.randrange(len(data))
        return data[:at] + data[a:a + rng.randrange(1, 200)] + data[at:]
    n = rng.randrange(1, 64)
    return data[:at] + b"\x00" * n + data[at + n:]


def garbage(rng, data, fmt):
    return bytes(rng.randrange(256) for _ in range(rng.choice([0, 16, 84, 1000, 70000])))


MUTATIONS = [text_number, text_number, text_lines, ply_header, ply_header, ply_header,
             face_sizes, face_sizes, off_header, stl_count, stl_ascii_structure, gltf_structure,
             gltf_structure, gltf_structure, truncate, bitflip, bitflip, splice, garbage]


def mutate(rng, data, fmt):
    """One to three mutations that apply to fmt; returns (bytes, label)."""
    names = []
    for _ in range(rng.choice([1, 1, 1, 2, 3])):
        for _ in range(20):
            fn = rng.choice(MUTATIONS)
            try:
                out = fn(rng, data, fmt)
            except Exception:  # a structured edit of data an earlier one broke: draw another
                out = None
            if out is not None:
                data = out
                names.append(fn.__name__)
                break
    return data, "+".join(names) or "copy"
