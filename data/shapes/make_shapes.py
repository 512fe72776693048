#!/usr/bin/env python3
"""Writes the small closed STL surfaces of this folder (outward-facing triangles):

  cube.stl        ASCII,  12 faces: [-0.5, 0.5]^3 (sharp edges and corners; faces on
                  lattice planes when scaled and placed on the lattice)
  octahedron.stl  binary,  8 faces: |x| + |y| + |z| <= 1 (vertices on the axes)
  torus.stl       binary, 768 faces: major radius 1, minor radius 0.4, axis z (not convex,
                  genus 1)

Run from anywhere: python3 data/shapes/make_shapes.py (standard library only).
"""
import math
import os
import struct

HERE = os.path.dirname(os.path.abspath(__file__))


def normal(a, b, c):
    u = [b[i] - a[i] for i in range(3)]
    v = [c[i] - a[i] for i in range(3)]
    n = [u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]]
    length = math.sqrt(sum(x * x for x in n)) or 1.0
    return [x / length for x in n]


def write_ascii(name, triangles):
    with open(os.path.join(HERE, name), "w") as f:
        f.write("solid %s\n" % name[:-4])
        for t in triangles:
            f.write("  facet normal %.9g %.9g %.9g\n    outer loop\n" % tuple(normal(*t)))
            for v in t:
                f.write("      vertex %.17g %.17g %.17g\n" % tuple(v))
            f.write("    endloop\n  endfacet\n")
        f.write("endsolid %s\n" % name[:-4])


def write_binary(name, triangles):
    with open(os.path.join(HERE, name), "wb") as f:
        f.write(("cisamr %s" % name).encode().ljust(80, b" "))
        f.write(struct.pack("<I", len(triangles)))
        for t in triangles:
            f.write(struct.pack("<3f", *normal(*t)))
            for v in t:
                f.write(struct.pack("<3f", *v))
            f.write(struct.pack("<H", 0))


def cube():
    # Each face as two triangles, counter-clockwise seen from outside.
    corners = [[x, y, z] for z in (-0.5, 0.5) for y in (-0.5, 0.5) for x in (-0.5, 0.5)]
    quads = [(0, 2, 3, 1), (4, 5, 7, 6), (0, 1, 5, 4), (2, 6, 7, 3), (0, 4, 6, 2), (1, 3, 7, 5)]
    tris = []
    for a, b, c, d in quads:
        tris.append((corners[a], corners[b], corners[c]))
        tris.append((corners[a], corners[c], corners[d]))
    return tris


def octahedron():
    tris = []
    for sx in (-1, 1):
        for sy in (-1, 1):
            for sz in (-1, 1):
                a, b, c = [sx, 0, 0], [0, sy, 0], [0, 0, sz]
                tris.append((a, b, c) if sx * sy * sz > 0 else (a, c, b))
    return tris


def torus(major=1.0, minor=0.4, nu=32, nv=12):
    def point(i, j):
        u, v = 2 * math.pi * (i % nu) / nu, 2 * math.pi * (j % nv) / nv
        r = major + minor * math.cos(v)
        return [r * math.cos(u), r * math.sin(u), minor * math.sin(v)]

    tris = []
    for i in range(nu):
        for j in range(nv):
            a, b, c, d = point(i, j), point(i + 1, j), point(i + 1, j + 1), point(i, j + 1)
            tris.append((a, b, c))
            tris.append((a, c, d))
    return tris


if __name__ == "__main__":
    write_ascii("cube.stl", cube())
    write_binary("octahedron.stl", octahedron())
    write_binary("torus.stl", torus())
