"""The assets of the Cycles harness (blender_cycles.py): Khronos sample assets downloaded on demand,
scenes written here (glass, many emissive triangles, a textured interior, a sphere grid),
and the camera node both renderers look through.

Standard library only (numpy-free), so that `cycles.py assets` runs on any python3.
"""

import base64
import json
import math
import struct
import sys
import urllib.request
import zlib
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))
from env_reference import look_at_quaternion  # noqa: E402

KHRONOS = "https://raw.githubusercontent.com/KhronosGroup/glTF-Sample-Assets/main/Models"

# name -> (Khronos model folder, variant file, camera override or None).
# A camera override is (look_from, look_at, yfov_degrees) in the file's world coordinates;
# without one the camera frames the bounding sphere of every mesh (frame_camera).
DOWNLOADED = {
    "DamagedHelmet": ("DamagedHelmet", "glTF-Binary/DamagedHelmet.glb", None),
    "FlightHelmet": ("FlightHelmet", "glTF/FlightHelmet.gltf", None),
    "MetalRoughSpheresNoTextures": ("MetalRoughSpheresNoTextures", "glTF/MetalRoughSpheresNoTextures.gltf", None),
    # Inside the atrium, looking down its length (about 300 MB less than nothing: ~50 MB).
    "Sponza": ("Sponza", "glTF/Sponza.gltf", ((9.0, 1.8, -0.4), (-9.0, 4.0, 0.6), 60.0)),
}


class AssetError(Exception):
    pass


def download(model, variant, dest):
    """Downloads a Khronos model's file and every buffer and image its JSON names."""
    dest.mkdir(parents=True, exist_ok=True)
    base = f"{KHRONOS}/{model}/{variant.rsplit('/', 1)[0]}"
    main = dest / variant.rsplit("/", 1)[1]
    files = [main.name]
    if not main.exists():
        fetch(f"{base}/{main.name}", main)
    if main.suffix == ".gltf":
        doc = json.loads(main.read_text())
        for item in doc.get("buffers", []) + doc.get("images", []):
            uri = item.get("uri", "")
            if uri and not uri.startswith("data:"):
                target = dest / urllib.request.url2pathname(uri)
                if not target.exists():
                    target.parent.mkdir(parents=True, exist_ok=True)
                    fetch(f"{base}/{uri}", target)
                files.append(uri)
    return main


def fetch(url, path):
    print(f"downloading {url}", flush=True)
    try:
        with urllib.request.urlopen(url, timeout=60) as r:
            data = r.read()
    except OSError as e:
        raise AssetError(f"cannot download {url}: {e} (put the model's files in the asset folder "
                         f"by hand, or run with --assets naming only the generated ones)")
    tmp = path.with_suffix(path.suffix + ".part")
    tmp.write_bytes(data)
    tmp.replace(path)


# ---------------------------------------------------------------------------------------
# glTF documents: reading (.gltf or .glb), bounds, adding a camera node, writing.


def read_gltf(path):
    """(json document, binary chunk or None) of a .gltf or .glb."""
    data = Path(path).read_bytes()
    if data[:4] != b"glTF":
        return json.loads(data), None
    _, _, length = struct.unpack_from("<4sII", data, 0)
    pos, doc, binary = 12, None, None
    while pos < length:
        clen, ctype = struct.unpack_from("<II", data, pos)
        chunk = data[pos + 8:pos + 8 + clen]
        if ctype == 0x4E4F534A:
            doc = json.loads(chunk)
        elif ctype == 0x004E4942:
            binary = chunk
        pos += 8 + clen
    return doc, binary


def write_glb(path, doc, binary):
    js = json.dumps(doc, separators=(",", ":")).encode()
    js += b" " * (-len(js) % 4)
    chunks = struct.pack("<II", len(js), 0x4E4F534A) + js
    if binary is not None:
        binary = binary + b"\0" * (-len(binary) % 4)
        chunks += struct.pack("<II", len(binary), 0x004E4942) + binary
    Path(path).write_bytes(struct.pack("<4sII", b"glTF", 2, 12 + len(chunks)) + chunks)


def mat_mul(a, b):
    return [[sum(a[i][k] * b[k][j] for k in range(4)) for j in range(4)] for i in range(4)]


def node_matrix(node):
    if "matrix" in node:
        m = node["matrix"]  # column-major
        return [[m[c * 4 + r] for c in range(4)] for r in range(4)]
    tx, ty, tz = node.get("translation", [0, 0, 0])
    qx, qy, qz, qw = node.get("rotation", [0, 0, 0, 1])
    sx, sy, sz = node.get("scale", [1, 1, 1])
    r = [[1 - 2 * (qy * qy + qz * qz), 2 * (qx * qy - qz * qw), 2 * (qx * qz + qy * qw)],
         [2 * (qx * qy + qz * qw), 1 - 2 * (qx * qx + qz * qz), 2 * (qy * qz - qx * qw)],
         [2 * (qx * qz - qy * qw), 2 * (qy * qz + qx * qw), 1 - 2 * (qx * qx + qy * qy)]]
    return [[r[0][0] * sx, r[0][1] * sy, r[0][2] * sz, tx], [r[1][0] * sx, r[1][1] * sy, r[1][2] * sz, ty],
            [r[2][0] * sx, r[2][1] * sy, r[2][2] * sz, tz], [0, 0, 0, 1]]


def bounds(doc):
    """World-space bounding box of the default scene's meshes, from the POSITION
    accessors' min/max (which glTF requires) and the node transforms."""
    lo, hi = [math.inf] * 3, [-math.inf] * 3
    scene = doc.get("scenes", [{}])[doc.get("scene", 0)]

    def visit(i, parent):
        node = doc["nodes"][i]
        m = mat_mul(parent, node_matrix(node))
        if "mesh" in node:
            for prim in doc["meshes"][node["mesh"]]["primitives"]:
                acc = doc["accessors"][prim["attributes"]["POSITION"]]
                a, b = acc["min"], acc["max"]
                for corner in range(8):
                    p = [b[k] if corner >> k & 1 else a[k] for k in range(3)]
                    w = [sum(m[r][k] * p[k] for k in range(3)) + m[r][3] for r in range(3)]
                    for k in range(3):
                        lo[k], hi[k] = min(lo[k], w[k]), max(hi[k], w[k])
        for c in node.get("children", []):
            visit(c, m)

    for i in scene.get("nodes", []):
        visit(i, [[1 if r == c else 0 for c in range(4)] for r in range(4)])
    if lo[0] == math.inf:
        raise AssetError("the scene has no meshes")
    return lo, hi


def frame_camera(doc, yfov=40.0):
    """A view of the whole bounding sphere from the front-right, slightly above."""
    lo, hi = bounds(doc)
    centre = [(a + b) / 2 for a, b in zip(lo, hi)]
    radius = math.dist(lo, hi) / 2
    d = [0.35, 0.25, 1.0]
    n = math.sqrt(sum(x * x for x in d))
    dist = radius / math.sin(math.radians(yfov) / 2) * 1.02
    eye = [c + dist * x / n for c, x in zip(centre, d)]
    return eye, centre, yfov


CAMERA = "vkvcm_cycles_cam"


def with_camera(src, dst, override=None):
    """Writes a copy of src (beside it, so relative URIs still resolve) with a perspective
    camera node named CAMERA added to the default scene; returns the view."""
    doc, binary = read_gltf(src)
    eye, target, yfov = override or frame_camera(doc)
    doc.setdefault("cameras", []).append({"type": "perspective", "name": CAMERA, "perspective": {
        "yfov": math.radians(yfov), "aspectRatio": 1.0, "znear": 0.01}})
    doc.setdefault("nodes", []).append({"name": CAMERA, "camera": len(doc["cameras"]) - 1,
                                        "translation": list(eye), "rotation": look_at_quaternion(eye, target, [0.0, 1.0, 0.0])})
    si = doc.get("scene", 0)
    doc["scenes"][si].setdefault("nodes", []).append(len(doc["nodes"]) - 1)
    if Path(src).suffix == ".glb":
        write_glb(dst, doc, binary)
    else:
        Path(dst).write_text(json.dumps(doc))
    return {"eye": list(eye), "target": list(target), "yfov": yfov}


# ---------------------------------------------------------------------------------------
# Scenes written here (no download): each is a glTF with embedded buffers and a camera.


class Builder:
    """A glTF document with one embedded buffer, built mesh by mesh."""

    def __init__(self):
        self.doc = {"asset": {"version": "2.0", "generator": "vkvcm cycles_assets.py"}, "scene": 0,
                    "scenes": [{"nodes": []}], "nodes": [], "meshes": [], "materials": [],
                    "accessors": [], "bufferViews": [], "buffers": []}
        self.blob = bytearray()

    def view(self, data, target=None):
        self.blob += b"\0" * (-len(self.blob) % 4)
        v = {"buffer": 0, "byteOffset": len(self.blob), "byteLength": len(data)}
        if target:
            v["target"] = target
        self.blob += data
        self.doc["bufferViews"].append(v)
        return len(self.doc["bufferViews"]) - 1

    def accessor(self, values, kind, comp=5126):
        flat = [x for v in values for x in (v if isinstance(v, (list, tuple)) else [v])]
        fmt = "<%d%s" % (len(flat), "f" if comp == 5126 else "I")
        view = self.view(struct.pack(fmt, *flat), 34963 if comp == 5125 else 34962)
        acc = {"bufferView": view, "componentType": comp, "count": len(values), "type": kind}
        if kind == "VEC3":
            acc["min"] = [min(v[k] for v in values) for k in range(3)]
            acc["max"] = [max(v[k] for v in values) for k in range(3)]
        self.doc["accessors"].append(acc)
        return len(self.doc["accessors"]) - 1

    def material(self, **m):
        self.doc["materials"].append(m)
        return len(self.doc["materials"]) - 1

    def mesh(self, pos, nrm, idx, material, uv=None, translation=None, scale=None):
        attrs = {"POSITION": self.accessor(pos, "VEC3"), "NORMAL": self.accessor(nrm, "VEC3")}
        if uv is not None:
            attrs["TEXCOORD_0"] = self.accessor(uv, "VEC2")
        prim = {"attributes": attrs, "indices": self.accessor(idx, "SCALAR", 5125), "material": material}
        self.doc["meshes"].append({"primitives": [prim]})
        node = {"mesh": len(self.doc["meshes"]) - 1}
        if translation:
            node["translation"] = list(translation)
        if scale:
            node["scale"] = list(scale)
        self.doc["nodes"].append(node)
        self.doc["scenes"][0]["nodes"].append(len(self.doc["nodes"]) - 1)

    def png_texture(self, png):
        self.doc.setdefault("images", []).append({"bufferView": self.view(png), "mimeType": "image/png"})
        self.doc.setdefault("samplers", []).append({"magFilter": 9729, "minFilter": 9987})
        self.doc.setdefault("textures", []).append({"source": len(self.doc["images"]) - 1, "sampler": 0})
        return len(self.doc["textures"]) - 1

    def write(self, path):
        self.doc["buffers"] = [{"byteLength": len(self.blob),
                                "uri": "data:application/octet-stream;base64," + base64.b64encode(self.blob).decode()}]
        if self.doc.get("extensionsUsed") == []:
            del self.doc["extensionsUsed"]
        Path(path).write_text(json.dumps(self.doc))


def sphere(radius, rings=24, segments=48):
    pos, nrm, idx = [], [], []
    for i in range(rings + 1):
        t = math.pi * i / rings
        for j in range(segments + 1):
            p = 2 * math.pi * j / segments
            n = (math.sin(t) * math.cos(p), math.cos(t), -math.sin(t) * math.sin(p))
            nrm.append(n)
            pos.append(tuple(radius * x for x in n))
    for i in range(rings):
        for j in range(segments):
            a, b = i * (segments + 1) + j, (i + 1) * (segments + 1) + j
            idx += [a, b, a + 1, a + 1, b, b + 1]
    return pos, nrm, idx


def box(lo, hi, inward=False):
    """An axis-aligned box as 6 faces with flat normals and UVs scaled by the face size."""
    pos, nrm, uv, idx = [], [], [], []
    for axis in range(3):
        for side in (0, 1):
            u_ax, v_ax = (axis + 1) % 3, (axis + 2) % 3
            n = [0.0, 0.0, 0.0]
            n[axis] = 1.0 if side else -1.0
            if inward:
                n[axis] = -n[axis]
            base = len(pos)
            for a, b in ((0, 0), (1, 0), (1, 1), (0, 1)):
                p = [0.0] * 3
                p[axis] = hi[axis] if side else lo[axis]
                p[u_ax] = hi[u_ax] if a else lo[u_ax]
                p[v_ax] = hi[v_ax] if b else lo[v_ax]
                pos.append(tuple(p))
                nrm.append(tuple(n))
                uv.append((p[u_ax] / 2.0, p[v_ax] / 2.0))
            quad = [base, base + 1, base + 2, base, base + 2, base + 3]
            e1 = [pos[base + 1][k] - pos[base][k] for k in range(3)]
            e2 = [pos[base + 2][k] - pos[base][k] for k in range(3)]
            c = [e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2], e1[0] * e2[1] - e1[1] * e2[0]]
            if sum(c[k] * n[k] for k in range(3)) < 0:  # counter-clockwise seen from the normal's side
                quad = [base, base + 2, base + 1, base, base + 3, base + 2]
            idx += quad
    return pos, nrm, uv, idx


def png(width, height, rgb_rows):
    """An 8-bit RGB PNG from rows of bytes (a dozen lines: not worth a dependency)."""
    raw = b"".join(b"\0" + bytes(row) for row in rgb_rows)

    def chunk(kind, data):
        return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data))
    return (b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", width, height, 8, 2, 0, 0, 0))
            + chunk(b"IDAT", zlib.compress(raw, 6)) + chunk(b"IEND", b""))


def floor(b, material, size=4.0, y=0.0):
    pos, nrm, uv, idx = box((-size, y - 0.05, -size), (size, y, size))
    b.mesh(pos, nrm, idx, material, uv=uv)


def gen_glass(path, parts="srb"):
    """Smooth (s) and rough (r) glass spheres and a tinted glass box (b) on a grey floor, under
    the sky; `parts` picks which (the glass_* assets: one each, to tell where noise comes from)."""
    b = Builder()
    b.doc["extensionsUsed"] = ["KHR_materials_transmission", "KHR_materials_ior"]
    grey = b.material(pbrMetallicRoughness={"baseColorFactor": [0.6, 0.6, 0.6, 1], "metallicFactor": 0,
                                            "roughnessFactor": 0.6}, doubleSided=True)
    glass = lambda colour, rough: b.material(  # noqa: E731
        pbrMetallicRoughness={"baseColorFactor": colour + [1], "metallicFactor": 0, "roughnessFactor": rough},
        extensions={"KHR_materials_transmission": {"transmissionFactor": 1.0}, "KHR_materials_ior": {"ior": 1.5}})
    floor(b, grey)
    pos, nrm, idx = sphere(0.5)
    if "s" in parts:
        b.mesh(pos, nrm, idx, glass([1, 1, 1], 0.0), translation=(-0.6, 0.5, 0))
    if "r" in parts:
        b.mesh(pos, nrm, idx, glass([1, 1, 1], 0.3), translation=(0.6, 0.5, 0))
    if "b" in parts:
        # The box stands 1 mm above the floor: a bottom face in the floor's top plane would
        # make the scene ill-defined (each renderer resolves coincident surfaces its own way).
        bpos, bnrm, _, bidx = box((-0.3, 0.001, -0.3), (0.3, 0.6, 0.3))
        b.mesh(bpos, bnrm, bidx, glass([0.9, 0.6, 0.3], 0.0), translation=(0.0, 0.0, 0.9))
    b.write(path)
    return ((0.0, 1.6, 3.2), (0.0, 0.4, 0.2), 40.0)


def white_room(sphere_at, box_top):
    """A Builder holding a closed white 4 x 2.5 x 4 room (inward faces) with a metal sphere
    of radius 0.45 centred at `sphere_at` and a white box from the floor to `box_top`: the
    room of the `emitters` and `panel` assets, which add their lights."""
    b = Builder()
    white = b.material(pbrMetallicRoughness={"baseColorFactor": [0.7, 0.7, 0.7, 1], "metallicFactor": 0,
                                             "roughnessFactor": 0.8}, doubleSided=True)
    metal = b.material(pbrMetallicRoughness={"baseColorFactor": [0.9, 0.8, 0.6, 1], "metallicFactor": 1,
                                             "roughnessFactor": 0.25}, doubleSided=True)
    pos, nrm, uv, idx = box((-2, 0, -2), (2, 2.5, 2), inward=True)
    b.mesh(pos, nrm, idx, white)
    spos, snrm, sidx = sphere(0.45)
    b.mesh(spos, snrm, sidx, metal, translation=sphere_at)
    bpos, bnrm, _, bidx = box((-1.2, 0, -0.8), (-0.4, box_top, 0.0))
    b.mesh(bpos, bnrm, bidx, white)
    return b


def gen_emitters(path, count=2000):
    """A closed white room lit only by `count` small emissive triangles of many colours on
    its ceiling and walls (the sky cannot enter): light selection's case."""
    b = white_room(sphere_at=(0.5, 0.45, -0.4), box_top=0.9)
    # Emitters: tiny triangles just inside the ceiling and the back and left walls, each in
    # a cell of its own of a 0.105 m grid on its wall: coplanar emitters that overlapped
    # would make the scene ill-defined (a ray meets one of them where next-event
    # estimation and light subpaths count both: pt, bpt and lt then disagree by several
    # per cent). A linear congruential generator keeps the scene the same everywhere.
    state = 12345
    cell, used = 0.105, set()

    def rnd():
        nonlocal state
        state = (state * 1103515245 + 12345) % 2**31
        return state / 2**31

    def free_cell(wall, rows):
        """A random unused cell (i, j) of the 36 x `rows` grid of `wall`."""
        while True:
            key = (wall, int(rnd() * 36), int(rnd() * rows))
            if key not in used:
                used.add(key)
                return key[1:]
    colours = [[1.0, 0.9, 0.7], [0.6, 0.8, 1.0], [1.0, 0.5, 0.4], [0.7, 1.0, 0.6]]
    mats = [b.material(emissiveFactor=c, extensions={"KHR_materials_emissive_strength": {"emissiveStrength": 4.0}},
                       pbrMetallicRoughness={"baseColorFactor": [0, 0, 0, 1], "metallicFactor": 0}, doubleSided=True)
            for c in colours]
    b.doc["extensionsUsed"] = ["KHR_materials_emissive_strength"]
    for m, mat in enumerate(mats):
        epos, enrm, eidx = [], [], []
        for _ in range(count // len(mats)):
            wall = rnd()
            s = 0.04 + 0.06 * rnd()
            if wall < 0.5:  # ceiling, facing down
                i, j = free_cell(0, 36)
                c, tri, n = (-1.9 + cell * i, 2.499, -1.9 + cell * j), [(0, 0, 0), (s, 0, 0), (0, 0, s)], (0, -1, 0)
            elif wall < 0.75:  # back wall z = -2, facing +z
                i, j = free_cell(1, 21)
                c, tri, n = (-1.9 + cell * i, 0.1 + cell * j, -1.999), [(0, 0, 0), (s, 0, 0), (0, s, 0)], (0, 0, 1)
            else:  # left wall x = -2, facing +x (the winding's normal: vkvcm emits on its side)
                i, j = free_cell(2, 21)
                c, tri, n = (-1.999, 0.1 + cell * j, -1.9 + cell * i), [(0, 0, 0), (0, s, 0), (0, 0, s)], (1, 0, 0)
            base = len(epos)
            for t in tri:
                epos.append(tuple(c[k] + t[k] for k in range(3)))
                enrm.append(n)
            eidx += [base, base + 1, base + 2]
        b.mesh(epos, enrm, eidx, mat)
    b.write(path)
    return ((1.6, 1.4, 1.9), (-0.3, 0.8, -0.8), 60.0)


def gen_interior(path, columns=12):
    """A large textured hall (checker-textured floor, walls, ceiling; rows of textured
    pillars with many faces) lit by the sky through an open end and a roof slot."""
    b = Builder()
    n = 64
    rows = [[c for x in range(n) for c in ((200, 180, 150) if (x // 8 + y // 8) % 2 else (90, 80, 70))]
            for y in range(n)]
    tex = b.png_texture(png(n, n, rows))
    textured = b.material(pbrMetallicRoughness={"baseColorTexture": {"index": tex}, "metallicFactor": 0,
                                                "roughnessFactor": 0.7}, doubleSided=True)
    plaster = b.material(pbrMetallicRoughness={"baseColorFactor": [0.75, 0.72, 0.68, 1], "metallicFactor": 0,
                                               "roughnessFactor": 0.9}, doubleSided=True)
    length, width, height = 20.0, 6.0, 5.0
    # Floor and walls as thin boxes; the +x end is open, the ceiling has a slot.
    for lo, hi, mat in (((-length / 2, -0.1, -width / 2), (length / 2, 0, width / 2), textured),
                        ((-length / 2, 0, -width / 2 - 0.1), (length / 2, height, -width / 2), textured),
                        ((-length / 2, 0, width / 2), (length / 2, height, width / 2 + 0.1), textured),
                        ((-length / 2 - 0.1, 0, -width / 2), (-length / 2, height, width / 2), plaster),
                        ((-length / 2, height, -width / 2), (length / 2, height + 0.1, -0.6), plaster),
                        ((-length / 2, height, 0.6), (length / 2, height + 0.1, width / 2), plaster)):
        pos, nrm, uv, idx = box(lo, hi)
        b.mesh(pos, nrm, uv=uv, idx=idx, material=mat)
    # Pillars: 8-sided prisms of many stacked segments (triangle count, as a real interior).
    for i in range(columns):
        for zs in (-1.8, 1.8):
            x = -length / 2 + (i + 0.5) * length / columns
            pos, nrm, uv, idx = [], [], [], []
            segs, sides, r = 20, 8, 0.3
            for s in range(segs + 1):
                for k in range(sides + 1):
                    a = 2 * math.pi * k / sides
                    nrm.append((math.cos(a), 0.0, math.sin(a)))
                    pos.append((r * math.cos(a), height * s / segs, r * math.sin(a)))
                    uv.append((k / sides, s * 4.0 / segs))
            for s in range(segs):
                for k in range(sides):
                    a0, a1 = s * (sides + 1) + k, (s + 1) * (sides + 1) + k
                    idx += [a0, a1, a0 + 1, a0 + 1, a1, a1 + 1]
            b.mesh(pos, nrm, idx, textured, uv=uv, translation=(x, 0, zs))
    b.write(path)
    return ((9.5, 1.7, 0.0), (-10.0, 2.5, 0.0), 55.0)


def gen_spheres(path):
    """A 5x5 grid of spheres, metallic 0..1 across, roughness 0..1 up (a stand-in for
    MetalRoughSpheresNoTextures where it cannot be downloaded), on a grey floor."""
    b = Builder()
    pos, nrm, idx = sphere(0.4, 16, 32)
    for i in range(5):
        for j in range(5):
            mat = b.material(pbrMetallicRoughness={"baseColorFactor": [0.95, 0.75, 0.45, 1],
                                                   "metallicFactor": i / 4, "roughnessFactor": j / 4})
            b.mesh(pos, nrm, idx, mat, translation=(i - 2.0, j + 0.5, 0.0))
    grey = b.material(pbrMetallicRoughness={"baseColorFactor": [0.5, 0.5, 0.5, 1], "metallicFactor": 0,
                                            "roughnessFactor": 0.5}, doubleSided=True)
    pos, nrm, uv, idx = box((-3, -0.2, -1.5), (3, 0.0, 1.5))
    b.mesh(pos, nrm, idx, grey, uv=uv)
    b.write(path)
    return ((0.0, 2.7, 7.5), (0.0, 2.5, 0.0), 45.0)


def gen_panel(path):
    """A closed white room lit only by one large emissive panel (two triangles, 2.4 x 2.4)
    just below its 2.5-high ceiling, over a metal sphere and a box whose top is 0.9 below
    the panel: a large nearby area light, solid-angle sampling's case."""
    b = white_room(sphere_at=(0.6, 0.45, -0.3), box_top=1.6)
    glow = b.material(emissiveFactor=[1.0, 0.9, 0.8], pbrMetallicRoughness={"baseColorFactor": [0, 0, 0, 1],
                                                                          "metallicFactor": 0})
    y = 2.499
    epos = [(-1.2, y, -1.2), (1.2, y, -1.2), (1.2, y, 1.2), (-1.2, y, 1.2)]
    b.mesh(epos, [(0, -1, 0)] * 4, [0, 1, 2, 0, 2, 3], glow)  # counter-clockwise seen from below
    b.write(path)
    return ((1.6, 1.4, 1.9), (-0.3, 1.0, -0.8), 60.0)


def gen_tint_slab(path):
    """A smooth glass slab of base colour (0.25, 0.5, 1), 0.2 thick, filling the view in front of
    the sky: how many times a renderer applies the transmission tint on one pass through a
    closed object (vkvcm: at each of the two crossings; docs/scene-format.md)."""
    b = Builder()
    b.doc["extensionsUsed"] = ["KHR_materials_transmission", "KHR_materials_ior"]
    tinted = b.material(
        pbrMetallicRoughness={"baseColorFactor": [0.25, 0.5, 1.0, 1], "metallicFactor": 0, "roughnessFactor": 0.0},
        extensions={"KHR_materials_transmission": {"transmissionFactor": 1.0}, "KHR_materials_ior": {"ior": 1.5}})
    pos, nrm, _, idx = box((-1, -1, -0.1), (1, 1, 0.1))
    b.mesh(pos, nrm, idx, tinted)
    b.write(path)
    return ((0.0, 0.0, 3.0), (0.0, 0.0, 0.0), 10.0)


def gen_grazing_floor(path, roughness):
    """The glass asset's grey floor alone (base 0.6, a dielectric of the given roughness),
    seen from 0.4 above it out to grazing angles: how bright each renderer's
    metallic/roughness dielectric is at grazing incidence (docs/scene-format.md)."""
    b = Builder()
    grey = b.material(pbrMetallicRoughness={"baseColorFactor": [0.6, 0.6, 0.6, 1], "metallicFactor": 0,
                                            "roughnessFactor": roughness}, doubleSided=True)
    floor(b, grey)
    b.write(path)
    return ((0.0, 0.4, 3.9), (0.0, 0.0, 0.0), 40.0)


GENERATED = {"glass": gen_glass, "emitters": gen_emitters, "interior": gen_interior, "spheres": gen_spheres,
             "panel": gen_panel}
# By name only, not in the default (all): the glass asset's parts, one each beside the floor,
# the tinted slab, and its floor alone, rough and nearly smooth.
BY_NAME = {"glass_smooth": lambda path: gen_glass(path, "s"), "glass_rough": lambda path: gen_glass(path, "r"),
           "glass_box": lambda path: gen_glass(path, "b"), "tint_slab": gen_tint_slab,
           "floor_rough": lambda path: gen_grazing_floor(path, 0.6),
           "floor_smooth": lambda path: gen_grazing_floor(path, 0.05)}
ALL = list(DOWNLOADED) + list(GENERATED)


def prepare(name, folder):
    """The asset `name` with its camera node, under folder; returns (path, view)."""
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    generate = GENERATED.get(name) or BY_NAME.get(name)
    if generate:
        src = folder / f"{name}.gltf"
        override = generate(src)
    elif name in DOWNLOADED:
        model, variant, override = DOWNLOADED[name]
        src = download(model, variant, folder / model)
    else:
        raise AssetError(f"unknown asset {name!r} (known: {', '.join(ALL + list(BY_NAME))})")
    dst = src.with_name(src.stem + ".cycles" + src.suffix)
    view = with_camera(src, dst, override)
    return dst, view
