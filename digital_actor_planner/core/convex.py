# Copyright 2026 digital_actor_planner developers
#
# Licensed under the Apache License, Version 2.0 (the "License");
# you may not use this file except in compliance with the License.
# You may obtain a copy of the License at
#
#     http://www.apache.org/licenses/LICENSE-2.0
#
# Unless required by applicable law or agreed to in writing, software
# distributed under the License is distributed on an "AS IS" BASIS,
# WITHOUT WARRANTIES OR CONDITIONS OF ANY KIND, either express or implied.
# See the License for the specific language governing permissions and
# limitations under the License.

"""
Exact contact tests of convex shapes, compiled: whether two shapes touch.

The upper-body planner's narrow phase (see :mod:`.ct_space`). The shapes are those of the
actor's collision model, a box, a cylinder (its axis the shape's z axis, as in FCL and URDF) or
a sphere, posed by a rotation and a centre, and the triangles of the environment's meshes. Each
is given by its support mapping (its farthest point along a direction), and the
Gilbert-Johnson-Keerthi algorithm decides whether the origin lies in the Minkowski difference
of the two shapes, that is whether they share a point.

Shapes that touch (distance 0) count as touching, as FCL counts them. The answers agree with
FCL's collision test except for shapes within about a micrometre of touching, where either
answer is right to within both libraries' tolerances (``test_convex.py`` compares them on
thousands of poses). When the iteration cap is reached without an answer (numerically
degenerate shapes), the shapes count as touching: a planner then avoids a pose it could not
prove clear.
"""
from __future__ import annotations

import math

import numpy as np

from .jit import kernel

#: Shape kinds, as in ``collision._KIND_CODES``, and a triangle.
BOX, CYLINDER, SPHERE, TRIANGLE = 0, 1, 2, 3
#: Iterations after which GJK gives up and reports a contact.
MAX_ITERATIONS = 64
# Squared length below which a search direction means the origin is on the simplex.
_TINY = 1e-24


@kernel('UniTuple(f8, 3)(i8, f8[:], f8[:, :], f8[:], f8[:, :], f8, f8, f8)')
def support(kind, half, rotation, centre, corners, dx, dy, dz):
    """
    Return the shape's farthest point along the direction (dx, dy, dz), world frame, m.

    ``kind`` is :data:`BOX` (``half``: half extents), :data:`CYLINDER` (radius, half length),
    :data:`SPHERE` (radius) posed at ``rotation`` (3, 3) and ``centre`` (3,), or
    :data:`TRIANGLE` with ``corners`` (3, 3), one per row.
    """
    if kind == TRIANGLE:
        best = 0
        value = corners[0, 0] * dx + corners[0, 1] * dy + corners[0, 2] * dz
        for k in range(1, 3):
            other = corners[k, 0] * dx + corners[k, 1] * dy + corners[k, 2] * dz
            if other > value:
                best, value = k, other
        return corners[best, 0], corners[best, 1], corners[best, 2]
    # The direction in the shape's frame.
    lx = rotation[0, 0] * dx + rotation[1, 0] * dy + rotation[2, 0] * dz
    ly = rotation[0, 1] * dx + rotation[1, 1] * dy + rotation[2, 1] * dz
    lz = rotation[0, 2] * dx + rotation[1, 2] * dy + rotation[2, 2] * dz
    if kind == BOX:
        px = half[0] if lx >= 0.0 else -half[0]
        py = half[1] if ly >= 0.0 else -half[1]
        pz = half[2] if lz >= 0.0 else -half[2]
    elif kind == CYLINDER:
        radial = math.sqrt(lx * lx + ly * ly)
        if radial > 1e-300:
            px, py = half[0] * lx / radial, half[0] * ly / radial
        else:
            px, py = 0.0, 0.0
        pz = half[1] if lz >= 0.0 else -half[1]
    else:
        length = math.sqrt(lx * lx + ly * ly + lz * lz)
        if length > 1e-300:
            px, py, pz = half[0] * lx / length, half[0] * ly / length, half[0] * lz / length
        else:
            px, py, pz = half[0], 0.0, 0.0
    return (centre[0] + rotation[0, 0] * px + rotation[0, 1] * py + rotation[0, 2] * pz,
            centre[1] + rotation[1, 0] * px + rotation[1, 1] * py + rotation[1, 2] * pz,
            centre[2] + rotation[2, 0] * px + rotation[2, 1] * py + rotation[2, 2] * pz)


@kernel('UniTuple(f8, 3)(f8, f8, f8, f8, f8, f8)')
def _cross(ax, ay, az, bx, by, bz):
    return ay * bz - az * by, az * bx - ax * bz, ax * by - ay * bx


@kernel('UniTuple(f8, 3)(i8, f8[:], f8[:, :])')
def _middle(kind, centre, corners):
    """Return a point inside the shape: its centre, a triangle's centroid."""
    if kind != TRIANGLE:
        return centre[0], centre[1], centre[2]
    return ((corners[0, 0] + corners[1, 0] + corners[2, 0]) / 3.0,
            (corners[0, 1] + corners[1, 1] + corners[2, 1]) / 3.0,
            (corners[0, 2] + corners[1, 2] + corners[2, 2]) / 3.0)


@kernel('b1(i8, f8[:], f8[:, :], f8[:], f8[:, :], i8, f8[:], f8[:, :], f8[:], f8[:, :])')
def touching(kind_a, half_a, rotation_a, centre_a, corners_a, kind_b, half_b, rotation_b,
             centre_b, corners_b):
    """
    Whether two convex shapes share a point (each as in :func:`support`).

    GJK on the Minkowski difference A - B: the simplex (newest point last) is reduced to the
    feature nearest the origin at each iteration, and the next direction points from it to
    the origin; a support point that does not pass the origin proves the shapes apart.
    """
    points = np.empty((4, 3))
    # Start along the line between the shapes' middles.
    ax, ay, az = _middle(kind_a, centre_a, corners_a)
    bx, by, bz = _middle(kind_b, centre_b, corners_b)
    dx, dy, dz = bx - ax, by - ay, bz - az
    if dx * dx + dy * dy + dz * dz < _TINY:
        dx, dy, dz = 1.0, 0.0, 0.0
    count = 0
    for _ in range(MAX_ITERATIONS):
        sa = support(kind_a, half_a, rotation_a, centre_a, corners_a, dx, dy, dz)
        sb = support(kind_b, half_b, rotation_b, centre_b, corners_b, -dx, -dy, -dz)
        px, py, pz = sa[0] - sb[0], sa[1] - sb[1], sa[2] - sb[2]
        if px * dx + py * dy + pz * dz < 0.0:
            return False  # the support point does not reach the origin: a separating plane
        points[count, 0], points[count, 1], points[count, 2] = px, py, pz
        count += 1
        # Reduce the simplex to the feature nearest the origin; new direction towards it.
        while True:
            a0, a1, a2 = points[count - 1, 0], points[count - 1, 1], points[count - 1, 2]
            o0, o1, o2 = -a0, -a1, -a2
            if count == 1:
                dx, dy, dz = o0, o1, o2
                break
            if count == 2:
                b0, b1, b2 = points[0, 0] - a0, points[0, 1] - a1, points[0, 2] - a2
                if b0 * o0 + b1 * o1 + b2 * o2 > 0.0:
                    c = _cross(b0, b1, b2, o0, o1, o2)
                    dx, dy, dz = _cross(c[0], c[1], c[2], b0, b1, b2)
                else:
                    points[0] = points[1]
                    count = 1
                    dx, dy, dz = o0, o1, o2
                break
            if count == 3:
                b0, b1, b2 = points[1, 0] - a0, points[1, 1] - a1, points[1, 2] - a2
                c0, c1, c2 = points[0, 0] - a0, points[0, 1] - a1, points[0, 2] - a2
                n0, n1, n2 = _cross(b0, b1, b2, c0, c1, c2)  # ab x ac
                e = _cross(n0, n1, n2, c0, c1, c2)  # abc x ac: out of the edge ac
                if e[0] * o0 + e[1] * o1 + e[2] * o2 > 0.0:
                    if c0 * o0 + c1 * o1 + c2 * o2 > 0.0:
                        # Edge ac: keep c (points[0]) and a.
                        points[1] = points[2]
                        count = 2
                        t = _cross(c0, c1, c2, o0, o1, o2)
                        dx, dy, dz = _cross(t[0], t[1], t[2], c0, c1, c2)
                        break
                    # Towards ab or a alone: drop c and go on as a segment.
                    points[0] = points[1]
                    points[1] = points[2]
                    count = 2
                    continue
                e = _cross(b0, b1, b2, n0, n1, n2)  # ab x abc: out of the edge ab
                if e[0] * o0 + e[1] * o1 + e[2] * o2 > 0.0:
                    points[0] = points[1]
                    points[1] = points[2]
                    count = 2
                    continue
                side = n0 * o0 + n1 * o1 + n2 * o2
                if side > 0.0:
                    dx, dy, dz = n0, n1, n2
                elif side < 0.0:
                    # The other side: swap b and c so the next point makes a tetrahedron
                    # wound the same way.
                    for j in range(3):
                        points[0, j], points[1, j] = points[1, j], points[0, j]
                    dx, dy, dz = -n0, -n1, -n2
                else:
                    return True  # the origin lies in the triangle's plane, inside it
                break
            # A tetrahedron: a and the triangle (points 0, 1, 2) before it.
            inside = True
            for face in range(3):
                # Faces through a: (a, p, q) with r the vertex left out.
                p = face
                q = (face + 1) % 3
                r = (face + 2) % 3
                p0, p1, p2 = points[p, 0] - a0, points[p, 1] - a1, points[p, 2] - a2
                q0, q1, q2 = points[q, 0] - a0, points[q, 1] - a1, points[q, 2] - a2
                r0, r1, r2 = points[r, 0] - a0, points[r, 1] - a1, points[r, 2] - a2
                n0, n1, n2 = _cross(p0, p1, p2, q0, q1, q2)
                if n0 * r0 + n1 * r1 + n2 * r2 > 0.0:
                    n0, n1, n2 = -n0, -n1, -n2
                if n0 * o0 + n1 * o1 + n2 * o2 > 0.0:
                    # Outside this face: go on with its triangle (a newest).
                    keep_p, keep_q = points[p].copy(), points[q].copy()
                    points[0] = keep_q
                    points[1] = keep_p
                    points[2, 0], points[2, 1], points[2, 2] = a0, a1, a2
                    count = 3
                    inside = False
                    break
            if inside:
                return True
        if dx * dx + dy * dy + dz * dz < _TINY:
            return True  # the origin lies on the simplex
    return True
