#!/usr/bin/env python3
"""Write scenes/corridor.gltf: a long corridor (2.4 m wide, 2.6 m high, 40 m
long, white floor and ceiling, tinted walls) lit by a row of small ceiling
lamps of varied colour and brightness, with a camera at one end looking down
it. Most lamps are far from any point the camera sees, so next-event
estimation that picks lamps by power alone wastes most of its shadow rays:
the scene the light tree is for (docs/integrators.md).

Run from the repository root: python3 scripts/make-corridor-scene.py
[--lamps N] [--out FILE]  (default 50 lamps, scenes/corridor.gltf).
"""
import argparse
import base64
import json
import math
import random
import sys
import os


sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from gltf_quads import pack_quads  # noqa: E402


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--lamps", type=int, default=50)
    parser.add_argument("--out", default="scenes/corridor.gltf")
    args = parser.parse_args()

    width, height, length = 2.4, 2.6, 40.0
    hx, hz = 1.2, 0.0
    quads = []  # (material, 4 corners, counter-clockwise seen from the side they face)
    quads.append(("floor", [(-hx, 0, 0), (hx, 0, 0), (hx, 0, -length), (-hx, 0, -length)]))
    quads.append(("ceiling", [(-hx, height, 0), (hx, height, 0), (hx, height, -length), (-hx, height, -length)]))
    quads.append(("left", [(-hx, 0, 0), (-hx, 0, -length), (-hx, height, -length), (-hx, height, 0)]))
    quads.append(("right", [(hx, 0, 0), (hx, 0, -length), (hx, height, -length), (hx, height, 0)]))
    quads.append(("floor", [(-hx, 0, -length), (hx, 0, -length), (hx, height, -length), (-hx, height, -length)]))  # end wall
    quads.append(("floor", [(-hx, 0, 0.5), (hx, 0, 0.5), (hx, height, 0.5), (-hx, height, 0.5)]))  # behind the camera

    rng = random.Random(17)
    lamps = []
    spacing = (length - 1.0) / max(args.lamps, 1)
    for i in range(args.lamps):
        z = -0.5 - spacing * (i + 0.5)
        x = rng.uniform(-0.6, 0.6)
        s = 0.12
        y = height - 1e-3  # just below the ceiling, facing down
        corners = [(x - s, y, z - s), (x + s, y, z - s), (x + s, y, z + s), (x - s, y, z + s)]
        name = f"lamp{i}"
        lamps.append((name, [rng.uniform(0.6, 1.0), rng.uniform(0.6, 1.0), rng.uniform(0.5, 1.0)], 20.0 * 10 ** rng.uniform(0, 1)))
        quads.append((name, corners))

    materials = {
        "floor": {"pbrMetallicRoughness": {"baseColorFactor": [0.7, 0.7, 0.68, 1], "metallicFactor": 0.0, "roughnessFactor": 0.6}},
        "ceiling": {"pbrMetallicRoughness": {"baseColorFactor": [0.8, 0.8, 0.8, 1], "metallicFactor": 0.0, "roughnessFactor": 1.0}},
        "left": {"pbrMetallicRoughness": {"baseColorFactor": [0.6, 0.3, 0.25, 1], "metallicFactor": 0.0, "roughnessFactor": 0.9}},
        "right": {"pbrMetallicRoughness": {"baseColorFactor": [0.25, 0.4, 0.6, 1], "metallicFactor": 0.0, "roughnessFactor": 0.9}},
    }
    for name, colour, strength in lamps:
        materials[name] = {"pbrMetallicRoughness": {"baseColorFactor": [0.8, 0.8, 0.8, 1], "metallicFactor": 0.0, "roughnessFactor": 1.0},
                           "emissiveFactor": colour,
                           "extensions": {"KHR_materials_emissive_strength": {"emissiveStrength": strength}}}
    names = list(materials)

    buffer, buffer_views, accessors, primitives = pack_quads(quads, names)

    gltf = {
        "asset": {"version": "2.0", "generator": "wavetrace scripts/make-corridor-scene.py"},
        "extensionsUsed": ["KHR_materials_emissive_strength"],
        "scene": 0,
        "scenes": [{"name": "corridor", "nodes": [0, 1]}],
        "nodes": [
            {"name": "corridor", "mesh": 0},
            # at 1.6 m, looking down the corridor and a little down
            {"name": "camera", "camera": 0, "translation": [0.0, 1.6, 0.0],
             "rotation": [-math.sin(0.04), 0.0, 0.0, math.cos(0.04)]},
        ],
        "cameras": [{"type": "perspective", "perspective": {"yfov": 1.0, "aspectRatio": 1.0, "znear": 0.01}}],
        "meshes": [{"name": "corridor", "primitives": primitives}],
        "materials": [dict(name=n, **materials[n]) for n in names],
        "accessors": accessors,
        "bufferViews": buffer_views,
        "buffers": [{"byteLength": len(buffer), "uri": "data:application/octet-stream;base64," + base64.b64encode(buffer).decode()}],
    }
    with open(args.out, "w") as f:
        json.dump(gltf, f, indent=1)
        f.write("\n")
    print("wrote", args.out + ":", len(quads) * 2, "triangles,", args.lamps, "lamps")


if __name__ == "__main__":
    main()
