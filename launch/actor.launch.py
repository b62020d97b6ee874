"""Launch the digital actor: planner, robot_state_publisher, RViz2 and mouse teleop.

    ros2 launch digital_actor_planner actor.launch.py [scene:=FILE] [use_rviz:=true]
        [use_teleop:=true] [namespace:=NS] [use_dynamixel:=false]

Drag in the mouse_teleop window to direct the actor (forward speed and turning, §3.1 of the
paper); mouse_teleop's ``mouse_vel`` is remapped to the planner's ``cmd_vel``.
"""
import os

from ament_index_python.packages import get_package_share_directory
from launch import LaunchDescription
from launch.actions import DeclareLaunchArgument, GroupAction, IncludeLaunchDescription
from launch.conditions import IfCondition
from launch.launch_description_sources import PythonLaunchDescriptionSource
from launch.substitutions import LaunchConfiguration
from launch_ros.actions import Node, PushRosNamespace
from launch_ros.parameter_descriptions import ParameterValue

PACKAGE = 'digital_actor_planner'


def generate_launch_description():
    share = get_package_share_directory(PACKAGE)
    with open(os.path.join(share, 'urdf', 'digital_actor.urdf')) as urdf:
        robot_description = urdf.read()
    scene = LaunchConfiguration('scene')
    arguments = [
        DeclareLaunchArgument(
            'scene', default_value=os.path.join(share, 'config', 'scenes', 'flat.yaml'),
            description='Scene YAML or mesh file the actor walks on'),
        DeclareLaunchArgument('use_rviz', default_value='true', description='Start RViz2'),
        DeclareLaunchArgument('use_teleop', default_value='true',
                              description='Start mouse_teleop (teleop_tools) on cmd_vel'),
        DeclareLaunchArgument('namespace', default_value='',
                              description='Namespace of the actor and its helpers'),
        DeclareLaunchArgument('use_dynamixel', default_value='false',
                              description='Also drive a servo figure (launch/bridge.launch.py)'),
    ]
    actor = GroupAction([
        PushRosNamespace(LaunchConfiguration('namespace')),
        Node(package=PACKAGE, executable='actor_planner', name='actor_planner',
             output='screen',
             parameters=[os.path.join(share, 'config', 'planner.yaml'),
                         {'scene': ParameterValue(scene, value_type=str)}]),
        Node(package='robot_state_publisher', executable='robot_state_publisher',
             name='robot_state_publisher', output='screen',
             parameters=[{'robot_description': ParameterValue(robot_description,
                                                              value_type=str)}]),
        Node(package='rviz2', executable='rviz2', name='rviz2',
             arguments=['-d', os.path.join(share, 'config', 'actor.rviz')],
             condition=IfCondition(LaunchConfiguration('use_rviz'))),
        Node(package='mouse_teleop', executable='mouse_teleop', name='mouse_teleop',
             remappings=[('mouse_vel', 'cmd_vel')],
             condition=IfCondition(LaunchConfiguration('use_teleop'))),
        IncludeLaunchDescription(
            PythonLaunchDescriptionSource(os.path.join(share, 'launch', 'bridge.launch.py')),
            condition=IfCondition(LaunchConfiguration('use_dynamixel'))),
    ])
    return LaunchDescription(arguments + [actor])
