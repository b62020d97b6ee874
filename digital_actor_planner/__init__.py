"""Real-time whole-body motion planning for a mouse-directed humanoid digital actor."""
