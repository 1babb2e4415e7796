#!/usr/bin/env python3
"""Writes the scaled and translated Cornell boxes of the hard-cases suite (tests/hard_cases.rs):
scenes/glm_c.gltf with every root node placed under one new root node that scales it by
1e-4 or 1e+4, or translates it by 1e+5 along (1, 1, 1). Radiance is invariant under a
uniform scale of the whole scene (camera included), so each renders the unit box's image.
Python 3 standard library only. Run from the repository root:
python3 scripts/make_hard_scenes.py"""
import json

VARIANTS = {
    "cornell_scale_1e-4": {"scale": [1e-4, 1e-4, 1e-4]},
    "cornell_scale_1e4": {"scale": [1e4, 1e4, 1e4]},
    "cornell_offset_1e5": {"translation": [1e5, 1e5, 1e5]},
}

def main():
    with open("scenes/glm_c.gltf") as f:
        base = json.load(f)
    for name, transform in VARIANTS.items():
        doc = json.loads(json.dumps(base))
        scene = doc["scenes"][doc.get("scene", 0)]
        root = dict(name="hard_case_root", children=scene["nodes"], **transform)
        doc["nodes"].append(root)
        scene["nodes"] = [len(doc["nodes"]) - 1]
        scene["name"] = name
        doc["asset"]["generator"] = "vkvcm scripts/make_hard_scenes.py (from scenes/glm_c.gltf)"
        with open(f"scenes/hard/{name}.gltf", "w") as f:
            json.dump(doc, f, indent=1)
            f.write("\n")

if __name__ == "__main__":
    main()
