#!/usr/bin/env python3
"""Writes the stem mesher's hard-case skeletons (ARCHITECTURE section 9) to tests/data/stems/.

Development-time generator: its outputs are committed, so tests need no Python. Each skeleton is
small and named after the difficulty it carries. Rerun after changing a case:
    python3 scripts/make_hard_cases.py
"""
import math
import os
import random

OUT = os.path.join(os.path.dirname(__file__), "..", "tests", "data", "stems")
# random trees: too large for every hard-case test at every k, and the construction alone
# leaves pairs at their joints; tests/test_stems.c holds the default build to them
OUT_RANDOM = os.path.join(os.path.dirname(__file__), "..", "tests", "data", "stems_random")


class Skel:
    def __init__(self):
        self.nodes = []  # (parent, x, y, z, r)

    def add(self, parent, p, r):
        self.nodes.append((parent, p[0], p[1], p[2], r))
        return len(self.nodes) - 1

    def chain(self, parent, start, direction, length, count, r0, r1=None):
        r1 = r0 if r1 is None else r1
        n = parent
        for i in range(1, count + 1):
            t = i / count
            p = [start[k] + direction[k] * length * t for k in range(3)]
            n = self.add(n, p, r0 + (r1 - r0) * t)
        return n

    def write(self, name, comment, origin=(0.0, 0.0, 0.0), out=OUT):
        """Positions are written as origin + local (the .skel reader takes the first root's
        position as the skeleton's origin)."""
        path = os.path.join(out, name + ".skel")
        with open(path, "w") as f:
            f.write("xylem-skeleton 1\n# %s\n" % comment)
            f.write("nodes %d\nleaves 0\n" % len(self.nodes))
            for i, (parent, x, y, z, r) in enumerate(self.nodes):
                fmt = "n %d %d %.9g %.9g %.9g %.9g\n" if origin == (0.0, 0.0, 0.0) else \
                    "n %d %d %.17g %.17g %.17g %.9g\n"
                f.write(fmt % (i, parent, x + origin[0], y + origin[1], z + origin[2], r))
            f.write("end\n")


def unit(v):
    n = math.sqrt(sum(c * c for c in v))
    return [c / n for c in v]


def direction(theta_deg, phi_deg=0.0):
    """Angle theta from +y, azimuth phi around y."""
    t, p = math.radians(theta_deg), math.radians(phi_deg)
    return [math.sin(t) * math.cos(p), math.cos(t), math.sin(t) * math.sin(p)]


def fork(name, comment, angles, r_parent=0.1, r_child=0.06, length=1.0, continue_main=True):
    s = Skel()
    root = s.add(-1, [0, 0, 0], r_parent)
    node = s.add(root, [0, length, 0], r_parent)
    if continue_main:
        s.chain(node, [0, length, 0], [0, 1, 0], length, 2, r_parent * 0.9)
    for theta, phi in angles:
        s.chain(node, [0, length, 0], direction(theta, phi), length, 2, r_child)
    s.write(name, comment)


def turned(d, theta_deg, phi):
    """d turned by theta_deg away from itself, towards azimuth phi (radians) around it."""
    a = [1.0, 0.0, 0.0] if abs(d[0]) < 0.9 else [0.0, 0.0, 1.0]
    u = unit([d[1] * a[2] - d[2] * a[1], d[2] * a[0] - d[0] * a[2], d[0] * a[1] - d[1] * a[0]])
    v = [d[1] * u[2] - d[2] * u[1], d[2] * u[0] - d[0] * u[2], d[0] * u[1] - d[1] * u[0]]
    t = math.radians(theta_deg)
    w = [math.cos(phi) * u[k] + math.sin(phi) * v[k] for k in range(3)]
    return unit([math.cos(t) * d[k] + math.sin(t) * w[k] for k in range(3)])


def random_tree(seed, depth, children, max_nodes, tip_radius=0.01, length=1.0):
    """A seeded random tree, grown breadth first to `depth` forks or `max_nodes` nodes: each
    node gets children(rng) children, each turned off its parent's direction by an angle drawn
    from 0..170 degrees around a random azimuth, internodes 0.6..1.0 of their parent's; radii by
    the pipe rule (a node's squared radius is the sum of its children's, tips tip_radius). Node
    ids grow breadth first, so every parent precedes its children."""
    rng = random.Random(seed)
    pos, direc, par, level, kids = [[0.0, 0.0, 0.0]], [[0.0, 1.0, 0.0]], [-1], [0], [[]]
    step = [length]
    queue, head = [0], 0
    while head < len(queue):
        n = queue[head]
        head += 1
        if level[n] >= depth:
            continue
        for c in range(children(rng)):
            if len(pos) >= max_nodes:
                break
            d = turned(direc[n], rng.uniform(0.0, 170.0), rng.uniform(0.0, 2.0 * math.pi))
            if n == 0:
                d = [0.0, 1.0, 0.0] if c == 0 else d  # the trunk's first segment stands up
            l = step[n] * rng.uniform(0.6, 1.0)
            pos.append([pos[n][k] + d[k] * l for k in range(3)])
            direc.append(d)
            par.append(n)
            level.append(level[n] + (0 if n == 0 else 1))
            kids.append([])
            step.append(l)
            kids[n].append(len(pos) - 1)
            queue.append(len(pos) - 1)
    r2 = [0.0] * len(pos)
    for n in range(len(pos) - 1, -1, -1):
        r2[n] = sum(r2[c] for c in kids[n]) if kids[n] else tip_radius * tip_radius
    s = Skel()
    for n in range(len(pos)):
        s.add(par[n], pos[n], math.sqrt(r2[n]))
    return s


def main():
    os.makedirs(OUT, exist_ok=True)
    os.makedirs(OUT_RANDOM, exist_ok=True)
    cases = 0

    def done():
        nonlocal cases
        cases += 1

    # straight stems and frame singularities
    for name, d in [("stem_up", [0, 1, 0]), ("stem_down", [0, -1, 0]), ("stem_x", [1, 0, 0]),
                    ("stem_diagonal", unit([1, 1, 1])), ("stem_minus_z", [0, 0, -1])]:
        s = Skel()
        s.chain(s.add(-1, [0, 0, 0], 0.1), [0, 0, 0], d, 2.0, 4, 0.1)
        s.write(name, "straight stem along %s" % d)
        done()
    s = Skel()
    s.chain(s.add(-1, [0, 0, 0], 0.2), [0, 0, 0], [0, 1, 0], 3.0, 12, 0.2, 0.02)
    s.write("stem_taper", "vertical stem tapering 10:1 over 12 segments")
    done()
    s = Skel()
    s.chain(s.add(-1, [0, 0, 0], 0.1), [0, 0, 0], [0, 1, 0], 1.0, 4, 0.1, 1e-5)
    s.write("stem_taper_1e-4", "radius ratio 1e-4 along one stem")
    done()
    s = Skel()
    s.chain(s.add(-1, [0, 0, 0], 0.02), [0, 0, 0], [0, 1, 0], 1.0, 4, 0.02, 0.2)
    s.write("stem_inverse_taper", "stem getting thicker towards its tip")
    done()

    # forks at many angles (theta from the parent's direction)
    for theta in [90, 60, 30, 10, 1, 0.1, 0]:
        fork("fork_%s" % str(theta).replace(".", "p"),
             "one lateral child at %s degrees from the continuing parent" % theta, [(theta, 0)])
        done()
    for theta in [120, 150, 179, 179.9, 180]:
        fork("fork_back_%s" % str(theta).replace(".", "p"),
             "one lateral child at %s degrees: pointing back along the parent" % theta,
             [(theta, 0)])
        done()
    fork("fork_y_symmetric", "two equal children at +-30 degrees, no continuation",
         [(30, 0), (30, 180)], r_child=0.07, continue_main=False)
    done()
    fork("fork_parallel_pair", "two equal children, both parallel to the parent (Murray n = 2)",
         [(0, 0), (0, 0)], r_child=0.07, continue_main=False)
    done()
    fork("fork_siblings_1deg", "two children one degree apart", [(40, 0), (41, 0)])
    done()
    fork("fork_equal_radius", "lateral child as thick as the parent", [(45, 0)], r_child=0.1)
    done()
    fork("fork_thin_1e-4", "lateral child 10^4 times thinner than the parent", [(45, 0)],
         r_child=1e-5)
    done()
    fork("fork_thin_1e-3_parallel", "thin child almost parallel to the parent", [(2, 0)],
         r_child=1e-4)
    done()
    fork("fork_both_sides", "two horizontal children on opposite sides", [(90, 0), (90, 180)])
    done()
    fork("fork_up_down", "children at 45 and 135 degrees in one plane", [(45, 0), (135, 0)])
    done()
    for n in [3, 5, 8, 12, 16]:
        fork("spokes_%d" % n, "%d children evenly around at 60 degrees" % n,
             [(60, 360.0 * i / n) for i in range(n)], r_child=0.03)
        done()
    fork("spokes_8_horizontal", "8 horizontal children around one node",
         [(90, 45.0 * i) for i in range(8)], r_child=0.03)
    done()
    fork("spokes_8_near_parallel", "8 children within 5 degrees of the parent",
         [(5, 45.0 * i) for i in range(8)], r_child=0.02)
    done()
    fork("spokes_8_thick", "8 children as thick as the parent", [(70, 45.0 * i) for i in range(8)],
         r_child=0.1)
    done()

    # segment lengths: zero, tiny, shorter than the radius, coincident nodes
    s = Skel()
    a = s.add(-1, [0, 0, 0], 0.1)
    b = s.add(a, [0, 1, 0], 0.1)
    c = s.add(b, [0, 1, 0], 0.1)
    s.chain(c, [0, 1, 0], [0, 1, 0], 1.0, 2, 0.1)
    s.write("zero_length_segment", "a segment of length 0 inside a stem (coincident nodes)")
    done()
    s = Skel()
    a = s.add(-1, [0, 0, 0], 0.1)
    b = s.add(a, [0, 1, 0], 0.1)
    c = s.add(b, [0, 1, 0], 0.05)
    s.chain(c, [0, 1, 0], [1, 0, 0], 1.0, 2, 0.05)
    s.chain(b, [0, 1, 0], [0, 1, 0], 1.0, 2, 0.1)
    s.write("coincident_child", "a lateral child whose first node coincides with the fork")
    done()
    s = Skel()
    s.chain(s.add(-1, [0, 0, 0], 0.1), [0, 0, 0], [0, 1, 0], 1e-6, 3, 0.1)
    s.write("tiny_segments", "three segments of 3e-7: much shorter than the radius")
    done()
    s = Skel()
    n = s.add(-1, [0, 0, 0], 0.3)
    for i in range(10):
        n = s.add(n, [0, 0.05 * (i + 1), 0], 0.3)
    s.write("short_segments", "ten segments each 1/6 of the radius")
    done()
    s = Skel()
    s.add(-1, [0, 0, 0], 0.1)
    s.write("single_node", "one node, no segment")
    done()

    # kinks
    for angle in [45, 90, 120, 150, 170]:
        s = Skel()
        a = s.add(-1, [0, 0, 0], 0.1)
        b = s.add(a, [0, 1, 0], 0.1)
        d = direction(angle, 0)
        s.add(b, [d[0], 1 + d[1], d[2]], 0.1)
        s.write("kink_%d" % angle, "one stem turning by %d degrees at a node" % angle)
        done()
    s = Skel()
    n = s.add(-1, [0, 0, 0], 0.05)
    p = [0.0, 0.0, 0.0]
    for i in range(8):
        p = [p[0] + (0.5 if i % 2 else 0.0), p[1] + (0.0 if i % 2 else 0.5), p[2]]
        n = s.add(n, list(p), 0.05)
    s.write("zigzag_90", "a staircase of 90 degree kinks")
    done()
    s = Skel()
    n = s.add(-1, [0.5, 0, 0], 0.05)
    for i in range(1, 40):
        t = i * 0.4
        n = s.add(n, [0.5 * math.cos(t), 0.05 * i, 0.5 * math.sin(t)], 0.05)
    s.write("helix", "a helix: the frame must not twist")
    done()

    # scale and structure
    for scale in [1e-3, 1e3]:
        s = Skel()
        a = s.add(-1, [0, 0, 0], 0.1 * scale)
        b = s.add(a, [0, scale, 0], 0.1 * scale)
        s.chain(b, [0, scale, 0], direction(35, 0), scale, 2, 0.06 * scale)
        s.chain(b, [0, scale, 0], direction(35, 180), scale, 2, 0.08 * scale)
        s.write("scale_%g" % scale, "a Y fork scaled by %g" % scale)
        done()
    s = Skel()
    s.chain(s.add(-1, [0, 0, 0], 0.1), [0, 0, 0], [0, 1, 0], 1.0, 2, 0.1)
    s.chain(s.add(-1, [2, 0, 0], 0.1), [2, 0, 0], [0, 1, 0], 1.0, 2, 0.1)
    s.write("two_roots", "two separate stems: two components")
    done()
    s = Skel()
    r = s.add(-1, [0, 0, 0], 0.1)
    s.chain(r, [0, 0, 0], direction(30, 0), 1.0, 2, 0.07)
    s.chain(r, [0, 0, 0], direction(30, 180), 1.0, 2, 0.07)
    s.write("root_fork", "the root node itself forks")
    done()
    s = Skel()
    trunk = s.add(-1, [0, 0, 0], 0.1)
    prev = trunk
    for i in range(1, 9):
        node = s.add(prev, [0, 0.25 * i, 0], 0.1)
        s.chain(node, [0, 0.25 * i, 0], direction(70, 90 * i), 0.6, 1, 0.03)
        prev = node
    s.write("comb", "a lateral child at each of 8 consecutive nodes")
    done()
    s = Skel()
    a = s.add(-1, [0, 0, 0], 0.1)
    b = s.add(a, [0, 1, 0], 0.1)
    c = s.add(b, [0, 1.01, 0], 0.1)
    s.chain(b, [0, 1, 0], direction(60, 0), 1.0, 2, 0.05)
    s.chain(c, [0, 1.01, 0], direction(60, 180), 1.0, 2, 0.05)
    s.chain(c, [0, 1.01, 0], [0, 1, 0], 1.0, 2, 0.1)
    s.write("close_forks", "two forks 0.01 apart (a tenth of the radius)")
    done()
    s = Skel()
    a = s.add(-1, [0, 0, 0], 0.1)
    b = s.add(a, [0, 1, 0], 0.1)
    d = direction(50, 0)
    c = s.add(b, [d[0] * 0.3, 1 + d[1] * 0.3, 0], 0.05)
    s.chain(c, [d[0] * 0.3, 1 + d[1] * 0.3, 0], direction(20, 0), 0.5, 1, 0.03)
    s.chain(c, [d[0] * 0.3, 1 + d[1] * 0.3, 0], direction(80, 0), 0.5, 1, 0.03)
    s.chain(b, [0, 1, 0], [0, 1, 0], 1.0, 1, 0.1)
    s.write("fork_on_child", "a child forking again after a segment shorter than the parent radius")
    done()

    def binary(s, parent, p, d, r, depth):
        if depth == 0:
            return
        q = [p[k] + d[k] * 0.6 for k in range(3)]
        n = s.add(parent, q, r)
        for side in (-1, 1):
            nd = unit([d[0] + side * 0.6, d[1], d[2] + 0.3 * side * (depth % 2)])
            binary(s, n, q, nd, r * 0.75, depth - 1)

    s = Skel()
    binary(s, s.add(-1, [0, 0, 0], 0.1), [0, 0, 0], [0, 1, 0], 0.1, 7)
    s.write("binary_depth7", "a binary tree of depth 7 (127 forks)")
    done()

    # seeded random trees: pipe-rule radii, fork angles spread over 0..170 degrees
    two = lambda rng: 2
    one_to_six = lambda rng: rng.randint(1, 6)
    for name, seed, depth, children, max_nodes, origin, comment in [
            ("random_binary_d10", 10, 10, two, 8000, (0.0, 0.0, 0.0),
             "random binary tree, depth 10, pipe-rule radii, forks of 0..170 degrees"),
            ("random_binary_d12", 12, 12, two, 8000, (0.0, 0.0, 0.0),
             "random binary tree, depth 12 (capped at 8000 nodes), pipe-rule radii, forks of "
             "0..170 degrees"),
            ("random_1to6_d10", 16, 10, one_to_six, 6000, (0.0, 0.0, 0.0),
             "random tree of 1..6 children per node, depth 10 (capped at 6000 nodes), pipe-rule "
             "radii, forks of 0..170 degrees"),
            ("random_binary_far", 21, 11, two, 8000, (1e5, 0.0, -1e5),
             "random binary tree, depth 11, placed 1e5 units from the origin")]:
        random_tree(seed, depth, children, max_nodes).write(name, comment, origin, OUT_RANDOM)
        done()
    print("wrote %d skeletons to %s and %s" % (cases, os.path.normpath(OUT),
                                               os.path.normpath(OUT_RANDOM)))


if __name__ == "__main__":
    main()
