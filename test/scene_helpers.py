"""Small builders shared by the planner tests."""
import numpy as np
import trimesh


def box(lower, upper):
    """A closed box mesh spanning ``lower``..``upper`` ((3,) m each corner)."""
    lower, upper = np.asarray(lower, float), np.asarray(upper, float)
    mesh = trimesh.creation.box(extents=upper - lower)
    mesh.apply_translation((lower + upper) / 2)
    return mesh
