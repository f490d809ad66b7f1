#!/usr/bin/env python3
"""Writes an animated skinned mesh of about N triangles as one .glb: the benchmark content of
`raypipe bench FILE --motion` (scripts/gpu-bench.sh) and a test input (crates/raypipe/tests/files/gltf.rs
loads it and runs it through the Khronos glTF-Validator).

The mesh is a tube along y (SIDES around, RINGS along) with file normals, bound to a chain of
three joints; each vertex follows the two joints nearest it, blended smoothly. One LINEAR clip of
2 s bends the chain back and forth and turns it about its axis. No dependency beyond Python 3.

    scripts/skinned-mesh.py --triangles 100000 -o skinned-100k.glb
"""

import argparse
import json
import math
import struct
import sys

JOINTS = 3
LENGTH = 3.0
RADIUS = 0.4
DURATION = 2.0
KEYS = 9


def tube(triangles):
    """Sides and rings for at least `triangles` triangles, rings about four times sides (a long
    tube bends visibly)."""
    sides = max(8, round(math.sqrt(triangles / 8)))
    rings = max(2, math.ceil(triangles / (2 * sides)) + 1)
    return sides, rings


def quaternion(axis, angle):
    s = math.sin(angle / 2)
    return [axis[0] * s, axis[1] * s, axis[2] * s, math.cos(angle / 2)]


def multiply(a, b):
    ax, ay, az, aw = a
    bx, by, bz, bw = b
    return [
        aw * bx + ax * bw + ay * bz - az * by,
        aw * by - ax * bz + ay * bw + az * bx,
        aw * bz + ax * by - ay * bx + az * bw,
        aw * bw - ax * bx - ay * by - az * bz,
    ]


def build(triangles):
    sides, rings = tube(triangles)
    positions, normals, joints, weights = [], [], [], []
    segment = LENGTH / (JOINTS - 1)
    for ring in range(rings):
        y = LENGTH * ring / (rings - 1)
        # Between joint j (at j * segment) and j + 1, smoothstepped.
        j = min(int(y / segment), JOINTS - 2)
        x = (y - j * segment) / segment
        w = x * x * (3 - 2 * x)
        for k in range(sides):
            a = 2 * math.pi * k / sides
            c, s = math.cos(a), math.sin(a)
            positions += [RADIUS * c, y, RADIUS * s]
            normals += [c, 0.0, s]
            # A joint is named only where it weighs something (the validator warns of the others).
            if w == 0.0:
                joints += [j, 0, 0, 0]
                weights += [1.0, 0.0, 0.0, 0.0]
            elif w == 1.0:
                joints += [j + 1, 0, 0, 0]
                weights += [1.0, 0.0, 0.0, 0.0]
            else:
                joints += [j, j + 1, 0, 0]
                weights += [1.0 - w, w, 0.0, 0.0]
    indices = []
    for ring in range(rings - 1):
        for k in range(sides):
            a = ring * sides + k
            b = ring * sides + (k + 1) % sides
            indices += [a, a + sides, b, b, a + sides, b + sides]
    return sides, rings, positions, normals, joints, weights, indices


def clip():
    """Key times and each joint's rotations: the root turns about y, the others bend about z
    and x, out of phase."""
    times = [DURATION * k / (KEYS - 1) for k in range(KEYS)]
    rotations = []
    for joint in range(JOINTS):
        keys = []
        for t in times:
            phase = 2 * math.pi * t / DURATION
            if joint == 0:
                q = quaternion([0, 1, 0], 0.5 * math.sin(phase))
            else:
                bend = quaternion([0, 0, 1], 0.6 * math.sin(phase + joint))
                q = multiply(bend, quaternion([1, 0, 0], 0.3 * math.cos(phase + joint)))
            keys += q
        rotations.append(keys)
    return times, rotations


class Buffer:
    def __init__(self):
        self.data = bytearray()
        self.views = []
        self.accessors = []

    def add(self, fmt, values, component, kind, count, target=None, bounds=False):
        while len(self.data) % 4:
            self.data.append(0)
        view = {"buffer": 0, "byteOffset": len(self.data), "byteLength": struct.calcsize(fmt) * len(values)}
        if target:
            view["target"] = target
        self.data += struct.pack("<%d%s" % (len(values), fmt), *values)
        self.views.append(view)
        accessor = {"bufferView": len(self.views) - 1, "componentType": component, "count": count, "type": kind}
        if bounds:
            width = len(values) // count
            accessor["min"] = [min(values[i::width]) for i in range(width)]
            accessor["max"] = [max(values[i::width]) for i in range(width)]
        self.accessors.append(accessor)
        return len(self.accessors) - 1


def f32(values):
    """Values as float32 rounds them, so that accessor bounds match the stored data."""
    return list(struct.unpack("<%df" % len(values), struct.pack("<%df" % len(values), *values)))


def glb(triangles):
    sides, rings, positions, normals, joints, weights, indices = build(triangles)
    vertices = len(positions) // 3
    b = Buffer()
    position = b.add("f", f32(positions), 5126, "VEC3", vertices, 34962, bounds=True)
    normal = b.add("f", f32(normals), 5126, "VEC3", vertices, 34962)
    joint = b.add("B", joints, 5121, "VEC4", vertices, 34962)
    weight = b.add("f", f32(weights), 5126, "VEC4", vertices, 34962)
    index = b.add("I", indices, 5125, "SCALAR", len(indices), 34963)
    segment = LENGTH / (JOINTS - 1)
    # Joint j sits at j * segment along y; its inverse bind matrix (column-major) takes it back.
    inverse_binds = []
    for j in range(JOINTS):
        inverse_binds += [1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, -j * segment, 0, 1]
    binds = b.add("f", inverse_binds, 5126, "MAT4", JOINTS)
    times, rotations = clip()
    key_times = b.add("f", f32(times), 5126, "SCALAR", len(times), bounds=True)
    samplers, channels = [], []
    # Nodes: 0 the mesh, 1.. the joints, each the child of the one before.
    for j in range(JOINTS):
        output = b.add("f", f32(rotations[j]), 5126, "VEC4", len(times))
        samplers.append({"input": key_times, "output": output, "interpolation": "LINEAR"})
        channels.append({"sampler": j, "target": {"node": 1 + j, "path": "rotation"}})
    nodes = [{"mesh": 0, "skin": 0, "name": "tube"}]
    for j in range(JOINTS):
        node = {"name": "joint%d" % j, "translation": [0, 0 if j == 0 else segment, 0]}
        if j + 1 < JOINTS:
            node["children"] = [2 + j]
        nodes.append(node)
    document = {
        "asset": {"version": "2.0", "generator": "raypipe scripts/skinned-mesh.py"},
        "scene": 0,
        "scenes": [{"nodes": [0, 1]}],
        "nodes": nodes,
        "meshes": [
            {
                "primitives": [
                    {
                        "attributes": {"POSITION": position, "NORMAL": normal, "JOINTS_0": joint, "WEIGHTS_0": weight},
                        "indices": index,
                        "material": 0,
                    }
                ]
            }
        ],
        "materials": [{"pbrMetallicRoughness": {"baseColorFactor": [0.8, 0.55, 0.35, 1.0], "metallicFactor": 0.0}}],
        "skins": [{"joints": [1 + j for j in range(JOINTS)], "inverseBindMatrices": binds, "skeleton": 1}],
        "animations": [{"name": "bend", "samplers": samplers, "channels": channels}],
        "buffers": [{"byteLength": len(b.data)}],
        "bufferViews": b.views,
        "accessors": b.accessors,
    }
    text = json.dumps(document, separators=(",", ":")).encode()
    text += b" " * (-len(text) % 4)
    binary = bytes(b.data) + b"\0" * (-len(b.data) % 4)
    total = 12 + 8 + len(text) + 8 + len(binary)
    out = struct.pack("<III", 0x46546C67, 2, total)
    out += struct.pack("<II", len(text), 0x4E4F534A) + text
    out += struct.pack("<II", len(binary), 0x004E4942) + binary
    return out, len(indices) // 3, vertices


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--triangles", type=int, required=True, help="at least this many (8 to 16,000,000)")
    parser.add_argument("-o", "--output", required=True)
    args = parser.parse_args()
    if not 8 <= args.triangles <= 16_000_000:
        sys.exit("skinned-mesh.py: --triangles must be between 8 and 16,000,000")
    data, triangles, vertices = glb(args.triangles)
    with open(args.output, "wb") as f:
        f.write(data)
    print("%s: %d triangles, %d vertices, %d joints" % (args.output, triangles, vertices, JOINTS))


if __name__ == "__main__":
    main()
