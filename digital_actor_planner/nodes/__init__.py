"""Thin rclpy adapters over the planning core."""
