#!/usr/bin/env python3
"""Writes the leaf meshes of the OBJ leaf reader's tests and fuzz seeds to tests/data/leaves/.

Development-time generator: its outputs are committed, so tests need no Python. Rerun after
changing a mesh:
    python3 scripts/make_leaf_meshes.py

broadleaf.obj: six leaves on a twig along +Y through the origin (the twig itself is not in the
file), leaf i at height 0.3 i, turned 137.5 degrees from the one before, its stalk at the
twig and its tip pointing out and up at 30 degrees. Each leaf is a petiole of length 0.15 and
an elliptic blade of length 1 and width 0.45 whose midrib sags by 0.03 in the middle, 16
sections of up to 4 triangles, 62 triangles a leaf, 372 in all. The faces mix every corner form
(i, i/t, i//n, i/t/n, negative indices) and the file carries the records the reader skips.
template_leaf.obj: one such leaf alone, stalk at the origin, tip along +Y, facing +Z.
card.obj: a 2 x 1 leaf card (one quad face), stalk edge at y = 0, facing +Z.
"""
import math
import os

OUT = os.path.join(os.path.dirname(__file__), "..", "tests", "data", "leaves")
SECTIONS = 16
PETIOLE = 0.15
BLADE = 1.0
WIDTH = 0.45
SAG = 0.03


def leaf_points():
    """A leaf in its own frame: x across, y along the midrib from the stalk, z its normal.
    Returns the vertices and the triangles (0-based, counter-clockwise seen from +z)."""
    pts = [(0.0, 0.0, 0.0), (0.01, PETIOLE, 0.0), (-0.01, PETIOLE, 0.0)]
    tris = []
    # sections: a midrib point with a left and a right edge point (the first and last are on
    # the midrib: the blade's base and tip)
    rows = []
    for i in range(SECTIONS + 1):
        u = i / SECTIONS
        y = PETIOLE + BLADE * u
        z = -SAG * math.sin(math.pi * u)
        half = 0.5 * WIDTH * math.sin(math.pi * u) ** 0.8
        if i in (0, SECTIONS):
            pts.append((0.0, y, z))
            rows.append((len(pts) - 1,) * 3)
        else:
            pts.extend([(-half, y, z + SAG * 0.3), (0.0, y, z), (half, y, z + SAG * 0.3)])
            rows.append((len(pts) - 3, len(pts) - 2, len(pts) - 1))
    base = rows[0][1]
    tris.append((0, 1, base))
    tris.append((0, base, 2))
    for a, b in zip(rows, rows[1:]):
        (l0, m0, r0), (l1, m1, r1) = a, b
        for tri in ((m0, r0, r1), (m0, r1, m1), (m0, m1, l1), (m0, l1, l0)):
            if len(set(tri)) == 3:
                tris.append(tri)
    return pts, tris


def place(p, frame, origin):
    x, y, z = p
    ax, ay, az = frame
    return tuple(origin[k] + x * ax[k] + y * ay[k] + z * az[k] for k in range(3))


def cross(a, b):
    return (a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0])


def num(v):
    text = ("%.6f" % v).rstrip("0").rstrip(".")
    return "0" if text in ("", "-0") else text


def write(name, text, crlf=False):
    with open(os.path.join(OUT, name), "w", newline="") as f:
        f.write(text.replace("\n", "\r\n") if crlf else text)


def broadleaf():
    pts, tris = leaf_points()
    out = ["# six leaves on a twig along +Y (scripts/make_leaf_meshes.py)", "mtllib leaves.mtl",
           "o twig_leaves"]
    count = 0
    for i in range(6):
        turn = math.radians(137.5 * i)
        rise = math.radians(30.0)
        out_dir = (math.cos(turn), 0.0, math.sin(turn))
        tip = (math.cos(rise) * out_dir[0], math.sin(rise), math.cos(rise) * out_dir[2])
        across = (-math.sin(turn), 0.0, math.cos(turn))
        normal = cross(across, tip)
        origin = (0.02 * out_dir[0], 0.3 * i, 0.02 * out_dir[2])
        out.append("g leaf%d" % i)
        out.append("usemtl leaf")
        out.append("s 1")
        first = count + 1
        for p in pts:
            q = place(p, (across, tip, normal), origin)
            out.append("v " + " ".join(num(c) for c in q))
            out.append("vt %s %s" % (num(0.5 + p[0]), num(p[1] / (PETIOLE + BLADE))))
            out.append("vn %s %s %s" % tuple(num(c) for c in normal))
        count += len(pts)
        for k, (a, b, c) in enumerate(tris):
            form = (i + k) % 5
            idx = [first + a, first + b, first + c]
            if form == 0:
                corners = ["%d" % j for j in idx]
            elif form == 1:
                corners = ["%d/%d" % (j, j) for j in idx]
            elif form == 2:
                corners = ["%d//%d" % (j, j) for j in idx]
            elif form == 3:
                corners = ["%d/%d/%d" % (j, j, j) for j in idx]
            else:  # relative to the last vertex so far
                corners = ["%d" % (j - count - 1) for j in idx]
            out.append("f " + " ".join(corners))
    write("broadleaf.obj", "\n".join(out) + "\n")


def template_leaf():
    pts, tris = leaf_points()
    out = ["# one leaf: stalk at the origin, tip along +Y, facing +Z"]
    out += ["v " + " ".join(num(c) for c in p) for p in pts]
    out += ["f %d %d %d" % (a + 1, b + 1, c + 1) for a, b, c in tris]
    write("template_leaf.obj", "\n".join(out) + "\n", crlf=True)


def card():
    write("card.obj", "# a 2 x 1 leaf card\nv -0.5 0 0\nv 0.5 0 0\nv 0.5 2 0\nv -0.5 2 0\nf 1 2 3 4\n")


if __name__ == "__main__":
    os.makedirs(OUT, exist_ok=True)
    broadleaf()
    template_leaf()
    card()
