#!/usr/bin/env python3
"""Write scenes/cornell.gltf, the default scene: the Cornell box from the
Cornell University Program of Computer Graphics measurements (geometry in
millimetres), converted to metres, rotated so the camera looks down -Z as
glTF requires, with a glTF camera and an emissive light quad. Also
scenes/cornell_small_light.gltf: the same box lit by a light of 1/100 the
area and 100 times the radiance (the same power), which brute-force path
tracing finds rarely.

Run from the repository root: python3 scripts/make-cornell-scene.py
"""
import sys
import base64
import json
import math
import os

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from gltf_quads import pack_quads  # noqa: E402


def write(LIGHT_SCALE, OUTPUT):
    # Camera at (278, 273, -800) mm looking +z in the original data. Turning by
    # 180 degrees about y (x -> -x, z -> -z) keeps it right-handed and makes the
    # view direction -z; then centre x and put the back wall at z = -0.5592.
    def convert(p):
        x, y, z = p
        return ((278.0 - x) / 1000.0, y / 1000.0, -z / 1000.0)

    WHITE = "white"
    quads = []  # (material, [4 corners in mm])
    quads.append((WHITE, [(552.8, 0, 0), (0, 0, 0), (0, 0, 559.2), (549.6, 0, 559.2)]))            # floor
    quads.append((WHITE, [(556.0, 548.8, 0), (556.0, 548.8, 559.2), (0, 548.8, 559.2), (0, 548.8, 0)]))  # ceiling
    quads.append((WHITE, [(549.6, 0, 559.2), (0, 0, 559.2), (0, 548.8, 559.2), (556.0, 548.8, 559.2)]))  # back
    quads.append(("green", [(0, 0, 559.2), (0, 0, 0), (0, 548.8, 0), (0, 548.8, 559.2)]))          # right wall
    quads.append(("red", [(552.8, 0, 0), (549.6, 0, 559.2), (556.0, 548.8, 559.2), (556.0, 548.8, 0)]))  # left wall
    # The light sits just below the ceiling so it does not share the ceiling's plane.
    cx, cz, hx, hz = 278.0, 279.5, 65.0 * LIGHT_SCALE, 52.5 * LIGHT_SCALE
    quads.append(("light", [(cx + hx, 548.7, cz - hz), (cx + hx, 548.7, cz + hz), (cx - hx, 548.7, cz + hz), (cx - hx, 548.7, cz - hz)]))

    def block(top, height):
        """Top quad and four sides of a block whose top corners are given."""
        result = [[(x, height, z) for x, _, z in top]]
        for i in range(4):
            a, b = top[i], top[(i + 1) % 4]
            result.append([(a[0], height, a[2]), (a[0], 0.0, a[2]), (b[0], 0.0, b[2]), (b[0], height, b[2])])
        return result

    short_top = [(130.0, 165.0, 65.0), (82.0, 165.0, 225.0), (240.0, 165.0, 272.0), (290.0, 165.0, 114.0)]
    tall_top = [(423.0, 330.0, 247.0), (265.0, 330.0, 296.0), (314.0, 330.0, 456.0), (472.0, 330.0, 406.0)]
    for q in block(short_top, 165.0) + block(tall_top, 330.0):
        quads.append((WHITE, q))

    materials = {
        "white": {"pbrMetallicRoughness": {"baseColorFactor": [0.725, 0.71, 0.68, 1.0], "metallicFactor": 0.0, "roughnessFactor": 1.0}},
        "red": {"pbrMetallicRoughness": {"baseColorFactor": [0.63, 0.065, 0.05, 1.0], "metallicFactor": 0.0, "roughnessFactor": 1.0}},
        "green": {"pbrMetallicRoughness": {"baseColorFactor": [0.14, 0.45, 0.091, 1.0], "metallicFactor": 0.0, "roughnessFactor": 1.0}},
        # Radiance (17, 12, 4) as in the usual renderer test scenes: factor x strength.
        "light": {"pbrMetallicRoughness": {"baseColorFactor": [0.78, 0.78, 0.78, 1.0], "metallicFactor": 0.0, "roughnessFactor": 1.0},
                  "emissiveFactor": [1.0, 12.0 / 17.0, 4.0 / 17.0],
                  "extensions": {"KHR_materials_emissive_strength": {"emissiveStrength": 17.0 / LIGHT_SCALE ** 2}}},
    }
    names = list(materials)

    buffer, buffer_views, accessors, primitives = pack_quads(quads, names, convert)

    gltf = {
        "asset": {"version": "2.0", "generator": "wavetrace scripts/make-cornell-scene.py"},
        "extensionsUsed": ["KHR_materials_emissive_strength"],
        "scene": 0,
        "scenes": [{"name": "cornell", "nodes": [0, 1]}],
        "nodes": [
            {"name": "box", "mesh": 0},
            # 35 mm lens on a 25 mm film: yfov = 2 atan(12.5 / 35).
            {"name": "camera", "camera": 0, "translation": [0.0, 0.273, 0.8]},
        ],
        "cameras": [{"type": "perspective", "perspective": {"yfov": 2.0 * math.atan(12.5 / 35.0), "aspectRatio": 1.0, "znear": 0.01}}],
        "meshes": [{"name": "cornell", "primitives": primitives}],
        "materials": [dict(name=n, **materials[n]) for n in names],
        "accessors": accessors,
        "bufferViews": buffer_views,
        "buffers": [{"byteLength": len(buffer), "uri": "data:application/octet-stream;base64," + base64.b64encode(buffer).decode()}],
    }
    with open(OUTPUT, "w") as f:
        json.dump(gltf, f, indent=1)
        f.write("\n")
    print("wrote", OUTPUT + ":", len(quads) * 2, "triangles")


write(1.0, "scenes/cornell.gltf")
write(0.1, "scenes/cornell_small_light.gltf")
