"""`digital-actor simulate`: files in, trajectory/summary/pictures out, clear errors."""
import csv
import json
import os
import subprocess
import sys

import numpy as np
import pytest
import trimesh

from digital_actor_planner.cli import read_commands, read_trajectory
from digital_actor_planner.core.skeleton import Skeleton

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
SCENES = os.path.join(ROOT, 'config', 'scenes')


def run_cli(*args, cwd=None):
    env = dict(os.environ, MPLBACKEND='Agg')
    return subprocess.run([sys.executable, '-m', 'digital_actor_planner.cli', *args],
                          capture_output=True, text=True, cwd=cwd, env=env, timeout=600)


def write_commands(path, rows, header='time,linear_x,angular_z'):
    path.write_text(header + '\n' + '\n'.join(rows) + '\n')
    return str(path)


@pytest.fixture(scope='module')
def stairs_run(tmp_path_factory):
    out = tmp_path_factory.mktemp('stairs')
    args = ['simulate', '--scene', os.path.join(SCENES, 'stairs_up.yaml'),
            '--commands', os.path.join(SCENES, 'stairs_up.csv'),
            '--out', str(out / 'traj.csv'), '--summary', str(out / 'summary.json'),
            '--render', str(out / 'poses.png')]
    result = run_cli(*args)
    assert result.returncode == 0, result.stderr
    return out, args, result


def test_trajectory_csv_has_the_22_joints_at_100_hz(stairs_run):
    out, _, _ = stairs_run
    names, times, frames = read_trajectory(str(out / 'traj.csv'))
    assert names == Skeleton().joint_names
    assert frames.shape == (times.size, 22)
    np.testing.assert_allclose(np.diff(times), 0.01, atol=1e-6)
    assert np.all(np.isfinite(frames))
    assert frames[-1, 0] > 4.0 and frames[-1, 2] > 0.75 + 0.8  # up the stairs


def test_summary_reports_steps_timing_and_status(stairs_run):
    out, _, _ = stairs_run
    summary = json.loads((out / 'summary.json').read_text())
    assert summary['steps_taken'] == len(summary['planning_time_per_step']) > 5
    assert summary['step_categories']['uphill'] >= 2
    assert summary['real_time_factor'] > 1.0
    assert summary['final_status'] in ('walking', 'idle')
    assert summary['stuck_events'] == []


def test_render_writes_a_picture(stairs_run):
    out, _, _ = stairs_run
    from PIL import Image
    image = np.asarray(Image.open(out / 'poses.png').convert('RGB'), dtype=float)
    assert image.shape[0] > 300 and image.std() > 10


def test_same_inputs_give_the_same_trajectory(stairs_run, tmp_path):
    out, args, _ = stairs_run
    again = list(args)
    again[again.index('--out') + 1] = str(tmp_path / 'again.csv')
    again = again[:again.index('--summary')]
    assert run_cli(*again).returncode == 0
    assert (tmp_path / 'again.csv').read_text() == (out / 'traj.csv').read_text()


def test_wall_reports_stuck_in_the_summary(tmp_path):
    result = run_cli('simulate', '--scene', os.path.join(SCENES, 'wall.yaml'),
                     '--commands', os.path.join(SCENES, 'wall.csv'),
                     '--out', str(tmp_path / 't.csv'), '--summary', str(tmp_path / 's.json'))
    assert result.returncode == 0, result.stderr
    summary = json.loads((tmp_path / 's.json').read_text())
    assert summary['final_status'] == 'stuck'
    assert summary['stuck_events'] and 'footstep' in summary['stuck_events'][0]['reason']


def test_paper_search_reproduces_figure_8_with_a_one_step_window(tmp_path):
    """`--paper-search` runs the paper's footstep search alone (the summary says so): with one
    footstep in the window the actor steps into the Figure 8 pit and is stuck there."""
    result = run_cli('simulate', '--scene', os.path.join(SCENES, 'figure8_trap.yaml'),
                     '--commands', os.path.join(SCENES, 'figure8_trap.csv'),
                     '--out', str(tmp_path / 't.csv'), '--summary', str(tmp_path / 's.json'),
                     '--window-steps', '1', '--paper-search')
    assert result.returncode == 0, result.stderr
    summary = json.loads((tmp_path / 's.json').read_text())
    assert summary['greedy_restart'] is False and summary['window_steps'] == 1
    assert summary['final_status'] == 'stuck' and summary['final_pose']['root_x'] < 2.6


def test_a_bare_mesh_file_is_a_scene(tmp_path):
    floor = trimesh.creation.box(extents=(8.0, 3.0, 0.2))
    floor.apply_translation((3.0, 0.0, -0.1))
    floor.export(tmp_path / 'floor.obj')
    commands = write_commands(tmp_path / 'c.csv', ['0,0.8,0', '3,0,0'])
    result = run_cli('simulate', '--scene', str(tmp_path / 'floor.obj'), '--commands', commands,
                     '--out', str(tmp_path / 't.csv'))
    assert result.returncode == 0, result.stderr
    _, _, frames = read_trajectory(str(tmp_path / 't.csv'))
    assert frames[-1, 0] > 1.0


def test_speeds_beyond_the_limits_are_clamped_with_a_warning(tmp_path):
    commands = write_commands(tmp_path / 'c.csv', ['0,5.0,0', '2,0,0'])
    result = run_cli('simulate', '--scene', os.path.join(SCENES, 'flat.yaml'), '--commands',
                     commands, '--out', str(tmp_path / 't.csv'))
    assert result.returncode == 0, result.stderr
    assert 'c.csv:2' in result.stderr and 'clamped' in result.stderr


@pytest.mark.parametrize('rows, header, expected', [
    (['0,0.8,0', '1,nan,0'], None, 'c.csv:3: non-finite'),
    (['0,0.8,0', '1,0.5'], None, 'c.csv:3: expected 3 values'),
    (['0,0.8,0', '1,fast,0'], None, 'c.csv:3: not a number'),
    (['1,0.8,0', '0.5,0,0'], None, 'c.csv:3: time 0.5'),
    (['0,0.8,0'], 'time,v,w', 'c.csv:1: header'),
    ([], None, 'no command rows'),
])
def test_bad_command_files_exit_2_naming_the_line(tmp_path, rows, header, expected):
    commands = write_commands(tmp_path / 'c.csv', rows, header or 'time,linear_x,angular_z')
    out = tmp_path / 't.csv'
    result = run_cli('simulate', '--scene', os.path.join(SCENES, 'flat.yaml'), '--commands',
                     commands, '--out', str(out))
    assert result.returncode == 2
    assert expected in result.stderr
    assert not out.exists()


@pytest.mark.parametrize('content, expected', [
    (None, 'missing.yaml'),
    ('meshes: [{file: nothing.stl}]\n', 'nothing.stl'),
    ('meshes: [{file: floor.obj, pose: [0, 0]}]\n', 'pose'),
    ('meshes: []\n', 'meshes'),
    ('start: [1, 2, 3]\nmeshes: [{file: floor.obj}]\nbogus: 1\n', 'bogus'),
    ('meshes: [{file: floor.obj}]\nstart: [40, 0, 0]\n', 'no ground'),
    ('meshes: [{file: floor.obj}, {file: block.obj}]\nstart: [0, 0, 0]\n', 'inside an obstacle'),
    ('meshes: [{file: nan.obj}]\n', 'nan.obj'),
])
def test_bad_scenes_exit_2_naming_the_problem(tmp_path, content, expected):
    floor = trimesh.creation.box(extents=(8.0, 3.0, 0.2))
    floor.apply_translation((3.0, 0.0, -0.1))
    floor.export(tmp_path / 'floor.obj')
    post = trimesh.creation.box(extents=(0.2, 0.2, 2.0))  # where the left arm hangs
    post.apply_translation((0.0, 0.3, 1.0))
    post.export(tmp_path / 'block.obj')
    (tmp_path / 'nan.obj').write_text('v 0 0 0\nv 1 0 nan\nv 0 1 0\nf 1 2 3\n')
    scene = tmp_path / ('missing.yaml' if content is None else 'scene.yaml')
    if content is not None:
        scene.write_text(content)
    commands = write_commands(tmp_path / 'c.csv', ['0,0.8,0', '1,0,0'])
    out = tmp_path / 't.csv'
    result = run_cli('simulate', '--scene', str(scene), '--commands', commands, '--out', str(out))
    assert result.returncode == 2, result.stdout + result.stderr
    assert expected in result.stderr
    assert not out.exists()


def test_read_commands_accepts_the_shipped_files():
    for name in os.listdir(SCENES):
        if name.endswith('.csv'):
            rows = read_commands(os.path.join(SCENES, name))
            assert rows[-1].linear_x == 0.0 and rows[-1].angular_z == 0.0


def test_trajectory_columns_are_in_csv_order(stairs_run):
    out, _, _ = stairs_run
    with open(out / 'traj.csv') as f:
        header = next(csv.reader(f))
    assert header[0] == 'time' and header[1:5] == ['root_x', 'root_y', 'root_z', 'root_yaw']
