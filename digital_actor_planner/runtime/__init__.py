"""ROS-free real time for the planner node: the stand-in pose, frame buffer, planning processes."""
