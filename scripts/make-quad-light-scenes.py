"""Write two scenes lit by one rectangle light each, for measuring how
next-event estimation samples rectangles (docs/lab/2026-12-06-quad-lights.md);
neither is tuned on: a room corner (a floor, a back wall, two boxes) lit by

- near-quad.gltf: a large lamp (1.6 m x 1.0 m) 0.3 m above the floor, face
  down, whose solid angle from the floor below it is most of a hemisphere;
- far-quad.gltf: a small lamp (0.3 m x 0.2 m) 4 m up, turned 30 degrees,
  of the same power as the large one.

All materials exactly Lambertian. Usage:
  python3 scripts/make-quad-light-scenes.py OUT_DIR
"""
import base64
import json
import math
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from gltf_quads import pack_quads  # noqa: E402


def box(x0, z0, x1, z1, h):
    """The top and four sides of a box on the floor, faces out."""
    top = [(x0, h, z0), (x0, h, z1), (x1, h, z1), (x1, h, z0)]
    sides = [
        [(x0, 0, z1), (x1, 0, z1), (x1, h, z1), (x0, h, z1)],
        [(x1, 0, z0), (x0, 0, z0), (x0, h, z0), (x1, h, z0)],
        [(x0, 0, z0), (x0, 0, z1), (x0, h, z1), (x0, h, z0)],
        [(x1, 0, z1), (x1, 0, z0), (x1, h, z0), (x1, h, z1)],
    ]
    return [top] + sides


def lamp(center, w, d, tilt_degrees):
    """A face-down rectangle of w x d turned by tilt about the x axis."""
    cx, cy, cz = center
    t = math.radians(tilt_degrees)

    def at(x, z):
        return (cx + x, cy + z * math.sin(t), cz + z * math.cos(t))
    return [at(-w / 2, -d / 2), at(w / 2, -d / 2), at(w / 2, d / 2), at(-w / 2, d / 2)]


def write(path, light, strength):
    quads = [("white", [(-3, 0, -3), (-3, 0, 3), (3, 0, 3), (3, 0, -3)]),     # floor, up
             ("white", [(-3, 0, -3), (3, 0, -3), (3, 3, -3), (-3, 3, -3)])]    # back wall, towards +z
    for q in box(-1.6, -1.2, -0.9, -0.5, 0.7):
        quads.append(("red", q))
    for q in box(0.7, 0.3, 1.3, 0.9, 0.35):
        quads.append(("white", q))
    quads.append(("light", light))
    lambert = {"metallicFactor": 0.0, "roughnessFactor": 1.0}
    materials = {
        "white": {"pbrMetallicRoughness": dict(baseColorFactor=[0.72, 0.71, 0.68, 1.0], **lambert)},
        "red": {"pbrMetallicRoughness": dict(baseColorFactor=[0.63, 0.065, 0.05, 1.0], **lambert)},
        "light": {"pbrMetallicRoughness": dict(baseColorFactor=[0.0, 0.0, 0.0, 1.0], **lambert),
                  "emissiveFactor": [1.0, 0.85, 0.6],
                  "extensions": {"KHR_materials_emissive_strength": {"emissiveStrength": strength}}},
    }
    names = list(materials)
    buffer, views, accessors, primitives = pack_quads(quads, names)
    pitch = math.atan2(1.4, 4.0)
    gltf = {
        "asset": {"version": "2.0", "generator": "wavetrace scripts/make-quad-light-scenes.py"},
        "extensionsUsed": ["KHR_materials_emissive_strength"],
        "scene": 0,
        "scenes": [{"nodes": [0, 1]}],
        "nodes": [{"name": "room", "mesh": 0},
                  {"name": "camera", "camera": 0, "translation": [0.0, 1.8, 3.5],
                   "rotation": [-math.sin(pitch / 2), 0.0, 0.0, math.cos(pitch / 2)]}],
        "cameras": [{"type": "perspective", "perspective": {"yfov": 0.9, "aspectRatio": 1.0, "znear": 0.01}}],
        "meshes": [{"primitives": primitives}],
        "materials": [dict(name=n, **materials[n]) for n in names],
        "accessors": accessors,
        "bufferViews": views,
        "buffers": [{"byteLength": len(buffer),
                     "uri": "data:application/octet-stream;base64," + base64.b64encode(buffer).decode()}],
    }
    with open(path, "w") as f:
        json.dump(gltf, f, indent=1)
        f.write("\n")
    print("wrote", path)


def main():
    out = sys.argv[1] if len(sys.argv) > 1 else "."
    os.makedirs(out, exist_ok=True)
    write(os.path.join(out, "near-quad.gltf"), lamp((0.0, 0.3, -0.2), 1.6, 1.0, 0.0), 4.0)
    # the same power from 1/26.7 of the area
    write(os.path.join(out, "far-quad.gltf"), lamp((0.3, 4.0, 0.0), 0.3, 0.2, 30.0), 4.0 * 1.6 / 0.06)


if __name__ == "__main__":
    main()
