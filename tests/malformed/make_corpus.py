#!/usr/bin/env python3
"""Writes the malformed-scene corpus of tests/scene_malformed.rs into this folder.

Each case is `<name>.gltf` or `<name>.glb` plus `<name>.<ext>.expect`: one line, a
substring the loader's error must contain ("ok": the file must load and render-check
cleanly). Re-run after changing a case: python3 tests/malformed/make_corpus.py
(The symbolic-link case is built at test time in a temporary folder.)
"""
import base64, copy, json, os, struct, zlib

HERE = os.path.dirname(os.path.abspath(__file__))


def f32s(vals):
    return b"".join(struct.pack("<f", v) for v in vals)


POS = [-1.0, -1.0, 0.0, 1.0, -1.0, 0.0, 0.0, 1.0, 0.0]
BIN = f32s(POS) + struct.pack("<3H", 0, 1, 2) + b"\0\0"  # 36 + 6 + 2 = 44 bytes


def data_uri(b):
    return "data:application/octet-stream;base64," + base64.b64encode(b).decode()


BASE = {
    "asset": {"version": "2.0"},
    "scene": 0,
    "scenes": [{"nodes": [0, 1]}],
    "nodes": [{"name": "tri", "mesh": 0}, {"name": "cam", "camera": 0, "translation": [0.0, 0.0, 3.0]}],
    "cameras": [{"type": "perspective", "perspective": {"yfov": 0.8, "znear": 0.01}}],
    "meshes": [{"primitives": [{"attributes": {"POSITION": 0}, "indices": 1, "material": 0}]}],
    "materials": [{"name": "lamp", "emissiveFactor": [1.0, 1.0, 1.0]}],
    "accessors": [
        {"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3", "min": [-1, -1, 0], "max": [1, 1, 0]},
        {"bufferView": 1, "componentType": 5123, "count": 3, "type": "SCALAR"},
    ],
    "bufferViews": [{"buffer": 0, "byteOffset": 0, "byteLength": 36}, {"buffer": 0, "byteOffset": 36, "byteLength": 6}],
    "buffers": [{"byteLength": len(BIN), "uri": data_uri(BIN)}],
}


def doc(edit=None):
    d = copy.deepcopy(BASE)
    if edit:
        edit(d)
    return d


def glb(d, bin_chunk=BIN, version=2, length=None, json_len=None, json_type=b"JSON"):
    d = copy.deepcopy(d)
    d["buffers"][0].pop("uri", None)
    js = json.dumps(d).encode()
    js += b" " * (-len(js) % 4)
    body = struct.pack("<I", len(js) if json_len is None else json_len) + json_type + js
    if bin_chunk is not None:
        body += struct.pack("<I", len(bin_chunk)) + b"BIN\0" + bin_chunk
    total = 12 + len(body) if length is None else length
    return b"glTF" + struct.pack("<II", version, total) + body


CASES = {}


def case(name, data, expect):
    CASES[name] = (data if isinstance(data, bytes) else json.dumps(data, indent=1).encode(), expect)


def set_(path, value):
    def edit(d):
        o = d
        for k in path[:-1]:
            o = o[k]
        o[path[-1]] = value
    return edit


def remove(path):
    def edit(d):
        o = d
        for k in path[:-1]:
            o = o[k]
        del o[path[-1]]
    return edit


def with_bin(b, byte_length=None):
    def edit(d):
        d["buffers"][0] = {"byteLength": len(b) if byte_length is None else byte_length, "uri": data_uri(b)}
    return edit


valid = json.dumps(BASE, indent=1).encode()
case("valid.gltf", BASE, "ok")
case("valid.glb", glb(BASE), "ok")

# Container and JSON.
case("empty.gltf", b"", "invalid glTF JSON")
case("truncated_json.gltf", valid[: len(valid) // 2], "invalid glTF JSON")
case("bad_json.gltf", b'{"asset": {"version": "2.0"},, }', "invalid glTF JSON")
case("not_an_object.gltf", b"[1, 2, 3]", "invalid glTF JSON")
case("binary_garbage.gltf", bytes(range(256)), "invalid glTF JSON")
case("missing_asset.gltf", doc(remove(["asset"])), "missing field `asset`")
case("gltf_version_1.gltf", doc(set_(["asset", "version"], "1.0")), "vkvcm reads glTF 2.0 files only")
case("wrong_types.gltf", doc(set_(["nodes"], {"mesh": 0})), "invalid glTF JSON")
case("glb_truncated_header.glb", b"glTF\x02\x00", "ends inside the 12-byte header")
case("glb_version_1.glb", glb(BASE, version=1), "version 1 is not supported")
case("glb_length_below_header.glb", glb(BASE, length=4), "too short")
full = glb(BASE)
case("glb_truncated_mid_bin.glb", full[: len(full) - 20], "truncated")
case("glb_truncated_mid_json.glb", full[:40], "truncated")
case("glb_json_chunk_too_long.glb", glb(BASE, json_len=100000), "invalid GLB container")
case("glb_first_chunk_not_json.glb", glb(BASE, json_type=b"BIN\0"), "invalid GLB container")
bad_json_glb = glb(BASE)
case("glb_bad_json_chunk.glb", bad_json_glb[:20] + b"{{{{" + bad_json_glb[24:], "invalid glTF JSON in the GLB JSON chunk")
case("glb_without_bin_chunk.glb", glb(BASE, bin_chunk=None), "no (unused) GLB binary chunk")

# Buffers, views, accessors.
case("buffer_file_missing.gltf", doc(set_(["buffers", 0], {"byteLength": 44, "uri": "absent.bin"})), "absent.bin")
case("buffer_shorter_than_byte_length.gltf", doc(with_bin(BIN, 4000)), "byteLength is 4000")
case("buffer_byte_length_2_pow_53.gltf", doc(with_bin(BIN, 2**53)), "byteLength is 9007199254740992")
case("data_uri_bad_base64.gltf", doc(set_(["buffers", 0, "uri"], "data:application/octet-stream;base64,QUJD*EFG")), "invalid base64")
case("data_uri_not_base64.gltf", doc(set_(["buffers", 0, "uri"], "data:text/plain,hello")), "without base64")
case("view_beyond_buffer.gltf", doc(set_(["bufferViews", 1, "byteOffset"], 40)), "exceeds buffer 0")
case("accessor_beyond_view.gltf", doc(set_(["accessors", 0, "count"], 4)), "exceeds buffer view 0")
case("accessor_offset_beyond_view.gltf", doc(set_(["accessors", 0, "byteOffset"], 12)), "exceeds buffer view 0")
case("accessor_count_2_pow_31.gltf", doc(set_(["accessors", 0, "count"], 2**31)), "2147483648 elements")
case("accessor_without_view.gltf", doc(remove(["accessors", 0, "bufferView"])), "accessors[0].bufferView")
case("byte_stride_too_small.gltf", doc(set_(["bufferViews", 0, "byteStride"], 8)), "byteStride")
case("dangling_position_accessor.gltf", doc(set_(["meshes", 0, "primitives", 0, "attributes", "POSITION"], 9)), "refers to accessor 9")
case("dangling_buffer_view.gltf", doc(set_(["accessors", 1, "bufferView"], 7)), "accessors[1].bufferView")
case("index_out_of_range.gltf", doc(with_bin(f32s(POS) + struct.pack("<3H", 0, 1, 3) + b"\0\0")), "element 2 = 3 is out of range")
case("index_float_component.gltf", doc(set_(["accessors", 1, "componentType"], 5126)), "UNSIGNED_BYTE/SHORT/INT")
case("index_vec3.gltf", doc(set_(["accessors", 1, "type"], "VEC3")), "must be SCALAR")
case("position_u16.gltf", doc(set_(["accessors", 0, "componentType"], 5123)), "must be FLOAT VEC3")
case("position_vec2.gltf", doc(set_(["accessors", 0, "type"], "VEC2")), "must be FLOAT VEC3")
case("bad_component_type.gltf", doc(set_(["accessors", 0, "componentType"], 1234)), "componentType")
nan = float("nan")
inf = float("inf")
case("nan_positions.gltf", doc(with_bin(f32s([nan] * 9) + struct.pack("<3H", 0, 1, 2) + b"\0\0")), "1 degenerate triangle(s) were skipped")
case("inf_positions.gltf", doc(with_bin(f32s([inf, 0, 0] + POS[3:]) + struct.pack("<3H", 0, 1, 2) + b"\0\0")), "no geometry")

# URIs.
case("uri_absolute.gltf", doc(set_(["buffers", 0, "uri"], "/etc/passwd")), "absolute path")
case("uri_parent.gltf", doc(set_(["buffers", 0, "uri"], "../scene_malformed.rs")), "contains '..'")
case("uri_nested_parent.gltf", doc(set_(["buffers", 0, "uri"], "sub/../../x.bin")), "contains '..'")
case("uri_percent_parent.gltf", doc(set_(["buffers", 0, "uri"], "%2e%2e/scene_malformed.rs")), "contains '..'")
case("uri_percent_bad.gltf", doc(set_(["buffers", 0, "uri"], "a%zz.bin")), "bad %-escape")
case("uri_scheme_file.gltf", doc(set_(["buffers", 0, "uri"], "file:///etc/passwd")), "has a scheme")
case("uri_scheme_http.gltf", doc(set_(["buffers", 0, "uri"], "http://example.com/x.bin")), "has a scheme")
case("uri_drive_letter.gltf", doc(set_(["buffers", 0, "uri"], "C:\\\\x.bin")), "absolute path")
case("uri_directory.gltf", doc(set_(["buffers", 0, "uri"], ".")), "buffer 0")

# Features, structure, content.
case("required_extension.gltf", doc(set_(["extensionsRequired"], ["KHR_materials_unlit"])), "unsupported required extension(s) KHR_materials_unlit")
# Compression extensions: refused with the tool that removes them.
case("required_draco.gltf", doc(set_(["extensionsRequired"], ["KHR_draco_mesh_compression"])), "KHR_draco_mesh_compression is not supported: Draco-compressed meshes are not decoded: decompress the file with `gltf-transform cp")
# EXT_meshopt_compression and EXT_texture_webp are decoded: a view whose bytes are not a
# meshopt stream is an error; a file that only lists WebP loads.
def meshopt_view(d):
    d["extensionsRequired"] = ["EXT_meshopt_compression"]
    d["bufferViews"][0]["extensions"] = {"EXT_meshopt_compression": {
        "buffer": 0, "byteOffset": 0, "byteLength": 36, "byteStride": 12, "count": 3, "mode": "ATTRIBUTES"}}
case("meshopt_not_a_stream.gltf", doc(meshopt_view), "the compressed bytes do not decode")
case("required_basisu.gltf", doc(set_(["extensionsRequired"], ["KHR_texture_basisu"])), "KHR_texture_basisu is not supported: KTX2 / Basis Universal textures are not decoded")
case("required_webp.gltf", doc(set_(["extensionsRequired"], ["EXT_texture_webp"])), "ok")
case("no_scenes.gltf", doc(lambda d: (d.pop("scenes"), d.pop("scene"))), "the file has no scene")
case("scene_index_out_of_range.gltf", doc(set_(["scene"], 5)), "scene")
case("no_nodes.gltf", doc(set_(["scenes", 0, "nodes"], [])), "no geometry for a default camera to frame")
case("no_camera.gltf", doc(set_(["scenes", 0, "nodes"], [0])), "ok")
case("orthographic_camera.gltf", doc(set_(["cameras", 0], {"type": "orthographic", "orthographic": {"xmag": 1, "ymag": 1, "znear": 0.1, "zfar": 10}})), "ok")
case("camera_yfov_zero.gltf", doc(set_(["cameras", 0, "perspective", "yfov"], 0.0)), "yfov")
case("camera_scale_zero.gltf", doc(set_(["nodes", 1, "scale"], [0.0, 0.0, 0.0])), "degenerate world transform")
case("node_cycle.gltf", doc(lambda d: (d["nodes"][0].update(children=[1]), d["nodes"][1].update(children=[0]), d["scenes"][0].update(nodes=[0]))), "not a tree")
case("node_listed_twice.gltf", doc(set_(["scenes", 0, "nodes"], [0, 1, 0])), "reached twice")
case("no_emitter.gltf", doc(set_(["materials", 0], {"name": "grey"})), "ok")  # lit by the default white sky
case("zero_power_light.gltf", doc(lambda d: (d["materials"].__setitem__(0, {"name": "grey"}), d.update(extensionsUsed=["KHR_lights_punctual"], extensions={"KHR_lights_punctual": {"lights": [{"type": "point", "intensity": 0.0}]}}), d["nodes"][0].update(extensions={"KHR_lights_punctual": {"light": 0}}))), "every light has zero power")
case("negative_light.gltf", doc(lambda d: (d.update(extensionsUsed=["KHR_lights_punctual"], extensions={"KHR_lights_punctual": {"lights": [{"type": "point", "intensity": -5.0}]}}), d["nodes"][0].update(extensions={"KHR_lights_punctual": {"light": 0}}))), "must be finite and non-negative")
case("only_points.gltf", doc(set_(["meshes", 0, "primitives", 0, "mode"], 0)), "no geometry")
case("sphere_negative_radius.gltf", doc(lambda d: d["nodes"][0].update(extensions={"VKVCM_spheres": {"spheres": [{"center": [0, 0, 0], "radius": -1}]}})), "radius must be a positive number")
case("sphere_bad_material.gltf", doc(lambda d: d["nodes"][0].update(extensions={"VKVCM_spheres": {"spheres": [{"center": [0, 0, 0], "radius": 1, "material": 99}]}})), "out of range")
case("phong_not_object.gltf", doc(set_(["materials", 0, "extensions"], {"VKVCM_materials_phong": 3})), "must be an object")
case("background_string.gltf", doc(set_(["extensions"], {"VKVCM_background": {"radiance": [1, "x", 1]}})), "VKVCM_background.radiance[1]")
case("environment_without_uri.gltf", doc(set_(["extensions"], {"VKVCM_environment": {"strength": 1}})), "VKVCM_environment.uri must be a string")
case("environment_file_missing.gltf", doc(set_(["extensions"], {"VKVCM_environment": {"uri": "no_such_sky.hdr"}})), "cannot read environment map file")
case("environment_not_an_image.gltf", doc(set_(["extensions"], {"VKVCM_environment": {"uri": data_uri(b"not an image at all")}})), "neither a Radiance HDR")
case("environment_negative_strength.gltf", doc(set_(["extensions"], {"VKVCM_environment": {"uri": data_uri(b"#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y 3 +X 2\n" + bytes([128, 128, 128, 129]) * 6), "strength": -1}})), "strength must not be negative")
case("environment_and_background.gltf", doc(set_(["extensions"], {"VKVCM_background": {"radiance": [1, 1, 1]}, "VKVCM_environment": {"uri": "sky.hdr"}})), "a scene has one background")

# Sparse accessors (glTF 2.0 section 3.6.2.3): POSITION (accessor 0) with elements replaced.
# Buffer: BIN (44 bytes), the UNSIGNED_SHORT sparse indices (padded to 4), the values.
def sparse(indices, values, count=None, idx_len=None, val_len=None, base_view=True):
    def edit(d):
        b = BIN + struct.pack("<%dH" % len(indices), *indices)
        b += b"\0" * (-len(b) % 4)
        val_off = len(b)
        b += f32s(values)
        with_bin(b)(d)
        d["bufferViews"] += [
            {"buffer": 0, "byteOffset": 44, "byteLength": 2 * len(indices) if idx_len is None else idx_len},
            {"buffer": 0, "byteOffset": val_off, "byteLength": 4 * len(values) if val_len is None else val_len},
        ]
        d["accessors"][0]["sparse"] = {
            "count": len(indices) if count is None else count,
            "indices": {"bufferView": 2, "componentType": 5123},
            "values": {"bufferView": 3},
        }
        d["accessors"][0]["max"] = [1, 2, 0]
        if not base_view:
            del d["accessors"][0]["bufferView"]
    return edit


case("sparse_position.gltf", doc(sparse([2], [0.0, 2.0, 0.0])), "ok")
case("sparse_without_view.gltf", doc(sparse([0, 1, 2], POS, base_view=False)), "ok")
case("sparse_index_out_of_range.gltf", doc(sparse([3], [0.0, 2.0, 0.0])), "accessor 0: sparse index 0 = 3 is out of range")
case("sparse_indices_not_increasing.gltf", doc(sparse([2, 1], [0.0, 2.0, 0.0] * 2)), "sparse indices must strictly increase")
case("sparse_count_beyond_accessor.gltf", doc(sparse([0, 1, 2, 2], [0.0] * 12)), "sparse.count 4 exceeds the accessor's count 3")
case("sparse_indices_beyond_view.gltf", doc(sparse([1, 2], [0.0] * 6, idx_len=2)), "accessor 0 sparse.indices")
case("sparse_values_beyond_view.gltf", doc(sparse([2], [0.0, 2.0, 0.0], val_len=8)), "accessor 0 sparse.values")
case("sparse_count_huge.gltf", doc(sparse([2], [0.0, 2.0, 0.0], count=2**62)), "exceeds the accessor's count")
case("sparse_without_view_huge.gltf", doc(lambda d: (sparse([2], [0.0, 2.0, 0.0], base_view=False)(d), d["accessors"][0].update(count=2**40))), "zero-initialised accessors of more than 33554432 components are refused")

# KHR_mesh_quantization: SHORT positions (8-byte stride: 4-byte alignment), BYTE normals.
QBIN = struct.pack("<12h", -1, -1, 0, 0, 1, -1, 0, 0, 0, 1, 0, 0) + struct.pack("<12b", 0, 0, 127, 0, 0, 0, 127, 0, 0, 0, 127, 0) + struct.pack("<3H", 0, 1, 2) + b"\0\0"


def quantized(normal_normalized=True, ext=True):
    def edit(d):
        with_bin(QBIN)(d)
        d["bufferViews"] = [
            {"buffer": 0, "byteOffset": 0, "byteLength": 24, "byteStride": 8},
            {"buffer": 0, "byteOffset": 36, "byteLength": 6},
            {"buffer": 0, "byteOffset": 24, "byteLength": 12, "byteStride": 4},
        ]
        d["accessors"][0].update(componentType=5122)
        d["accessors"].append({"bufferView": 2, "componentType": 5120, "normalized": normal_normalized, "count": 3, "type": "VEC3"})
        d["meshes"][0]["primitives"][0]["attributes"]["NORMAL"] = 2
        if ext:
            d.update(extensionsUsed=["KHR_mesh_quantization"], extensionsRequired=["KHR_mesh_quantization"])
    return edit


case("quantized_mesh.gltf", doc(quantized()), "ok")
case("quantized_without_extension.gltf", doc(quantized(ext=False)), "integer formats need the KHR_mesh_quantization extension")
case("quantized_normal_not_normalized.gltf", doc(quantized(normal_normalized=False)), "must be FLOAT or BYTE normalized or SHORT normalized VEC3, is BYTE VEC3")

# Morph targets (glTF 2.0 section 3.7.2.2).
case("morph_weights_mismatch.gltf", doc(lambda d: (d["meshes"][0]["primitives"][0].update(targets=[{"POSITION": 0}]), d["meshes"][0].update(weights=[1.0, 1.0]))), "2 morph target weight(s) (node or mesh weights), but the primitive has 1 morph target(s)")
case("morph_target_short.gltf", doc(lambda d: (d["accessors"].append({"bufferView": 0, "componentType": 5126, "count": 2, "type": "VEC3"}), d["meshes"][0]["primitives"][0].update(targets=[{"POSITION": 2}]))), "morph target POSITION accessor 2 has 2 elements, the primitive has 3 vertices")

# Skins (glTF 2.0 section 3.7.3): JOINTS_0 (UNSIGNED_BYTE), WEIGHTS_0 (FLOAT), inverse bind matrices.
def skinned(joint=0, weight=1.0, joints=(1,), ibm_count=None):
    def edit(d):
        b = BIN + bytes([joint, 0, 0, 0] * 3) + f32s([weight, 0, 0, 0] * 3) + f32s([1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1])
        with_bin(b)(d)
        d["bufferViews"] += [{"buffer": 0, "byteOffset": 44, "byteLength": 12}, {"buffer": 0, "byteOffset": 56, "byteLength": 48}, {"buffer": 0, "byteOffset": 104, "byteLength": 64}]
        d["accessors"] += [
            {"bufferView": 2, "componentType": 5121, "count": 3, "type": "VEC4"},
            {"bufferView": 3, "componentType": 5126, "count": 3, "type": "VEC4"},
            {"bufferView": 4, "componentType": 5126, "count": 1 if ibm_count is None else ibm_count, "type": "MAT4"},
        ]
        d["meshes"][0]["primitives"][0]["attributes"].update(JOINTS_0=2, WEIGHTS_0=3)
        d["nodes"][0]["skin"] = 0
        d["nodes"].append({"name": "joint"})
        d["scenes"][0]["nodes"].append(2)
        d["skins"] = [{"joints": [2 if j == 1 else j for j in joints], "inverseBindMatrices": 4}]
    return edit


case("skinned.gltf", doc(skinned()), "ok")
case("skin_joint_out_of_range.gltf", doc(skinned(joint=1)), "JOINTS_0 accessor 2 vertex 0 names joint 1, but the skin has 1 joints")
case("skin_negative_weight.gltf", doc(skinned(weight=-1.0)), "weights must be finite and not negative")
case("skin_too_few_inverse_bind_matrices.gltf", doc(skinned(joints=(1, 0))), "inverseBindMatrices accessor 4 has 1 matrices for 2 joints")
case("skin_ibm_beyond_view.gltf", doc(skinned(ibm_count=2)), "accessor 4 (2 elements of 64 bytes")

# Textures (glTF 2.0 section 3.8): material 0's baseColorTexture is texture 0, image 0.
def png_chunk(kind, data):
    return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data) & 0xFFFFFFFF)


def png(w, h, rows=None):
    """An 8-bit RGBA PNG; `rows` None: an IDAT of w x h zero texels."""
    ihdr = png_chunk(b"IHDR", struct.pack(">IIBBBBB", w, h, 8, 6, 0, 0, 0))
    raw = rows if rows is not None else b"".join(b"\0" + b"\0" * 4 * w for _ in range(h))
    return b"\x89PNG\r\n\x1a\n" + ihdr + png_chunk(b"IDAT", zlib.compress(raw)) + png_chunk(b"IEND", b"")


def textured(image, sampler=None, extra=None):
    def edit(d):
        d["images"] = [image]
        d["textures"] = [{"source": 0}]
        if sampler is not None:
            d["samplers"] = [sampler]
            d["textures"][0]["sampler"] = 0
        d["materials"][0]["pbrMetallicRoughness"] = {"baseColorTexture": {"index": 0}}
        if extra:
            extra(d)
    return edit


def image_data_uri(b):
    return "data:image/png;base64," + base64.b64encode(b).decode()


case("texture_ok.gltf", doc(textured({"uri": image_data_uri(png(2, 2))})), "ok")
case("image_file_missing.gltf", doc(textured({"uri": "no_such_texture.png"})), "material 0 'lamp' baseColorTexture (texture 0): image 0: cannot read image file")
case("image_data_uri_undecodable.gltf", doc(textured({"uri": image_data_uri(b"this is not a PNG")})), "image 0: the data is not a PNG or JPEG image")
case("image_truncated_png.gltf", doc(textured({"uri": image_data_uri(png(2, 2)[:-30])})), "cannot decode the PNG image")
case("image_view_beyond_buffer.gltf", doc(textured({"bufferView": 2, "mimeType": "image/png"}, extra=lambda d: d["bufferViews"].append({"buffer": 0, "byteOffset": 40, "byteLength": 100}))), "buffer view 2 (offset 40, length 100) exceeds buffer 0 (44 bytes)")
case("image_view_without_mime_type.gltf", doc(textured({"bufferView": 0}, extra=lambda d: d["bufferViews"].append({"buffer": 0, "byteOffset": 0, "byteLength": 4}))), "the data is not a PNG or JPEG image")
case("image_huge_declared_size.gltf", doc(textured({"uri": image_data_uri(png(100000, 100000, rows=b"\0" * 8))})), "the PNG image is 100000 x 100000 texels")
case("image_without_uri_or_view.gltf", doc(textured({"name": "nothing"})), "image 0 'nothing' has neither a uri nor a bufferView")
case("sampler_bad_wrap.gltf", doc(textured({"uri": image_data_uri(png(2, 2))}, sampler={"wrapS": 12345})), "samplers[0].wrapS")
case("sampler_bad_filter.gltf", doc(textured({"uri": image_data_uri(png(2, 2))}, sampler={"magFilter": 9986})), "samplers[0].magFilter")
case("texture_transform_bad.gltf", doc(textured({"uri": image_data_uri(png(2, 2))}, extra=lambda d: d["materials"][0]["pbrMetallicRoughness"]["baseColorTexture"].update(extensions={"KHR_texture_transform": {"offset": [0, "x"]}}))), "KHR_texture_transform.offset[1] must be a finite number")
case("texture_basisu_only.gltf", doc(textured({"uri": "never_read.ktx2", "mimeType": "image/ktx2"}, extra=lambda d: d["textures"].__setitem__(0, {"extensions": {"KHR_texture_basisu": {"source": 0}}}))), "ok")
case("alpha_cutoff_negative.gltf", doc(set_(["materials", 0], {"name": "lamp", "emissiveFactor": [1, 1, 1], "alphaMode": "MASK", "alphaCutoff": -0.5})), "alphaCutoff -0.5 must be a finite number >= 0")
case("texcoord_wrong_type.gltf", doc(lambda d: d["meshes"][0]["primitives"][0]["attributes"].update(TEXCOORD_0=0)), "accessor 0 (TEXCOORD_0) must be FLOAT or UNSIGNED_BYTE normalized or UNSIGNED_SHORT normalized VEC2, is FLOAT VEC3")
case("color_count_mismatch.gltf", doc(lambda d: (d["accessors"].append({"bufferView": 0, "componentType": 5126, "count": 2, "type": "VEC3"}), d["meshes"][0]["primitives"][0]["attributes"].update(COLOR_0=2))), "COLOR_0 accessor 2 has 2 elements, the primitive has 3 vertices")


if __name__ == "__main__":
    for f in os.listdir(HERE):
        if f.endswith((".gltf", ".glb", ".expect")):
            os.remove(os.path.join(HERE, f))
    for name, (data, expect) in CASES.items():
        with open(os.path.join(HERE, name), "wb") as f:
            f.write(data)
        with open(os.path.join(HERE, name + ".expect"), "w") as f:
            f.write(expect + "\n")
    print(f"{len(CASES)} cases")
