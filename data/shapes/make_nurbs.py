#!/usr/bin/env python3
"""Writes the NURBS surface fixtures of this folder (docs/nurbs-step-design.md §6): each file
is one JSON object, a `nurbs_surface` inclusion entry without phase, ready to be pasted into
a scene's "inclusions" (add "phase", "scale", "rotation", "translate" as needed). Every patch
is written as count_v rows of count_u control points (and weights), u fastest within a row;
the normals S_u x S_v point outwards everywhere except at poles.

  nurbs_sphere.json      the exact rational unit sphere as ONE biquadratic patch: in u the
                         full unit circle as 9 control points (the square's corners and edge
                         midpoints), knots [0,0,0,.25,.25,.5,.5,.75,.75,1,1,1], weights
                         1, sqrt(2)/2 alternating; in v the half circle from the south pole
                         to the north pole as 5 control points, knots [0,0,0,.5,.5,1,1,1],
                         weights 1, sqrt(2)/2, 1, sqrt(2)/2, 1. Control point (i, j) =
                         (rho_j * cx_i, rho_j * cy_i, z_j), weight w_i * w_j (0.5 exactly at
                         the corners, not sqrt(0.5)**2). Two poles (rows j = 0 and 4 are
                         9 copies of (0, 0, -1) and (0, 0, 1), written as +0.0) and one seam
                         (column 8 = column 0).
  nurbs_sphere2.json     the same sphere as TWO patches, split in u at 0.5 (the knot 0.5
                         already has multiplicity 2, so control column 4 lies on the surface):
                         columns 0..4 and 4..8, each a 5 x 5 net with knots_u
                         [0,0,0,.5,.5,1,1,1]. The patches share their sides bit for bit.
  nurbs_torus.json       the exact torus, major radius R = 1 around z, minor radius r = 0.3,
                         as one 9 x 9 biquadratic patch: the unit circle's net in u (around
                         z) and in v (around the tube); control point (i, j) =
                         ((R + r cx_j) cx_i, (R + r cx_j) cy_i, r cy_j), weight w_i * w_j.
                         Seams in both directions (row 8 = row 0, column 8 = column 0).
  nurbs_cubesphere.json  a bicubic six-patch "cube-sphere" particle: each face of the cube
                         [-1, 1]^3 as a 4 x 4 Bezier patch (knots [0,0,0,0,1,1,1,1], weights
                         1) whose control points, the face's uniform grid at -1, -1/3, 1/3,
                         1, are projected onto the unit sphere (p / |p|). Each cube point is
                         projected once and shared, so neighbouring patches have
                         bit-identical boundary control points (in opposite directions); the
                         face axes (e1, e2) have e1 x e2 = the outward face normal. The
                         surface is a closed, slightly flattened sphere, G0 across the edges.

Run from anywhere: python3 data/shapes/make_nurbs.py [--check] (standard library only).
--check re-reads the written files and verifies them with an independent rational de Boor
evaluation: the sphere and torus patches evaluate onto the analytic surfaces within 1e-14 on
a grid and at random parameters, poles and seams are bit-identical, every cube-sphere side
meets exactly one other side bit for bit, and the normals point outwards.
"""
import json
import math
import os
import random
import sys

HERE = os.path.dirname(os.path.abspath(__file__))

H = math.sqrt(0.5)  # sqrt(2)/2, correctly rounded
# The unit circle as a rational quadratic: 9 control points (x, y) and weights.
CIRCLE = [(1.0, 0.0), (1.0, 1.0), (0.0, 1.0), (-1.0, 1.0), (-1.0, 0.0),
          (-1.0, -1.0), (0.0, -1.0), (1.0, -1.0), (1.0, 0.0)]
CIRCLE_W = [1.0, H, 1.0, H, 1.0, H, 1.0, H, 1.0]
CIRCLE_KNOTS = [0.0, 0.0, 0.0, 0.25, 0.25, 0.5, 0.5, 0.75, 0.75, 1.0, 1.0, 1.0]
HALF_KNOTS = [0.0, 0.0, 0.0, 0.5, 0.5, 1.0, 1.0, 1.0]
# The half circle from the south to the north pole: (rho, z) and weights.
HALF = [(0.0, -1.0), (1.0, -1.0), (1.0, 0.0), (1.0, 1.0), (0.0, 1.0)]
HALF_W = [1.0, H, 1.0, H, 1.0]


def weight(a, b):
    """w_a * w_b with the product of two sqrt(2)/2 written as the exact 1/2."""
    return 0.5 if a == H and b == H else a * b


def sphere_patch():
    points, weights = [], []
    for j, (rho, z) in enumerate(HALF):
        row, wrow = [], []
        for i, (cx, cy) in enumerate(CIRCLE):
            if rho == 0.0:
                row.append((0.0, 0.0, z))  # a pole: 9 identical points, no -0.0
            else:
                row.append((rho * cx, rho * cy, z))
            wrow.append(weight(CIRCLE_W[i], HALF_W[j]))
        points.append(row)
        weights.append(wrow)
    return {"degree": [2, 2], "knots_u": CIRCLE_KNOTS, "knots_v": HALF_KNOTS,
            "control_points": points, "weights": weights}


def sphere2_patches():
    whole = sphere_patch()
    halves = []
    for first in (0, 4):
        cols = range(first, first + 5)
        halves.append({"degree": [2, 2], "knots_u": HALF_KNOTS, "knots_v": HALF_KNOTS,
                       "control_points": [[row[i] for i in cols] for row in whole["control_points"]],
                       "weights": [[row[i] for i in cols] for row in whole["weights"]]})
    return halves


def torus_patch(R=1.0, r=0.3):
    points, weights = [], []
    for j, (tx, ty) in enumerate(CIRCLE):
        rho = R + r * tx
        row, wrow = [], []
        for i, (cx, cy) in enumerate(CIRCLE):
            row.append((rho * cx, rho * cy, r * ty))
            wrow.append(weight(CIRCLE_W[i], CIRCLE_W[j]))
        points.append(row)
        weights.append(wrow)
    return {"degree": [2, 2], "knots_u": CIRCLE_KNOTS, "knots_v": CIRCLE_KNOTS,
            "control_points": points, "weights": weights}


def cubesphere_patches():
    grid = [-3, -1, 1, 3]  # the face grid in thirds: -1, -1/3, 1/3, 1
    projected = {}

    def point(key):  # each cube point projected once: shared sides are the same objects
        if key not in projected:
            c = [k / 3.0 for k in key]
            n = math.sqrt(c[0] * c[0] + c[1] * c[1] + c[2] * c[2])
            projected[key] = (c[0] / n, c[1] / n, c[2] / n)
        return projected[key]

    patches = []
    for axis in range(3):
        for sign in (1, -1):
            # e1 x e2 = sign * axis: S_u x S_v points outwards.
            e1, e2 = ((axis + 1) % 3, (axis + 2) % 3) if sign > 0 else ((axis + 2) % 3, (axis + 1) % 3)
            rows = []
            for b in grid:
                row = []
                for a in grid:
                    key = [0, 0, 0]
                    key[axis], key[e1], key[e2] = 3 * sign, a, b
                    row.append(point(tuple(key)))
                rows.append(row)
            patches.append({"degree": [3, 3], "knots_u": [0.0] * 4 + [1.0] * 4,
                            "knots_v": [0.0] * 4 + [1.0] * 4, "control_points": rows})
    return patches


# ---- writing: repr() of every double (shortest text that reads back to the same bits)

def number(x):
    assert math.isfinite(x) and not (x == 0 and math.copysign(1, x) < 0), x
    return repr(float(x))


def numbers(xs):
    return "[" + ", ".join(number(x) for x in xs) + "]"


def patch_text(p, indent):
    pad = " " * indent
    lines = [pad + "{\"degree\": [%d, %d]," % tuple(p["degree"]),
             pad + " \"knots_u\": " + numbers(p["knots_u"]) + ",",
             pad + " \"knots_v\": " + numbers(p["knots_v"]) + ","]
    rows = [pad + "   [" + ", ".join(numbers(q) for q in row) + "]" for row in p["control_points"]]
    lines.append(pad + " \"control_points\": [\n" + ",\n".join(rows) + "]" + ("," if "weights" in p else ""))
    if "weights" in p:
        wrows = [pad + "   " + numbers(row) for row in p["weights"]]
        lines.append(pad + " \"weights\": [\n" + ",\n".join(wrows) + "]")
    return "\n".join(lines) + "}"


def write(name, patches):
    text = "{\"shape\": \"nurbs_surface\",\n \"patches\": [\n"
    text += ",\n".join(patch_text(p, 2) for p in patches) + "]}\n"
    json.loads(text)  # well-formed
    with open(os.path.join(HERE, name), "w") as f:
        f.write(text)


FILES = {"nurbs_sphere.json": lambda: [sphere_patch()],
         "nurbs_sphere2.json": sphere2_patches,
         "nurbs_torus.json": lambda: [torus_patch()],
         "nurbs_cubesphere.json": cubesphere_patches}


# ---- --check: an independent rational de Boor evaluation of the written files

def span(knots, p, u):
    n = len(knots) - p - 1  # control points
    if u >= knots[n]:
        k = n - 1
        while knots[k] == knots[k + 1]:
            k -= 1
        return k
    k = p
    while not (knots[k] <= u < knots[k + 1]):
        k += 1
    return k


def de_boor(knots, p, ctrl, u):
    """The point at u of the B-spline curve with (homogeneous) control points ctrl."""
    k = span(knots, p, u)
    d = [list(ctrl[j + k - p]) for j in range(p + 1)]
    for r in range(1, p + 1):
        for j in range(p, r - 1, -1):
            lo, hi = knots[j + k - p], knots[j + 1 + k - r]
            a = (u - lo) / (hi - lo)
            d[j] = [(1 - a) * x + a * y for x, y in zip(d[j - 1], d[j])]
    return d[p]


class Patch:
    def __init__(self, p):
        self.pu, self.pv = p["degree"]
        self.ku, self.kv = p["knots_u"], p["knots_v"]
        self.points = p["control_points"]
        nv, nu = len(self.points), len(self.points[0])
        assert nu == len(self.ku) - self.pu - 1 and nv == len(self.kv) - self.pv - 1
        self.weights = p.get("weights", [[1.0] * nu for _ in range(nv)])
        self.hom = [[[w * c for c in q] + [w] for q, w in zip(prow, wrow)]
                    for prow, wrow in zip(self.points, self.weights)]

    def range_u(self):
        return self.ku[self.pu], self.ku[len(self.ku) - self.pu - 1]

    def range_v(self):
        return self.kv[self.pv], self.kv[len(self.kv) - self.pv - 1]

    def at(self, s, t):  # s, t in [0, 1], mapped onto the parameter ranges
        (u0, u1), (v0, v1) = self.range_u(), self.range_v()
        u, v = u0 + s * (u1 - u0), v0 + t * (v1 - v0)
        column = [de_boor(self.ku, self.pu, row, u) for row in self.hom]
        h = de_boor(self.kv, self.pv, column, v)
        return [h[0] / h[3], h[1] / h[3], h[2] / h[3]]

    def sides(self):  # u_min, u_max, v_min, v_max as lists of (point, weight)
        pw = [[(tuple(q), w) for q, w in zip(prow, wrow)] for prow, wrow in zip(self.points, self.weights)]
        return {"u_min": [row[0] for row in pw], "u_max": [row[-1] for row in pw],
                "v_min": pw[0], "v_max": pw[-1]}


def samples(rng, count=2000, grid=41):
    out = [(i / (grid - 1), j / (grid - 1)) for i in range(grid) for j in range(grid)]
    return out + [(rng.random(), rng.random()) for _ in range(count)]


def cross(a, b):
    return [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]


def outward(patch, s, t, centre=(0.0, 0.0, 0.0), axis_point=None):
    """(S_u x S_v) . (S - reference) > 0 at an interior (s, t), by central differences."""
    e = 1e-6
    su = [a - b for a, b in zip(patch.at(s + e, t), patch.at(s - e, t))]
    sv = [a - b for a, b in zip(patch.at(s, t + e), patch.at(s, t - e))]
    x = patch.at(s, t)
    ref = axis_point(x) if axis_point else centre
    return sum(n * (a - b) for n, a, b in zip(cross(su, sv), x, ref)) > 0


def check():
    rng = random.Random(14)
    problems = []
    loaded = {}
    for name in FILES:
        with open(os.path.join(HERE, name)) as f:
            entry = json.load(f)
        assert entry["shape"] == "nurbs_surface" and set(entry) == {"shape", "patches"}, name
        loaded[name] = [Patch(p) for p in entry["patches"]]

    def worst(name, distance):
        err = max(distance(p.at(s, t)) for p in loaded[name] for s, t in samples(rng))
        print("%-22s max distance to the analytic surface %.2e" % (name, err))
        if err > 1e-14:
            problems.append("%s: %.3e > 1e-14" % (name, err))

    sphere = lambda x: abs(math.sqrt(x[0] * x[0] + x[1] * x[1] + x[2] * x[2]) - 1.0)
    torus = lambda x: abs(math.hypot(math.hypot(x[0], x[1]) - 1.0, x[2]) - 0.3)
    worst("nurbs_sphere.json", sphere)
    worst("nurbs_sphere2.json", sphere)
    worst("nurbs_torus.json", torus)

    # Closure: poles are rows of one point, seams and shared sides are bit-identical.
    for name, patches in loaded.items():
        sides = []
        for k, p in enumerate(patches):
            for side, pts in p.sides().items():
                if all(q[0] == pts[0][0] for q in pts):
                    continue  # a pole
                sides.append(("patches[%d].%s" % (k, side), pts))
        for label, pts in sides:
            mates = [other for other, qts in sides if other != label and (qts == pts or qts == pts[::-1])]
            if len(mates) != 1:
                problems.append("%s %s: meets %d sides bit for bit" % (name, label, len(mates)))
        # Normals: outward from the centre (sphere-like), from the tube's axis (torus).
        tube = lambda x: [x[0] / math.hypot(x[0], x[1]), x[1] / math.hypot(x[0], x[1]), 0.0]
        for k, p in enumerate(patches):
            for s, t in samples(rng, 200, 9):
                s, t = 0.02 + 0.96 * s, 0.02 + 0.96 * t
                if not outward(p, s, t, axis_point=tube if "torus" in name else None):
                    problems.append("%s patches[%d]: inward normal at (%g, %g)" % (name, k, s, t))
                    break
        print("%-22s %d patches, %d matched sides" % (name, len(patches), len(sides)))
    for p in problems:
        print("PROBLEM:", p)
    return not problems


def main():
    for name, make in FILES.items():
        write(name, make())
    if "--check" in sys.argv[1:]:
        sys.exit(0 if check() else 1)


if __name__ == "__main__":
    main()
