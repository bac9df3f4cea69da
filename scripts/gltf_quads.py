"""Pack quads into one glTF buffer: one primitive per material, positions and
16-bit indices, as the scene generators (make-cornell-scene.py,
make-corridor-scene.py) write them."""
import struct


def pack_quads(quads, names, convert=lambda p: p):
    """quads: (material name, 4 corners) pairs; names: the materials in
    order. Returns (buffer bytes, bufferViews, accessors, primitives)."""
    buffer = bytearray()
    buffer_views, accessors, primitives = [], [], []
    for name in names:
        positions, indices = [], []
        for mat, corners in quads:
            if mat != name:
                continue
            base = len(positions)
            positions += [convert(c) for c in corners]
            indices += [base, base + 1, base + 2, base, base + 2, base + 3]
        lo = [min(p[i] for p in positions) for i in range(3)]
        hi = [max(p[i] for p in positions) for i in range(3)]
        pos_offset = len(buffer)
        for p in positions:
            buffer += struct.pack("<3f", *p)
        idx_offset = len(buffer)
        for i in indices:
            buffer += struct.pack("<H", i)
        while len(buffer) % 4:
            buffer += b"\0"
        buffer_views.append({"buffer": 0, "byteOffset": pos_offset, "byteLength": 12 * len(positions), "target": 34962})
        buffer_views.append({"buffer": 0, "byteOffset": idx_offset, "byteLength": 2 * len(indices), "target": 34963})
        accessors.append({"bufferView": len(buffer_views) - 2, "componentType": 5126, "count": len(positions),
                          "type": "VEC3", "min": lo, "max": hi})
        accessors.append({"bufferView": len(buffer_views) - 1, "componentType": 5123, "count": len(indices), "type": "SCALAR"})
        primitives.append({"attributes": {"POSITION": len(accessors) - 2}, "indices": len(accessors) - 1,
                           "material": names.index(name)})
    return bytes(buffer), buffer_views, accessors, primitives
