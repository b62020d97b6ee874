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
The 22-DOF actor model read from the URDF: joint order, limits, segment lengths, kinematics.

This is the one place the joint names come from (paper §3.1, Figure 1). Forward kinematics is
one compiled kernel (:func:`_compose`, see ``jit``), batched over configurations, because it sits
on every planner's hot path.
"""
from __future__ import annotations

from dataclasses import dataclass
import math
import os
import sys
from typing import Dict, Optional, Tuple
import xml.etree.ElementTree as ElementTree

import numpy as np

from .jit import kernel

URDF_FILE_NAME = 'digital_actor.urdf'
PACKAGE_NAME = 'digital_actor_planner'


class UrdfError(ValueError):
    """The URDF cannot describe the paper's actor (missing joint, bad number, wrong count)."""


def default_urdf_path() -> str:
    """
    Return the path of the package's actor URDF, in a source tree or an install.

    The environment variable ``DIGITAL_ACTOR_URDF`` overrides the search.
    """
    override = os.environ.get('DIGITAL_ACTOR_URDF')
    if override:
        return override
    here = os.path.dirname(os.path.abspath(__file__))
    candidates = [os.path.join(here, '..', '..', 'urdf', URDF_FILE_NAME),
                  os.path.join(sys.prefix, 'share', PACKAGE_NAME, 'urdf', URDF_FILE_NAME)]
    # colcon install: <prefix>/lib/pythonX.Y/site-packages/<pkg>/core/skeleton.py
    prefix = here
    for _ in range(6):
        prefix = os.path.dirname(prefix)
        candidates.append(os.path.join(prefix, 'share', PACKAGE_NAME, 'urdf', URDF_FILE_NAME))
    for path in candidates:
        if os.path.isfile(path):
            return os.path.normpath(path)
    raise FileNotFoundError(f'{URDF_FILE_NAME} not found; looked in: {", ".join(candidates[:3])}')


# The paper's kinematic model (§3.1): the names the URDF must provide, in canonical order.
ROOT_JOINTS = ('root_x', 'root_y', 'root_z', 'root_yaw')
WAIST_JOINTS = ('waist_yaw', 'waist_pitch')
ARM_SUFFIXES = ('shoulder_pitch', 'shoulder_roll', 'shoulder_yaw', 'elbow')
LEG_SUFFIXES = ('hip_yaw', 'hip_pitch', 'knee', 'ankle')
SIDES = ('left', 'right')


def _expected_joint_names() -> Tuple[str, ...]:
    names = list(ROOT_JOINTS) + list(WAIST_JOINTS)
    for side in SIDES:
        names += [f'{side}_{suffix}' for suffix in ARM_SUFFIXES]
    for side in SIDES:
        names += [f'{side}_{suffix}' for suffix in LEG_SUFFIXES]
    return tuple(names)


EXPECTED_JOINT_NAMES = _expected_joint_names()


@dataclass(frozen=True)
class Joint:
    """One URDF joint. ``origin`` is (4, 4) parent->joint frame; ``axis`` is a unit (3,)."""

    name: str
    kind: str
    parent: str
    child: str
    origin: np.ndarray
    axis: np.ndarray
    lower: float
    upper: float
    velocity: float


@dataclass(frozen=True)
class CollisionShape:
    """
    A collision primitive of a link.

    ``kind`` is 'box' (size = (3,) edge lengths), 'cylinder' (size = (radius, length), axis z)
    or 'sphere' (size = (radius,)); ``origin`` is (4, 4) link->shape frame. Metres.
    """

    link: str
    kind: str
    size: Tuple[float, ...]
    origin: np.ndarray


@dataclass(frozen=True)
class LegGeometry:
    """Sagittal-plane leg dimensions (paper §4: legs projected to the sagittal plane), metres."""

    hip_half_width: float
    thigh: float
    shank: float
    ankle_height: float
    heel: float
    toe: float
    foot_width: float
    # Radii of the thigh's and the shank's collision cylinders (0 where the URDF gives none).
    thigh_radius: float = 0.0
    shank_radius: float = 0.0

    @property
    def max_reach(self) -> float:
        """Largest hip-to-ankle distance (straight knee)."""
        return self.thigh + self.shank

    @property
    def standing_height(self) -> float:
        """Hip joint height above the sole with straight legs."""
        return self.thigh + self.shank + self.ankle_height


def _floats(text: Optional[str], count: int, what: str) -> np.ndarray:
    values = np.array([float(v) for v in (text or ' '.join(['0'] * count)).split()])
    if values.shape != (count,) or not np.all(np.isfinite(values)):
        raise UrdfError(f'{what}: expected {count} finite numbers, got {text!r}')
    return values


def _rpy_matrix(rpy: np.ndarray) -> np.ndarray:
    roll, pitch, yaw = rpy
    cr, sr, cp, sp, cy, sy = (np.cos(roll), np.sin(roll), np.cos(pitch), np.sin(pitch),
                              np.cos(yaw), np.sin(yaw))
    return np.array([[cy * cp, cy * sp * sr - sy * cr, cy * sp * cr + sy * sr],
                     [sy * cp, sy * sp * sr + cy * cr, sy * sp * cr - cy * sr],
                     [-sp, cp * sr, cp * cr]])


def _origin_matrix(element) -> np.ndarray:
    transform = np.eye(4)
    if element is not None:
        transform[:3, :3] = _rpy_matrix(_floats(element.get('rpy'), 3, 'origin rpy'))
        transform[:3, 3] = _floats(element.get('xyz'), 3, 'origin xyz')
    return transform


def _compile_plan(plan) -> tuple:
    """
    Constant matrices of a kinematic chain plan for :meth:`Skeleton.forward_kinematics`.

    ``plan``: (parent, child, origin (4, 4), q index or -1, kind, axis (3,)) per joint, parents
    first. Every joint's local transform origin @ motion(q) is A + w1 B + w2 C with (w1, w2) =
    (cos q, sin q) for a revolute joint, (q, 0) prismatic and (0, 0) fixed.
    """
    basis = np.zeros((len(plan), 3, 4, 4))
    # Each joint's motion (0 fixed, 1 revolute, 2 prismatic) and its q index.
    motion = np.zeros(len(plan), dtype=np.int64)
    joint_q = np.zeros(len(plan), dtype=np.int64)
    for j, (_, _, origin, qi, kind, axis) in enumerate(plan):
        basis[j, 0] = origin
        if qi < 0:
            continue
        joint_q[j] = qi
        if kind == 'prismatic':
            shift = np.zeros((4, 4))
            shift[:3, 3] = axis
            basis[j, 1] = origin @ shift
            motion[j] = 2
            continue
        # Rodrigues: R(q) = (I + K^2) - cos(q) K^2 + sin(q) K.
        x, y, z = axis
        skew = np.zeros((4, 4))
        skew[:3, :3] = [[0.0, -z, y], [z, 0.0, -x], [-y, x, 0.0]]
        square = skew @ skew
        basis[j, 0] = origin @ (np.eye(4) + square)
        basis[j, 1] = -(origin @ square)
        basis[j, 2] = origin @ skew
        motion[j] = 1
    return (np.array([e[0] for e in plan], dtype=np.int64).reshape(len(plan)),
            np.array([e[1] for e in plan], dtype=np.int64).reshape(len(plan)),
            basis.reshape(len(plan), 3, 16), motion, joint_q)


@kernel('void(f8[:, ::1], i8[::1], i8[::1], f8[:, :, ::1], i8[::1], i8[::1], '
        'f8[:, :, :, ::1])')
def _compose(qs, parents, children, basis, motion, joint_q, out):
    """
    Compose a compiled chain for configurations into link transforms.

    Compose a compiled chain (see :func:`_compile_plan`) for configurations ``qs`` (k, 22) into
    ``out`` (k, L, 4, 4), whose link row 0 is the root (set to the identity here).

    Per frame, each joint's local transform A + w1 B + w2 C is composed onto its parent link's;
    ``motion``: 0 fixed, 1 revolute, 2 prismatic, with the joint's index ``joint_q`` into a
    configuration. Every transform is rigid (bottom row 0 0 0 1), so only the top three rows
    are composed.
    """
    local = np.empty((3, 4))
    for f in range(qs.shape[0]):
        out[f, 0] = 0.0
        for d in range(4):
            out[f, 0, d, d] = 1.0
        for j in range(parents.shape[0]):
            w1, w2 = 0.0, 0.0
            if motion[j] == 1:
                w1, w2 = math.cos(qs[f, joint_q[j]]), math.sin(qs[f, joint_q[j]])
            elif motion[j] == 2:
                w1 = qs[f, joint_q[j]]
            for e in range(12):
                local[e // 4, e % 4] = basis[j, 0, e] + w1 * basis[j, 1, e] + w2 * basis[j, 2, e]
            a, child = parents[j], children[j]
            for r in range(3):
                for c in range(3):
                    out[f, child, r, c] = (out[f, a, r, 0] * local[0, c]
                                           + out[f, a, r, 1] * local[1, c]
                                           + out[f, a, r, 2] * local[2, c])
                out[f, child, r, 3] = (out[f, a, r, 0] * local[0, 3]
                                       + out[f, a, r, 1] * local[1, 3]
                                       + out[f, a, r, 2] * local[2, 3] + out[f, a, r, 3])
            out[f, child, 3, 0] = out[f, child, 3, 1] = out[f, child, 3, 2] = 0.0
            out[f, child, 3, 3] = 1.0


@kernel('f8[:, :, :, ::1](f8[:, ::1], i8[::1], i8[::1], f8[:, :, ::1], i8[::1], i8[::1], '
        'i8[::1], f8[:, :, ::1])')
def _shape_transforms(qs, parents, children, basis, motion, joint_q, rows, origins):
    """
    Compute shape->world transforms of a compact chain.

    Shape->world transforms (k, S, 4, 4) of a compact chain (see
    :meth:`Skeleton.shape_transforms_at`): :func:`_compose`, then each shape's origin
    ``origins[i]`` composed onto its link's row ``rows[i]`` (rigid, top three rows).
    """
    k, count = qs.shape[0], rows.shape[0]
    link = np.empty((k, parents.shape[0] + 1, 4, 4))
    _compose(qs, parents, children, basis, motion, joint_q, link)
    out = np.zeros((k, count, 4, 4))
    for f in range(k):
        for s in range(count):
            a = rows[s]
            for r in range(3):
                for c in range(3):
                    out[f, s, r, c] = (link[f, a, r, 0] * origins[s, 0, c]
                                       + link[f, a, r, 1] * origins[s, 1, c]
                                       + link[f, a, r, 2] * origins[s, 2, c])
                out[f, s, r, 3] = (link[f, a, r, 0] * origins[s, 0, 3]
                                   + link[f, a, r, 1] * origins[s, 1, 3]
                                   + link[f, a, r, 2] * origins[s, 2, 3] + link[f, a, r, 3])
            out[f, s, 3, 3] = 1.0
    return out


class Skeleton:
    """
    The actor's kinematic tree, joint order and limits, read from a URDF.

    Parameters
    ----------
    urdf_path
        URDF file; defaults to the package's ``urdf/digital_actor.urdf``.

    """

    def __init__(self, urdf_path: Optional[str] = None):
        self.urdf_path = urdf_path or default_urdf_path()
        try:
            root = ElementTree.parse(self.urdf_path).getroot()
        except (OSError, ElementTree.ParseError) as error:
            raise UrdfError(f'{self.urdf_path}: cannot read URDF: {error}') from error
        self._read(root)

    # -- reading -------------------------------------------------------------------------
    def _read(self, root) -> None:
        joints = []
        for element in root.findall('joint'):
            kind = element.get('type')
            limit = element.find('limit')
            lower, upper, velocity = -np.inf, np.inf, np.inf
            if limit is not None:
                lower = float(limit.get('lower', '-inf'))
                upper = float(limit.get('upper', 'inf'))
                velocity = float(limit.get('velocity', 'inf'))
            axis_element = element.find('axis')
            axis = _floats(axis_element.get('xyz') if axis_element is not None else '1 0 0', 3,
                           f'joint {element.get("name")} axis')
            norm = np.linalg.norm(axis)
            if kind != 'fixed' and norm == 0.0:
                raise UrdfError(f'joint {element.get("name")}: zero axis')
            joints.append(Joint(name=element.get('name'), kind=kind,
                                parent=element.find('parent').get('link'),
                                child=element.find('child').get('link'),
                                origin=_origin_matrix(element.find('origin')),
                                axis=axis / (norm or 1.0), lower=lower, upper=upper,
                                velocity=velocity))
        movable = [j for j in joints if j.kind != 'fixed']
        names = tuple(j.name for j in movable)
        if len(names) != 22:
            raise UrdfError(f'{self.urdf_path}: expected 22 non-fixed joints, found {len(names)}')
        if set(names) != set(EXPECTED_JOINT_NAMES):
            missing = sorted(set(EXPECTED_JOINT_NAMES) - set(names))
            extra = sorted(set(names) - set(EXPECTED_JOINT_NAMES))
            raise UrdfError(f'{self.urdf_path}: joint names differ: missing {missing}, '
                            f'unexpected {extra}')
        for j in movable:
            if j.kind not in ('revolute', 'prismatic', 'continuous'):
                raise UrdfError(f'joint {j.name}: unsupported type {j.kind!r}')
            if j.kind != 'continuous' and not (np.isfinite(j.lower) and np.isfinite(j.upper)
                                               and j.lower < j.upper):
                raise UrdfError(f'joint {j.name}: bad limits [{j.lower}, {j.upper}]')
            if not (np.isfinite(j.velocity) and j.velocity > 0):
                raise UrdfError(f'joint {j.name}: bad velocity limit {j.velocity}')

        #: The 22 joint names in URDF order; the order of every configuration vector.
        self.joint_names: Tuple[str, ...] = names
        self.index: Dict[str, int] = {name: i for i, name in enumerate(names)}
        self.lower = np.array([j.lower for j in movable])
        self.upper = np.array([j.upper for j in movable])
        self.velocity_limit = np.array([j.velocity for j in movable])
        self.joints: Tuple[Joint, ...] = tuple(joints)

        # Topological order from the root link.
        children: Dict[str, list] = {}
        child_links = set()
        for j in joints:
            children.setdefault(j.parent, []).append(j)
            child_links.add(j.child)
        roots = [j.parent for j in joints if j.parent not in child_links]
        if len(set(roots)) != 1:
            raise UrdfError(
                f'{self.urdf_path}: expected one root link, found {sorted(set(roots))}')
        self.root_link = roots[0]
        order, stack = [], [self.root_link]
        while stack:
            parent = stack.pop()
            for j in children.get(parent, []):
                order.append(j)
                stack.append(j.child)
        self._chain = tuple(order)
        self.link_names: Tuple[str, ...] = (self.root_link,) + tuple(j.child for j in order)
        self.link_index = {name: i for i, name in enumerate(self.link_names)}
        self._partial_plans = {}
        # Link index and origin of each shape, per tuple of shape indices (None: all shapes).
        self._shape_layouts = {}
        # Compact chain, link rows and origins per tuple of shape indices (shape_transforms_at).
        self._shape_chains = {}
        self._branches = {}
        self._chain_plan = tuple(
            (self.link_index[j.parent], self.link_index[j.child], j.origin,
             self.index.get(j.name, -1), j.kind, j.axis) for j in order)
        self._chain_compiled = _compile_plan(self._chain_plan)

        shapes = []
        for link in root.findall('link'):
            for collision in link.findall('collision'):
                geometry = collision.find('geometry')
                shape = self._shape(link.get('name'), geometry,
                                    _origin_matrix(collision.find('origin')))
                if shape is not None:
                    shapes.append(shape)
        self.collision_shapes: Tuple[CollisionShape, ...] = tuple(shapes)
        self.leg = self._leg_geometry()

    @staticmethod
    def _shape(link: str, geometry, origin: np.ndarray) -> Optional[CollisionShape]:
        if geometry is None:
            return None
        for element in geometry:
            if element.tag == 'box':
                return CollisionShape(link, 'box', tuple(
                    _floats(element.get('size'), 3, 'box')), origin)
            if element.tag == 'cylinder':
                return CollisionShape(link, 'cylinder', (float(element.get('radius')),
                                                         float(element.get('length'))), origin)
            if element.tag == 'sphere':
                return CollisionShape(link, 'sphere', (float(element.get('radius')),), origin)
        return None

    def _joint(self, name: str) -> Joint:
        for j in self.joints:
            if j.name == name:
                return j
        raise UrdfError(f'{self.urdf_path}: no joint {name!r}')

    def _leg_geometry(self) -> LegGeometry:
        hip = self._joint('left_hip_yaw').origin[:3, 3]
        knee = self._joint('left_knee').origin[:3, 3]
        ankle = self._joint('left_ankle').origin[:3, 3]
        feet = [s for s in self.collision_shapes if s.link == 'left_foot' and s.kind == 'box']
        if not feet:
            raise UrdfError(f'{self.urdf_path}: left_foot needs a box collision shape (the sole)')
        foot = feet[0]
        length, width, height = foot.size
        centre = foot.origin[:3, 3]

        def radius(link):
            return max((float(s.size[0]) for s in self.collision_shapes
                        if s.link == link and s.kind == 'cylinder'), default=0.0)

        return LegGeometry(hip_half_width=float(abs(hip[1])), thigh=float(np.linalg.norm(knee)),
                           shank=float(np.linalg.norm(ankle)),
                           ankle_height=float(-(centre[2] - height / 2)),
                           heel=float(length / 2 - centre[0]), toe=float(length / 2 + centre[0]),
                           foot_width=float(width), thigh_radius=radius('left_thigh'),
                           shank_radius=radius('left_shank'))

    # -- configurations ------------------------------------------------------------------
    def indices(self, *names: str) -> np.ndarray:
        """Return the configuration-vector indices of the named joints."""
        try:
            return np.array([self.index[n] for n in names], dtype=int)
        except KeyError as error:
            raise ValueError(f'unknown joint name {error.args[0]!r}') from None

    def branch(self, name: str) -> np.ndarray:
        """
        Return the indices of a branch of Figure 2.

        ``name`` is 'root', 'waist', 'left_arm', 'right_arm', 'left_leg' or 'right_leg'.
        """
        # Built once per name (the motion patterns ask for them every step); a copy each time
        # so a caller may change its own.
        cached = self._branches.get(name)
        if cached is None:
            cached = self._branch(name)
            self._branches[name] = cached
        return cached.copy()

    def _branch(self, name: str) -> np.ndarray:
        if name == 'root':
            return self.indices(*ROOT_JOINTS)
        if name == 'waist':
            return self.indices(*WAIST_JOINTS)
        side, _, part = name.partition('_')
        if side in SIDES and part == 'arm':
            return self.indices(*(f'{side}_{s}' for s in ARM_SUFFIXES))
        if side in SIDES and part == 'leg':
            return self.indices(*(f'{side}_{s}' for s in LEG_SUFFIXES))
        raise ValueError(f'unknown branch {name!r}')

    def neutral(self) -> np.ndarray:
        """Return a standing configuration at the origin: (22,) float64, rad or m."""
        q = np.zeros(len(self.joint_names))
        q[self.index['root_z']] = self.leg.standing_height
        for side in SIDES:
            q[self.index[f'{side}_shoulder_roll']] = 0.06
        return np.clip(q, self.lower, self.upper)

    def within_limits(self, q: np.ndarray, tolerance: float = 1e-9) -> np.ndarray:
        """Return whether each configuration respects the position limits: (k,) bool."""
        q = np.atleast_2d(q)
        return np.all((q >= self.lower - tolerance) & (q <= self.upper + tolerance), axis=-1)

    # -- kinematics ----------------------------------------------------------------------
    def _plan_for(self, links):
        """Return the compiled chain needed to place ``links`` (cached per link set)."""
        key = frozenset(links)
        compiled = self._partial_plans.get(key)
        if compiled is None:
            needed = set()
            for link in key:
                if link not in self.link_index:
                    raise ValueError(f'unknown link {link!r}')
                while link != self.root_link and link not in needed:
                    needed.add(link)
                    link = next(j.parent for j in self._chain if j.child == link)
            compiled = _compile_plan(tuple(entry for entry, joint
                                           in zip(self._chain_plan, self._chain)
                                           if joint.child in needed))
            self._partial_plans[key] = compiled
        return compiled

    def forward_kinematics(self, q: np.ndarray, links=None) -> np.ndarray:
        """
        World transforms of every link.

        Parameters
        ----------
        q
            (22,) or (k, 22) configurations, rad or m.
        links
            Optional link names: only these links (and their ancestors) are computed; the
            other entries of the result are left unset.

        Returns
        -------
        numpy.ndarray
            (L, 4, 4) or (k, L, 4, 4) link->world transforms, in ``link_names`` order.

        """
        q = np.asarray(q, dtype=float)
        single = q.ndim == 1
        qs = np.atleast_2d(q)
        if qs.shape[-1] != len(self.joint_names):
            raise ValueError(f'configuration has {qs.shape[-1]} values, expected '
                             f'{len(self.joint_names)}')
        shape = (qs.shape[0], len(self.link_names), 4, 4)
        out = np.empty(shape) if links is None else np.zeros(shape)
        chain = self._chain_compiled if links is None else self._plan_for(links)
        _compose(np.array(qs, dtype=np.float64, order='C'), *chain, out)
        return out[0] if single else out

    def shape_transforms_at(self, q: np.ndarray, shapes) -> np.ndarray:
        """
        World transforms of some collision shapes straight from configurations.

        The same as ``shape_transforms(forward_kinematics(q, links), shapes)`` for the shapes'
        links, but only the links the shapes hang from (and their ancestors) are composed,
        in a compact array.

        Parameters
        ----------
        q
            (k, 22) configurations, rad or m.
        shapes
            Indices into ``collision_shapes``.

        Returns
        -------
        numpy.ndarray
            (k, S, 4, 4) shape->world transforms, in ``shapes`` order (C-contiguous).

        """
        key = tuple(int(i) for i in shapes)
        layout = self._shape_chains.get(key)
        if layout is None:
            chain = self._plan_for({self.collision_shapes[i].link for i in key})
            # Compact rows: 0 the root link (identity), then each joint's child in plan order.
            row = {0: 0}
            for child in chain[1].tolist():
                row[child] = len(row)
            parents, children, basis, motion, joint_q = chain
            layout = (np.array([row[p] for p in parents.tolist()], dtype=np.int64),
                      np.array([row[c] for c in children.tolist()], dtype=np.int64),
                      basis, motion, joint_q,
                      np.array([row[self.link_index[self.collision_shapes[i].link]]
                                for i in key], dtype=np.int64),
                      np.ascontiguousarray(np.stack([self.collision_shapes[i].origin
                                                     for i in key])))
            self._shape_chains[key] = layout
        qs = np.asarray(q, dtype=float)
        if qs.ndim != 2 or qs.shape[1] != len(self.joint_names):
            raise ValueError(f'configurations must have shape (k, {len(self.joint_names)}), '
                             f'got {qs.shape}')
        return _shape_transforms(np.array(qs, dtype=np.float64, order='C'), *layout)

    def link_transform(self, q: np.ndarray, link: str) -> np.ndarray:
        """World transform(s) of one link: (4, 4) or (k, 4, 4)."""
        return self.forward_kinematics(q)[..., self.link_index[link], :, :]

    def shape_transforms(self, link_transforms: np.ndarray, shapes=None) -> np.ndarray:
        """
        World transforms of every collision shape, in ``collision_shapes`` order.

        Parameters
        ----------
        link_transforms
            (L, 4, 4) or (k, L, 4, 4) from :meth:`forward_kinematics`.
        shapes
            Optional indices into ``collision_shapes``: only those shapes, in that order.

        Returns
        -------
        numpy.ndarray
            (S, 4, 4) or (k, S, 4, 4).

        """
        key = None if shapes is None else tuple(int(i) for i in shapes)
        layout = self._shape_layouts.get(key)
        if layout is None:
            chosen = (self.collision_shapes if shapes is None
                      else [self.collision_shapes[i] for i in shapes])
            layout = (np.array([self.link_index[s.link] for s in chosen], dtype=int),
                      np.stack([s.origin for s in chosen]))
            self._shape_layouts[key] = layout
        links, origins = layout
        return link_transforms[..., links, :, :] @ origins
