#!/usr/bin/env python3
"""Writes a big binary PLY for memory and load measurements: a sphere of radius 1 as a grid of
rows x columns quads (two triangles each, about TRIANGLES in all), its radius jittered by up to 2 %
per vertex (a scan's noise, from a fixed hash: the same file every time).

    scripts/big-model.py TRIANGLES OUT.ply

The file holds float32 positions and uint8-counted int32 triangle lists, as scanners write them.
"""
import math
import struct
import sys


def jitter(i: int) -> float:
    """A number in [-1, 1) from the vertex index (splitmix64's finalizer)."""
    z = (i + 0x9E3779B97F4A7C15) & 0xFFFFFFFFFFFFFFFF
    z = ((z ^ (z >> 30)) * 0xBF58476D1CE4E5B9) & 0xFFFFFFFFFFFFFFFF
    z = ((z ^ (z >> 27)) * 0x94D049BB133111EB) & 0xFFFFFFFFFFFFFFFF
    z ^= z >> 31
    return (z >> 11) / float(1 << 52) - 1.0


def main() -> int:
    if len(sys.argv) != 3:
        print(__doc__.strip().splitlines()[-3].strip(), file=sys.stderr)
        return 2
    try:
        wanted = int(sys.argv[1])
    except ValueError:
        print(f"{sys.argv[1]}: expected a number of triangles", file=sys.stderr)
        return 2
    if not 8 <= wanted <= 200_000_000:
        print(f"{wanted}: expected 8 to 200000000 triangles", file=sys.stderr)
        return 2
    # rows x columns quads between the poles' rings; columns = 2 * rows keeps them square.
    rows = max(2, round(math.sqrt(wanted / 4)))
    columns = 2 * rows
    vertices = (rows + 1) * columns
    triangles = 2 * rows * columns
    with open(sys.argv[2], "wb") as out:
        out.write(
            (
                "ply\nformat binary_little_endian 1.0\n"
                f"comment a jittered sphere, scripts/big-model.py {wanted}\n"
                f"element vertex {vertices}\nproperty float x\nproperty float y\nproperty float z\n"
                f"element face {triangles}\nproperty list uchar int vertex_indices\nend_header\n"
            ).encode()
        )
        point = struct.Struct("<3f")
        for row in range(rows + 1):
            # Short of the poles, where a ring would collapse to a point.
            polar = math.pi * (0.5 + row) / (rows + 1)
            ring = bytearray()
            for column in range(columns):
                azimuth = 2.0 * math.pi * column / columns
                r = 1.0 + 0.02 * jitter(row * columns + column)
                ring += point.pack(
                    r * math.sin(polar) * math.cos(azimuth),
                    r * math.cos(polar),
                    r * math.sin(polar) * math.sin(azimuth),
                )
            out.write(ring)
        face = struct.Struct("<B3i")
        for row in range(rows):
            band = bytearray()
            for column in range(columns):
                a = row * columns + column
                b = row * columns + (column + 1) % columns
                c, d = a + columns, b + columns
                band += face.pack(3, a, c, b)
                band += face.pack(3, b, c, d)
            out.write(band)
    print(f"{sys.argv[2]}: {vertices} vertices, {triangles} triangles")
    return 0


if __name__ == "__main__":
    sys.exit(main())
