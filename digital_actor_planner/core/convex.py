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
Contact tests of convex shapes, compiled: whether two shapes touch.

The upper-body planner's contact tests (see :mod:`.ct_space`): a conservative separating axis
test of the oriented boxes holding two shapes (:func:`boxes_apart`, :func:`box_triangle_apart`),
then the exact test (:func:`touching`) of the pairs it cannot part (:func:`touches_shape`,
:func:`touches_triangle`). The shapes are those of the
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

#: Shape kinds, as in ``collision.KIND_CODES``, and a triangle.
BOX, CYLINDER, SPHERE, TRIANGLE = 0, 1, 2, 3
#: Iterations after which GJK gives up and reports a contact.
MAX_ITERATIONS = 64
#: Gap, m, beyond which the separating axis test of oriented boxes lets a pair that the boxes
#: along the world axes could not tell apart skip the exact test: far more than its
#: tolerances, so a pair it skips is one the exact test would find apart (the same plans,
#: fewer exact tests).
SAT_MARGIN = 1e-3
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


@kernel('UniTuple(f8, 3)(f8[:, :], f8[:, :], i8)')
def _column_dots(rotation_a, rotation_b, i):
    """Column i of A's rotation dotted with each column of B's."""
    return ((rotation_a[0, i] * rotation_b[0, 0] + rotation_a[1, i] * rotation_b[1, 0]
             + rotation_a[2, i] * rotation_b[2, 0]),
            (rotation_a[0, i] * rotation_b[0, 1] + rotation_a[1, i] * rotation_b[1, 1]
             + rotation_a[2, i] * rotation_b[2, 1]),
            (rotation_a[0, i] * rotation_b[0, 2] + rotation_a[1, i] * rotation_b[1, 2]
             + rotation_a[2, i] * rotation_b[2, 2]))


@kernel('b1(f8[:, :], f8[:], f8[:], f8[:, :], f8[:], f8[:], f8)')
def boxes_apart(rotation_a, centre_a, half_a, rotation_b, centre_b, half_b, margin):
    """
    Return whether two oriented boxes are more than ``margin`` apart (separating axes).

    Whether two oriented boxes are more than ``margin`` apart along one of the 15 axes of the
    separating axis test (box axes are the rotations' columns, half extents in them).

    True only for boxes that do not touch: a conservative test, never True for boxes whose
    gap is less than ``margin`` (m). Near-parallel edge axes are skipped (their face axes
    decide).
    """
    # The centre offset and the axes of B in A's frame, as tuples (no arrays to allocate:
    # this runs for every pair of boxes that meet).
    dx, dy, dz = (centre_b[0] - centre_a[0], centre_b[1] - centre_a[1],
                  centre_b[2] - centre_a[2])
    offset = (dx * rotation_a[0, 0] + dy * rotation_a[1, 0] + dz * rotation_a[2, 0],
              dx * rotation_a[0, 1] + dy * rotation_a[1, 1] + dz * rotation_a[2, 1],
              dx * rotation_a[0, 2] + dy * rotation_a[1, 2] + dz * rotation_a[2, 2])
    turn = (_column_dots(rotation_a, rotation_b, 0), _column_dots(rotation_a, rotation_b, 1),
            _column_dots(rotation_a, rotation_b, 2))
    size = ((abs(turn[0][0]), abs(turn[0][1]), abs(turn[0][2])),
            (abs(turn[1][0]), abs(turn[1][1]), abs(turn[1][2])),
            (abs(turn[2][0]), abs(turn[2][1]), abs(turn[2][2])))
    for i in range(3):  # A's axes
        reach = (half_a[i] + half_b[0] * size[i][0] + half_b[1] * size[i][1]
                 + half_b[2] * size[i][2])
        if abs(offset[i]) > reach + margin:
            return True
    for j in range(3):  # B's axes
        reach = (half_b[j] + half_a[0] * size[0][j] + half_a[1] * size[1][j]
                 + half_a[2] * size[2][j])
        distance = offset[0] * turn[0][j] + offset[1] * turn[1][j] + offset[2] * turn[2][j]
        if abs(distance) > reach + margin:
            return True
    for i in range(3):  # A's axis i x B's axis j, in A's frame
        i1, i2 = (i + 1) % 3, (i + 2) % 3
        for j in range(3):
            j1, j2 = (j + 1) % 3, (j + 2) % 3
            length = np.sqrt(max(1.0 - size[i][j] * size[i][j], 0.0))
            if length < 1e-6:
                continue
            reach = (half_a[i1] * size[i2][j] + half_a[i2] * size[i1][j]
                     + half_b[j1] * size[i][j2] + half_b[j2] * size[i][j1])
            distance = offset[i2] * turn[i1][j] - offset[i1] * turn[i2][j]
            if abs(distance) > reach + margin * length:
                return True
    return False


@kernel('b1(f8, f8, f8, f8, f8, f8, f8, f8, f8, f8, f8, f8, f8[:], f8)')
def _triangle_apart_along(x, y, z, a0, a1, a2, b0, b1, b2, d0, d1, d2, half, margin):
    """
    Return whether a box and a triangle are more than ``margin`` apart along one axis.

    Whether a box (half extents ``half``, centred at the origin of its frame) and a triangle
    (corners a, b, d in that frame) are more than ``margin`` apart along the axis (x, y, z), which
    need not be a unit vector (a near-zero one parts nothing).
    """
    length = np.sqrt(x * x + y * y + z * z)
    if length < 1e-12:
        return False
    reach = half[0] * abs(x) + half[1] * abs(y) + half[2] * abs(z)
    p0 = a0 * x + a1 * y + a2 * z
    p1 = b0 * x + b1 * y + b2 * z
    p2 = d0 * x + d1 * y + d2 * z
    return (min(p0, p1, p2) > reach + margin * length
            or max(p0, p1, p2) < -reach - margin * length)


@kernel('b1(f8[:, :], f8[:], f8[:], f8[:, :], f8)')
def box_triangle_apart(rotation, centre, half, corners, margin):
    """
    Return whether an oriented box and a triangle are more than ``margin`` apart.

    Whether an oriented box and a triangle (corners (3, 3), m) are more than ``margin`` apart along
    one of the 13 axes of the separating axis test (a conservative test, as in
    :func:`boxes_apart`). Scalars only: it runs for every box and triangle that meet.
    """
    # The corners in the box's frame: a, b, d.
    x, y, z = corners[0, 0] - centre[0], corners[0, 1] - centre[1], corners[0, 2] - centre[2]
    a0 = x * rotation[0, 0] + y * rotation[1, 0] + z * rotation[2, 0]
    a1 = x * rotation[0, 1] + y * rotation[1, 1] + z * rotation[2, 1]
    a2 = x * rotation[0, 2] + y * rotation[1, 2] + z * rotation[2, 2]
    x, y, z = corners[1, 0] - centre[0], corners[1, 1] - centre[1], corners[1, 2] - centre[2]
    b0 = x * rotation[0, 0] + y * rotation[1, 0] + z * rotation[2, 0]
    b1 = x * rotation[0, 1] + y * rotation[1, 1] + z * rotation[2, 1]
    b2 = x * rotation[0, 2] + y * rotation[1, 2] + z * rotation[2, 2]
    x, y, z = corners[2, 0] - centre[0], corners[2, 1] - centre[1], corners[2, 2] - centre[2]
    d0 = x * rotation[0, 0] + y * rotation[1, 0] + z * rotation[2, 0]
    d1 = x * rotation[0, 1] + y * rotation[1, 1] + z * rotation[2, 1]
    d2 = x * rotation[0, 2] + y * rotation[1, 2] + z * rotation[2, 2]
    # The box's axes.
    if (min(a0, b0, d0) > half[0] + margin or max(a0, b0, d0) < -half[0] - margin
            or min(a1, b1, d1) > half[1] + margin or max(a1, b1, d1) < -half[1] - margin
            or min(a2, b2, d2) > half[2] + margin or max(a2, b2, d2) < -half[2] - margin):
        return True
    # The edges a -> b, b -> d, d -> a.
    e0, e1, e2 = b0 - a0, b1 - a1, b2 - a2
    f0, f1, f2 = d0 - b0, d1 - b1, d2 - b2
    g0, g1, g2 = a0 - d0, a1 - d1, a2 - d2
    # The triangle's normal, then each box axis crossed with each edge.
    return (_triangle_apart_along(e1 * f2 - e2 * f1, e2 * f0 - e0 * f2, e0 * f1 - e1 * f0,
                                  a0, a1, a2, b0, b1, b2, d0, d1, d2, half, margin)
            or _triangle_apart_along(0.0, -e2, e1, a0, a1, a2, b0, b1, b2, d0, d1, d2, half,
                                     margin)
            or _triangle_apart_along(0.0, -f2, f1, a0, a1, a2, b0, b1, b2, d0, d1, d2, half,
                                     margin)
            or _triangle_apart_along(0.0, -g2, g1, a0, a1, a2, b0, b1, b2, d0, d1, d2, half,
                                     margin)
            or _triangle_apart_along(e2, 0.0, -e0, a0, a1, a2, b0, b1, b2, d0, d1, d2, half,
                                     margin)
            or _triangle_apart_along(f2, 0.0, -f0, a0, a1, a2, b0, b1, b2, d0, d1, d2, half,
                                     margin)
            or _triangle_apart_along(g2, 0.0, -g0, a0, a1, a2, b0, b1, b2, d0, d1, d2, half,
                                     margin)
            or _triangle_apart_along(-e1, e0, 0.0, a0, a1, a2, b0, b1, b2, d0, d1, d2, half,
                                     margin)
            or _triangle_apart_along(-f1, f0, 0.0, a0, a1, a2, b0, b1, b2, d0, d1, d2, half,
                                     margin)
            or _triangle_apart_along(-g1, g0, 0.0, a0, a1, a2, b0, b1, b2, d0, d1, d2, half,
                                     margin))


@kernel('b1(i8, f8[:], f8[:], f8[:, :], f8[:], f8[:, :], f8)')
def touches_triangle(kind, half, box_half, rotation, centre, corners, margin):
    """
    Return whether a shape touches a triangle (``corners`` (3, 3)).

    Whether a shape (kind code, padded ``half`` extents, its box's ``box_half``, posed at
    ``rotation``, ``centre``) touches a triangle (``corners`` (3, 3)): the separating axis test of
    the box holding the shape (``margin`` apart), then the exact test.
    """
    # A shape's corners are not read: the triangle's stand in for them.
    return (not box_triangle_apart(rotation, centre, box_half, corners, margin)
            and touching(kind, half, rotation, centre, corners, TRIANGLE, half, rotation,
                         centre, corners))


@kernel('b1(i8, f8[:], f8[:], f8[:, :], f8[:], i8, f8[:], f8[:], f8[:, :], f8[:], f8)')
def touches_shape(kind_a, half_a, box_a, rotation_a, centre_a, kind_b, half_b, box_b,
                  rotation_b, centre_b, margin):
    """
    Return whether two shapes (as in :func:`touches_triangle`) touch.

    Whether two shapes (as in :func:`touches_triangle`) touch: the separating axis test of their
    boxes, then the exact test.
    """
    # A shape's corners are not read: its rotation stands in for them.
    return (not boxes_apart(rotation_a, centre_a, box_a, rotation_b, centre_b, box_b, margin)
            and touching(kind_a, half_a, rotation_a, centre_a, rotation_a, kind_b, half_b,
                         rotation_b, centre_b, rotation_b))
