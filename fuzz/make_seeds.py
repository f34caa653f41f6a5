"""Writes the trace and raster seed corpora (fuzz/corpus/trace, fuzz/corpus/raster):
small valid requests in the byte layout the harnesses read (fuzz_input.h: uint16
for a choice, raw float32 for a value), so the fuzzer starts from inputs that reach
the marches and the triangle set-up instead of being refused at the first check.
With glint_core importable (GLINT_BUILD_DIR/python on sys.path), also writes the EXR
seeds (fuzz/corpus/exr): tiny files in every lossless compression glint writes."""
import os
import struct
import sys
from pathlib import Path

HERE = Path(__file__).resolve().parent


def u16(v):
    return struct.pack("<H", v)


def f32(*vs):
    return struct.pack(f"<{len(vs)}f", *vs)


def trace_seed(w, h, march, proj_kind, flags):
    out = u16(w - 1) + u16(h - 1) + u16(march) + f32(15.0, 0.3) + u16(10) + f32(0.5)
    out += u16(flags) + u16(proj_kind) + u16(40 if proj_kind == 0 else 3)
    if proj_kind == 1:
        out += u16(3)
    # A floor y = -1 seen by every pixel: position, then normal, specular, back.
    pos, nrm, spec, back = b"", b"", b"", b""
    for j in range(h):
        for i in range(w):
            z = -2.0 - 6.0 * j / max(1, h - 1)
            x = (i - w / 2) / w * -z
            pos += f32(x, -1.0, z, 1.0)
            nrm += f32(0.0, 1.0, 0.0, 0.0)
            spec += f32(0.8, 0.8, 0.8, 1.0)
            back += f32(x, -1.5, z - 0.5, 1.0)
    return out + pos + nrm + spec + back


def raster_seed(w, h, back_layer, tris):
    out = u16(w - 1) + u16(h - 1) + u16(int(back_layer)) + u16(1) + u16(40) + u16(10) + u16(90)
    out += u16(0) + u16(80) + u16(400)  # one material
    out += u16(len(tris))
    for corners in tris:
        for c in corners:  # positions as int8 / 16 with mode != 0
            for v in c:
                out += u16(1) + struct.pack("<b", max(-128, min(127, round(v * 16))))
        for _ in range(3):
            for v in (0.0, 0.0, 1.0):
                out += u16(1) + struct.pack("<b", round(v * 16))
        out += u16(0)
    return out


def main():
    marches = 3  # rows of march_table() without needs_mesh, in table order
    for m in range(marches):
        for pk in (0, 1):
            (HERE / "corpus/trace" / f"floor_{m}_{pk}").write_bytes(trace_seed(6, 5, m, pk, 3))
    (HERE / "corpus/trace" / "one_pixel").write_bytes(trace_seed(1, 1, 0, 0, 1))
    quad = [((-1, -1, -3), (1, -1, -3), (1, 1, -3)), ((-1, -1, -3), (1, 1, -3), (-1, 1, -3))]
    box_back = [((-2, -2, -5), (-2, 2, -5), (2, 2, -5))]
    (HERE / "corpus/raster" / "quad").write_bytes(raster_seed(16, 12, False, quad))
    (HERE / "corpus/raster" / "quad_back").write_bytes(raster_seed(16, 12, True, quad + box_back))
    (HERE / "corpus/raster" / "clipped").write_bytes(
        raster_seed(8, 8, False, [((-1, -1, 1), (1, -1, -3), (0, 1, -3))]))
    exr_seeds()


def exr_seeds():
    sys.path.insert(0, str(Path(os.environ.get("GLINT_BUILD_DIR", HERE.parent / "build")) / "python"))
    import numpy as np
    import glint_core
    rng = np.random.default_rng(1)
    img = rng.standard_normal((3, 4, 4)).astype(np.float32)
    proj = np.array([[1.5, 0, 0, 0], [0, 2, 0, 0], [0, 0, -1.002, -0.2], [0, 0, -1, 0]])
    for comp in ("none", "rle", "zips", "zip", "piz"):
        glint_core.write_exr(str(HERE / "corpus/exr" / f"two_layers_{comp}.exr"),
                             {"position": img, "normal": img[::-1].copy()}, projection=proj,
                             options="march=seed", compression=comp)
    glint_core.write_exr(str(HERE / "corpus/exr" / "plain_rgba.exr"), {"": img[:1, :1].copy()},
                         compression="none")


if __name__ == "__main__":
    main()
