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
Render the README pictures with `digital-actor simulate --render` (the project draws itself).

Run: .venv/bin/python scripts/make_pictures.py [PICTURE ...]
     (writes docs/images/*.png and *.gif; with names, e.g. table.gif, only those)
"""
import os
import subprocess
import sys
import tempfile

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
SCENES = os.path.join(ROOT, 'config', 'scenes')
IMAGES = os.path.join(ROOT, 'docs', 'images')

PICTURES = [
    ('stairs_up', 'stairs_up.png', []),
    ('stairs_down', 'stairs_down.gif', []),
    # Figure 8 is about the window of the paper's search (with one footstep in the window the
    # greedy second climb is the exhaustive choice of that footstep).
    ('figure8_trap', 'figure8_n3.png', ['--window-steps', '3', '--paper-search']),
    ('figure8_trap', 'figure8_n1.png', ['--window-steps', '1', '--paper-search']),
    ('blocks', 'blocks.png', []),
    ('rough', 'rough.png', []),
    ('turn', 'turn.png', []),
    ('wall', 'wall.png', []),
    ('low_beam', 'low_beam.png', []),
    ('low_beam', 'low_beam.gif', []),
    ('table', 'table.png', []),
    ('table', 'table.gif', []),
    ('pillars', 'pillars.png', []),
    ('uneven_beam', 'uneven_beam.png', []),
]


def main(names=()):
    known = [picture for _, picture, _ in PICTURES]
    unknown = [name for name in names if name not in known]
    if unknown:
        print(f'unknown picture(s) {", ".join(unknown)}; known: {", ".join(known)}',
              file=sys.stderr)
        return 2
    os.makedirs(IMAGES, exist_ok=True)
    env = dict(os.environ, MPLBACKEND='Agg')
    for course, picture, extra in PICTURES:
        if names and picture not in names:
            continue
        with tempfile.TemporaryDirectory() as tmp:
            command = [sys.executable, '-m', 'digital_actor_planner.cli', 'simulate',
                       '--scene', os.path.join(SCENES, course + '.yaml'),
                       '--commands', os.path.join(SCENES, course + '.csv'),
                       '--out', os.path.join(tmp, 'trajectory.csv'),
                       '--render', os.path.join(IMAGES, picture)] + extra
            result = subprocess.run(command, capture_output=True, text=True, env=env)
            print(picture, result.stdout.strip() or result.stderr.strip())
            if result.returncode != 0:
                return result.returncode
    return 0


if __name__ == '__main__':
    sys.exit(main(sys.argv[1:]))
