"""ROS-free planning core: one module per stage of the paper (Li, §3-§5)."""
