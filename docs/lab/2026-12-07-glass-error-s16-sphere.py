# Usage, from the repository root, with numpy: python3 docs/lab/2026-12-07-glass-error-s16-sphere.py OUT.gltf
# A generated scene nothing was tuned on: a smooth glass sphere (ior 1.5) over a
# diffuse floor and back wall, lit by one small quad light (off to one side).
import importlib.machinery, importlib.util, math, sys
import numpy as np
loader = importlib.machinery.SourceFileLoader("cp", "scripts/compare-peers")
spec = importlib.util.spec_from_loader("cp", loader)
m = importlib.util.module_from_spec(spec); loader.exec_module(m)
n = 48
theta = np.linspace(0, math.pi, n)[:, None]
phi = np.linspace(0, 2 * math.pi, n + 1)[None, :-1]
d = np.stack(np.broadcast_arrays(np.sin(theta) * np.cos(phi), np.cos(theta), np.sin(theta) * np.sin(phi)), -1)
p = (d * 0.45 + np.array([0.0, 0.45, 0.0])).reshape(-1, 3)
r, c = np.meshgrid(np.arange(n - 1), np.arange(n), indexing="ij")
a, b = r * n + c, r * n + (c + 1) % n
idx = np.concatenate([np.stack([a, b, b + n], -1).reshape(-1, 3), np.stack([a, b + n, a + n], -1).reshape(-1, 3)])
# drop degenerate pole triangles
pp = p[idx]
area = np.linalg.norm(np.cross(pp[:, 1] - pp[:, 0], pp[:, 2] - pp[:, 0]), axis=1)
idx = idx[area > 1e-9]
floor = np.array([[-2, 0, 2], [2, 0, 2], [2, 0, -2], [-2, 0, -2]], dtype=np.float64)
wall = np.array([[-2, 0, -1.2], [2, 0, -1.2], [2, 2.5, -1.2], [-2, 2.5, -1.2]], dtype=np.float64)
quad = np.array([[0, 1, 2], [0, 2, 3]])
s = 0.12
light = np.array([[0.7 - s, 1.6, 0.3 - s], [0.7 + s, 1.6, 0.3 - s], [0.7 + s, 1.6, 0.3 + s], [0.7 - s, 1.6, 0.3 + s]])
materials = {"glass": m.glass(1.5), "floor": m.lambert([0.6, 0.55, 0.5]), "wall": m.lambert([0.5, 0.6, 0.7]),
             "light": dict(m.lambert([0.0, 0.0, 0.0]), emissiveFactor=[1.0, 0.9, 0.8])}
materials["light"]["extensions"] = dict(materials["light"]["extensions"], KHR_materials_emissive_strength={"emissiveStrength": 60.0})
cam = np.eye(4)
pitch = -0.3
cam[:3, :3] = np.array([[1, 0, 0], [0, math.cos(pitch), -math.sin(pitch)], [0, math.sin(pitch), math.cos(pitch)]])
cam[:3, 3] = [0.0, 1.3, 2.2]
# is the sphere's winding outward? check one triangle
t = p[idx[len(idx) // 3]]
nrm = np.cross(t[1] - t[0], t[2] - t[0]); ctr = t.mean(0) - np.array([0, 0.45, 0])
if np.dot(nrm, ctr) < 0: idx = idx[:, ::-1].copy()
m.write_gltf(sys.argv[1], [("glass", p, idx), ("floor", floor, quad), ("wall", wall, quad), ("light", light, quad)],
             materials, cam, 0.9, "glass16: glass sphere over a floor, one small quad light")
