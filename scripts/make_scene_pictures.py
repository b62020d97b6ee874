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
Render the actor walking on the third-party scenes (pybullet_data's warehouse and monastery).

Each walk is planned by the core Actor (whole body), judged by the trajectory check (its
verdict is printed) and drawn with the course meshes cropped to a few metres around it.

Run: .venv/bin/python scripts/make_scene_pictures.py [--gif] [SCENE ...]
     (fetches the scenes once, as ``./quickstart.sh setup`` does; writes
     docs/images/<scene>.png, and <scene>.gif with --gif)
"""
import argparse
from dataclasses import dataclass
import math
import os
import sys
import time
from typing import Optional, Tuple

import numpy as np

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
IMAGES = os.path.join(ROOT, 'docs', 'images')
sys.path.insert(0, os.path.join(ROOT, 'bench'))
import third_party_meshes  # noqa: E402


@dataclass(frozen=True)
class Walk:
    """A walk to picture: where it starts and the command stream that drives it."""

    description: str
    start: Tuple[float, float, float]        # x m, y m, yaw rad
    commands: Tuple[Tuple[float, float, float], ...]   # (time s, linear m/s, angular rad/s)
    poses: int = 6
    face_budget: int = 12000     # faces of a mesh near the walk drawn as they are
    azimuth: Optional[float] = None   # rad, camera direction; None: beside the travel


WALKS = {
    # Down the corridor between the two rows of shelf pods, then a turn left out of it
    # towards the crate with the mug.
    'warehouse': Walk('down the corridor between the Kiva pods, then a turn left',
                      (3.0, 0.0, 0.0),
                      ((0.0, 0.5, 0.0), (17.0, 0.5, 0.4), (21.0, 0.5, 0.4))),
    # Across the inner courtyard and up the first two steps of the east gate's stairs (rises
    # of 0.25 m and 0.27 m on 1.1 m treads); the actor stops there, since the third riser
    # (0.33 m) is higher than a leg can step up.
    # Seen from its left and a little behind, so that the risers face the camera.
    'monastery': Walk('across the courtyard and up the first steps of the east gate',
                      (16.0, 0.0, 0.0), ((0.0, 0.5, 0.0), (18.0, 0.0, 0.0), (20.0, 0.0, 0.0)),
                      face_budget=60000, azimuth=math.radians(120.0)),
}


def landed_feet(skeleton, frames: np.ndarray) -> np.ndarray:
    """
    Places the feet rested on, for the footprint marks of a picture.

    Parameters
    ----------
    skeleton
        :class:`~digital_actor_planner.core.skeleton.Skeleton`.
    frames
        (k, 22) configurations, rad or m.

    Returns
    -------
    numpy.ndarray
        (f, 4) x, y, z (m) and yaw (rad) of each distinct foot placement.

    """
    transforms = skeleton.forward_kinematics(frames[::5])
    feet = []
    for link in ('left_foot', 'right_foot'):
        placed = transforms[:, skeleton.link_index[link]]
        last = None
        for pose in placed:
            if last is None or np.linalg.norm(pose[:2, 3] - last[:2]) > 0.1:
                feet.append([*pose[:3, 3], np.arctan2(pose[1, 0], pose[0, 0])])
                last = pose[:3, 3]
    return np.array(feet).reshape(-1, 4)


def picture(name: str, walk: Walk, gif: bool) -> int:
    """Plan, judge and draw one walk: 0 when it is judged clean, 1 otherwise."""
    from digital_actor_planner.evaluation import render
    from digital_actor_planner.core.actor import Actor, ActorConfig, run_commands
    from digital_actor_planner.core.scene import load_scene
    from digital_actor_planner.core.skeleton import Skeleton
    from digital_actor_planner.evaluation.trajectory_check import check_trajectory

    skeleton = Skeleton()
    scene = load_scene(third_party_meshes.scene_path(name))
    actor = Actor(skeleton, scene.environment, ActorConfig(), start=walk.start)
    clock = time.perf_counter()
    times, linear, angular = (list(column) for column in zip(*walk.commands))
    blocks = run_commands(actor, times, linear, angular)
    wall = time.perf_counter() - clock
    times = np.concatenate([b.times for b in blocks])
    frames = np.vstack([b.frames for b in blocks])
    steps = sum(b.status == 'walking' for b in blocks)
    stuck = sorted({b.reason for b in blocks if b.status == 'stuck'})
    walked = float(np.linalg.norm(frames[-1, :2] - frames[0, :2]))
    rise = float(frames[-1, 2] - frames[0, 2])
    print(f'{name}: {walk.description}: {steps} steps, {walked:.1f} m, rise {rise:+.2f} m '
          f'in {times[-1]:.1f} s (planned in {wall:.0f} s), final status {actor.status}'
          + (f'; stuck: {"; ".join(stuck)}' if stuck else ''), flush=True)
    report = check_trajectory(skeleton, scene.environment, times, frames)
    verdict = 'clean' if report.ok else '; '.join(report.failures())
    print(f'{name}: trajectory check: {verdict}', flush=True)
    feet = landed_feet(skeleton, frames)
    title = f'{name} (pybullet_data): {walk.description}'
    render.render_png(os.path.join(IMAGES, f'{name}.png'), skeleton, scene.environment.meshes,
                      times, frames, footsteps=feet, n_poses=walk.poses, title=title,
                      face_budget=walk.face_budget, azimuth=walk.azimuth)
    if gif:
        render.render_gif(os.path.join(IMAGES, f'{name}.gif'), skeleton,
                          scene.environment.meshes, times, frames, footsteps=feet, fps=8,
                          title=name)
    return 0 if report.ok and not stuck else 1


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.strip().splitlines()[0])
    parser.add_argument('scenes', nargs='*', metavar='SCENE',
                        help=f'scenes to draw (default: all of {", ".join(WALKS)})')
    parser.add_argument('--gif', action='store_true',
                        help='also write an animation (a few MB: too large for the README)')
    args = parser.parse_args(argv)
    unknown = [name for name in args.scenes if name not in WALKS]
    if unknown:
        parser.exit(2, f'{parser.prog}: error: unknown scene(s) {", ".join(unknown)}; '
                       f'known: {", ".join(WALKS)}\n')
    try:
        third_party_meshes.fetch()
    except (OSError, RuntimeError) as error:
        print(f'{parser.prog}: third-party scenes not fetched: {error}', file=sys.stderr)
        return 1
    os.environ.setdefault('MPLBACKEND', 'Agg')
    failed = 0
    for name in args.scenes or list(WALKS):
        failed |= picture(name, WALKS[name], args.gif)
    return failed


if __name__ == '__main__':
    sys.exit(main())
