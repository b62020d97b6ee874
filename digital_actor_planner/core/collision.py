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
Exact collision tests of the actor's URDF collision shapes against the environment.

The paper checks the legs' swing (§4.1), the footsteps (§4.2) and the upper body's branches
(§5) for collisions in 3D. Every check here uses the URDF's own primitives (boxes, cylinders,
spheres) as python-fcl objects against the environment's BVH meshes.
"""
from __future__ import annotations

import math
from typing import Dict, Iterable, List, Optional, Sequence, Tuple

import fcl
import numpy as np

from .environment import top_near
from .jit import float_array, kernel

# Contacts asked of FCL per shape when measuring penetration.
_MAX_CONTACTS = 64


_IDENTITY = (1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0)


# Shape kinds as the compiled kernels know them (their half extents padded to 3 values).
KIND_CODES = {'box': 0, 'cylinder': 1, 'sphere': 2}
# No poses (first_collision with no free end to compare the first frame with).
_NO_POSES = np.zeros((0, 3, 4))


@kernel('f8(i8, f8[::1], f8[:, :], i8)')
def axis_extent(kind, half, rotation, axis):
    """
    Return a turned shape's world axis-aligned half extent along ``axis``, m.

    World axis-aligned half extent along ``axis`` of a shape (kind code, padded half extents)
    turned by ``rotation`` (its top-left 3 x 3 is read), m.
    """
    if kind == 0:
        return (abs(rotation[axis, 0]) * half[0] + abs(rotation[axis, 1]) * half[1]
                + abs(rotation[axis, 2]) * half[2])
    if kind == 1:
        along = abs(rotation[axis, 2])
        return half[0] * math.sqrt(min(max(1.0 - along * along, 0.0), 1.0)) + half[1] * along
    return half[0]


@kernel('f8[:, :, ::1](i8[::1], f8[:, ::1], f8[:, :, :, :])')
def half_extents(kinds, halves, rotations):
    """:func:`axis_extent` of (k, S) rotations for S shapes: (k, S, 3), m."""
    k, count = rotations.shape[0], rotations.shape[1]
    out = np.empty((k, count, 3))
    for f in range(k):
        for c in range(count):
            for axis in range(3):
                out[f, c, axis] = axis_extent(kinds[c], halves[c], rotations[f, c], axis)
    return out


@kernel('b1(f8[:, :], f8[:, :])')
def _unmoved(a, b):
    """Whether two (3+, 4) poses differ by at most 1e-9 in every entry of their top 3 rows."""
    for r in range(3):
        for c in range(4):
            if not abs(a[r, c] - b[r, c]) <= 1e-9:
                return False
    return True


@kernel('Tuple((i8[:, ::1], b1[:, ::1]))(f8[:, :, :, ::1], i8[::1], f8[:, ::1], b1, '
        'f8[::1], i8[::1], i8[::1], i8, u1[::1], i8[::1], i8, i8, i8, f8, f8, f8, '
        'f8[:, :, ::1], b1, f8[::1], f8[:, ::1], f8[:, ::1])')
def _suspects(transforms, kinds, halves, top_bound, pyramid, slot_of, stamp, clock, wanted,
              missed, tiles_x, nx, ny, x0, y0, inverse, free_end, after_free_end, reach,
              mesh_low, mesh_high):
    """
    Return the broad phase of :meth:`BodyCollision.first_collision` in one pass.

    ``transforms``: (k, S, 4, 4) shape poses over a motion. A shape is a suspect at a frame
    unless ``top_bound`` and its lowest point lies above the environment's height bound over
    its footprint (:func:`environment.top_near`, the tiled top map's layout in ``pyramid``
    to ``inverse``; where a tile is not cached yet the shape is a suspect). A suspect that
    has not moved since the frame before, where it was a suspect too (or, with
    ``after_free_end``, at the first frame since ``free_end``, the poses the last motion found
    free) needs no exact test. Returns the (frame, shape column) pairs to
    test in time order and, for each, which meshes' bounds (``mesh_low``, ``mesh_high``) come
    within its ``reach`` of its centre.
    """
    k, count = transforms.shape[0], transforms.shape[1]
    suspect = np.ones((k, count), dtype=np.bool_)
    if top_bound:
        for f in range(k):
            for c in range(count):
                pose = transforms[f, c]
                width = max(axis_extent(kinds[c], halves[c], pose, 0),
                            axis_extent(kinds[c], halves[c], pose, 1))
                bottom = pose[2, 3] - axis_extent(kinds[c], halves[c], pose, 2)
                top = top_near(pyramid, slot_of, stamp, clock, wanted, missed, tiles_x, nx,
                               ny, x0, y0, inverse, pose[0, 3], pose[1, 3], width)
                suspect[f, c] = not bottom > top
    pairs = np.empty((k * count, 2), dtype=np.int64)
    found = 0
    for f in range(k):
        for c in range(count):
            if not suspect[f, c]:
                continue
            if f > 0 and suspect[f - 1, c] and _unmoved(transforms[f, c], transforms[f - 1, c]):
                continue
            if f == 0 and after_free_end and _unmoved(transforms[0, c], free_end[c]):
                continue
            pairs[found, 0], pairs[found, 1] = f, c
            found += 1
    meshes = mesh_low.shape[0]
    near = np.zeros((found, meshes), dtype=np.bool_)
    for p in range(found):
        f, c = pairs[p, 0], pairs[p, 1]
        for m in range(meshes):
            inside = True
            for axis in range(3):
                centre = transforms[f, c, axis, 3]
                if not (mesh_low[m, axis] <= centre + reach[c]
                        and centre - reach[c] <= mesh_high[m, axis]):
                    inside = False
                    break
            near[p, m] = inside
    return pairs[:found].copy(), near


def _matmul(a: Sequence[float], b: Sequence[float]) -> Tuple[float, ...]:
    """Product of two row-major 3x3 matrices held as 9 floats."""
    return (a[0] * b[0] + a[1] * b[3] + a[2] * b[6], a[0] * b[1] + a[1] * b[4] + a[2] * b[7],
            a[0] * b[2] + a[1] * b[5] + a[2] * b[8], a[3] * b[0] + a[4] * b[3] + a[5] * b[6],
            a[3] * b[1] + a[4] * b[4] + a[5] * b[7], a[3] * b[2] + a[4] * b[5] + a[5] * b[8],
            a[6] * b[0] + a[7] * b[3] + a[8] * b[6], a[6] * b[1] + a[7] * b[4] + a[8] * b[7],
            a[6] * b[2] + a[7] * b[5] + a[8] * b[8])


def _apply(r: Sequence[float], v: Sequence[float]) -> Tuple[float, float, float]:
    """Row-major 3x3 matrix (9 floats) times a 3-vector."""
    return (r[0] * v[0] + r[1] * v[1] + r[2] * v[2], r[3] * v[0] + r[4] * v[1] + r[5] * v[2],
            r[6] * v[0] + r[7] * v[1] + r[8] * v[2])


def _rotate_columns(r: Sequence[float], axis: int, angle: float) -> Tuple[float, ...]:
    """``r`` times the rotation by ``angle`` about local principal axis 0, 1 or 2."""
    c, s = math.cos(angle), math.sin(angle)
    i, j = ((1, 2), (2, 0), (0, 1))[axis]
    out = list(r)
    for row in (0, 3, 6):
        a, b = r[row + i], r[row + j]
        out[row + i] = c * a + s * b
        out[row + j] = c * b - s * a
    return tuple(out)


def _quaternion(r: Sequence[float]) -> Tuple[float, float, float, float]:
    """Return the unit quaternion (w, x, y, z) of a rotation matrix as 9 floats, row-major."""
    trace = r[0] + r[4] + r[8]
    if trace > 0.0:
        s = 2.0 * math.sqrt(trace + 1.0)
        return (0.25 * s, (r[7] - r[5]) / s, (r[2] - r[6]) / s, (r[3] - r[1]) / s)
    if r[0] > r[4] and r[0] > r[8]:
        s = 2.0 * math.sqrt(1.0 + r[0] - r[4] - r[8])
        return ((r[7] - r[5]) / s, 0.25 * s, (r[1] + r[3]) / s, (r[2] + r[6]) / s)
    if r[4] > r[8]:
        s = 2.0 * math.sqrt(1.0 + r[4] - r[0] - r[8])
        return ((r[2] - r[6]) / s, (r[1] + r[3]) / s, 0.25 * s, (r[5] + r[7]) / s)
    s = 2.0 * math.sqrt(1.0 + r[8] - r[0] - r[4])
    return ((r[3] - r[1]) / s, (r[2] + r[6]) / s, (r[5] + r[7]) / s, 0.25 * s)


@kernel('f8[:, :, ::1](f8[:, :, :, :])')
def _quaternions(rotation):
    """
    Return :func:`_quaternion` of every rotation of an (m, n, 3, 3) batch: (m, n, 4).

    :func:`_quaternion` of every rotation of an (m, n, 3, 3) batch: (m, n, 4), the same numbers
    (posing an FCL object by quaternion and translation is several times cheaper than by an
    ``fcl.Transform``).
    """
    m, n = rotation.shape[0], rotation.shape[1]
    out = np.empty((m, n, 4))
    for i in range(m):
        for j in range(n):
            r = rotation[i, j]
            trace = r[0, 0] + r[1, 1] + r[2, 2]
            if trace > 0.0:
                s = 2.0 * math.sqrt(trace + 1.0)
                out[i, j, 0], out[i, j, 1] = 0.25 * s, (r[2, 1] - r[1, 2]) / s
                out[i, j, 2], out[i, j, 3] = (r[0, 2] - r[2, 0]) / s, (r[1, 0] - r[0, 1]) / s
            elif r[0, 0] > r[1, 1] and r[0, 0] > r[2, 2]:
                s = 2.0 * math.sqrt(1.0 + r[0, 0] - r[1, 1] - r[2, 2])
                out[i, j, 0], out[i, j, 1] = (r[2, 1] - r[1, 2]) / s, 0.25 * s
                out[i, j, 2], out[i, j, 3] = (r[0, 1] + r[1, 0]) / s, (r[0, 2] + r[2, 0]) / s
            elif r[1, 1] > r[2, 2]:
                s = 2.0 * math.sqrt(1.0 + r[1, 1] - r[0, 0] - r[2, 2])
                out[i, j, 0], out[i, j, 1] = (r[0, 2] - r[2, 0]) / s, (r[0, 1] + r[1, 0]) / s
                out[i, j, 2], out[i, j, 3] = 0.25 * s, (r[1, 2] + r[2, 1]) / s
            else:
                s = 2.0 * math.sqrt(1.0 + r[2, 2] - r[0, 0] - r[1, 1])
                out[i, j, 0], out[i, j, 1] = (r[1, 0] - r[0, 1]) / s, (r[0, 2] + r[2, 0]) / s
                out[i, j, 2], out[i, j, 3] = (r[1, 2] + r[2, 1]) / s, 0.25 * s
    return out


def _rodrigues(axis: Sequence[float], angle: float) -> Tuple[float, ...]:
    """Rotation matrix (9 floats, row-major) about a unit axis."""
    x, y, z = axis
    c, s = math.cos(angle), math.sin(angle)
    t = 1.0 - c
    return (t * x * x + c, t * x * y - s * z, t * x * z + s * y,
            t * x * y + s * z, t * y * y + c, t * y * z - s * x,
            t * x * z - s * y, t * y * z + s * x, t * z * z + c)


def shape_geometry(shape, padding: float = 0.0):
    """
    Return the FCL geometry of one URDF shape grown by ``padding`` m, and its (kind, half extents).

    FCL geometry of one URDF shape grown by ``padding`` (m; negative shrinks it, to no less than a
    micrometre), and its (kind, half extents).
    """
    if shape.kind == 'box':
        size = np.maximum(np.asarray(shape.size, dtype=float) + 2 * padding, 1e-6)
        return fcl.Box(*size), ('box', size / 2)
    if shape.kind == 'cylinder':
        radius = max(shape.size[0] + padding, 1e-6)
        length = max(shape.size[1] + 2 * padding, 1e-6)
        return fcl.Cylinder(radius, length), ('cylinder', np.array([radius, length / 2]))
    if shape.kind == 'sphere':
        radius = max(shape.size[0] + padding, 1e-6)
        return fcl.Sphere(radius), ('sphere', np.array([radius]))
    raise ValueError(f'link {shape.link}: unsupported collision shape {shape.kind!r}')


def shape_reach(half) -> float:
    """
    Return the radius of the sphere about a shape's centre that holds it, m.

    Radius of the sphere about a shape's centre that holds it, from ``shape_geometry``'s (kind,
    half extents), m.
    """
    kind, extent = half
    if kind == 'box':
        return float(np.linalg.norm(extent))
    if kind == 'cylinder':
        return float(math.hypot(*extent))
    return float(extent[0])


class BodyCollision:
    """
    The actor's collision shapes as FCL objects, tested against an environment.

    Parameters
    ----------
    skeleton
        :class:`skeleton.Skeleton`; its ``collision_shapes`` are the body.
    environment
        :class:`environment.Environment`.
    padding
        Safety margin added to every shape (radius, half extents), m; >= 0.
    top_bound
        Let :meth:`first_collision` clear a shape without an exact test when it lies above the
        environment's height bound (:meth:`environment.Environment.top_height`) over its
        footprint, and a shape at the first frame of a motion without an exact test when it
        has not moved from the last frame of the previous motion found free; False: every
        shape at every frame gets an exact test (same answers, slower).

    Notes
    -----
    ``q`` arguments are (22,) configurations in ``skeleton.joint_names`` order, rad or m.
    ``links`` arguments are iterables of link names (links without shapes are ignored);
    ``None`` means every link with a shape.

    """

    def __init__(self, skeleton, environment, padding: float = 0.0, top_bound: bool = True):
        if not (isinstance(padding, (int, float)) and math.isfinite(padding) and padding >= 0):
            raise ValueError(f'padding must be a finite number of metres >= 0, got {padding!r}')
        self.skeleton = skeleton
        self.environment = environment
        self.padding = float(padding)
        self.top_bound = bool(top_bound)
        self.shapes = tuple(skeleton.collision_shapes)
        self._geometries, self._objects, self._half_extent = [], [], []
        for shape in self.shapes:
            geometry, half = shape_geometry(shape, self.padding)
            self._geometries.append(geometry)
            self._objects.append(fcl.CollisionObject(geometry, fcl.Transform()))
            self._half_extent.append(half)
        self._reach = [shape_reach(half) for half in self._half_extent]
        self._mesh_boxes = [(i, tuple(float(v) for v in m.bounds.ravel()))
                            for i, m in enumerate(environment.meshes)]
        self._mesh_low = np.array([m.bounds[0] for m in environment.meshes], dtype=float)
        self._mesh_high = np.array([m.bounds[1] for m in environment.meshes], dtype=float)
        self._reach_array = np.array(self._reach, dtype=float)
        # Each shape's kind code and half extents padded to three values, for the kernels.
        self._kind_codes = np.array([KIND_CODES[kind] for kind, _ in self._half_extent],
                                    dtype=np.int64)
        self._halves = np.zeros((len(self.shapes), 3))
        for i, (_, half) in enumerate(self._half_extent):
            self._halves[i, :len(half)] = half
        # first_collision's shapes per ``links`` argument, with their kind codes, half
        # extents and reaches.
        self._broad_phase_sets: Dict[Optional[tuple], tuple] = {}
        self.link_shapes: Dict[str, Tuple[int, ...]] = {}
        for i, shape in enumerate(self.shapes):
            self.link_shapes[shape.link] = self.link_shapes.get(shape.link, ()) + (i,)
        self.links: Tuple[str, ...] = tuple(self.link_shapes)
        self._prepare_kinematics()
        self._cache_values: Optional[list] = None
        self._cache_links: Dict[str, tuple] = {}
        self._placed: Dict[int, tuple] = {}
        self._request = fcl.CollisionRequest()
        self._contact_request = fcl.CollisionRequest(num_max_contacts=_MAX_CONTACTS,
                                                     enable_contact=True)
        # first_collision's last frame when it found the motion free: (shapes, (S, 3, 4)
        # transforms). The next motion usually starts there (the feet of the next step).
        self._free_end: Optional[tuple] = None

    # -- construction --------------------------------------------------------------------
    def _prepare_kinematics(self) -> None:
        """Joint data as plain floats for a fast single-configuration forward kinematics."""
        skeleton = self.skeleton
        self._joint_of = {}
        for j in skeleton.joints:
            rotation = tuple(float(v) for v in j.origin[:3, :3].ravel())
            if np.allclose(j.origin[:3, :3], np.eye(3), atol=1e-15):
                rotation = None
            principal = int(np.argmax(np.abs(j.axis)))
            if abs(abs(j.axis[principal]) - 1.0) < 1e-12:
                axis_sign = (principal, float(np.sign(j.axis[principal])))
            else:
                axis_sign = None
            offset = (tuple(float(v) for v in j.origin[:3, 3]) if np.any(j.origin[:3, 3])
                      else None)
            self._joint_of[j.child] = (j.parent, rotation, offset,
                                       skeleton.index.get(j.name, -1), j.kind,
                                       tuple(float(v) for v in j.axis), axis_sign)
        self._shape_origin = []
        for shape in self.shapes:
            rotation = tuple(float(v) for v in shape.origin[:3, :3].ravel())
            if np.allclose(shape.origin[:3, :3], np.eye(3), atol=1e-15):
                rotation = None
            self._shape_origin.append((rotation, tuple(float(v) for v in shape.origin[:3, 3])))

    # -- kinematics ----------------------------------------------------------------------
    def _check_q(self, q) -> np.ndarray:
        q = np.asarray(q, dtype=float)
        if q.shape != (len(self.skeleton.joint_names),):
            raise ValueError(f'configuration must have shape ({len(self.skeleton.joint_names)},),'
                             f' got {q.shape}')
        return q

    def _link_pose(self, link: str):
        """World (rotation 9 floats row-major, position 3 floats) of one link, cached per q."""
        pose = self._cache_links.get(link)
        if pose is not None:
            return pose
        joint = self._joint_of.get(link)
        if joint is None:
            pose = (_IDENTITY, (0.0, 0.0, 0.0))
            self._cache_links[link] = pose
            return pose
        parent, rotation0, offset0, qi, kind, axis, axis_sign = joint
        base_rotation, base_position = self._link_pose(parent)
        if offset0 is None:
            position = base_position
        else:
            moved = _apply(base_rotation, offset0)
            position = (base_position[0] + moved[0], base_position[1] + moved[1],
                        base_position[2] + moved[2])
        rotation = base_rotation if rotation0 is None else _matmul(base_rotation, rotation0)
        if qi >= 0:
            value = self._cache_values[qi]
            if kind == 'prismatic':
                step = _apply(rotation, axis)
                position = (position[0] + value * step[0], position[1] + value * step[1],
                            position[2] + value * step[2])
            elif axis_sign is not None:
                rotation = _rotate_columns(rotation, axis_sign[0], axis_sign[1] * value)
            else:
                rotation = _matmul(rotation, _rodrigues(axis, value))
        pose = (rotation, position)
        self._cache_links[link] = pose
        return pose

    def _set_configuration(self, q: np.ndarray) -> None:
        values = q.tolist()
        if values != self._cache_values:
            self._cache_values = values
            self._cache_links = {}
            self._placed = {}

    def _place(self, shape: int):
        """Move one shape's FCL object to its pose at the current configuration."""
        obj = self._objects[shape]
        if shape not in self._placed:
            link_rotation, link_position = self._link_pose(self.shapes[shape].link)
            rotation0, offset0 = self._shape_origin[shape]
            moved = _apply(link_rotation, offset0)
            rotation = (link_rotation if rotation0 is None
                        else _matmul(link_rotation, rotation0))
            position = (link_position[0] + moved[0], link_position[1] + moved[1],
                        link_position[2] + moved[2])
            # Quaternion and translation setters are several times cheaper than fcl.Transform.
            obj.setQuatRotation(np.array(_quaternion(rotation)))
            obj.setTranslation(np.array(position))
            self._placed[shape] = (rotation, position)
        return obj

    def _candidates(self, shape: int) -> List[int]:
        """Return the indices of environment meshes whose bounds overlap the placed shape's box."""
        return self._candidates_near(self._placed[shape][1], self._reach[shape])

    def _candidates_near(self, centre, reach: float) -> List[int]:
        """Return indices of environment meshes with bounds within ``reach`` of ``centre``."""
        x, y, z = centre
        x0, x1, y0, y1, z0, z1 = x - reach, x + reach, y - reach, y + reach, z - reach, z + reach
        return [i for i, (lx, ly, lz, hx, hy, hz) in self._mesh_boxes
                if lx <= x1 and x0 <= hx and ly <= y1 and y0 <= hy and lz <= z1 and z0 <= hz]

    def _shapes_of(self, links: Optional[Iterable[str]]) -> List[Tuple[str, Tuple[int, ...]]]:
        if links is None:
            return list(self.link_shapes.items())
        if isinstance(links, str):
            raise ValueError(f'links must be an iterable of link names, got the string {links!r}')
        out = []
        for link in links:
            if link not in self.skeleton.link_index:
                raise ValueError(f'unknown link {link!r}')
            if link in self.link_shapes:
                out.append((link, self.link_shapes[link]))
        return out

    def shape_poses(self, q) -> List[Tuple[np.ndarray, np.ndarray]]:
        """World (rotation (3, 3), position (3,)) of every collision shape at ``q``, m."""
        q = self._check_q(q)
        self._set_configuration(q)
        out = []
        for i in range(len(self.shapes)):
            self._place(i)
            rotation, position = self._placed[i]
            out.append((np.array(rotation).reshape(3, 3), np.array(position)))
        return out

    # -- queries against the environment -------------------------------------------------
    def _shape_collides(self, shape: int) -> bool:
        obj = self._place(shape)
        targets = self.environment.objects
        for mesh in self._candidates(shape):
            if fcl.collide(obj, targets[mesh], self._request, fcl.CollisionResult()):
                return True
        return False

    def collides(self, q, links: Optional[Iterable[str]] = None) -> bool:
        """Whether any shape of the given links touches the environment (early exit)."""
        q = self._check_q(q)
        self._set_configuration(q)
        for _, shapes in self._shapes_of(links):
            for shape in shapes:
                if self._shape_collides(shape):
                    return True
        return False

    def first_collision(self, frames: np.ndarray,
                        links: Optional[Iterable[str]] = None) -> Tuple[int, List[str]]:
        """
        First frame of a motion at which the given links touch the environment.

        Batched: forward kinematics for all frames at once, a conservative height bound that
        clears the shapes lying above everything near their footprint (``top_bound``), then
        exact FCL tests of the rest in time order. Nothing else clears a shape: reading the
        ground map at a few points of a footprint (the centre and the corners) misses a post
        between them, and a swinging foot can go tens of millimetres into one.

        Parameters
        ----------
        frames
            (k, 22) configurations, rad or m.
        links
            Link names; None = every link with a shape.

        Returns
        -------
        tuple
            (frame index, link names) of the first collision, or (-1, []) when free.

        """
        frames = np.atleast_2d(np.asarray(frames, dtype=float))
        if frames.shape[1:] != (len(self.skeleton.joint_names),):
            raise ValueError(f'frames must have shape (k, {len(self.skeleton.joint_names)}), '
                             f'got {frames.shape}')
        key = None if links is None else tuple(links)
        chosen = self._broad_phase_sets.get(key)
        if chosen is None:
            shapes = tuple(s for _, shapes in self._shapes_of(links) for s in shapes)
            index = np.array(shapes, dtype=np.int64)
            chosen = (shapes, self._kind_codes[index], self._halves[index],
                      self._reach_array[index])
            self._broad_phase_sets[key] = chosen
        chosen, kinds, halves, reach = chosen
        if not chosen or frames.shape[0] == 0:
            return -1, []
        transforms = self.skeleton.shape_transforms_at(frames, chosen)
        # A shape entirely above the environment's height bound over its footprint cannot
        # touch it (most shapes, and a foot resting on level ground); a shape that has not
        # moved since it was last tested or found free needs no other test (a stance foot:
        # the 1e-9 m per frame that counts as unmoved adds up to well under a micrometre over
        # a step). The rest go to FCL, in time order.
        after_free_end = (self.top_bound and self._free_end is not None
                          and self._free_end[0] == chosen)
        pairs, near = _suspects(
            transforms, kinds, halves, self.top_bound, *self.environment.top_near_grid(),
            self._free_end[1] if after_free_end else _NO_POSES, after_free_end, reach,
            self._mesh_low, self._mesh_high)
        hit_frame, hits = -1, []
        if pairs.shape[0]:
            targets = self.environment.objects
            for (j, column), meshes in zip(pairs.tolist(), near.tolist()):
                if hit_frame >= 0 and j != hit_frame:
                    break
                shape = chosen[column]
                obj = self._objects[shape]
                obj.setRotation(transforms[j, column, :3, :3])
                obj.setTranslation(transforms[j, column, :3, 3])
                if any(fcl.collide(obj, targets[m], self._request, fcl.CollisionResult())
                       for m, is_near in enumerate(meshes) if is_near):
                    hit_frame = int(j)
                    hits.append(self.shapes[shape].link)
        # The objects were moved outside the single-configuration cache: forget it.
        self._cache_values = None
        self._placed = {}
        if hit_frame < 0:
            self._free_end = (chosen, transforms[-1, :, :3, :].copy())
        return hit_frame, sorted(set(hits))

    def _aabb_half_extents(self, shapes: Sequence[int], rotations: np.ndarray) -> np.ndarray:
        """World axis-aligned half extents of shapes: rotations (k, S, 3, 3) -> (k, S, 3), m."""
        index = np.asarray(shapes, dtype=np.int64)
        return half_extents(self._kind_codes[index], self._halves[index],
                            float_array(rotations))

    def links_in_collision(self, q, links: Optional[Iterable[str]] = None) -> List[str]:
        """Names of the given links that touch the environment, in ``links`` order."""
        q = self._check_q(q)
        self._set_configuration(q)
        return [link for link, shapes in self._shapes_of(links)
                if any(self._shape_collides(s) for s in shapes)]

    def _support(self, shape: int, direction: np.ndarray) -> float:
        """How far the shape reaches from its centre along a unit ``direction``, m."""
        kind, half = self._half_extent[shape]
        rotation = np.array(self._placed[shape][0]).reshape(3, 3)
        if kind == 'sphere':
            return float(half[0])
        local = rotation.T @ direction
        if kind == 'box':
            return float(np.abs(local) @ half)
        along = min(1.0, abs(float(local[2])))
        return float(half[0] * math.sqrt(max(0.0, 1.0 - along * along)) + half[1] * along)

    def _shape_penetration(self, shape: int) -> float:
        """
        Depth of one placed shape behind the surfaces it touches, m (0.0 if free).

        FCL's own contact depth for a primitive against a single triangle measures how far
        the shape must move to clear that triangle (often sideways off its edge), not how deep
        it is in the solid. So each touched triangle's depth is taken along its outward normal:
        how far the shape reaches behind the triangle's plane. Within one mesh the smallest of
        these is reported (touching a convex edge, the shape reaches far behind the plane of the
        face it only grazes); across meshes the largest. The result is exact for a shape in a
        flat face or a convex solid and a lower bound in a concave corner of one mesh.
        """
        if not self._shape_collides(shape):
            return 0.0
        obj = self._objects[shape]
        centre = np.array(self._placed[shape][1])
        geometry = self._geometries[shape]
        per_mesh: Dict[int, float] = {}
        for mesh in self._candidates(shape):
            result = fcl.CollisionResult()
            fcl.collide(obj, self.environment.objects[mesh], self._contact_request, result)
            for contact in result.contacts:
                triangle = contact.b2 if contact.o1 is geometry else contact.b1
                if triangle < 0:
                    continue
                depth = self._depth_behind(shape, centre, mesh, triangle)
                per_mesh[mesh] = min(per_mesh.get(mesh, math.inf), depth)
        return max(per_mesh.values()) if per_mesh else 0.0

    def _depth_behind(self, shape: int, centre: np.ndarray, mesh: int, triangle: int) -> float:
        """How far a placed shape reaches behind one triangle's plane (along -normal), m."""
        vertices = self.environment.triangle(mesh, triangle)
        normal = np.cross(vertices[1] - vertices[0], vertices[2] - vertices[0])
        length = float(np.linalg.norm(normal))
        if length == 0.0:
            return 0.0
        normal /= length
        return max(0.0, float((vertices[0] - centre) @ normal) + self._support(shape, normal))

    def penetration(self, q, links: Optional[Iterable[str]] = None) -> Dict[str, float]:
        """
        Largest penetration depth of each link's shapes into the environment.

        Returns
        -------
        dict
            {link: depth m}, 0.0 for a link that does not touch the environment. See
            :meth:`_shape_penetration` for how depth is measured.

        """
        q = self._check_q(q)
        self._set_configuration(q)
        out = {}
        for link, shapes in self._shapes_of(links):
            depth = 0.0
            for shape in shapes:
                self._place(shape)
                depth = max(depth, self._shape_penetration(shape))
            out[link] = depth
        return out

    def distance(self, q, links: Optional[Iterable[str]] = None) -> Dict[str, float]:
        """Smallest distance from each link's shapes to the environment, m (0.0 in contact)."""
        q = self._check_q(q)
        self._set_configuration(q)
        request = fcl.DistanceRequest()
        out = {}
        for link, shapes in self._shapes_of(links):
            best = math.inf
            for shape in shapes:
                obj = self._place(shape)
                if self._shape_collides(shape):
                    best = 0.0
                    break
                for target in self.environment.objects:
                    best = min(best, fcl.distance(obj, target, request, fcl.DistanceResult()))
            out[link] = max(0.0, float(best))
        return out

    # -- self collision ------------------------------------------------------------------
    def self_collides(self, q, links_a: Sequence[str], links_b: Sequence[str]) -> bool:
        """
        Whether any shape of a link in ``links_a`` touches any shape of a link in ``links_b``.

        The caller chooses the pairs: links joined by a joint (the upper arm and the forearm,
        the torso and the shoulders) overlap by construction and must not be passed against
        each other.
        """
        q = self._check_q(q)
        self._set_configuration(q)
        shapes_b = [s for _, shapes in self._shapes_of(links_b) for s in shapes]
        if not shapes_b:
            return False
        for _, shapes in self._shapes_of(links_a):
            for a in shapes:
                obj_a = self._place(a)
                for b in shapes_b:
                    if a == b:
                        continue
                    if fcl.collide(obj_a, self._place(b), self._request,
                                   fcl.CollisionResult()):
                        return True
        return False
