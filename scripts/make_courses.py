#!/usr/bin/env python3

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
Write the shipped courses: config/scenes/<course>.yaml, <course>.csv and meshes/.

The courses are committed; this script is how they were made and how to change them. It is
deterministic (seeded terrain, fixed number formats), so re-running it reproduces the files.
Run: python3 scripts/make_courses.py [--out config/scenes]

Each course is a YAML scene (meshes in the world frame, z up, metres; the ground is one of the
meshes), a velocity command CSV (``time,linear_x,angular_z``; each row holds until the next; the
last row, all zeros, ends the run) and an ``expect`` mapping the tests read:

``reach_x`` / ``reach_y``
    the pelvis (root_x / root_y) gets at least this far by the end of the run, m.
``final_yaw``, ``yaw_tolerance``
    root_yaw at the end of the run, rad.
``stuck``, ``stop_before_x``
    the planner reports stuck and root_x stays below ``stop_before_x`` (m) with no contact.
``trap_x``
    [x0, x1] of the Figure 8 pit (a one-step window steps in there or is stuck).
``obstacle_x``, ``deviation``
    [x0, x1] where the upper body must leave its motion pattern, and the joint that has to.
"""
import argparse
import math
import os

import numpy as np
import trimesh
import yaml

HERE = os.path.dirname(os.path.abspath(__file__))
DEFAULT_OUT = os.path.join(HERE, '..', 'config', 'scenes')

SLAB_BOTTOM = -0.2      # floor slabs are 0.2 m thick with their top at z = 0
WALK_SPEED = 0.8        # m/s, commanded walking speed on every course
FLOOR_HALF_WIDTH = 2.0  # m, floor extent either side of a straight path
# Underside of the low beams above the ground, m: the standing head (top 1.75 m) hits it, a
# waist bent forward 0.6 rad clears it by 2 cm (waist joint 1.02 m, head centre 0.62 m above
# it, radius 0.11 m); the least bend that passes is 0.55 rad.
LOW_BEAM_UNDERSIDE = 1.66


# -- mesh builders -----------------------------------------------------------------------
def box(x0, x1, y0, y1, z0, z1):
    """Return a watertight axis-aligned box spanning the given world intervals (m)."""
    mesh = trimesh.creation.box(extents=[x1 - x0, y1 - y0, z1 - z0])
    mesh.apply_translation([(x0 + x1) / 2, (y0 + y1) / 2, (z0 + z1) / 2])
    return mesh


def slab(x0, x1, y0=-FLOOR_HALF_WIDTH, y1=FLOOR_HALF_WIDTH, top=0.0, bottom=None):
    """Return a floor slab with its top at ``top`` (m)."""
    return box(x0, x1, y0, y1, top - 0.2 if bottom is None else bottom, top)


def merge(*meshes):
    """Concatenate watertight parts into one mesh (each part stays a closed shell)."""
    return trimesh.util.concatenate(list(meshes))


def profile_solid(points, y0, y1, bottom):
    """
    Return a closed solid whose top follows a profile z(x), extruded across y.

    Parameters
    ----------
    points
        (p, 2) polyline of (x, z) along the top, m; x non-decreasing, and two points with the
        same x make a vertical riser (stairs, ditch walls). The first and last x appear once.
    y0, y1
        extent across the path, m.
    bottom
        z of the flat underside, m; below every profile point.

    """
    points = np.asarray(points, dtype=float)
    xs = points[:, 0]
    if np.any(np.diff(xs) < 0) or np.any(points[:, 1] <= bottom):
        raise ValueError(f'profile must have non-decreasing x above z = {bottom}: {points}')
    vertices, faces = [], []

    def vertex(x, y, z):
        vertices.append((x, y, z))
        return len(vertices) - 1

    # One vertex per profile point and per distinct x at the bottom, on each side.
    columns = np.unique(xs)
    top = {side: [vertex(x, y, z) for x, z in points] for side, y in ((0, y0), (1, y1))}
    low = {side: {x: vertex(x, y, bottom) for x in columns} for side, y in ((0, y0), (1, y1))}
    for k in range(len(points) - 1):
        # Top strip (treads, slopes and risers alike), normal up or towards -x/+x.
        a0, b0, a1, b1 = top[0][k], top[0][k + 1], top[1][k], top[1][k + 1]
        faces += [[a0, b0, b1], [a0, b1, a1]]
    for xa, xb in zip(columns[:-1], columns[1:]):
        za = points[np.flatnonzero(xs == xa)[-1], 1]   # top leaving xa
        zb = points[np.flatnonzero(xs == xb)[0], 1]    # top arriving at xb
        for side, y in ((0, y0), (1, y1)):
            # Side wall of this column, boundary counter-clockwise seen from -y; every profile
            # point on its vertical edges is included so neighbouring columns share edges.
            right = [top[side][k] for k in np.flatnonzero(xs == xb) if points[k, 1] < zb]
            right = sorted(right, key=lambda v: vertices[v][2])
            left = [top[side][k] for k in np.flatnonzero(xs == xa) if points[k, 1] < za]
            left = sorted(left, key=lambda v: -vertices[v][2])
            ring = ([low[side][xa], low[side][xb]] + right
                    + [top[side][np.flatnonzero(xs == xb)[0]],
                       top[side][np.flatnonzero(xs == xa)[-1]]] + left)
            centre = vertex((xa + xb) / 2, y, (bottom + min(za, zb)) / 2)
            for u, v in zip(ring, ring[1:] + ring[:1]):
                faces.append([centre, u, v])
        faces += [[low[0][xa], low[1][xb], low[0][xb]], [low[0][xa], low[1][xa], low[1][xb]]]
    first, last = 0, len(points) - 1
    faces += [[low[0][xs[0]], top[0][first], top[1][first]],
              [low[0][xs[0]], top[1][first], low[1][xs[0]]]]
    faces += [[low[0][xs[-1]], top[1][last], top[0][last]],
              [low[0][xs[-1]], low[1][xs[-1]], top[1][last]]]
    mesh = trimesh.Trimesh(np.array(vertices), np.array(faces), process=True)
    mesh.fix_normals()
    if not mesh.is_watertight:
        raise ValueError('profile solid is not watertight')
    return mesh


def heightfield_solid(xs, ys, heights, bottom):
    """
    Return a closed solid whose top is the height grid and whose underside is flat.

    Parameters
    ----------
    xs, ys
        (nx,), (ny,) increasing grid coordinates, m.
    heights
        (nx, ny) surface heights, m.
    bottom
        z of the flat underside, m.

    """
    nx, ny = len(xs), len(ys)
    gx, gy = np.meshgrid(xs, ys, indexing='ij')
    top = np.column_stack([gx.ravel(), gy.ravel(), np.asarray(heights).ravel()])
    index = np.arange(nx * ny).reshape(nx, ny)
    a, b = index[:-1, :-1].ravel(), index[1:, :-1].ravel()
    c, d = index[1:, 1:].ravel(), index[:-1, 1:].ravel()
    faces = [np.column_stack([a, b, c]), np.column_stack([a, c, d])]
    # Border ring of the top grid, counter-clockwise seen from above.
    ring = np.concatenate([index[:, 0], index[-1, 1:], index[-2::-1, -1], index[0, -2:0:-1]])
    n_top = nx * ny
    under = top[ring].copy()
    under[:, 2] = bottom
    centre = np.array([[(xs[0] + xs[-1]) / 2, (ys[0] + ys[-1]) / 2, bottom]])
    vertices = np.concatenate([top, under, centre])
    m = len(ring)
    k = np.arange(m)
    k1 = (k + 1) % m
    faces.append(np.column_stack([ring[k], n_top + k, n_top + k1]))          # sides
    faces.append(np.column_stack([ring[k], n_top + k1, ring[k1]]))
    faces.append(np.column_stack([np.full(m, n_top + m), n_top + k1, n_top + k]))  # bottom
    mesh = trimesh.Trimesh(vertices, np.concatenate(faces), process=True)
    mesh.fix_normals()
    return mesh


def smoothstep(edge0, edge1, x):
    """Return the C1 ramp from 0 at ``edge0`` to 1 at ``edge1``."""
    t = np.clip((x - edge0) / (edge1 - edge0), 0.0, 1.0)
    return t * t * (3.0 - 2.0 * t)


def bumps(xs, ys, amplitude, seed, x_flat_until, x_flat_from):
    """
    Smooth random heights: a sum of plane waves of 1.2-3 m wavelength, seeded.

    Returns
    -------
    numpy.ndarray
        (nx, ny) heights within +-``amplitude`` m, zero before ``x_flat_until`` - 1 m and
        after ``x_flat_from`` + 1 m, blended in between.

    """
    rng = np.random.default_rng(seed)
    gx, gy = np.meshgrid(xs, ys, indexing='ij')
    heights = np.zeros_like(gx)
    for _ in range(12):
        wavelength = rng.uniform(1.2, 3.0)
        direction = rng.uniform(0.0, 2.0 * math.pi)
        phase = rng.uniform(0.0, 2.0 * math.pi)
        along = gx * math.cos(direction) + gy * math.sin(direction)
        heights += rng.uniform(0.5, 1.0) * np.sin(2.0 * math.pi * along / wavelength + phase)
    window = (smoothstep(x_flat_until - 1.0, x_flat_until, gx)
              * (1.0 - smoothstep(x_flat_from, x_flat_from + 1.0, gx)))
    heights *= window
    return heights * (amplitude / np.max(np.abs(heights)))


def beam_with_posts(underside, depth=0.15, height=0.15, half_span=1.5, post=0.12):
    """Return a beam across y (centred on x = 0) held by two posts far to the sides."""
    top = underside + height
    # The posts reach into the beam rather than touching it, so no two parts share a vertex
    # (each part stays a closed shell after a loader merges duplicate vertices).
    return merge(box(-depth / 2, depth / 2, -half_span, half_span, underside, top),
                 box(-post / 2, post / 2, -half_span - post, -half_span + post / 2, 0.0,
                     top - 0.02),
                 box(-post / 2, post / 2, half_span - post / 2, half_span + post, 0.0,
                     top - 0.02))


# -- courses -----------------------------------------------------------------------------
def straight(duration, speed=WALK_SPEED):
    """Commands: walk straight at ``speed`` m/s for ``duration`` s, then stop."""
    return [(0.0, speed, 0.0), (duration, 0.0, 0.0)]


def course_flat():
    return {
        'description': '10 m straight on a flat floor.',
        'meshes': [('floor', 'stl', slab(-2.0, 16.0), None)],
        'start': [0.0, 0.0, 0.0], 'expect': {'reach_x': 9.0}, 'commands': straight(14.0)}


def course_slope():
    rise = 0.6
    run = rise / math.tan(math.radians(12.0))
    x_up, plateau = 1.5, 2.0
    xs = [-2.0, x_up, x_up + run, x_up + run + plateau, x_up + 2 * run + plateau, 16.0]
    points = list(zip(xs, [0.0, 0.0, rise, rise, 0.0, 0.0]))
    return {
        'description': (f'Flat, a 12 degree ramp up ({run:.2f} m long) to a {rise} m plateau '
                        f'({plateau} m long), a 12 degree ramp down, flat again.'),
        'meshes': [('ground', 'obj', profile_solid(points, -FLOOR_HALF_WIDTH, FLOOR_HALF_WIDTH,
                                                   SLAB_BOTTOM), None)],
        'start': [0.0, 0.0, 0.0], 'expect': {'reach_x': 9.0}, 'commands': straight(15.0)}


def stair_profile(x_first, heights, tread, floor_x0, floor_top, end_x, end_top):
    """Return the (x, z) top polyline of a floor, treads of the given heights and a landing."""
    points = [(floor_x0, floor_top), (x_first, floor_top)]
    x = x_first
    for height in list(heights) + [end_top]:
        points += [(x, height), (x + tread, height)]
        x += tread
    points[-1] = (end_x, end_top)
    return points


def course_stairs_up():
    rise, tread = 0.15, 0.30
    ground = profile_solid(stair_profile(1.5, [rise * k for k in range(1, 5)], tread, -2.0, 0.0,
                                         11.0, 5 * rise), -FLOOR_HALF_WIDTH, FLOOR_HALF_WIDTH,
                           SLAB_BOTTOM)
    return {
        'description': (f'Five steps up (rise {rise} m, tread {tread} m) from x = 1.5 m to a '
                        f'landing {5 * rise:.2f} m high from x = 2.7 m.'),
        'meshes': [('ground', 'ply', ground, None)],
        'start': [0.0, 0.0, 0.0], 'expect': {'reach_x': 4.0}, 'commands': straight(10.0)}


def course_stairs_down():
    rise, tread = 0.15, 0.30
    ground = profile_solid(stair_profile(1.5, [rise * k for k in range(4, 0, -1)], tread, -2.0,
                                         5 * rise, 11.0, 0.0), -FLOOR_HALF_WIDTH,
                           FLOOR_HALF_WIDTH, SLAB_BOTTOM)
    return {
        'description': (f'Start on a landing {5 * rise:.2f} m high; five steps down (rise {rise} '
                        f'm, tread {tread} m) from x = 1.5 m to the floor from x = 2.7 m.'),
        'meshes': [('ground', 'glb', ground, None)],
        'start': [0.0, 0.0, 0.0], 'expect': {'reach_x': 5.0}, 'commands': straight(10.0)}


def course_gap():
    x0, width, depth = 3.0, 0.45, 1.0
    ground = profile_solid([(-2.0, 0.0), (x0, 0.0), (x0, -depth), (x0 + width, -depth),
                            (x0 + width, 0.0), (13.0, 0.0)], -FLOOR_HALF_WIDTH,
                           FLOOR_HALF_WIDTH, -depth - 0.2)
    return {
        'description': (f'A ditch {width} m wide and {depth} m deep across the path at '
                        f'x = {x0} m; the actor strides over it.'),
        'meshes': [('ground', 'stl', ground, None)],
        'start': [0.0, 0.0, 0.0], 'expect': {'reach_x': 5.5}, 'commands': straight(10.0)}


def course_figure8_trap():
    # 0.5 m: a pit a sole can be placed before, toes over its edge, and stridden over from
    # there only if that foothold is chosen ahead (0.35 m, stridden over from any toe-over-edge
    # foothold, let a one-step window past it from some start positions).
    height, pit_x0, pit_length = 0.33, 2.0, 0.5
    half = 0.6
    walkway = merge(box(-2.0, pit_x0, -half, half, -0.1, height),
                    box(pit_x0 + pit_length, 11.0, -half, half, -0.1, height))
    return {
        'description': ('Paper Figure 8: a walkway 0.33 m high with a pit 0.5 m long down to the '
                        'ground at x = 2.0 m. Stepping down into it is allowed (<= 0.35 m), '
                        'climbing out is not (> 0.30 m): a one-step window gets stuck, n = 3 '
                        'strides over.'),
        'meshes': [('ground', 'stl', slab(-2.0, 11.0), None),
                   ('walkway', 'obj', walkway, None)],
        'start': [0.0, 0.0, 0.0],
        'expect': {'reach_x': 5.0, 'trap_x': [pit_x0, pit_x0 + pit_length]},
        'commands': straight(10.0)}


def course_blocks():
    half = 0.6
    blocks = merge(box(1.5, 2.3, -half, half, -0.1, 0.10),
                   box(3.3, 4.2, -half, half, -0.1, 0.20),
                   box(5.2, 6.2, -half, half, -0.1, 0.28))
    return {
        'description': ('Blocks 0.10 m (x 1.5-2.3), 0.20 m (x 3.3-4.2) and 0.28 m (x 5.2-6.2) '
                        'high with floor between: step onto and off each.'),
        'meshes': [('floor', 'glb', slab(-2.0, 15.0), None),
                   ('blocks', 'ply', blocks, None)],
        'start': [0.0, 0.0, 0.0], 'expect': {'reach_x': 7.0}, 'commands': straight(14.0)}


def course_rough():
    xs = np.arange(-2.0, 14.0 + 1e-9, 0.05)
    ys = np.arange(-1.5, 1.5 + 1e-9, 0.05)
    heights = bumps(xs, ys, 0.04, seed=8, x_flat_until=1.0, x_flat_from=9.0)
    return {
        'description': ('Seeded random terrain, bumps within +-4 cm and smooth on the scale of a '
                        'foot (1.2-3 m wavelengths), from x = 1 m to x = 9 m; flat around it.'),
        'meshes': [('terrain', 'ply', heightfield_solid(xs, ys, heights, SLAB_BOTTOM), None)],
        'start': [0.0, 0.0, 0.0], 'expect': {'reach_x': 7.0}, 'commands': straight(14.0)}


def course_turn():
    rate = 0.5
    turn_start = 4.0
    turn_end = turn_start + (math.pi / 2) / rate
    return {
        'description': ('Walk 4 s straight along +x, turn 90 degrees left on an arc '
                        f'({rate} rad/s for {turn_end - turn_start:.2f} s), walk on along +y.'),
        'meshes': [('floor', 'glb', slab(-2.0, 9.0, -4.0, 10.0), None)],
        'start': [0.0, 0.0, 0.0],
        'expect': {'reach_y': 2.5, 'final_yaw': round(math.pi / 2, 4), 'yaw_tolerance': 0.35},
        'commands': [(0.0, WALK_SPEED, 0.0), (turn_start, WALK_SPEED, rate),
                     (round(turn_end, 4), WALK_SPEED, 0.0), (11.0, 0.0, 0.0)]}


def course_wall():
    wall_x = 3.0
    # The wall is built along x and turned onto the path by its pose (exercises yaw poses).
    wall = box(-3.0, 3.0, 0.0, 0.2, 0.0, 2.0)
    return {
        'description': f'A 2 m high wall across the path at x = {wall_x} m: infeasible.',
        'meshes': [('floor', 'stl', slab(-2.0, 6.0), None),
                   ('wall', 'obj', wall, [wall_x + 0.2, 0.0, 0.0, 0.0, 0.0, math.pi / 2])],
        'start': [0.0, 0.0, 0.0],
        'expect': {'stuck': True, 'stop_before_x': wall_x - 0.1},
        'commands': straight(8.0)}


def course_low_beam():
    beam_x, underside = 3.0, LOW_BEAM_UNDERSIDE
    return {
        'description': (f'A beam across the path at x = {beam_x} m, underside {underside} m: the '
                        'standing head hits it; bending the waist forward about 0.6 rad passes '
                        'under (0.55 rad at least, standing height).'),
        'meshes': [('floor', 'stl', slab(-2.0, 12.0), None),
                   ('beam', 'glb', beam_with_posts(underside), [beam_x, 0.0, 0.0, 0.0, 0.0, 0.0])],
        'start': [0.0, 0.0, 0.0],
        'expect': {'reach_x': 5.5, 'obstacle_x': [beam_x - 0.8, beam_x + 0.3],
                   'deviation': 'waist_pitch'},
        'commands': straight(10.0)}


def course_beam_too_low():
    beam_x, underside = 3.0, 1.05
    return {
        'description': (f'A beam across the path at x = {beam_x} m, underside {underside} m: no '
                        'bend gets under it; the actor stops cleanly before it.'),
        'meshes': [('floor', 'stl', slab(-2.0, 8.0), None),
                   ('beam', 'ply', beam_with_posts(underside), [beam_x, 0.0, 0.0, 0.0, 0.0, 0.0])],
        'start': [0.0, 0.0, 0.0],
        'expect': {'stuck': True, 'stop_before_x': beam_x - 0.1},
        'commands': straight(8.0)}


def table_with_objects():
    """Return the table and the things on it, in the table frame (near edge on y = 0)."""
    length, depth, top = 1.6, 0.7, 0.78
    leg = 0.05
    table = merge(box(0.0, length, 0.0, depth, top - 0.04, top),
                  box(0.05, 0.05 + leg, 0.05, 0.05 + leg, 0.0, top - 0.04),
                  box(length - 0.05 - leg, length - 0.05, 0.05, 0.05 + leg, 0.0, top - 0.04),
                  box(0.05, 0.05 + leg, depth - 0.05 - leg, depth - 0.05, 0.0, top - 0.04),
                  box(length - 0.05 - leg, length - 0.05, depth - 0.05 - leg, depth - 0.05,
                      0.0, top - 0.04))
    jar = trimesh.creation.cylinder(radius=0.05, height=0.10, sections=24)
    jar.apply_translation([0.85, 0.08, top + 0.05])
    bottle = trimesh.creation.cylinder(radius=0.04, height=0.28, sections=24)
    bottle.apply_translation([0.6, 0.45, top + 0.14])
    ball = trimesh.creation.icosphere(subdivisions=2, radius=0.07)
    ball.apply_translation([1.2, 0.40, top + 0.07])
    objects = merge(box(0.20, 0.55, 0.01, 0.16, top, top + 0.08),     # books at the edge
                    jar,
                    box(1.05, 1.45, 0.02, 0.26, top, top + 0.025),    # a closed laptop
                    bottle, ball)
    return table, objects


def course_table():
    table_x0, edge_y = 2.0, 0.20
    table, objects = table_with_objects()
    pose = [table_x0, edge_y, 0.0, 0.0, 0.0, 0.0]
    return {
        'description': (f'A table (top 0.78 m) on the left of the path from x = {table_x0} m, '
                        f'near edge at y = {edge_y} m, under the hanging left hand; books and a '
                        "jar at the edge are in the swinging arm's way: the left arm must leave "
                        'its swing (a flexed elbow clears them).'),
        'meshes': [('floor', 'stl', slab(-2.0, 11.0), None),
                   ('table', 'obj', table, pose),
                   ('objects', 'glb', objects, pose)],
        'start': [0.0, 0.0, 0.0],
        'expect': {'reach_x': 5.0, 'obstacle_x': [table_x0 - 0.4, table_x0 + 1.6 + 0.4],
                   'deviation': 'left_elbow'},
        'commands': straight(9.0)}


def course_pillars():
    pillar_x, half_gap, radius = 3.0, 0.25, 0.12
    pillar = trimesh.creation.cylinder(radius=radius, height=2.2, sections=32)
    pillar.apply_translation([0.0, 0.0, 1.1])
    centre = half_gap + radius
    return {
        'description': (f'Two round pillars at x = {pillar_x} m leaving a {2 * half_gap:.2f} m '
                        'gap, narrower than the shoulders (0.52 m): passable by turning the '
                        'waist.'),
        'meshes': [('floor', 'ply', slab(-2.0, 11.0), None),
                   ('pillar', 'stl', pillar, [pillar_x, centre, 0.0, 0.0, 0.0, 0.0]),
                   ('pillar', 'stl', pillar, [pillar_x, -centre, 0.0, 0.0, 0.0, 0.0])],
        'start': [0.0, 0.0, 0.0],
        'expect': {'reach_x': 5.0, 'obstacle_x': [pillar_x - 0.5, pillar_x + 0.5],
                   'deviation': 'waist_yaw'},
        'commands': straight(9.0)}


def course_uneven_beam():
    xs = np.arange(-2.0, 13.0 + 1e-9, 0.05)
    ys = np.arange(-1.5, 1.5 + 1e-9, 0.05)
    heights = bumps(xs, ys, 0.03, seed=9, x_flat_until=1.0, x_flat_from=7.0)
    platform_top, beam_x = 0.12, 3.6
    platform = box(2.6, 4.6, -0.8, 0.8, -0.2, platform_top)
    underside = platform_top + LOW_BEAM_UNDERSIDE
    return {
        'description': ('Bumpy ground (+-3 cm) with a platform 0.12 m high from x = 2.6 m to '
                        f'4.6 m and a beam over it at x = {beam_x} m, underside {underside:.2f} m '
                        f'({LOW_BEAM_UNDERSIDE} m above the platform): step up, bend under, step '
                        'down.'),
        'meshes': [('terrain', 'ply', heightfield_solid(xs, ys, heights, SLAB_BOTTOM), None),
                   ('platform', 'obj', platform, None),
                   ('beam', 'glb', beam_with_posts(underside), [beam_x, 0.0, 0.0, 0.0, 0.0, 0.0])],
        'start': [0.0, 0.0, 0.0],
        'expect': {'reach_x': 6.5, 'obstacle_x': [beam_x - 0.8, beam_x + 0.3],
                   'deviation': 'waist_pitch'},
        'commands': straight(12.0)}


COURSES = {
    'flat': course_flat, 'slope': course_slope, 'stairs_up': course_stairs_up,
    'stairs_down': course_stairs_down, 'gap': course_gap,
    'figure8_trap': course_figure8_trap, 'blocks': course_blocks, 'rough': course_rough,
    'turn': course_turn, 'wall': course_wall, 'low_beam': course_low_beam,
    'beam_too_low': course_beam_too_low, 'table': course_table, 'pillars': course_pillars,
    'uneven_beam': course_uneven_beam,
}


# -- writing -----------------------------------------------------------------------------
def _export(mesh, path, file_type):
    data = mesh.export(file_type=file_type)
    if isinstance(data, str):
        data = data.encode()
    with open(path, 'wb') as stream:
        stream.write(data)


def write_course(name, course, out_dir):
    """Write one course's meshes, YAML scene and command CSV under ``out_dir``."""
    mesh_dir = os.path.join(out_dir, 'meshes')
    os.makedirs(mesh_dir, exist_ok=True)
    entries, written = [], set()
    for part, file_type, mesh, pose in course['meshes']:
        relative = f'meshes/{name}_{part}.{file_type}'
        if relative not in written:
            if not mesh.is_watertight:
                raise ValueError(f'{name}/{part}: mesh is not watertight')
            _export(mesh, os.path.join(out_dir, relative), file_type)
            written.add(relative)
        entry = {'file': relative}
        if pose is not None:
            entry['pose'] = [round(float(v), 6) for v in pose]
        entries.append(entry)
    scene = {'description': course['description'], 'meshes': entries,
             'start': [float(v) for v in course['start']], 'expect': course['expect']}
    header = (f'# Course {name!r}; generated by scripts/make_courses.py, edit that script.\n'
              f'# Commands: {name}.csv (time s, linear_x m/s, angular_z rad/s).\n')
    with open(os.path.join(out_dir, f'{name}.yaml'), 'w') as stream:
        stream.write(header)
        yaml.safe_dump(scene, stream, sort_keys=False, default_flow_style=None, width=99)
    with open(os.path.join(out_dir, f'{name}.csv'), 'w') as stream:
        stream.write('time,linear_x,angular_z\n')
        for time, linear, angular in course['commands']:
            stream.write(f'{time:.4f},{linear:.3f},{angular:.4f}\n')


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.strip().splitlines()[0])
    parser.add_argument('--out', default=DEFAULT_OUT, help='output folder (config/scenes)')
    args = parser.parse_args(argv)
    for name, build in COURSES.items():
        write_course(name, build(), args.out)
        print(f'wrote {name}')


if __name__ == '__main__':
    main()
