"""The peer scene vkvcm and Mitsuba 3 both describe exactly, from ONE description.

`CORNELL` below is the description (a plain dict); `write_gltf` and `write_mitsuba_xml`
turn it into vkvcm's glTF (with its VKVCM_* extensions, docs/scene-format.md) and into a
Mitsuba 3 XML scene. Nothing about the scene is stated anywhere else: change the dict and
both files follow. Standard library only (the driver runs it with the system python3).

Conventions both writers follow (the ones docs/toolchain.md section 6 lists as needed for
the same image):
  * quads are parallelograms (p0, p1, p2, p3) with p2 = p1 + p3 - p0; their front side is
    (p1 - p0) x (p3 - p0). glTF gets the triangles (p0, p1, p2), (p0, p2, p3) (same
    geometric normal), Mitsuba a `rectangle` mapped onto the same parallelogram;
  * diffuse surfaces reflect on both sides (vkvcm's rule; Mitsuba: `twosided`);
  * an emitter emits on its front side only and its surface is black (vkvcm's rule;
    Mitsuba's default surface under an `area` emitter would be 50% grey);
  * the mirror has no Fresnel term (vkvcm: `mirror` with ior -1; Mitsuba: `conductor`
    with material `none`, which reflects 100%, scaled by specular_reflectance);
  * glass is a smooth dielectric with air of ior exactly 1 outside (Mitsuba's default
    ext_ior is 1.000277);
  * camera: look-at, vertical field of view (Mitsuba fov_axis y), box pixel filter,
    emitters visible to the camera, max path length in segments (Mitsuba max_depth).
"""

import base64
import json
import math
import struct
from xml.sax.saxutils import quoteattr

# The description. Units: metres; colours: linear RGB; radiance in W/(m^2 sr).
# Box: x in [-1, 1], y in [0, 2] (y up), z in [-1, 1.6]; closed (the camera is inside it,
# in front of the front wall). Every wall's front side faces into the box.
CORNELL = {
    "name": "cornell_mg",
    "what": "closed Cornell box: diffuse walls, a mirror sphere, a glass sphere, a ceiling area light",
    "resolution": [128, 128],
    "max_path_length": 10,
    "camera": {"position": [0.0, 1.0, 1.5], "look_at": [0.0, 0.75, -1.0], "up": [0.0, 1.0, 0.0], "yfov_deg": 52.0},
    "materials": {
        "white": {"type": "diffuse", "reflectance": [0.73, 0.73, 0.73]},
        "red": {"type": "diffuse", "reflectance": [0.63, 0.065, 0.05]},
        "green": {"type": "diffuse", "reflectance": [0.14, 0.45, 0.091]},
        "mirror": {"type": "mirror", "reflectance": [0.9, 0.9, 0.9]},
        "glass": {"type": "dielectric", "ior": 1.5},
        "light": {"type": "emitter", "radiance": [12.0, 10.0, 8.0]},
    },
    "quads": [
        {"name": "floor", "material": "white", "corners": [[-1, 0, -1], [-1, 0, 1.6], [1, 0, 1.6], [1, 0, -1]]},
        {"name": "ceiling", "material": "white", "corners": [[-1, 2, -1], [1, 2, -1], [1, 2, 1.6], [-1, 2, 1.6]]},
        {"name": "back", "material": "white", "corners": [[-1, 0, -1], [1, 0, -1], [1, 2, -1], [-1, 2, -1]]},
        {"name": "front", "material": "white", "corners": [[-1, 0, 1.6], [-1, 2, 1.6], [1, 2, 1.6], [1, 0, 1.6]]},
        {"name": "left", "material": "red", "corners": [[-1, 0, -1], [-1, 2, -1], [-1, 2, 1.6], [-1, 0, 1.6]]},
        {"name": "right", "material": "green", "corners": [[1, 0, -1], [1, 0, 1.6], [1, 2, 1.6], [1, 2, -1]]},
        # 1 cm below the ceiling, front side down.
        {"name": "light", "material": "light",
         "corners": [[-0.3, 1.99, -0.3], [0.3, 1.99, -0.3], [0.3, 1.99, 0.3], [-0.3, 1.99, 0.3]]},
    ],
    "spheres": [
        {"name": "mirror_sphere", "material": "mirror", "center": [-0.45, 0.451, -0.35], "radius": 0.45},
        {"name": "glass_sphere", "material": "glass", "center": [0.5, 0.451, 0.3], "radius": 0.45},
    ],
}

# Scenes this module can write, by name.
SCENES = {CORNELL["name"]: CORNELL}


class SceneError(Exception):
    pass


def _sub(a, b):
    return [a[i] - b[i] for i in range(3)]


def _add(a, b):
    return [a[i] + b[i] for i in range(3)]


def _cross(a, b):
    return [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]


def _dot(a, b):
    return sum(a[i] * b[i] for i in range(3))


def _norm(a):
    n = math.sqrt(_dot(a, a))
    if n == 0:
        raise SceneError("zero-length vector")
    return [x / n for x in a]


def check(desc):
    """Checks what both writers rely on; raises SceneError with the offending item."""
    mats = desc["materials"]
    for q in desc["quads"]:
        p0, p1, p2, p3 = q["corners"]
        if max(abs(x) for x in _sub(p2, _sub(_add(p1, p3), p0))) > 1e-9:
            raise SceneError(f"quad {q['name']}: not a parallelogram (p2 != p1 + p3 - p0)")
        if _dot(_cross(_sub(p1, p0), _sub(p3, p0)), _cross(_sub(p1, p0), _sub(p3, p0))) == 0:
            raise SceneError(f"quad {q['name']}: degenerate")
        if q["material"] not in mats:
            raise SceneError(f"quad {q['name']}: unknown material {q['material']!r}")
    for s in desc["spheres"]:
        if s["material"] not in mats:
            raise SceneError(f"sphere {s['name']}: unknown material {s['material']!r}")
        if mats[s["material"]]["type"] == "emitter":
            raise SceneError(f"sphere {s['name']}: emissive spheres are not lights in vkvcm")
    for name, m in mats.items():
        if m["type"] not in ("diffuse", "mirror", "dielectric", "emitter"):
            raise SceneError(f"material {name}: unknown type {m['type']!r}")


def _vkvcm_material(name, m):
    """glTF material: exact vkvcm model (VKVCM_materials_phong) plus a core-glTF fallback."""
    zero = [0.0, 0.0, 0.0]
    out = {"name": name}
    ext = {}
    t = m["type"]
    if t == "diffuse":
        out["pbrMetallicRoughness"] = {"baseColorFactor": m["reflectance"] + [1.0], "metallicFactor": 0.0, "roughnessFactor": 1.0}
        ext["VKVCM_materials_phong"] = {"diffuse": m["reflectance"], "phong": zero, "exponent": 1, "mirror": zero, "ior": -1}
    elif t == "mirror":
        out["pbrMetallicRoughness"] = {"baseColorFactor": m["reflectance"] + [1.0], "metallicFactor": 1.0, "roughnessFactor": 0.0}
        ext["VKVCM_materials_phong"] = {"diffuse": zero, "phong": zero, "exponent": 1, "mirror": m["reflectance"], "ior": -1}
    elif t == "dielectric":
        out["pbrMetallicRoughness"] = {"metallicFactor": 0.0, "roughnessFactor": 0.0}
        ext["KHR_materials_transmission"] = {"transmissionFactor": 1.0}
        ext["KHR_materials_ior"] = {"ior": m["ior"]}
        ext["VKVCM_materials_phong"] = {"diffuse": zero, "phong": zero, "exponent": 1, "mirror": [1.0, 1.0, 1.0], "ior": m["ior"]}
    elif t == "emitter":
        peak = max(m["radiance"])
        out["pbrMetallicRoughness"] = {"baseColorFactor": [0.0, 0.0, 0.0, 1.0], "metallicFactor": 0.0, "roughnessFactor": 1.0}
        out["emissiveFactor"] = [c / peak for c in m["radiance"]]
        ext["KHR_materials_emissive_strength"] = {"emissiveStrength": peak}
        ext["VKVCM_materials_phong"] = {"diffuse": zero, "phong": zero, "exponent": 1, "mirror": zero, "ior": -1}
    out["extensions"] = ext
    out["doubleSided"] = True  # vkvcm's two-sided surfaces (Mitsuba: `twosided`)
    return out


def _camera_quaternion(cam):
    """Rotation (x, y, z, w) taking the glTF camera frame (-Z forward, +Y up) to the look-at."""
    fwd = _norm(_sub(cam["look_at"], cam["position"]))
    right = _norm(_cross(fwd, cam["up"]))
    up = _cross(right, fwd)
    back = [-x for x in fwd]
    # Rotation matrix with columns right, up, back; m[r][c].
    m = [[right[r], up[r], back[r]] for r in range(3)]
    tr = m[0][0] + m[1][1] + m[2][2]
    if tr > 0:
        s = math.sqrt(tr + 1.0) * 2
        w, x, y, z = 0.25 * s, (m[2][1] - m[1][2]) / s, (m[0][2] - m[2][0]) / s, (m[1][0] - m[0][1]) / s
    elif m[0][0] > m[1][1] and m[0][0] > m[2][2]:
        s = math.sqrt(1.0 + m[0][0] - m[1][1] - m[2][2]) * 2
        w, x, y, z = (m[2][1] - m[1][2]) / s, 0.25 * s, (m[0][1] + m[1][0]) / s, (m[0][2] + m[2][0]) / s
    elif m[1][1] > m[2][2]:
        s = math.sqrt(1.0 + m[1][1] - m[0][0] - m[2][2]) * 2
        w, x, y, z = (m[0][2] - m[2][0]) / s, (m[0][1] + m[1][0]) / s, 0.25 * s, (m[1][2] + m[2][1]) / s
    else:
        s = math.sqrt(1.0 + m[2][2] - m[0][0] - m[1][1]) * 2
        w, x, y, z = (m[1][0] - m[0][1]) / s, (m[0][2] + m[2][0]) / s, (m[1][2] + m[2][1]) / s, 0.25 * s
    return [x, y, z, w]


def gltf_document(desc):
    """The glTF 2.0 document (a dict) for `desc`, with one embedded buffer."""
    check(desc)
    names = list(desc["materials"])
    index = {n: i for i, n in enumerate(names)}
    blob = bytearray()
    accessors, primitives = [], []
    for q in desc["quads"]:
        p0, p1, p2, p3 = [[float(c) for c in p] for p in q["corners"]]
        verts = [p0, p1, p2, p0, p2, p3]
        offset = len(blob)
        for v in verts:
            blob += struct.pack("<3f", *v)
        accessors.append({
            "bufferView": 0, "byteOffset": offset, "componentType": 5126, "count": 6, "type": "VEC3",
            "min": [min(v[i] for v in verts) for i in range(3)],
            "max": [max(v[i] for v in verts) for i in range(3)],
        })
        primitives.append({"attributes": {"POSITION": len(accessors) - 1}, "material": index[q["material"]], "mode": 4})
    cam = desc["camera"]
    nodes = [
        {"name": "walls_and_light", "mesh": 0},
        {"name": "spheres", "extensions": {"VKVCM_spheres": {"spheres": [
            {"center": s["center"], "radius": s["radius"], "material": index[s["material"]]} for s in desc["spheres"]]}}},
        {"name": "camera", "camera": 0, "translation": cam["position"], "rotation": _camera_quaternion(cam)},
    ]
    w, h = desc["resolution"]
    return {
        "asset": {"version": "2.0", "generator": "vkvcm scripts/peers/scene_desc.py"},
        "extensionsUsed": ["VKVCM_spheres", "VKVCM_materials_phong", "KHR_materials_transmission",
                           "KHR_materials_ior", "KHR_materials_emissive_strength"],
        "scene": 0,
        "scenes": [{"name": desc["name"], "nodes": [0, 1, 2]}],
        "nodes": nodes,
        "meshes": [{"name": "quads", "primitives": primitives}],
        "materials": [_vkvcm_material(n, desc["materials"][n]) for n in names],
        "cameras": [{"type": "perspective", "perspective": {
            "yfov": math.radians(cam["yfov_deg"]), "aspectRatio": w / h, "znear": 0.001, "zfar": 1000.0}}],
        "accessors": accessors,
        "bufferViews": [{"buffer": 0, "byteOffset": 0, "byteLength": len(blob)}],
        "buffers": [{"byteLength": len(blob),
                     "uri": "data:application/octet-stream;base64," + base64.b64encode(bytes(blob)).decode()}],
    }


def write_gltf(desc, path):
    with open(path, "w") as f:
        json.dump(gltf_document(desc), f, indent=1)
        f.write("\n")


def _v(a):
    return ", ".join(repr(float(x)) for x in a)


def _mitsuba_bsdf(m):
    t = m["type"]
    if t == "diffuse":
        return (f'<bsdf type="twosided"><bsdf type="diffuse"><rgb name="reflectance" value="{_v(m["reflectance"])}"/>'
                f'</bsdf></bsdf>')
    if t == "mirror":
        return (f'<bsdf type="conductor"><string name="material" value="none"/>'
                f'<rgb name="specular_reflectance" value="{_v(m["reflectance"])}"/></bsdf>')
    if t == "dielectric":
        return (f'<bsdf type="dielectric"><float name="int_ior" value="{float(m["ior"])!r}"/>'
                f'<float name="ext_ior" value="1.0"/></bsdf>')
    if t == "emitter":
        return ('<bsdf type="diffuse"><rgb name="reflectance" value="0, 0, 0"/></bsdf>'
                f'<emitter type="area"><rgb name="radiance" value="{_v(m["radiance"])}"/></emitter>')
    raise SceneError(f"unknown material type {t!r}")


def mitsuba_xml(desc, integrator="path"):
    """The Mitsuba 3 XML scene for `desc` (integrator: `path` or `ptracer`)."""
    check(desc)
    w, h = desc["resolution"]
    cam = desc["camera"]
    lines = [
        '<?xml version="1.0" encoding="utf-8"?>',
        f'<!-- Written by vkvcm scripts/peers/scene_desc.py from the description {quoteattr(desc["name"])}; do not edit. -->',
        '<scene version="3.0.0">',
        f'  <integrator type="{integrator}"><integer name="max_depth" value="{int(desc["max_path_length"])}"/>'
        '<boolean name="hide_emitters" value="false"/></integrator>',
        '  <sensor type="perspective">',
        f'    <float name="fov" value="{float(cam["yfov_deg"])!r}"/><string name="fov_axis" value="y"/>',
        f'    <transform name="to_world"><lookat origin="{_v(cam["position"])}" target="{_v(cam["look_at"])}"'
        f' up="{_v(cam["up"])}"/></transform>',
        '    <sampler type="independent"><integer name="sample_count" value="1"/></sampler>',
        f'    <film type="hdrfilm"><integer name="width" value="{w}"/><integer name="height" value="{h}"/>',
        '      <rfilter type="box"/><string name="pixel_format" value="rgb"/>'
        '<string name="component_format" value="float32"/><boolean name="sample_border" value="false"/></film>',
        '  </sensor>',
    ]
    for q in desc["quads"]:
        p0, p1, _, p3 = [[float(c) for c in p] for p in q["corners"]]
        # Mitsuba's rectangle is [-1, 1]^2 in z = 0 with normal +z: map x to (p1 - p0) / 2,
        # y to (p3 - p0) / 2, z to the unit normal, the origin to the centre.
        ex = [c / 2 for c in _sub(p1, p0)]
        ey = [c / 2 for c in _sub(p3, p0)]
        ez = _norm(_cross(ex, ey))
        centre = [p0[i] + ex[i] + ey[i] for i in range(3)]
        rows = [[ex[r], ey[r], ez[r], centre[r]] for r in range(3)] + [[0.0, 0.0, 0.0, 1.0]]
        matrix = " ".join(repr(float(x)) for row in rows for x in row)
        lines.append(f'  <shape type="rectangle" id={quoteattr(q["name"])}><transform name="to_world">'
                     f'<matrix value="{matrix}"/></transform>{_mitsuba_bsdf(desc["materials"][q["material"]])}</shape>')
    for s in desc["spheres"]:
        lines.append(f'  <shape type="sphere" id={quoteattr(s["name"])}><point name="center" value="{_v(s["center"])}"/>'
                     f'<float name="radius" value="{float(s["radius"])!r}"/>{_mitsuba_bsdf(desc["materials"][s["material"]])}</shape>')
    lines.append('</scene>')
    return "\n".join(lines) + "\n"


def write_mitsuba_xml(desc, path, integrator="path"):
    with open(path, "w") as f:
        f.write(mitsuba_xml(desc, integrator))
