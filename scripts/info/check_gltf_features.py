#!/usr/bin/env python3
"""Run `wavetrace info` on every glTF under ../shared/assets/gltf and compare
the features it prints with what the file's JSON says: alphaMode MASK and
BLEND, textures on drawn materials, normal maps, KHR_lights_punctual on a
node, clear coat, COLOR_0, emissive factors. Prints each disagreement and
exits 1 if there is one. Known readings of the renderer, not disagreements:
KHR_materials_unlit is a black Lambertian emitter (emissive_triangles), and a
texture only an unsupported extension reads (iridescence) is not loaded.

    scripts/info/check_gltf_features.py BUILD_DIR
"""
import glob
import json
import os
import subprocess
import sys

build = sys.argv[1] if len(sys.argv) > 1 else "build"
root = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..")
assets = os.path.join(root, "..", "shared", "assets", "gltf")
SUPPORTED_TEXTURE_KEYS = ("baseColorTexture", "metallicRoughnessTexture", "normalTexture", "emissiveTexture",
                          "transmissionTexture", "specularTexture", "specularColorTexture", "clearcoatTexture",
                          "clearcoatRoughnessTexture", "clearcoatNormalTexture", "sheenColorTexture",
                          "sheenRoughnessTexture")


def keys(obj):
    if isinstance(obj, dict):
        for k, v in obj.items():
            yield k
            yield from keys(v)
    elif isinstance(obj, list):
        for v in obj:
            yield from keys(v)


bad = 0
files = sorted(glob.glob(os.path.join(assets, "*", "glTF", "*.gltf")))
for path in files:
    doc = json.load(open(path))
    out = subprocess.run([os.path.join(build, "wavetrace"), "info", path], capture_output=True, text=True)
    lines = [l for l in out.stdout.splitlines() if l.startswith("features:")]
    if out.returncode != 0 or not lines:
        print(f"{path}: wavetrace info failed: {out.stderr.strip()}")
        bad += 1
        continue
    features = set(lines[0].split()[1:])
    materials = doc.get("materials", [])
    drawn = {p.get("material", -1) for m in doc.get("meshes", []) for p in m["primitives"] if p.get("mode", 4) in (4, 5, 6)}
    used = [materials[i] for i in drawn if 0 <= i < len(materials)]
    unlit = [m for m in used if "KHR_materials_unlit" in m.get("extensions", {})]
    expected = {
        "alpha_mask": any(m.get("alphaMode") == "MASK" for m in used),
        "alpha_blend": any(m.get("alphaMode") == "BLEND" for m in used),
        "textures": any(k in SUPPORTED_TEXTURE_KEYS for m in used for k in keys(m)),
        "normal_maps": any(k in ("normalTexture", "clearcoatNormalTexture") for m in used for k in keys(m)),
        "punctual_lights": any("KHR_lights_punctual" in n.get("extensions", {}) for n in doc.get("nodes", [])),
        "clearcoat": any(m.get("extensions", {}).get("KHR_materials_clearcoat", {}).get("clearcoatFactor", 0) > 0
                         for m in used),
        "vertex_colors": any("COLOR_0" in p["attributes"] for m in doc.get("meshes", []) for p in m["primitives"]),
        "emissive_triangles": bool(unlit) or any(any(c > 0 for c in m.get("emissiveFactor", [0, 0, 0])) for m in used),
        "lambertian": bool(unlit),
    }
    for name, want in expected.items():
        if want != (name in features):
            print(f"{os.path.basename(path)}: {name}: the file says {want}, info says {name in features}")
            bad += 1
print(f"{len(files)} files, {bad} disagreements")
sys.exit(1 if bad else 0)
