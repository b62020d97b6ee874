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
Launch the digital actor: planner, robot_state_publisher, RViz2 and mouse teleop.

    ros2 launch digital_actor_planner actor.launch.py [scene:=FILE] [use_rviz:=true]
        [use_teleop:=true] [teleop_frequency:=10.0] [namespace:=NS] [use_dynamixel:=false]

Drag in the mouse_teleop window to direct the actor (forward speed and turning, §3.1 of the
paper); mouse_teleop's ``mouse_vel`` is remapped to the planner's ``cmd_vel`` and repeated at
``teleop_frequency`` while the drag is held, so holding the drag keeps the actor walking.

Under ``namespace:=actor1`` every topic is the namespace's and the TF frames carry the prefix
``actor1/`` (robot_state_publisher's ``frame_prefix``, the planner's ``frame_id``, RViz's fixed
frame), so actors launched side by side each show in their own RViz.

Before anything starts, the ROS packages the chosen options need are looked up; a missing one
stops the launch with the command that installs it.
"""
import os
import tempfile

from ament_index_python.packages import get_package_share_directory
from digital_actor_planner.launch_support import (
    check_packages, frame_prefix, launched_package_switches, required_packages, rviz_config,
    switched_on, TELEOP_FREQUENCY, world_frame)
from launch import LaunchDescription
from launch.actions import (
    DeclareLaunchArgument, GroupAction, IncludeLaunchDescription, OpaqueFunction)
from launch.launch_description_sources import PythonLaunchDescriptionSource
from launch.substitutions import LaunchConfiguration
from launch_ros.actions import Node, PushRosNamespace
from launch_ros.parameter_descriptions import ParameterValue

PACKAGE = 'digital_actor_planner'
ARGUMENTS = ('scene', 'use_rviz', 'use_teleop', 'teleop_frequency', 'namespace',
             'use_dynamixel')


def generate_launch_description():
    """Declare the arguments; the actions are made once their values are known."""
    share = get_package_share_directory(PACKAGE)
    arguments = [
        DeclareLaunchArgument(
            'scene', default_value=os.path.join(share, 'config', 'scenes', 'flat.yaml'),
            description='Scene YAML or mesh file the actor walks on'),
        DeclareLaunchArgument('use_rviz', default_value='true', description='Start RViz2'),
        DeclareLaunchArgument('use_teleop', default_value='true',
                              description='Start mouse_teleop (teleop_tools) on cmd_vel'),
        DeclareLaunchArgument(
            'teleop_frequency', default_value=str(TELEOP_FREQUENCY),
            description='Hz at which mouse_teleop repeats the command while a drag is held '
                        '(0: only while the mouse moves; a held drag then stops the actor '
                        "after the planner's cmd_timeout)"),
        DeclareLaunchArgument('namespace', default_value='',
                              description='Namespace of the actor and its helpers; also the '
                                          'prefix of its TF frames'),
        DeclareLaunchArgument('use_dynamixel', default_value='false',
                              description='Also drive a servo figure (launch/bridge.launch.py)'),
    ]
    return LaunchDescription(arguments + [OpaqueFunction(function=_actor, args=[share])])


def _actor(context, share):
    """Return the actor's actions for the arguments; raise before any starts if one cannot."""
    values = {name: LaunchConfiguration(name).perform(context) for name in ARGUMENTS}
    # A Node of a missing package fails only when it is reached, after the planner started.
    check_packages(required_packages(values), get_package_share_directory,
                   launched_package_switches())
    namespace = values['namespace']
    prefix = frame_prefix(namespace)
    try:
        teleop_frequency = float(values['teleop_frequency'])
    except ValueError:
        raise ValueError(f'teleop_frequency must be a number (Hz), got '
                         f'{values["teleop_frequency"]!r}') from None
    with open(os.path.join(share, 'urdf', 'digital_actor.urdf')) as urdf:
        robot_description = urdf.read()
    actions = [
        PushRosNamespace(namespace),
        Node(package=PACKAGE, executable='actor_planner', name='actor_planner',
             output='screen',
             parameters=[os.path.join(share, 'config', 'planner.yaml'),
                         {'scene': _text(values['scene']),
                          'frame_id': _text(world_frame(namespace))}]),
        Node(package='robot_state_publisher', executable='robot_state_publisher',
             name='robot_state_publisher', output='screen',
             parameters=[{'robot_description': _text(robot_description),
                          'frame_prefix': _text(prefix)}]),
    ]
    if switched_on(values, 'use_rviz'):
        actions.append(Node(package='rviz2', executable='rviz2', name='rviz2',
                            arguments=['-d', _rviz_config_file(share, namespace)]))
    if switched_on(values, 'use_teleop'):
        actions.append(Node(package='mouse_teleop', executable='mouse_teleop',
                            name='mouse_teleop',
                            parameters=[{'frequency': teleop_frequency}],
                            remappings=[('mouse_vel', 'cmd_vel')]))
    if switched_on(values, 'use_dynamixel'):
        actions.append(IncludeLaunchDescription(
            PythonLaunchDescriptionSource(os.path.join(share, 'launch', 'bridge.launch.py'))))
    return [GroupAction(actions)]


def _text(value):
    """Return a string parameter passed as written (launch_ros would otherwise read it as YAML)."""
    return ParameterValue(value, value_type=str)


def _rviz_config_file(share, namespace):
    """
    Return the shipped RViz config, or a copy of it with the namespace's frames.

    The copy is kept under ROS_HOME (``~/.ros``), one per namespace, written anew at each
    launch: launches leave no file behind them but that one.
    """
    path = os.path.join(share, 'config', 'actor.rviz')
    if not frame_prefix(namespace):
        return path
    with open(path) as source:
        text = rviz_config(source.read(), namespace)
    folder = os.path.join(os.environ.get('ROS_HOME') or os.path.expanduser('~/.ros'),
                          'digital_actor_planner')
    os.makedirs(folder, exist_ok=True)
    copy = os.path.join(folder,
                        'actor_' + frame_prefix(namespace).rstrip('/').replace('/', '_') + '.rviz')
    # Written beside and renamed over: an RViz of the same namespace starting meanwhile reads
    # the old copy or the new one, never half of one.
    descriptor, partial = tempfile.mkstemp(dir=folder, suffix='.rviz.partial')
    with os.fdopen(descriptor, 'w') as target:
        target.write(text)
    os.replace(partial, copy)
    return copy
