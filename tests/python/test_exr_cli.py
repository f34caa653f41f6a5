"""glint-exr end to end: an analytic scene written as EXR, run through the CLI.

The scene is ray-cast here in numpy (camera at the origin looking down -Z, a
mirror floor at y = -1, a striped wall at z = -6), so the expected geometry
does not come from the code under test. The build is found through
GLINT_BUILD_DIR (default /work/main/build): <build>/bin/glint-exr and the
glint_core module in <build>/python.
"""
import os
import struct
import subprocess
import sys
import zlib
from pathlib import Path

import numpy as np
import pytest

BUILD = Path(os.environ.get("GLINT_BUILD_DIR", "/work/main/build"))
TOOL = BUILD / "bin" / "glint-exr"

if not TOOL.is_file():
    pytest.skip(f"glint-exr not built: {TOOL} is missing (set GLINT_BUILD_DIR)",
                allow_module_level=True)
sys.path.insert(0, str(BUILD / "python"))
glint_core = pytest.importorskip("glint_core", reason=f"glint_core not importable from {BUILD / 'python'}")

W, H = 64, 48
FOV_Y = np.radians(60.0)
NEAR, FAR = 0.1, 100.0
FLOOR_Y, WALL_Z = -1.0, -6.0
FLOOR_COLOR = np.array([0.1, 0.1, 0.1], np.float32)
OPTIONS = ["--max-distance", "20", "--steps", "16", "--thickness", "1.0", "--resolution", "0.5",
           "--blur-size", "2", "--blur-separation", "1.5", "--combine", "over",
           "--march", "seed", "--backend", "cpu", "--threads", "2"]
KWARGS = dict(max_distance=20.0, steps=16, thickness=1.0, resolution=0.5, blur_size=2,
              blur_separation=1.5, combine="over", march="seed", backend="cpu", threads=2)


def perspective(fov_y, aspect, near, far):
    f = 1.0 / np.tan(fov_y / 2.0)
    p = np.zeros((4, 4))
    p[0, 0] = f / aspect
    p[1, 1] = f
    p[2, 2] = -(far + near) / (far - near)
    p[2, 3] = -2.0 * far * near / (far - near)
    p[3, 2] = -1.0
    return p


def wall_color(x):
    """Vertical stripes one view unit wide, so reflections are recognisable."""
    stripe = (np.floor(x) % 2 == 0).astype(np.float32)
    return np.stack([0.8 * stripe + 0.1, 0.2 + 0.0 * x, 0.9 - 0.8 * stripe], axis=-1).astype(np.float32)


def scene():
    """G-buffer of the floor and wall, ray-cast through pixel centres, row 0 at the bottom."""
    j, i = np.mgrid[0:H, 0:W]
    ndc_x = (i + 0.5) / W * 2.0 - 1.0
    ndc_y = (j + 0.5) / H * 2.0 - 1.0
    t = np.tan(FOV_Y / 2.0)
    d = np.stack([ndc_x * t * (W / H), ndc_y * t, -np.ones_like(ndc_x)], axis=-1)
    with np.errstate(divide="ignore"):
        t_floor = np.where(d[..., 1] < 0, FLOOR_Y / d[..., 1], np.inf)
    t_wall = WALL_Z / d[..., 2]
    floor = t_floor < t_wall
    hit = d * np.where(floor, t_floor, t_wall)[..., None]

    position = np.concatenate([hit, np.ones((H, W, 1))], axis=-1).astype(np.float32)
    normal = np.zeros((H, W, 4), np.float32)
    normal[floor, 1] = 1.0
    normal[~floor, 2] = 1.0
    color = np.ones((H, W, 4), np.float32)
    color[..., :3] = wall_color(hit[..., 0])
    color[floor, :3] = FLOOR_COLOR
    specular = np.zeros((H, W, 4), np.float32)
    # The left half of the floor is a mirror, the right half rough (blurred).
    specular[floor, :3] = 0.5
    specular[floor, 3] = np.where(i[floor] < W // 2, 1.0, 0.6)
    return dict(position=position, normal=normal, specular=specular, color=color), floor


def run(*args):
    return subprocess.run([str(TOOL), *map(str, args)], capture_output=True, text=True, timeout=120)


def srgb8(linear):
    v = np.clip(np.nan_to_num(linear.astype(np.float64)), 0.0, 1.0)
    e = np.where(v <= 0.0031308, 12.92 * v, 1.055 * v ** (1.0 / 2.4) - 0.055)
    return np.round(e * 255.0).astype(np.uint8)


def decode_png(path):
    """8-bit RGB/RGBA PNG -> uint8 [rows top first, W, C], with zlib only."""
    data = Path(path).read_bytes()
    assert data[:8] == b"\x89PNG\r\n\x1a\n"
    at, idat, ihdr = 8, b"", None
    while at < len(data):
        (length,) = struct.unpack(">I", data[at:at + 4])
        kind = data[at + 4:at + 8]
        body = data[at + 8:at + 8 + length]
        (crc,) = struct.unpack(">I", data[at + 8 + length:at + 12 + length])
        assert zlib.crc32(kind + body) == crc, kind
        if kind == b"IHDR":
            ihdr = struct.unpack(">IIBBBBB", body)
        elif kind == b"IDAT":
            idat += body
        at += 12 + length
    width, height, depth, ctype, _, _, interlace = ihdr
    assert depth == 8 and ctype in (2, 6) and interlace == 0
    channels = 3 if ctype == 2 else 4
    raw = zlib.decompress(idat)
    stride = width * channels
    out = np.zeros((height, stride), np.int32)
    prev = np.zeros(stride, np.int32)
    for r in range(height):
        kind = raw[r * (stride + 1)]
        line = np.frombuffer(raw, np.uint8, stride, r * (stride + 1) + 1).astype(np.int32)
        cur = np.zeros(stride, np.int32)
        for x in range(stride):
            a = cur[x - channels] if x >= channels else 0
            b = prev[x]
            c = prev[x - channels] if x >= channels else 0
            if kind == 0:
                pred = 0
            elif kind == 1:
                pred = a
            elif kind == 2:
                pred = b
            elif kind == 3:
                pred = (a + b) // 2
            else:
                p = a + b - c
                pa, pb, pc = abs(p - a), abs(p - b), abs(p - c)
                pred = a if pa <= pb and pa <= pc else (b if pb <= pc else c)
            cur[x] = (line[x] + pred) & 0xFF
        out[r] = cur
        prev = cur
    return out.reshape(height, width, channels).astype(np.uint8)


@pytest.fixture(scope="module")
def result(tmp_path_factory):
    tmp = tmp_path_factory.mktemp("exr_cli")
    layers, floor = scene()
    projection = perspective(FOV_Y, W / H, NEAR, FAR)
    src, dst, png = tmp / "in.exr", tmp / "out.exr", tmp / "out.png"
    glint_core.write_exr(src, layers, projection=projection)
    proc = run(*OPTIONS, "--png", png, src, dst)
    assert proc.returncode == 0, proc.stderr
    out, header = glint_core.read_exr(dst)
    return dict(layers=layers, floor=floor, projection=projection, proc=proc, out=out,
                header=header, png=png, src=src, tmp=tmp)


def test_output_holds_input_and_pipeline_layers(result):
    out = result["out"]
    assert set(out) == {"position", "normal", "specular", "color", *glint_core.LAYERS}
    for name, img in result["layers"].items():
        np.testing.assert_array_equal(out[name], img)
    np.testing.assert_allclose(result["header"]["projection"], result["projection"], rtol=0, atol=1e-15)
    assert "max_distance=20" in result["header"]["options"]
    assert "blur_size=2" in result["header"]["options"]


def test_combined_matches_the_python_pipeline(result):
    l = result["layers"]
    expected = glint_core.pipeline(l["position"], l["normal"], l["specular"], l["color"],
                                   result["projection"], **KWARGS)
    for name in glint_core.LAYERS:
        np.testing.assert_allclose(result["out"][name], expected[name], rtol=0, atol=1e-5, err_msg=name)
    # The flags must have reached the pipeline: the defaults give another image.
    defaults = glint_core.pipeline(l["position"], l["normal"], l["specular"], l["color"],
                                   result["projection"])
    assert np.abs(defaults["combined"] - expected["combined"]).max() > 1e-3


def test_non_reflective_pixels_keep_the_base_colour(result):
    wall = ~result["floor"]
    assert wall.sum() > 100
    np.testing.assert_array_equal(result["out"]["combined"][wall][:, :3],
                                  result["layers"]["color"][wall][:, :3])


def test_mirror_floor_shows_the_wall_where_geometry_says(result):
    """Reflected uv of the mirror half against the analytic mirror image of each floor point."""
    pos = result["layers"]["position"][..., :3].astype(np.float64)
    uv = result["out"]["uv"]
    j, i = np.mgrid[0:H, 0:W]
    mirror = result["floor"] & (i < W // 2) & (uv[..., 2] > 0)
    assert mirror.sum() > 50, "the mirror floor should see the wall"
    d = pos / np.linalg.norm(pos, axis=-1, keepdims=True)
    d[..., 1] *= -1.0  # reflect about the floor normal (0, 1, 0)
    t = (WALL_Z - pos[..., 2]) / d[..., 2]
    hit = pos + d * t[..., None]
    clip = np.einsum("ij,hwj->hwi", result["projection"], np.concatenate([hit, np.ones((H, W, 1))], -1))
    want = clip[..., :2] / clip[..., 3:4] * 0.5 + 0.5
    err_px = np.abs(uv[..., :2] - want) * np.array([W, H])
    # The bisection lands on the wall plane: measured error is ~1e-5 px.
    assert err_px[mirror].max() < 0.5, err_px[mirror].max()


def test_png_is_the_srgb_encoded_combined_layer(result):
    img = decode_png(result["png"])
    assert img.shape == (H, W, 3)
    combined = result["out"]["combined"][..., :3]
    # PNG rows run top first: the last PNG row is Image row 0 (the bottom).
    np.testing.assert_array_equal(img[-1, 0], srgb8(combined[0, 0]))
    np.testing.assert_array_equal(img[0, -1], srgb8(combined[H - 1, W - 1]))
    assert np.abs(img[::-1].astype(int) - srgb8(combined).astype(int)).max() == 0


def test_timings_are_printed(result):
    stdout = result["proc"].stdout
    for stage in ("trace", "reflection_color", "specular_weight", "cone_blur", "reflection", "combine"):
        assert f"  {stage} " in stdout, stdout


def test_projection_flags_override_the_header(result):
    dst = result["tmp"] / "ortho.exr"
    proc = run("--orthographic", "3,0.1,50", "--steps", "4", result["src"], dst)
    assert proc.returncode == 0, proc.stderr
    _, header = glint_core.read_exr(dst)
    p = header["projection"]
    assert p[3].tolist() == [0.0, 0.0, 0.0, 1.0]
    assert p[1, 1] == pytest.approx(1.0 / 3.0)
    assert p[0, 0] == pytest.approx(1.0 / (3.0 * W / H))


def test_help_and_bad_command_lines(result):
    proc = run("--help")
    assert proc.returncode == 0 and "usage: glint-exr" in proc.stdout
    src, dst = result["src"], result["tmp"] / "bad.exr"
    for args, needle in [
        (["--no-such-flag", src, dst], "unknown option"),
        (["--steps", "ten", src, dst], "--steps"),
        (["--max-distance", "-1", src, dst], "--max-distance"),
        (["--march", "zigzag", src, dst], "--march"),
        (["--projection", "1 2 3", src, dst], "16 numbers"),
        (["--perspective", "60,0.1,100", "--orthographic", "1,0.1,10", src, dst], "exclude"),
        ([src], "nothing to write"),
        (["--steps"], "expected a value"),
    ]:
        proc = run(*args)
        assert proc.returncode == 2, (args, proc.returncode, proc.stderr)
        assert needle in proc.stderr, (args, proc.stderr)
    assert not dst.exists()


def test_runtime_failures_exit_1_with_the_reason(result):
    tmp = result["tmp"]
    missing = tmp / "missing.exr"
    proc = run(missing, tmp / "x.exr")
    assert proc.returncode == 1 and str(missing) in proc.stderr and "no such file" in proc.stderr

    proc = run("--color-layer", "beauty", result["src"], tmp / "x.exr")
    assert proc.returncode == 1 and '"beauty"' in proc.stderr and "--color-layer" in proc.stderr

    # No projection anywhere: the header has none and no flag gives one.
    bare = tmp / "bare.exr"
    glint_core.write_exr(bare, result["layers"])
    proc = run(bare, tmp / "x.exr")
    assert proc.returncode == 1 and "glintProjection" in proc.stderr
    assert not (tmp / "x.exr").exists()


def test_layer_names_that_are_not_utf8_read_as_escapes():
    """Found by fuzz_exr: a valid file whose layer names hold bytes that are not
    UTF-8 made read_exr raise UnicodeDecodeError instead of returning the layers."""
    import glint_core
    layers, header = glint_core.read_exr(Path(__file__).parent / "data" / "exr_non_utf8_layer_names.exr")
    assert "nor\\x8a\\x9el" in layers and "normal" in layers
    assert all(isinstance(k, str) for k in layers)
