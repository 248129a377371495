#!/usr/bin/env python3
"""Generates data/textures/tiles.png: a seamless 256 x 256 texture of weathered stone tiles for the
textured_scan sample scene (prt-texture, thesis 5.5). Procedural and deterministic (fixed seed, no
dependencies beyond the Python standard library), so the PNG can be regenerated bit for bit:

    python3 data/textures/make_tiles.py [OUT.png]   (default: tiles.png next to this script)

Pattern: 4 x 4 tiles in a running bond (every other row shifted by half a tile), each tile with its
own hue and brightness, dark mortar joints 6% of a tile wide, and tileable value noise (two octaves
on a lattice that wraps at the image size) for the stone's grain. Every lattice wraps at 256 pixels,
so the image tiles without seams, as tri-planar projection repeats it.
"""
import math
import os
import random
import struct
import sys
import zlib

SIZE = 256
TILES = 4


def lattice_noise(rng, cells):
    """Bilinear-smoothstep value noise on a cells x cells lattice that wraps (seamless)."""
    grid = [[rng.random() for _ in range(cells)] for _ in range(cells)]

    def at(x, y):  # x, y in [0, 1)
        fx, fy = x * cells, y * cells
        i, j = int(fx) % cells, int(fy) % cells
        tx, ty = fx - math.floor(fx), fy - math.floor(fy)
        sx, sy = tx * tx * (3 - 2 * tx), ty * ty * (3 - 2 * ty)
        i1, j1 = (i + 1) % cells, (j + 1) % cells
        top = grid[j][i] * (1 - sx) + grid[j][i1] * sx
        bottom = grid[j1][i] * (1 - sx) + grid[j1][i1] * sx
        return top * (1 - sy) + bottom * sy

    return at


def make_pixels():
    rng = random.Random(20100607)
    coarse, fine = lattice_noise(rng, 8), lattice_noise(rng, 64)
    # One base color per tile (warm sandstone to cool grey).
    tile_color = {}
    for ty in range(TILES):
        for tx in range(TILES):
            warm = rng.random()
            value = 0.55 + 0.35 * rng.random()
            tile_color[(tx, ty)] = (value * (0.85 + 0.15 * warm), value * (0.78 + 0.12 * warm),
                                    value * (0.70 + 0.05 * (1 - warm)))
    rows = []
    tile = SIZE / TILES
    mortar = 0.06 * tile
    for y in range(SIZE):
        row = bytearray()
        ty = int(y // tile)
        shift = tile / 2 if ty % 2 else 0.0
        for x in range(SIZE):
            xs = (x + shift) % SIZE
            tx = int(xs // tile)
            lx, ly = xs - tx * tile, y - ty * tile
            edge = min(lx, tile - lx, ly, tile - ly)
            grain = 0.75 + 0.25 * coarse(x / SIZE, y / SIZE) + 0.15 * (fine(x / SIZE, y / SIZE) - 0.5)
            if edge < mortar:
                c = (0.22 * grain, 0.21 * grain, 0.20 * grain)
            else:
                base = tile_color[(tx % TILES, ty % TILES)]
                bevel = min(1.0, (edge - mortar) / (0.5 * mortar) * 0.15 + 0.85)
                c = tuple(v * grain * bevel for v in base)
            row += bytes(max(0, min(255, int(round(255 * v)))) for v in c)
        rows.append(bytes(row))
    return rows


def write_png(path, rows, width, height):
    """An 8-bit RGB PNG (filter 0 rows, zlib level 9), written to a temporary file and renamed."""
    def chunk(kind, data):
        body = kind + data
        return struct.pack(">I", len(data)) + body + struct.pack(">I", zlib.crc32(body) & 0xFFFFFFFF)

    raw = b"".join(b"\x00" + r for r in rows)
    png = (b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", width, height, 8, 2, 0, 0, 0)) +
           chunk(b"IDAT", zlib.compress(raw, 9)) + chunk(b"IEND", b""))
    tmp = path + ".tmp"
    with open(tmp, "wb") as f:
        f.write(png)
    os.replace(tmp, path)


def main():
    out = sys.argv[1] if len(sys.argv) > 1 else os.path.join(os.path.dirname(os.path.abspath(__file__)), "tiles.png")
    write_png(out, make_pixels(), SIZE, SIZE)
    print("wrote %s (%d bytes)" % (out, os.path.getsize(out)), file=sys.stderr)


if __name__ == "__main__":
    main()
