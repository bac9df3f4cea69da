# Usage (in a folder holding ref-glass-128.exr and split-{main,mainA,fix,fixA}-{1..4}.exr, see the note):
# per-pixel variance across seeds of the full image, of the paths that never
# refract (A) and of the rest (B = full - A, same random numbers), as shares of
# the expected relMSE sum var/ref^2 (luminance-free: mean over channels)
import sys, numpy as np, OpenEXR, Imath
def load(p):
    f = OpenEXR.InputFile(p); dw = f.header()['dataWindow']
    w, h = dw.max.x - dw.min.x + 1, dw.max.y - dw.min.y + 1
    pt = Imath.PixelType(Imath.PixelType.FLOAT)
    return np.stack([np.frombuffer(f.channel(c, pt), np.float32).reshape(h, w) for c in "RGB"], -1).astype(np.float64)
ref = load("ref-glass-128.exr")
den = ref ** 2 + 1e-2  # as host/render/image_error.cpp weighs relMSE
seeds = [1, 2, 3, 4]
for k in ("main", "fix"):
    full = np.stack([load(f"split-{k}-{s}.exr") for s in seeds]); a = np.stack([load(f"split-{k}A-{s}.exr") for s in seeds])
    b = full - a
    v = lambda x: (x.var(0, ddof=1) / den).mean()
    mse = (((full - ref) ** 2) / den).mean()
    print(f"{k}: relMSE-like full {v(full):.4g} (vs ref {mse:.4g}), never-refracted A {v(a):.4g}, refracted B {v(b):.4g}, 2cov {v(full)-v(a)-v(b):.3g}")
