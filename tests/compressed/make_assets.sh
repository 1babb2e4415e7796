#!/usr/bin/env bash
# Makes the compressed versions of tests/khronos/BoxTextured.gltf that tests/scene_compressed.rs
# loads (committed; rerun only to change them). Needs gltfpack from npm (`npm install
# gltfpack`, version 1.3: meshopt compression and filters) and Python with Pillow (WebP):
#   box_plain       gltfpack -noq: float attributes, no compression (the reference)
#   box_meshopt     gltfpack -noq -c: EXT_meshopt_compression, ATTRIBUTES and TRIANGLES
#   box_quant       gltfpack: KHR_mesh_quantization, no compression
#   box_quant_filters  gltfpack -cc: as box_quant, compressed, normals OCTAHEDRAL-filtered
#   box_float_exp   gltfpack -cc -vpf: float positions EXPONENTIAL-filtered (lossy)
#   box_webp        box_plain with its texture as a lossless WebP (EXT_texture_webp, required)
#   GLTFPACK=path/to/gltfpack tests/compressed/make_assets.sh
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
src=$here/../khronos/BoxTextured.gltf
gltfpack=${GLTFPACK:-gltfpack}
cd "$here"
"$gltfpack" -i "$src" -o box_plain.gltf -noq
"$gltfpack" -i "$src" -o box_meshopt.gltf -noq -c
"$gltfpack" -i "$src" -o box_quant.gltf
"$gltfpack" -i "$src" -o box_quant_filters.gltf -cc
"$gltfpack" -i "$src" -o box_float_exp.gltf -cc -vpf
python3 - <<'PY'
import io, json
from PIL import Image
doc = json.load(open("box_plain.gltf"))
bin_ = open("box_plain.bin", "rb").read()
view = doc["bufferViews"][doc["images"][0]["bufferView"]]
png = bin_[view.get("byteOffset", 0):view.get("byteOffset", 0) + view["byteLength"]]
out = io.BytesIO()
Image.open(io.BytesIO(png)).convert("RGBA").save(out, "WEBP", lossless=True, exact=True)
open("box.webp", "wb").write(out.getvalue())
doc["images"].append({"uri": "box.webp", "mimeType": "image/webp"})
doc["textures"] = [{"sampler": doc["textures"][0].get("sampler", 0),
                    "extensions": {"EXT_texture_webp": {"source": len(doc["images"]) - 1}}}]
doc["extensionsUsed"] = ["EXT_texture_webp"]
doc["extensionsRequired"] = ["EXT_texture_webp"]
json.dump(doc, open("box_webp.gltf", "w"), indent=1)
PY
