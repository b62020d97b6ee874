"""
ROS-free parts of the Dynamixel bridge: configuration, tick conversion, safety, bus driving.

Only :mod:`digital_actor_planner.dynamixel.bus` imports ``dynamixel_sdk``.
"""
