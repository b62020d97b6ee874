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
launch/actor.launch.py read without a ROS install: what it would start, and with what.

launch and launch_ros are stood in for by recorders that keep each action's arguments, so the
launch description is built exactly as ``ros2 launch`` builds it and then inspected: mouse_teleop
repeats a held drag, a namespace prefixes every TF frame, a missing package stops the launch
before anything starts. (test_actor_launch.py runs the same file on a ROS install.)
"""
import importlib.util
import os
import sys
import types

from digital_actor_planner.launch_support import MissingPackageError
import pytest
import yaml

REPO = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
LAUNCH_FILE = os.path.join(REPO, 'launch', 'actor.launch.py')
ROS_PACKAGES = ('robot_state_publisher', 'rviz2', 'mouse_teleop')


class Action:
    """Stands in for a launch action: keeps its arguments; every one made is in ``made``."""

    made = []

    def __init__(self, *args, **kwargs):
        self.args, self.kwargs = args, kwargs
        Action.made.append(self)


class LaunchConfiguration(Action):

    def perform(self, context):
        return context.launch_configurations[self.args[0]]


class ParameterValue(Action):
    pass


class PackageNotFoundError(KeyError):
    pass


def _kinds():
    names = {}
    for module, classes in (
            ('launch', ('LaunchDescription',)),
            ('launch.actions', ('DeclareLaunchArgument', 'GroupAction',
                                'IncludeLaunchDescription', 'OpaqueFunction')),
            ('launch.launch_description_sources', ('PythonLaunchDescriptionSource',)),
            ('launch_ros.actions', ('Node', 'PushRosNamespace'))):
        names[module] = {name: type(name, (Action,), {}) for name in classes}
    names['launch.substitutions'] = {'LaunchConfiguration': LaunchConfiguration}
    names['launch_ros.parameter_descriptions'] = {'ParameterValue': ParameterValue}
    return names


@pytest.fixture
def launch(monkeypatch):
    """
    Return a function that gives the actions actor.launch.py returns.

    Called as ``launch(installed=..., **arguments)``.
    """
    for module, classes in _kinds().items():
        fake = types.ModuleType(module)
        fake.__dict__.update(classes)
        monkeypatch.setitem(sys.modules, module, fake)
    monkeypatch.setitem(sys.modules, 'launch_ros', types.ModuleType('launch_ros'))
    installed_packages = set()

    def get_package_share_directory(package):
        if package == 'digital_actor_planner':
            return REPO
        if package not in installed_packages:
            raise PackageNotFoundError(package)
        return f'/opt/ros/share/{package}'

    index = types.ModuleType('ament_index_python.packages')
    index.get_package_share_directory = get_package_share_directory
    index.PackageNotFoundError = PackageNotFoundError
    monkeypatch.setitem(sys.modules, 'ament_index_python', types.ModuleType('ament_index_python'))
    monkeypatch.setitem(sys.modules, 'ament_index_python.packages', index)
    written = []

    def run(installed=ROS_PACKAGES, **arguments):
        installed_packages.clear()
        installed_packages.update(installed)
        Action.made.clear()
        spec = importlib.util.spec_from_file_location('actor_launch', LAUNCH_FILE)
        module = importlib.util.module_from_spec(spec)
        spec.loader.exec_module(module)
        description = module.generate_launch_description()
        (entities,) = description.args
        declared = {a.args[0]: a.kwargs['default_value'] for a in entities
                    if type(a).__name__ == 'DeclareLaunchArgument'}
        unknown = set(arguments) - set(declared)
        assert not unknown, f'not launch arguments: {unknown}'
        context = types.SimpleNamespace(launch_configurations={**declared, **arguments})
        (opaque,) = [a for a in entities if type(a).__name__ == 'OpaqueFunction']
        Action.made.clear()
        returned = opaque.kwargs['function'](context, *opaque.kwargs.get('args', []))
        actions = []
        for action in returned:
            actions.extend(action.args[0] if type(action).__name__ == 'GroupAction'
                           else [action])
        for node in nodes(actions).values():
            arguments = list(node.kwargs.get('arguments', []))
            if '-d' in arguments:
                config = arguments[arguments.index('-d') + 1]
                if not config.startswith(REPO):
                    written.append(config)
        return actions

    yield run
    for path in written:
        if os.path.exists(path):
            os.unlink(path)


def nodes(actions):
    """Return the launched nodes by package."""
    return {a.kwargs['package']: a for a in actions if type(a).__name__ == 'Node'}


def parameters(node):
    """Return a node's parameters from its dictionaries (ParameterValue unwrapped)."""
    merged = {}
    for entry in node.kwargs.get('parameters', []):
        if isinstance(entry, dict):
            merged.update({key: value.args[0] if isinstance(value, ParameterValue) else value
                           for key, value in entry.items()})
    return merged


def rviz_config_of(actions):
    arguments = list(nodes(actions)['rviz2'].kwargs['arguments'])
    with open(arguments[arguments.index('-d') + 1]) as config:
        return yaml.safe_load(config)


def test_mouse_teleop_repeats_the_command_while_a_drag_is_held(launch):
    teleop = nodes(launch())['mouse_teleop']
    # mouse_teleop's own default, 0, sends only while the mouse moves: a held drag would
    # fall silent and the planner stop the actor after cmd_timeout (0.5 s).
    assert parameters(teleop)['frequency'] >= 1.0 / 0.5
    assert ('mouse_vel', 'cmd_vel') in teleop.kwargs['remappings']
    assert parameters(nodes(launch(teleop_frequency='20'))['mouse_teleop'])['frequency'] == 20.0


def test_a_bad_teleop_frequency_is_named(launch):
    with pytest.raises(ValueError, match='teleop_frequency'):
        launch(teleop_frequency='fast')


def test_a_switch_that_is_neither_true_nor_false_is_named(launch):
    with pytest.raises(ValueError, match='use_rviz'):
        launch(use_rviz='maybe')
    with pytest.raises(ValueError, match='use_dynamixel'):
        launch(use_dynamixel='yes please')


def test_root_namespace_frames_are_the_urdf_names(launch):
    actions = launch()
    started = nodes(actions)
    assert parameters(started['robot_state_publisher'])['frame_prefix'] == ''
    assert parameters(started['digital_actor_planner'])['frame_id'] == 'world'
    assert rviz_config_of(actions)['Visualization Manager']['Global Options'][
        'Fixed Frame'] == 'world'


@pytest.mark.parametrize('namespace', ['actor1', '/actor1'])
def test_a_namespace_prefixes_every_tf_frame_and_rviz_follows(launch, namespace):
    actions = launch(namespace=namespace)
    started = nodes(actions)
    pushed = [a.args[0] for a in actions if type(a).__name__ == 'PushRosNamespace']
    assert pushed == [namespace]
    assert parameters(started['robot_state_publisher'])['frame_prefix'] == 'actor1/'
    # The planner's joint_states, markers and path are in the same prefixed world frame.
    assert parameters(started['digital_actor_planner'])['frame_id'] == 'actor1/world'
    manager = rviz_config_of(actions)['Visualization Manager']
    assert manager['Global Options']['Fixed Frame'] == 'actor1/world'
    models = [d for d in manager['Displays'] if d['Class'] == 'rviz_default_plugins/RobotModel']
    assert models and all(d['TF Prefix'] == 'actor1' for d in models)


def test_two_namespaces_get_rviz_configs_of_their_own(launch):
    first = rviz_config_of(launch(namespace='actor1'))
    second = rviz_config_of(launch(namespace='actor2'))
    frames = {c['Visualization Manager']['Global Options']['Fixed Frame'] for c in (first, second)}
    assert frames == {'actor1/world', 'actor2/world'}


def test_launches_leave_one_rviz_config_per_namespace(launch, tmp_path, monkeypatch):
    monkeypatch.setenv('ROS_HOME', str(tmp_path))
    paths = set()
    for _ in range(3):
        arguments = list(nodes(launch(namespace='actor1'))['rviz2'].kwargs['arguments'])
        paths.add(arguments[arguments.index('-d') + 1])
    launch(namespace='actor2')
    kept = sorted(p.name for p in (tmp_path / 'digital_actor_planner').iterdir())
    assert kept == ['actor_actor1.rviz', 'actor_actor2.rviz']
    assert paths == {str(tmp_path / 'digital_actor_planner' / 'actor_actor1.rviz')}


@pytest.mark.parametrize('package, switch', [('mouse_teleop', 'use_teleop'),
                                             ('rviz2', 'use_rviz')])
def test_a_missing_package_stops_the_launch_before_anything_starts(launch, package, switch):
    installed = [p for p in ROS_PACKAGES if p != package]
    with pytest.raises(MissingPackageError) as error:
        launch(installed=installed)
    message = str(error.value)
    assert package in message
    assert f'ros-{os.environ.get("ROS_DISTRO") or "<distro>"}-{package.replace("_", "-")}' \
        in message
    assert f'{switch}:=false' in message
    assert not [a for a in Action.made if type(a).__name__ == 'Node'], 'a node was made'
    # Turned off, the package is not needed.
    assert package not in nodes(launch(installed=installed, **{switch: 'false'}))


def test_robot_state_publisher_missing_is_always_fatal(launch):
    with pytest.raises(MissingPackageError, match='robot_state_publisher'):
        launch(installed=['rviz2', 'mouse_teleop'], use_rviz='false', use_teleop='false')


def test_headless_launch_starts_the_planner_and_robot_state_publisher_only(launch):
    started = nodes(launch(installed=['robot_state_publisher'], use_rviz='false',
                           use_teleop='false'))
    assert set(started) == {'digital_actor_planner', 'robot_state_publisher'}
