#!/usr/bin/env python3
"""Writes meshes built from formulas into a directory, as inputs for bench_remesh --dir that no
file of ../shared/data resembles: thin parts, pole fans of slivers, sharp edges across a plate
thinner than a cell, many holes, open sheets with corners, far-off coordinates, meshes of a few
triangles far coarser than any count (a square of 2, a box of 12), and meshes as CAD systems export
them (float coordinates, flat faces fanned into needles, strips of slivers along
cylinders, some faces written with the opposite orientation).

Usage: scripts/make_shapes.py OUT_DIR [SHARED_MESHES_DIR]

With SHARED_MESHES_DIR (../shared/data/meshes), two transformed copies of shared meshes are added:
spot rotated, scaled by 1e-4 and moved 1e4 away, and kitten rotated and scaled by 1e4.
"""
import math
import os
import struct
import sys


def write_obj(path, V, F):
    with open(path, "w") as f:
        for v in V:
            f.write("v %.17g %.17g %.17g\n" % tuple(v))
        for t in F:
            f.write("f %d %d %d\n" % (t[0] + 1, t[1] + 1, t[2] + 1))


def grid(nu, nv, at, wrap_u=False, wrap_v=False):
    """A (u, v) grid of nu x nv quads on the surface at(u, v), u and v in [0, 1], each quad split
    into two triangles along alternating diagonals."""
    cu, cv = (nu if wrap_u else nu + 1), (nv if wrap_v else nv + 1)
    V = [at(i / nu, j / nv) for j in range(cv) for i in range(cu)]
    idx = lambda i, j: (j % cv) * cu + (i % cu)
    F = []
    for j in range(nv):
        for i in range(nu):
            a, b, c, d = idx(i, j), idx(i + 1, j), idx(i + 1, j + 1), idx(i, j + 1)
            F += [(a, b, c), (a, c, d)] if (i + j) % 2 == 0 else [(a, b, d), (b, c, d)]
    return V, F


def weld(V, F):
    """Vertices at the same place merged; faces that collapse dropped."""
    first, NV, rep = {}, [], []
    for v in V:
        key = tuple(round(x, 9) for x in v)
        if key not in first:
            first[key] = len(NV)
            NV.append(v)
        rep.append(first[key])
    NF = [tuple(rep[x] for x in t) for t in F]
    return NV, [t for t in NF if len(set(t)) == 3]


def thin_torus():
    R, r = 1.0, 0.08
    return grid(160, 12, lambda u, v: ((R + r * math.cos(2 * math.pi * v)) * math.cos(2 * math.pi * u),
                                       (R + r * math.cos(2 * math.pi * v)) * math.sin(2 * math.pi * u),
                                       r * math.sin(2 * math.pi * v)), True, True)


def open_tube():
    return grid(64, 40, lambda u, v: (0.3 * math.cos(2 * math.pi * u), 0.3 * math.sin(2 * math.pi * u), 2 * v),
                True, False)


def latlong_sphere(nu=48, nv=24):
    """A unit sphere of latitude-longitude quads: fans of slivers at both poles."""
    V = [(0.0, 0.0, 1.0)]
    for j in range(1, nv):
        th = math.pi * j / nv
        V += [(math.sin(th) * math.cos(2 * math.pi * i / nu), math.sin(th) * math.sin(2 * math.pi * i / nu),
               math.cos(th)) for i in range(nu)]
    V.append((0.0, 0.0, -1.0))
    south = len(V) - 1
    ring = lambda j, i: 1 + (j - 1) * nu + (i % nu)
    F = [(0, ring(1, i), ring(1, i + 1)) for i in range(nu)]
    for j in range(1, nv - 1):
        for i in range(nu):
            F += [(ring(j, i), ring(j + 1, i), ring(j + 1, i + 1)), (ring(j, i), ring(j + 1, i + 1), ring(j, i + 1))]
    F += [(south, ring(nv - 1, i + 1), ring(nv - 1, i)) for i in range(nu)]
    return V, F


def box(size, step):
    """A box with a corner at the origin, each side a grid of squares of about `step`."""
    cells = [max(1, round(s / step)) for s in size]
    index, V, F = {}, [], []

    def vertex(g):
        if g not in index:
            index[g] = len(V)
            V.append(tuple(size[a] * g[a] / cells[a] for a in range(3)))
        return index[g]

    for axis in range(3):
        u, w = (axis + 1) % 3, (axis + 2) % 3
        for side in range(2):
            for i in range(cells[u]):
                for j in range(cells[w]):
                    def at(a, b):
                        g = [0, 0, 0]
                        g[axis], g[u], g[w] = side * cells[axis], a, b
                        return vertex(tuple(g))
                    p, q, r, s = at(i, j), at(i + 1, j), at(i + 1, j + 1), at(i, j + 1)
                    F += [(p, q, r), (p, r, s)] if side == 1 else [(p, r, q), (p, s, r)]
    return V, F


def capsule(r=0.06, length=1.0, nu=24, nv=120):
    """A thin capsule: a cylinder of radius r with hemispherical caps."""
    def at(u, v):
        s = v * (length + math.pi * r)
        if s < math.pi * r / 2:
            a = s / r - math.pi / 2
            z, rr = r * math.sin(a), r * math.cos(a)
        elif s > length + math.pi * r / 2:
            a = (s - length - math.pi * r / 2) / r
            z, rr = length + r * math.sin(a), r * math.cos(a)
        else:
            z, rr = s - math.pi * r / 2, r
        return (rr * math.cos(2 * math.pi * u), rr * math.sin(2 * math.pi * u), z)
    return weld(*grid(nu, nv, at, True, False))


def perforated(n=80, hole=5):
    """A gently curved square sheet with nine square holes (ten boundary loops)."""
    V = [(i / n, j / n, 0.05 * math.sin(3 * i / n) * math.cos(2 * j / n)) for j in range(n + 1) for i in range(n + 1)]
    corners = [(cx, cy) for cx in (15, 38, 61) for cy in (15, 38, 61)]
    in_hole = lambda i, j: any(cx <= i < cx + hole and cy <= j < cy + hole for cx, cy in corners)
    F = []
    for j in range(n):
        for i in range(n):
            if not in_hole(i, j):
                a = j * (n + 1) + i
                F += [(a, a + 1, a + n + 2), (a, a + n + 2, a + n + 1)]
    used = sorted({x for t in F for x in t})
    new = {v: k for k, v in enumerate(used)}
    return [V[v] for v in used], [tuple(new[x] for x in t) for t in F]


def square_sheet(n=40):
    """A flat unit square (one boundary loop with four 90-degree corners)."""
    return grid(n, n, lambda u, v: (u, v, 0.0))


def saddle_sheet(n=40):
    """The unit square lifted onto the saddle z = 1.2 (x - 1/2)(y - 1/2): a curved sheet whose
    border corners are not in one plane."""
    return grid(n, n, lambda u, v: (u, v, 1.2 * (u - 0.5) * (v - 0.5)))


def read_obj(path):
    V, F = [], []
    for line in open(path):
        p = line.split()
        if p and p[0] == "v":
            V.append([float(x) for x in p[1:4]])
        elif p and p[0] == "f":
            F.append([int(x.split("/")[0]) - 1 for x in p[1:]])
    return V, F


def as_float32(V):
    """Coordinates rounded to single precision, as a binary STL stores them."""
    r = lambda x: struct.unpack("<f", struct.pack("<f", x))[0]
    return [(r(x), r(y), r(z)) for x, y, z in V]


def extruded(outline, height):
    """A prism over a star-shaped outline as CAD exports it: each cap a fan of needles from the
    outline's centroid, each side face one quad of two triangles, outward orientation."""
    n = len(outline)
    V = [(x, y, 0.0) for x, y in outline] + [(x, y, height) for x, y in outline]
    cx, cy = sum(p[0] for p in outline) / n, sum(p[1] for p in outline) / n
    V += [(cx, cy, 0.0), (cx, cy, height)]
    bottom, top = 2 * n, 2 * n + 1
    F = []
    for i in range(n):
        j = (i + 1) % n
        F += [(i, j, n + j), (i, n + j, n + i), (bottom, j, i), (top, n + i, n + j)]
    return as_float32(V), F


def cad_cylinder(segments=64):
    return extruded([(0.5 * math.cos(2 * math.pi * i / segments), 0.5 * math.sin(2 * math.pi * i / segments))
                     for i in range(segments)], 2.0)


def cad_gear(teeth=12, r0=0.8, r1=1.0):
    outline = []
    for k in range(teeth):
        a, d = 2 * math.pi * k / teeth, 2 * math.pi / teeth
        for f, r in ((0, r0), (0.25, r0), (0.35, r1), (0.65, r1), (0.75, r0)):
            outline.append((r * math.cos(a + f * d), r * math.sin(a + f * d)))
    return extruded(outline, 0.4)


def cad_plate_with_hole(segments=32, half=1.0, r=0.3, height=0.5):
    """A square plate with a round through-hole (genus 1): each face of the plate a ring of
    triangles between the square and the hole, the side walls strips."""
    square = []
    for i in range(segments):
        a = 2 * math.pi * i / segments
        c, s = math.cos(a), math.sin(a)
        m = max(abs(c), abs(s))
        square.append((half * c / m, half * s / m))
    hole = [(r * math.cos(2 * math.pi * i / segments), r * math.sin(2 * math.pi * i / segments)) for i in range(segments)]
    V = []
    for z in (0.0, height):
        V += [(x, y, z) for x, y in square] + [(x, y, z) for x, y in hole]
    at = lambda layer, ring, i: layer * 2 * segments + ring * segments + i % segments
    F = []
    for i in range(segments):
        for layer, down in ((0, True), (1, False)):
            a0, a1, b0, b1 = at(layer, 0, i), at(layer, 0, i + 1), at(layer, 1, i), at(layer, 1, i + 1)
            for t in ((a0, a1, b1), (a0, b1, b0)):
                F.append(t[::-1] if down else t)
        a0, a1, c0, c1 = at(0, 0, i), at(0, 0, i + 1), at(1, 0, i), at(1, 0, i + 1)
        F += [(a0, a1, c1), (a0, c1, c0)]
        a0, a1, c0, c1 = at(0, 1, i), at(0, 1, i + 1), at(1, 1, i), at(1, 1, i + 1)
        F += [(a0, c1, a1), (a0, c0, c1)]
    return as_float32(V), F


def with_flipped_faces(mesh, every=5):
    V, F = mesh
    return V, [t[::-1] if i % every == 0 else t for i, t in enumerate(F)]


def transformed(V, scale, shift, angle=0.7):
    c, s = math.cos(angle), math.sin(angle)
    return [((c * x - s * y) * scale + shift, (s * x + c * y) * scale + shift, z * scale - shift) for x, y, z in V]


def main():
    if len(sys.argv) not in (2, 3):
        sys.exit(__doc__)
    out = sys.argv[1]
    os.makedirs(out, exist_ok=True)
    shapes = {
        "thin_torus": thin_torus(), "open_tube": open_tube(), "latlong_sphere": latlong_sphere(),
        "thin_plate": box((1, 1, 0.04), 1 / 40), "coarse_cube": box((1, 1, 1), 1 / 12),
        "thin_capsule": capsule(), "perforated": perforated(), "square_sheet": square_sheet(),
        "saddle_sheet": saddle_sheet(),
        "cad_cylinder": cad_cylinder(), "cad_gear": cad_gear(), "cad_plate_hole": cad_plate_with_hole(),
        "cad_cylinder_flipped_faces": with_flipped_faces(cad_cylinder()),
        "cad_cylinder_dense": cad_cylinder(2048), "cad_beam": extruded([(0, 0), (10, 0), (10, 0.1), (0, 0.1)], 0.1),
        "square_2_faces": grid(1, 1, lambda u, v: (u, v, 0.0)), "box_12_faces": box((1, 1, 1), 1.0),
    }
    if len(sys.argv) == 3:
        for name in ("spot.obj", "kitten.obj"):
            if not os.path.isfile(os.path.join(sys.argv[2], name)):
                sys.exit("make_shapes.py: %s: no %s there (expected ../shared/data/meshes)" % (sys.argv[2], name))
        spot = read_obj(os.path.join(sys.argv[2], "spot.obj"))
        kitten = read_obj(os.path.join(sys.argv[2], "kitten.obj"))
        shapes["spot_tiny_far"] = (transformed(spot[0], 1e-4, 1e4), spot[1])
        shapes["kitten_huge"] = (transformed(kitten[0], 1e4, 0.0), kitten[1])
    for name, (V, F) in shapes.items():
        write_obj(os.path.join(out, name + ".obj"), V, F)
        print("%s: %d vertices, %d faces" % (name, len(V), len(F)))


if __name__ == "__main__":
    main()
