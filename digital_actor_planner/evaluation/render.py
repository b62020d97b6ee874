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
Pictures of the actor on a course: key poses as a PNG, an animation as a GIF.

Headless and ROS-free: a small painter's-algorithm renderer on matplotlib's Agg canvas. The
course meshes are clipped to the region around the run, large faces are split into tiles so
that depth sorting works, and meshes with too many faces (scanned or heightfield terrain) are
resampled as a coarser heightfield. The actor is drawn from the URDF's collision shapes
(boxes, cylinders, spheres) placed by forward kinematics, each face shaded by its normal.
"""
from __future__ import annotations

from dataclasses import dataclass
import math
import os
from typing import Optional, Sequence, Tuple

import numpy as np

_LIGHT = np.array([-0.35, -0.55, 0.76])         # world direction towards the light
_TERRAIN_COLOURS = np.array([[0.78, 0.76, 0.70],   # the ground (first mesh)
                             [0.72, 0.52, 0.34],   # wood
                             [0.62, 0.64, 0.72],   # concrete
                             [0.55, 0.70, 0.50],
                             [0.80, 0.62, 0.45],
                             [0.50, 0.60, 0.75]])
_LINK_COLOURS = (('head', (0.87, 0.72, 0.60)), ('forearm', (0.87, 0.72, 0.60)),
                 ('torso', (0.20, 0.45, 0.75)), ('waist', (0.20, 0.45, 0.75)),
                 ('shoulder', (0.20, 0.45, 0.75)), ('upper_arm', (0.20, 0.45, 0.75)),
                 ('foot', (0.45, 0.20, 0.10)))
_DEFAULT_LINK_COLOUR = (0.28, 0.28, 0.34)       # trousers
_FOOTSTEP_COLOUR = (0.95, 0.55, 0.10)
_TILE = 0.25                 # m, largest tile edge the course faces are split into
_FACE_BUDGET = 12000         # faces per course mesh before it is resampled as a heightfield
_ACTOR_BIAS = 0.3            # m of depth-sort bias: the actor stands on the tiles around it
_FOOTSTEP_BIAS = 0.25        # m: footstep marks lie on the tiles around them


@dataclass(frozen=True)
class _Camera:
    """A pinhole camera: ``eye`` (3,) m, orthonormal ``right``, ``up``, ``forward`` (3,)."""

    eye: np.ndarray
    right: np.ndarray
    up: np.ndarray
    forward: np.ndarray

    @classmethod
    def looking_at(cls, target: np.ndarray, azimuth: float, elevation: float,
                   distance: float) -> '_Camera':
        """Place the camera ``distance`` m from ``target`` towards (azimuth, elevation), rad."""
        offset = np.array([math.cos(elevation) * math.cos(azimuth),
                           math.cos(elevation) * math.sin(azimuth), math.sin(elevation)])
        eye = np.asarray(target, dtype=float) + distance * offset
        forward = -offset
        right = np.cross(forward, [0.0, 0.0, 1.0])
        right /= np.linalg.norm(right)
        return cls(eye, right, np.cross(right, forward), forward)

    def project(self, points: np.ndarray) -> Tuple[np.ndarray, np.ndarray]:
        """Return image-plane coordinates (..., 2) and depths (...) of world points (..., 3)."""
        d = points - self.eye
        depth = d @ self.forward
        safe = np.maximum(depth, 1e-6)
        return np.stack([(d @ self.right) / safe, (d @ self.up) / safe], axis=-1), depth


# -- validation ------------------------------------------------------------------------------
def _check_run(skeleton, meshes, times, frames, footsteps):
    times = np.asarray(times, dtype=float)
    frames = np.asarray(frames, dtype=float)
    n_joints = len(skeleton.joint_names)
    if frames.ndim != 2 or frames.shape[1] != n_joints or frames.shape[0] < 1:
        raise ValueError(f'frames must have shape (k, {n_joints}), got {frames.shape}')
    if times.shape != (frames.shape[0],):
        raise ValueError(f'times must have shape ({frames.shape[0]},), got {times.shape}')
    if not (np.all(np.isfinite(frames)) and np.all(np.isfinite(times))):
        raise ValueError('times and frames must be finite (found NaN or inf)')
    if np.any(np.diff(times) < 0):
        raise ValueError('times must not decrease')
    for i, mesh in enumerate(meshes):
        if not (hasattr(mesh, 'vertices') and hasattr(mesh, 'faces')):
            raise ValueError(f'meshes[{i}] is not a triangle mesh: {type(mesh).__name__}')
    if footsteps is not None:
        footsteps = np.asarray(footsteps, dtype=float)
        if footsteps.ndim != 2 or footsteps.shape[1] != 4 or not np.all(np.isfinite(footsteps)):
            raise ValueError(f'footsteps must be finite (f, 4) [x, y, z, yaw], got '
                             f'shape {footsteps.shape}')
    return times, frames, footsteps


def _check_size(size):
    width, height = (int(v) for v in size)
    if width < 64 or height < 64 or width > 4096 or height > 4096:
        raise ValueError(f'image size must be between 64 and 4096 pixels, got {size}')
    return width, height


# -- course geometry -------------------------------------------------------------------------
def _split_faces(triangles: np.ndarray, tile: float,
                 max_count: int = 60000) -> Tuple[np.ndarray, np.ndarray]:
    """
    Split triangles (T, 3, 3) at their longest edge until every edge is below ``tile`` m.

    Longest-edge bisection keeps the pieces well shaped, which the depth sort needs.

    Returns
    -------
    tuple
        pieces (P, 3, 3) and the index (P,) of the triangle each piece came from.

    """
    parent = np.arange(len(triangles))
    done, done_parent = [], []
    while len(triangles):
        edges = np.stack([triangles[:, 1] - triangles[:, 0], triangles[:, 2] - triangles[:, 1],
                          triangles[:, 0] - triangles[:, 2]], axis=1)
        length = np.linalg.norm(edges, axis=2)
        longest = np.argmax(length, axis=1)
        small = length[np.arange(len(triangles)), longest] <= tile
        done.append(triangles[small])
        done_parent.append(parent[small])
        triangles, longest, parent = triangles[~small], longest[~small], parent[~small]
        if len(triangles) == 0 or sum(len(d) for d in done) + 2 * len(triangles) > max_count:
            done.append(triangles)
            done_parent.append(parent)
            break
        # Rotate each triangle so that its longest edge runs from vertex 0 to vertex 1.
        roll = np.stack([longest, (longest + 1) % 3, (longest + 2) % 3], axis=1)
        triangles = np.take_along_axis(triangles, roll[:, :, None], axis=1)
        middle = (triangles[:, 0] + triangles[:, 1]) / 2
        triangles = np.concatenate([
            np.stack([triangles[:, 0], middle, triangles[:, 2]], axis=1),
            np.stack([middle, triangles[:, 1], triangles[:, 2]], axis=1)])
        parent = np.concatenate([parent, parent])
    if not done:
        return triangles, parent
    return np.concatenate(done), np.concatenate(done_parent)


def _resample_heightfield(mesh, region, budget: int) -> np.ndarray:
    """Top surface of ``mesh`` inside ``region`` as a grid of at most ``budget`` triangles."""
    (x0, y0), (x1, y1) = region
    x0, y0 = max(x0, mesh.bounds[0, 0]), max(y0, mesh.bounds[0, 1])
    x1, y1 = min(x1, mesh.bounds[1, 0]), min(y1, mesh.bounds[1, 1])
    if x1 <= x0 or y1 <= y0:
        return np.zeros((0, 3, 3))
    cell = math.sqrt(2.0 * (x1 - x0) * (y1 - y0) / budget)
    xs = np.linspace(x0, x1, max(2, int(math.ceil((x1 - x0) / cell)) + 1))
    ys = np.linspace(y0, y1, max(2, int(math.ceil((y1 - y0) / cell)) + 1))
    gx, gy = np.meshgrid(xs, ys, indexing='ij')
    origins = np.column_stack([gx.ravel(), gy.ravel(),
                               np.full(gx.size, mesh.bounds[1, 2] + 1.0)])
    directions = np.tile([0.0, 0.0, -1.0], (gx.size, 1))
    heights = np.full(gx.size, np.nan)
    locations, rays, _ = mesh.ray.intersects_location(origins, directions, multiple_hits=False)
    heights[rays] = locations[:, 2]
    grid = np.stack([gx, gy, heights.reshape(gx.shape)], axis=-1)
    a, b = grid[:-1, :-1].reshape(-1, 3), grid[1:, :-1].reshape(-1, 3)
    c, d = grid[1:, 1:].reshape(-1, 3), grid[:-1, 1:].reshape(-1, 3)
    triangles = np.concatenate([np.stack([a, b, c], 1), np.stack([a, c, d], 1)])
    return triangles[np.all(np.isfinite(triangles[:, :, 2]), axis=1)]


def _course_triangles(meshes, region, tile=_TILE, budget=_FACE_BUDGET):
    """Clip, split or resample the course meshes: triangles (T, 3, 3) and colours (T, 3)."""
    (x0, y0), (x1, y1) = region
    triangles, colours = [], []
    for index, mesh in enumerate(meshes):
        faces = np.asarray(mesh.vertices, dtype=float)[np.asarray(mesh.faces)]
        if len(faces) == 0:
            continue
        low, high = faces[:, :, :2].min(axis=1), faces[:, :, :2].max(axis=1)
        inside = ((high[:, 0] >= x0) & (low[:, 0] <= x1) & (high[:, 1] >= y0)
                  & (low[:, 1] <= y1))
        faces = faces[inside]
        if len(faces) > budget:
            faces = _resample_heightfield(mesh, region, budget // 2)
        faces, _ = _split_faces(faces, tile)
        centre = faces.mean(axis=1)
        faces = faces[(centre[:, 0] >= x0) & (centre[:, 0] <= x1) & (centre[:, 1] >= y0)
                      & (centre[:, 1] <= y1)]
        triangles.append(faces)
        colours.append(np.tile(_TERRAIN_COLOURS[index % len(_TERRAIN_COLOURS)],
                               (len(faces), 1)))
    if not triangles:
        return np.zeros((0, 3, 3)), np.zeros((0, 3))
    owner = np.concatenate([np.full(len(t), i) for i, t in enumerate(triangles)])
    triangles, colours = np.concatenate(triangles), np.concatenate(colours)
    keep = ~_inside_other(meshes, _nudged_centres(triangles), owner)
    triangles, colours, owner = triangles[keep], colours[keep], owner[keep]
    # Faces that cross into another solid (the foot of a block sunk into the floor) are split
    # finer, so that the visible part ends close to the true intersection line.
    for level in (3, 9):
        centres = triangles.mean(axis=1, keepdims=True)
        corners = (triangles + 0.02 * (centres - triangles)).reshape(-1, 3)
        crossing = _inside_other(meshes, corners, owner.repeat(3)).reshape(-1, 3).any(axis=1)
        if not np.any(crossing):
            break
        pieces, parent = _split_faces(triangles[crossing], tile / level)
        parent = np.flatnonzero(crossing)[parent]
        visible = ~_inside_other(meshes, _nudged_centres(pieces), owner[parent])
        pieces, parent = pieces[visible], parent[visible]
        triangles = np.concatenate([triangles[~crossing], pieces])
        colours = np.concatenate([colours[~crossing], colours[parent]])
        owner = np.concatenate([owner[~crossing], owner[parent]])
    return triangles, colours


def _nudged_centres(triangles: np.ndarray) -> np.ndarray:
    """Face centres moved 2 mm out along the normal: (T, 3), for inside/outside tests."""
    return triangles.mean(axis=1) + 2e-3 * _normals(triangles)


def _inside_other(meshes, points: np.ndarray, owner: np.ndarray) -> np.ndarray:
    """
    Mark points (N, 3) that lie inside a closed course mesh other than their ``owner`` (N,).

    Solids that overlap (a walkway sunk into the floor slab) hide each other's faces; drawn
    anyway they would poke through in the depth sort.
    """
    inside = np.zeros(len(points), dtype=bool)
    for index, mesh in enumerate(meshes):
        if len(mesh.faces) == 0 or not mesh.is_watertight:
            continue
        low, high = mesh.bounds
        near = np.flatnonzero((owner != index) & np.all(points >= low, axis=1)
                              & np.all(points <= high, axis=1) & ~inside)
        if len(near):
            inside[near[mesh.contains(points[near])]] = True
    return inside


def _normals(triangles: np.ndarray) -> np.ndarray:
    normal = np.cross(triangles[:, 1] - triangles[:, 0], triangles[:, 2] - triangles[:, 0])
    return normal / np.maximum(np.linalg.norm(normal, axis=1, keepdims=True), 1e-12)


# -- actor geometry --------------------------------------------------------------------------
def _unit_box() -> np.ndarray:
    corners = np.array([[x, y, z] for x in (-0.5, 0.5) for y in (-0.5, 0.5) for z in (-0.5, 0.5)])
    quads = [(0, 1, 3, 2), (4, 6, 7, 5), (0, 4, 5, 1), (2, 3, 7, 6), (0, 2, 6, 4), (1, 5, 7, 3)]
    return np.array([[corners[q[0]], corners[q[k]], corners[q[k + 1]]]
                     for q in quads for k in (1, 2)])


def _unit_cylinder(sections: int = 14) -> np.ndarray:
    """Radius 1, length 1 along z, centred: (T, 3, 3) outward-wound triangles."""
    angle = np.linspace(0.0, 2.0 * math.pi, sections + 1)
    ring = np.column_stack([np.cos(angle), np.sin(angle)])
    triangles = []
    for k in range(sections):
        a0, a1 = ring[k], ring[k + 1]
        bottom0, bottom1 = [*a0, -0.5], [*a1, -0.5]
        top0, top1 = [*a0, 0.5], [*a1, 0.5]
        triangles += [[bottom0, bottom1, top1], [bottom0, top1, top0],
                      [[0, 0, 0.5], top0, top1], [[0, 0, -0.5], bottom1, bottom0]]
    return np.array(triangles, dtype=float)


def _unit_sphere(rings: int = 7, sections: int = 12) -> np.ndarray:
    """Radius 1: (T, 3, 3) outward-wound triangles of a UV sphere."""
    theta = np.linspace(0.0, math.pi, rings + 1)
    phi = np.linspace(0.0, 2.0 * math.pi, sections + 1)
    point = np.stack([np.outer(np.sin(theta), np.cos(phi)),
                      np.outer(np.sin(theta), np.sin(phi)),
                      np.outer(np.cos(theta), np.ones_like(phi))], axis=-1)
    triangles = []
    for i in range(rings):
        for j in range(sections):
            a, b, c, d = point[i, j], point[i + 1, j], point[i + 1, j + 1], point[i, j + 1]
            if i > 0:
                triangles.append([a, b, d])
            if i < rings - 1:
                triangles.append([b, c, d])
    return np.array(triangles)


class _ActorModel:
    """The actor's collision shapes as one triangle soup, placed per configuration."""

    def __init__(self, skeleton):
        self.skeleton = skeleton
        box, cylinder, sphere = _unit_box(), _unit_cylinder(), _unit_sphere()
        local, owner, colours = [], [], []
        for s, shape in enumerate(skeleton.collision_shapes):
            if shape.kind == 'box':
                triangles = box * np.asarray(shape.size)
            elif shape.kind == 'cylinder':
                radius, length = shape.size
                triangles = cylinder * [radius, radius, length]
            else:
                triangles = sphere * shape.size[0]
            colour = next((c for key, c in _LINK_COLOURS if key in shape.link),
                          _DEFAULT_LINK_COLOUR)
            local.append(triangles)
            owner.append(np.full(len(triangles), s))
            colours.append(np.tile(colour, (len(triangles), 1)))
        self.local = np.concatenate(local)               # (T, 3, 3) in shape frames
        self.owner = np.concatenate(owner)               # (T,) shape index
        self.colours = np.concatenate(colours)           # (T, 3)

    def triangles(self, q: np.ndarray) -> np.ndarray:
        """Return the collision shapes' world triangles at ``q`` (22,): (T, 3, 3), m."""
        shapes = self.skeleton.shape_transforms(self.skeleton.forward_kinematics(q))
        rotation, translation = shapes[self.owner, :3, :3], shapes[self.owner, :3, 3]
        return np.einsum('tij,tvj->tvi', rotation, self.local) + translation[:, None, :]


def _footstep_triangles(skeleton, footsteps) -> np.ndarray:
    """Sole outlines (2f, 3, 3), lifted 5 mm, from footsteps (f, 4) [x, y, z, yaw]."""
    if footsteps is None or len(footsteps) == 0:
        return np.zeros((0, 3, 3))
    leg = skeleton.leg
    half = leg.foot_width / 2
    corners = np.array([[-leg.heel, -half], [leg.toe, -half], [leg.toe, half], [-leg.heel, half]])
    c, s = np.cos(footsteps[:, 3]), np.sin(footsteps[:, 3])
    x = footsteps[:, None, 0] + c[:, None] * corners[:, 0] - s[:, None] * corners[:, 1]
    y = footsteps[:, None, 1] + s[:, None] * corners[:, 0] + c[:, None] * corners[:, 1]
    z = np.repeat(footsteps[:, None, 2] + 0.005, 4, axis=1)
    quad = np.stack([x, y, z], axis=-1)                 # (f, 4, 3)
    return np.concatenate([quad[:, [0, 1, 2]], quad[:, [0, 2, 3]]])


# -- drawing ---------------------------------------------------------------------------------
class _Canvas:
    """One Agg figure with a single polygon collection, reused for every frame."""

    def __init__(self, size: Tuple[int, int], title: Optional[str]):
        from matplotlib.backends.backend_agg import FigureCanvasAgg
        from matplotlib.collections import PolyCollection
        from matplotlib.figure import Figure

        width, height = size
        self.figure = Figure(figsize=(width / 100.0, height / 100.0), dpi=100)
        self.figure.patch.set_facecolor((0.86, 0.91, 0.97))
        FigureCanvasAgg(self.figure)
        self.axes = self.figure.add_axes([0.0, 0.0, 1.0, 1.0])
        self.axes.set_axis_off()
        self.axes.set_facecolor((0.86, 0.91, 0.97))
        self.polygons = PolyCollection([], linewidths=0.4, antialiaseds=True)
        self.axes.add_collection(self.polygons)
        self.labels = []
        self.title = self.figure.text(0.015, 0.975, title or '', va='top', ha='left',
                                      fontsize=13, color=(0.1, 0.1, 0.15))
        self.aspect = width / height

    def draw(self, camera: _Camera, triangles: np.ndarray, colours: np.ndarray,
             bias: np.ndarray, limits: Tuple[float, float, float, float], labels=()) -> None:
        """
        Cull, shade, depth-sort and draw ``triangles`` (T, 3, 3) with ``colours`` (T, 3).

        ``bias`` (T,) m is subtracted from each triangle's sorting depth, so that things lying
        on a surface (footsteps, soles) are drawn after the surface tiles around them.
        """
        normals = _normals(triangles)
        facing = np.einsum('ti,ti->t', normals, triangles.mean(axis=1) - camera.eye) < 0.0
        flat, depth = camera.project(triangles[facing])
        normals, colours, bias = normals[facing], colours[facing], bias[facing]
        x0, x1, y0, y1 = limits
        visible = (np.all(depth > 0.2, axis=1) & (flat[:, :, 0].max(1) >= x0)
                   & (flat[:, :, 0].min(1) <= x1) & (flat[:, :, 1].max(1) >= y0)
                   & (flat[:, :, 1].min(1) <= y1))
        flat, depth, normals, colours, bias = (flat[visible], depth[visible], normals[visible],
                                               colours[visible], bias[visible])
        light = _LIGHT / np.linalg.norm(_LIGHT)
        # Lambert shading plus a little light from the camera so no face goes black.
        shade = (0.42 + 0.48 * np.clip(normals @ light, 0.0, 1.0)
                 + 0.18 * np.clip(-(normals @ camera.forward), 0.0, 1.0))
        shaded = np.clip(colours * shade[:, None], 0.0, 1.0)
        order = np.argsort(bias - depth.mean(axis=1), kind='stable')
        self.polygons.set_verts(flat[order])
        self.polygons.set_facecolor(shaded[order])
        self.polygons.set_edgecolor(shaded[order])
        self.axes.set_xlim(x0, x1)
        self.axes.set_ylim(y0, y1)
        for label in self.labels:
            label.remove()
        self.labels = [self.axes.text(x, y, text, ha='center', va='bottom', fontsize=9,
                                      color=(0.1, 0.1, 0.15)) for x, y, text in labels]

    def save_png(self, path: str) -> None:
        self.figure.savefig(path, dpi=100, facecolor=self.figure.get_facecolor())

    def rgb(self) -> np.ndarray:
        """Render and return the image as (height, width, 3) uint8."""
        self.figure.canvas.draw()
        return np.asarray(self.figure.canvas.buffer_rgba())[:, :, :3].copy()


def _fit_limits(points: np.ndarray, aspect: float, margin: float = 0.08):
    """Image-plane limits (x0, x1, y0, y1) framing ``points`` (N, 2) at the figure's aspect."""
    low, high = points.min(axis=0), points.max(axis=0)
    centre = (low + high) / 2
    half = (high - low) / 2 * (1.0 + 2.0 * margin) + 1e-3
    half = np.maximum(half, [half[1] * aspect, half[0] / aspect])
    return centre[0] - half[0], centre[0] + half[0], centre[1] - half[1], centre[1] + half[1]


def _travel_azimuth(roots: np.ndarray) -> float:
    """Camera azimuth: on the right of the overall direction of travel, a little ahead."""
    travel = roots[-1, :2] - roots[0, :2]
    heading = (math.atan2(travel[1], travel[0]) if np.linalg.norm(travel) > 0.3
               else float(roots[0, 3]))
    return heading - math.radians(62.0)


def _write_atomically(path: str, write) -> None:
    """Write via a temporary file so a failed render leaves nothing half-written."""
    folder = os.path.dirname(os.path.abspath(path))
    if not os.path.isdir(folder):
        raise ValueError(f'output folder does not exist: {folder}')
    base, extension = os.path.splitext(path)
    temporary = f'{base}.partial{extension}'
    try:
        write(temporary)
        os.replace(temporary, path)
    finally:
        if os.path.exists(temporary):
            os.remove(temporary)


def render_png(path: str, skeleton, meshes: Sequence, times, frames, *, footsteps=None,
               n_poses: int = 6, title: Optional[str] = None,
               size: Tuple[int, int] = (1200, 800), face_budget: int = _FACE_BUDGET,
               azimuth: Optional[float] = None) -> None:
    """
    Write a PNG of the course with the actor at ``n_poses`` key poses along the run.

    Parameters
    ----------
    path
        output PNG file.
    skeleton
        :class:`~digital_actor_planner.core.skeleton.Skeleton` (joint order, collision shapes).
    meshes
        the course's trimesh meshes, world frame, m.
    times
        (k,) s, non-decreasing.
    frames
        (k, 22) configurations, rad or m.
    footsteps
        optional (f, 4) [x, y, z, yaw] footholds (ankle position on the ground, m, rad).
    n_poses
        number of key poses, evenly spaced in time, first and last included.
    title
        text in the top-left corner.
    size
        (width, height) of the image, pixels.
    face_budget
        faces of one course mesh near the run drawn as they are; a mesh with more is drawn
        as a heightfield of its top surface (a detailed game level needs a larger budget to
        keep its walls and steps).
    azimuth
        direction from the poses to the camera, rad from +x about z; by default on the right
        of the overall direction of travel, a little ahead (risers that face the actor are
        seen from behind it).

    """
    times, frames, footsteps = _check_run(skeleton, meshes, times, frames, footsteps)
    if int(face_budget) < 2:
        raise ValueError(f'face_budget must be at least 2, got {face_budget}')
    if int(n_poses) < 1:
        raise ValueError(f'n_poses must be at least 1, got {n_poses}')
    size = _check_size(size)
    roots = frames[:, skeleton.indices('root_x', 'root_y', 'root_z', 'root_yaw')]
    region = (roots[:, :2].min(axis=0) - 2.0, roots[:, :2].max(axis=0) + 2.0)
    terrain, terrain_colours = _course_triangles(meshes, region, budget=int(face_budget))

    wanted = np.linspace(times[0], times[-1], int(n_poses))
    keys, spans = [], []
    for k in np.unique(np.clip(np.searchsorted(times, wanted), 0, len(times) - 1)):
        # A pose where the previous key pose stood (the actor stopped) is drawn once, with
        # the time span in its label.
        if keys and (np.linalg.norm(roots[k, :2] - roots[keys[-1], :2]) < 0.15
                     and abs(roots[k, 3] - roots[keys[-1], 3]) < 0.2):
            spans[-1][1] = times[k]
        else:
            keys.append(k)
            spans.append([times[k], times[k]])
    actor = _ActorModel(skeleton)
    bodies = [actor.triangles(frames[k]) for k in keys]
    feet = _footstep_triangles(skeleton, footsteps)
    triangles = np.concatenate([terrain, *bodies, feet])
    colours = np.concatenate([terrain_colours, *([actor.colours] * len(bodies)),
                              np.tile(_FOOTSTEP_COLOUR, (len(feet), 1))])
    bias = np.concatenate([np.zeros(len(terrain)), np.full(len(actor.colours) * len(bodies),
                                                           _ACTOR_BIAS),
                           np.full(len(feet), _FOOTSTEP_BIAS)])

    # Frame the poses with at least a metre of course around each.
    surround = np.array([[dx, dy, -skeleton.leg.standing_height] for dx in (-1.0, 1.0)
                         for dy in (-1.0, 1.0)])
    body_points = np.concatenate([b.reshape(-1, 3) for b in bodies] + [feet.reshape(-1, 3)]
                                 + [roots[k, :3] + surround for k in keys])
    low, high = body_points.min(axis=0), body_points.max(axis=0)
    target = (low + high) / 2
    extent = float(np.linalg.norm(high - low))
    if azimuth is None:
        azimuth = _travel_azimuth(roots)
    elif not math.isfinite(azimuth):
        raise ValueError(f'azimuth must be finite, got {azimuth}')
    camera = _Camera.looking_at(target, float(azimuth), math.radians(24.0),
                                max(4.0, 1.6 * extent))
    canvas = _Canvas(size, title)
    flat, _ = camera.project(body_points)
    limits = _fit_limits(flat, canvas.aspect)
    labels = []
    for (start, end), body in zip(spans, bodies):
        top = body.reshape(-1, 3)[np.argmax(body[:, :, 2].ravel())] + [0.0, 0.0, 0.05]
        (x, y), _ = camera.project(top)
        span = f'{start:.1f} s' if end - start < 0.05 else f'{start:.1f}-{end:.1f} s'
        labels.append((x, y, f't = {span}'))
    canvas.draw(camera, triangles, colours, bias, limits, labels)
    _write_atomically(path, canvas.save_png)


def render_gif(path: str, skeleton, meshes: Sequence, times, frames, *, fps: float = 10,
               footsteps=None, follow: bool = True, size: Tuple[int, int] = (640, 480),
               title: Optional[str] = None) -> None:
    """
    Write an animated GIF of the run, the camera following the actor.

    Parameters
    ----------
    path
        output GIF file.
    skeleton
        :class:`~digital_actor_planner.core.skeleton.Skeleton`.
    meshes
        the course's trimesh meshes, world frame, m.
    times
        (k,) s, non-decreasing.
    frames
        (k, 22) configurations, rad or m; shown at the GIF frame times (nearest frame).
    fps
        GIF frames per second of run time (0 < fps <= 50).
    footsteps
        optional (f, 4) [x, y, z, yaw] footholds, m and rad.
    follow
        keep the actor in the centre (True) or frame the whole run with a fixed camera.
    size
        (width, height) of the animation, pixels.
    title
        text in the top-left corner; the run time is added to it.

    """
    from PIL import Image

    times, frames, footsteps = _check_run(skeleton, meshes, times, frames, footsteps)
    if not (np.isfinite(fps) and 0.0 < fps <= 50.0):
        raise ValueError(f'fps must be in (0, 50], got {fps}')
    size = _check_size(size)
    roots = frames[:, skeleton.indices('root_x', 'root_y', 'root_z', 'root_yaw')]
    region = (roots[:, :2].min(axis=0) - 3.5, roots[:, :2].max(axis=0) + 3.5)
    # Coarser tiles than the PNG: every polygon costs time in every frame.
    terrain, terrain_colours = _course_triangles(meshes, region, tile=0.7, budget=4000)
    terrain_centre = terrain.mean(axis=1) if len(terrain) else np.zeros((0, 3))
    actor = _ActorModel(skeleton)
    feet = _footstep_triangles(skeleton, footsteps)
    feet_colours = np.tile(_FOOTSTEP_COLOUR, (len(feet), 1))
    actor_bias = np.full(len(actor.colours), _ACTOR_BIAS)
    feet_bias = np.full(len(feet), _FOOTSTEP_BIAS)
    azimuth = _travel_azimuth(roots)
    elevation = math.radians(22.0)
    canvas = _Canvas(size, title)

    count = max(1, int(math.floor((times[-1] - times[0]) * fps + 1e-9)) + 1)
    shown = np.clip(np.searchsorted(times, times[0] + np.arange(count) / fps), 0,
                    len(times) - 1)
    if follow:
        distance = 5.0
        probe = _Camera.looking_at(np.zeros(3), azimuth, elevation, distance)
        # A fixed image window around a 3 m x 3 m x 2.1 m box centred on the actor.
        box = np.array([[x, y, z] for x in (-1.5, 1.5) for y in (-1.5, 1.5)
                        for z in (-1.0, 1.1)])
        limits = _fit_limits(probe.project(box)[0], canvas.aspect, 0.0)
    else:
        low = (roots[:, :3] - [0.8, 0.8, 1.0]).min(axis=0)
        high = (roots[:, :3] + [0.8, 0.8, 0.9]).max(axis=0)
        fixed = _Camera.looking_at((low + high) / 2, azimuth, elevation,
                                   max(4.0, 1.6 * float(np.linalg.norm(high - low))))
        corners = np.array([[x, y, z] for x in (low[0], high[0]) for y in (low[1], high[1])
                            for z in (low[2], high[2])])
        limits = _fit_limits(fixed.project(corners)[0], canvas.aspect, 0.02)

    images = []
    for k in shown:
        if follow:
            # Look at the middle of the body: 0.9 m above the feet of a standing actor.
            target = roots[k, :3] + [0.0, 0.0, 0.9 - skeleton.leg.standing_height]
            camera = _Camera.looking_at(target, azimuth, elevation, distance)
            near = np.linalg.norm(terrain_centre[:, :2] - roots[k, :2], axis=1) < 6.0
        else:
            camera = fixed
            near = np.ones(len(terrain), dtype=bool)
        triangles = np.concatenate([terrain[near], actor.triangles(frames[k]), feet])
        colours = np.concatenate([terrain_colours[near], actor.colours, feet_colours])
        bias = np.concatenate([np.zeros(int(near.sum())), actor_bias, feet_bias])
        canvas.title.set_text(f'{title + "   " if title else ""}t = {times[k]:.1f} s')
        canvas.draw(camera, triangles, colours, bias, limits)
        images.append(Image.fromarray(canvas.rgb()).quantize(colors=255, method=2))

    def write(temporary):
        images[0].save(temporary, format='GIF', save_all=True, append_images=images[1:],
                       duration=int(round(1000.0 / fps)), loop=0, optimize=False)

    _write_atomically(path, write)
