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
Launch the Dynamixel bridge with the package's servo table (config/dynamixel.yaml).

    ros2 launch digital_actor_planner bridge.launch.py port:=/dev/ttyUSB0
    ros2 launch digital_actor_planner bridge.launch.py dry_run:=true
"""
from launch import LaunchDescription
from launch.actions import DeclareLaunchArgument
from launch.substitutions import LaunchConfiguration, PathJoinSubstitution
from launch_ros.actions import Node
from launch_ros.parameter_descriptions import ParameterValue
from launch_ros.substitutions import FindPackageShare


def generate_launch_description():
    """Declare the arguments and start ``dynamixel_bridge``."""
    default_config = PathJoinSubstitution(
        [FindPackageShare('digital_actor_planner'), 'config', 'dynamixel.yaml'])
    arguments = [
        DeclareLaunchArgument('config_file', default_value=default_config,
                              description='ROS 2 parameter file with the servo table.'),
        DeclareLaunchArgument('port', default_value='/dev/ttyUSB0',
                              description='Serial device of the Dynamixel bus.'),
        DeclareLaunchArgument('joint_state_topic', default_value='joint_states',
                              description='JointState topic the servos follow.'),
        DeclareLaunchArgument('dry_run', default_value='false',
                              description='Open no port; log the ticks that would be sent.'),
        DeclareLaunchArgument('require_all_servos', default_value='false',
                              description='Exit if a configured servo does not answer.'),
    ]
    bridge = Node(
        package='digital_actor_planner',
        executable='dynamixel_bridge',
        name='dynamixel_bridge',
        output='screen',
        emulate_tty=True,
        parameters=[
            LaunchConfiguration('config_file'),
            {
                'port': LaunchConfiguration('port'),
                'joint_state_topic': LaunchConfiguration('joint_state_topic'),
                'dry_run': ParameterValue(LaunchConfiguration('dry_run'), value_type=bool),
                'require_all_servos': ParameterValue(LaunchConfiguration('require_all_servos'),
                                                     value_type=bool),
            },
        ],
    )
    return LaunchDescription(arguments + [bridge])
