"""Data shared by the evaluation tests."""

from __future__ import annotations

# Four clips of ../shared/mocap: the world puts one motion group in each split (val: two takes of one walk).
TINY = (
    "bandai_namco/dataset-1/dataset-1_walk_normal_001.bvh.gz",
    "bandai_namco/dataset-1/dataset-1_bow_normal_001.bvh.gz",
    "bandai_namco/dataset-2/dataset-2_walk_normal_001.bvh.gz",
    "bandai_namco/dataset-2/dataset-2_walk_normal_002.bvh.gz",
)
