"""Write the textured-mesh test site (tests/textures/mesh.toml): a 1 m x 0.75 m textured quad
with a plain second material, as OBJ + MTL + PNG, the way photogrammetry packages export them.
Deterministic (no random numbers, pure Python): `python3 make.py` rewrites the same bytes.

reef.png is 512 x 384 sRGB texels (1.95 mm on the quad): a mottled, coloured pattern at several
scales, and on a white square (half-size 3 radii) a black disk of radius 16 texels centred at
texel-edge coordinates (160, 128), i.e. at u = 160/512, v = 128/384 from the image's top-left
corner, which is the point (x, y) = (-0.1875, 0.125) m of the quad (tests/textured_mesh.rs
looks for it).
"""
import math
import struct
import zlib

W, H = 512, 384
DISK = (160.0, 128.0, 16.0)


def srgb(c):
    c = min(max(c, 0.0), 1.0)
    return 12.92 * c if c <= 0.0031308 else 1.055 * c ** (1 / 2.4) - 0.055


def hash01(i, j):
    h = (i * 374761393 + j * 668265263) & 0xFFFFFFFF
    h = ((h ^ (h >> 13)) * 1274126177) & 0xFFFFFFFF
    return ((h ^ (h >> 16)) & 0xFFFF) / 65535.0


def albedo(x, y):
    """Linear albedo of texel (x, y) (centre coordinates)."""
    cx, cy, r = DISK
    if abs(x - cx) < 3 * r and abs(y - cy) < 3 * r:
        # White card with a black disk, 4 x 4 supersampled coverage.
        inside = 0
        for a in range(4):
            for b in range(4):
                px = x - 0.5 + (a + 0.5) / 4
                py = y - 0.5 + (b + 0.5) / 4
                inside += (px - cx) ** 2 + (py - cy) ** 2 < r * r
        v = 0.8 * (1 - inside / 16) + 0.03 * inside / 16
        return (v, v, v)
    base = (
        0.25
        + 0.08 * math.sin(2 * math.pi * x / 97) * math.sin(2 * math.pi * y / 61)
        + 0.05 * math.sin(2 * math.pi * (x + 2 * y) / 23)
        + 0.04 * math.sin(2 * math.pi * (3 * x - y) / 7.3)
        + 0.06 * (hash01(int(x // 4), int(y // 4)) - 0.5)
    )
    tint = 0.5 + 0.5 * math.sin(2 * math.pi * (x - y) / 211)
    return (base * (1.1 + 0.3 * tint), base * (1.0 - 0.1 * tint), base * (0.7 - 0.2 * tint))


def png(path, w, h, pixel):
    rows = [
        bytes(round(255 * srgb(c)) for i in range(w) for c in pixel(i + 0.5, j + 0.5))
        for j in range(h)
    ]
    raw = bytearray()
    prev = bytes(3 * w)
    for row in rows:
        # PNG filter 2 ("Up"): each byte less the one above, which compresses smooth images.
        raw.append(2)
        raw.extend((a - b) & 0xFF for a, b in zip(row, prev))
        prev = row

    def chunk(kind, data):
        c = kind + data
        return struct.pack(">I", len(data)) + c + struct.pack(">I", zlib.crc32(c))

    data = b"\x89PNG\r\n\x1a\n"
    data += chunk(b"IHDR", struct.pack(">IIBBBBB", w, h, 8, 2, 0, 0, 0))
    data += chunk(b"IDAT", zlib.compress(bytes(raw), 9))
    data += chunk(b"IEND", b"")
    with open(path, "wb") as f:
        f.write(data)


png("reef.png", W, H, albedo)

with open("site.mtl", "w") as f:
    f.write(
        "# poser test site: the textured quad and a plain strip\n"
        "newmtl reef\nKd 1.000000 1.000000 1.000000\nmap_Kd reef.png\n\n"
        "newmtl plain\nKd 0.6 0.5 0.4\n"
    )

with open("site.obj", "w") as f:
    f.write(
        "# poser test site: a 1 m x 0.75 m textured quad (z = 0, facing +z) and a plain strip\n"
        "mtllib site.mtl\n"
        "o reef\n"
        "v -0.5 -0.375 0\nv 0.5 -0.375 0\nv 0.5 0.375 0\nv -0.5 0.375 0\n"
        "vt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\n"
        "vn 0 0 1\n"
        "usemtl reef\n"
        "f 1/1/1 2/2/1 3/3/1\n"
        "f 1/1/1 3/3/1 4/4/1\n"
        "o strip\n"
        "v 0.55 -0.375 0\nv 0.85 -0.375 0\nv 0.85 0.375 0\nv 0.55 0.375 0\n"
        "usemtl plain\n"
        "f -4//1 -3//1 -2//1 -1//1\n"
    )
